"""Gross motions lifted over the workcell: two via points above what a straight move would hit.

AL moves are joint-interpolated, and a straight joint path from the park (or the last step's
clear point) to a grasp's approach point, or from the departure point to the hole's approach
point, sweeps through whatever stands between them: a tower between the rack and the box
refused the task ("the move … sweeps palm into TOWER"). An engineer lifts the hand over it.
When the straight path is obstructed, :func:`lift_over` raises the hand straight up from the
motion's start, carries it at that height to above the motion's end and lowers it there: two
via points with the ends' own orientations, the hand's origin at the height

    z_via = max_k top_k + drop + need + SLACK,

* top_k the world height of each environment solid the path met (the top of its axis-aligned
  box at its nominal pose; its uncertainty is in ``need``);
* drop how far the hand's own assembly (fingers, palm and what it holds, the bodies on the
  hand's joint) reaches below the hand's origin, at either end;
* need the distance the sweep asked of the pair: the clearance and both solids' margins.

A via is left out where its end is already that high. The lifted path is swept as a whole, like
any gross motion; a solid it meets joins the tops, at most :data:`ROUNDS` times. The arm must
come down onto the end on the branch the straight move reached (the configurations after it
were solved from there).

The via points are world poses, not relative to a part: above the workcell the parts'
uncertainties shift nothing that matters, and the motion's last leg, from above the end, is
swept with the same margins as before.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from synth.models.arm import CollisionScene, SweepResult
from synth.models.arm.bodies import z_range
from synth.models.arm.sweep import swept_path
from synth.strategies.context import Configuration, PlanContext
from synth.strategies.records import WORLD_BASE, Destination

__all__ = ["ROUNDS", "SLACK", "Detour", "lift_over"]

ROUNDS = 3
"""Lifts tried per motion: each after the last one met another solid."""

SLACK = 0.01
"""[m] Above the height the sweep asked for: the joint-interpolated legs between the vias bow."""

_SAME_BRANCH = 1e-6  # [rad, m] the end configuration re-solved from the last via


@dataclass(frozen=True)
class Detour:
    """The via points of a lifted gross motion, in order.

    ``world_from_hand`` are the hand's poses there, ``configurations`` the arm's (solved nearest
    the one before, as the arm moves), ``height`` [m] the hand's origin at the top and ``over``
    the solids it was lifted over.
    """

    world_from_hand: tuple[pin.SE3, ...]
    configurations: tuple[Configuration, ...]
    height: float
    over: tuple[str, ...]

    def describe(self) -> str:
        """``over TOWER (the hand at 31.20 cm, 2 via points)``: for the plan's decisions.

        One via point where the start is already that high (from the park, say).
        """
        n = len(self.world_from_hand)
        vias = f"{n} via point{'s' if n != 1 else ''}"
        return f"over {', '.join(self.over)} (the hand at {100 * self.height:.2f} cm, {vias})"

    def destinations(
        self, what: str, hand_from_what: pin.SE3 | None = None
    ) -> tuple[Destination, ...]:
        """The via points as world destinations of ``what``, labelled ``lift 1``, ``lift 2``.

        ``what`` is the hand, or what it holds at ``hand_from_what``.
        """
        offset = pin.SE3.Identity() if hand_from_what is None else hand_from_what
        return tuple(
            Destination(f"lift {k + 1}", what, WORLD_BASE, hand * offset)
            for k, hand in enumerate(self.world_from_hand)
        )


def _drop(scene: CollisionScene, q: Configuration, hand_z: float) -> float:
    """How far below the hand's origin the bodies on the hand's joint reach at ``q`` [m]."""
    arm = scene.arm
    joint = int(arm.model.frames[arm.hand_frame].parentJoint)
    lowest = hand_z
    for body in scene.bodies:
        if body.joint == joint and body.role != "environment":
            lowest = min(lowest, z_range(body.geometry, scene.body_pose(q, body.name))[0])
    return hand_z - lowest


def _tops(scene: CollisionScene) -> dict[str, float]:
    return {o.name: z_range(o.geometry, o.pose)[1] for o in scene.environment}


def _lifted(world_from_hand: pin.SE3, height: float) -> pin.SE3 | None:
    """The pose raised to ``height``, or None when it is already that high."""
    if world_from_hand.translation[2] >= height:
        return None
    raised = world_from_hand.copy()
    raised.translation = np.array([*world_from_hand.translation[:2], height])
    return raised


def lift_over(
    ctx: PlanContext,
    scene: CollisionScene,
    q_from: Configuration,
    q_to: Configuration,
    straight: SweepResult,
) -> Detour | str:
    """Via points that carry the straight move ``q_from → q_to`` over the workcell.

    ``straight`` is the sweep that found the straight move obstructed (its pair is the first
    solid to lift over). Returns a :class:`Detour` whose whole path (``q_from``, its
    configurations, ``q_to``) sweeps clear, or why none was found (the module docstring gives
    the rule).
    """
    options = ctx.gross.options_for(scene)
    tops = _tops(scene)
    start, end = ctx.arm.forward(q_from), ctx.arm.forward(q_to)
    drop = max(
        _drop(scene, q_from, float(start.translation[2])),
        _drop(scene, q_to, float(end.translation[2])),
    )
    result = straight
    over: list[str] = []
    need = 0.0
    for _ in range(ROUNDS):
        met = [name for name in (result.pair or ()) if name in tops]
        if not met:
            return f"it meets {' and '.join(result.pair or ('?',))}, which no lift clears"
        if met[0] in over:
            return f"lifted over {met[0]} it still meets {met[0]}"
        over.append(met[0])
        need = max(need, float(options.required([result.pair])[0]) if result.pair else 0.0)
        height = max(tops[name] for name in over) + drop + need + SLACK
        poses = [p for p in (_lifted(start, height), _lifted(end, height)) if p is not None]
        configurations: list[Configuration] = []
        q = q_from
        for pose in poses:
            solved = ctx.nearest(pose, q)
            if solved is None:
                return f"no arm solution with the hand {100 * height:.2f} cm high"
            configurations.append(solved)
            q = solved
        landed = ctx.nearest(end, q)
        if landed is None or float(np.max(np.abs(landed - q_to))) > _SAME_BRANCH:
            return "coming down from the lift, the arm would reach the end on another branch"
        ctx.counters.sweeps += 1
        result = swept_path(scene, [q_from, *configurations, q_to], options)
        if result.free:
            return Detour(tuple(poses), tuple(configurations), height, tuple(over))
    return f"after {ROUNDS} lifts it still meets {' and '.join(result.pair or ('?',))}"
