"""The true workcell a replay machine runs in: its settings, its pins, how a run is stopped.

:class:`ReplayOptions` are the physical and numerical settings (SI units); :class:`PinState` is
one pin of the true world (where it is, whether the hand holds it, which hole it stands in);
:class:`ViolationStop` ends a run at a violation. The machine's parts
(:mod:`synth.replay.walk`, :mod:`synth.replay.sweeps`, :mod:`synth.replay.hand`,
:mod:`synth.replay.goal`) share these.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.al.interpreter import MAX_STATEMENTS, MAX_TIME, MAX_WALL_TIME
from synth.models.arm import JIFFY, Arm, Obstacle, SweepOptions
from synth.models.workcell import HoleSite, PinModel, Workcell
from synth.replay.bounds import PinExtent
from synth.replay.capture import inserted_depth
from synth.replay.motion import MotionState
from synth.replay.reach import ReachProblem, branch_jump, solve_near
from synth.replay.report import Violation

__all__ = [
    "PinState",
    "ReplayOptions",
    "ViolationStop",
    "complied",
    "configuration_of",
    "free_obstacles",
    "pin_states",
]


@dataclass(frozen=True)
class ReplayOptions:
    """Physical and numerical settings of the simulated workcell (SI units)."""

    stall_force: float = 20.0
    """[N] the force the arm pushes with when a motion is blocked [est]: 2 kg-force, far above
    the seed's 8 oz (2.2 N) thresholds."""
    contact_clearance: float = 2e-5
    """[m] pin–surface distance that counts as touching (a pin stops between half of it and
    it from the surface)."""
    sweep: SweepOptions = field(default_factory=lambda: SweepOptions(clearance=1e-3))
    """Swept checks of the arm, palm and fingers: a pair closer than 1 mm is a collision."""
    compliance: float = 0.01
    """[m] how far the arm yields sideways, to a hole guiding the pin or to a surface the pin or
    a finger slides along [est]: wider than any mouth of the seed's parts (0.57 cm), so no
    captured pin jams on its own offset."""
    exit_margin: float = 1e-3
    """[m] a withdrawn pin is clear of its hole when its tip is this far above the mouth."""
    hand_time: float = 50 * JIFFY
    """[s] OPEN, CLOSE and CENTER (seed App. 2, L3854–3857: 50 jiffies)."""
    slide_angle: float = math.radians(20.0)
    """[rad] a push that meets a surface at less than this angle slides along it, the arm
    yielding up to ``compliance`` [est: friction and the servo's give]; steeper pushes stop."""
    pad_tilt: float = math.radians(10.0)
    """[rad] largest angle between a pin's axis and the pads' plane for a grasp."""
    seat_tolerance: float = 1e-4
    """[m] a pin within this of its seated depth is seated."""
    clear_distance: float = 1e-3
    """[m] the hand is clear of the pin when palm and fingers are at least this far from it."""
    max_statements: int = MAX_STATEMENTS
    """Statements one run may execute (the interpreter's budgets: :mod:`synth.al.interpreter`)."""
    max_time: float = MAX_TIME
    """[s] simulated time one run may take; past it the run is an AL runtime error."""
    max_wall_time: float = MAX_WALL_TIME
    """[s] real time one run may take (a loop of motions that take no simulated time)."""
    reference: bool = False
    """Take the reference path: every distance measured at every step of every sweep and
    contact search, the collision scene rebuilt for every grasp and opening. The fast path
    (the default) measures only what can decide a step and reuses scenes; both give the same
    runs (``benchmarks/replay.py`` times one against the other)."""


class ViolationStop(Exception):
    """Raised by the machine to end the run at a violation (caught by the replay)."""

    def __init__(self, violation: Violation) -> None:
        super().__init__(f"{violation.kind} at line {violation.line}: {violation.detail}")
        self.violation = violation


@dataclass
class PinState:
    """A pin in the true world.

    ``pose``: its world pose [m]; ``grip``: hand-from-pin while held; ``hole`` and ``depth``:
    the hole whose bore it stands in and the tip's depth there [m]; ``rests_on``: the obstacle
    it was last stopped on.
    """

    model: PinModel
    pose: pin.SE3
    grip: pin.SE3 | None = None
    hole: HoleSite | None = None
    depth: float = 0.0
    rests_on: str | None = None
    extent: PinExtent | None = None
    """How far the held pin's points reach for its grip (the fast path's bounds; None: not
    yet computed)."""

    @property
    def held(self) -> bool:
        """True while the hand holds the pin."""
        return self.grip is not None


def pin_states(workcell: Workcell, poses: Mapping[str, pin.SE3]) -> dict[str, PinState]:
    """The workcell's pins at their true ``poses``, each in the first hole whose bore it is in."""
    out: dict[str, PinState] = {}
    for frame, pose in poses.items():
        model = workcell.pins[frame]
        state = PinState(model, pin.SE3(pose))
        for hole in workcell.holes:
            depth = inserted_depth(hole, model, pose)
            if depth is not None:
                state.hole, state.depth = hole, depth
                break
        out[frame] = state
    return out


def free_obstacles(workcell: Workcell, pins: Mapping[str, PinState]) -> list[Obstacle]:
    """The static solids and every pin the hand does not hold, at their true poses."""
    out = list(workcell.obstacles)
    for state in pins.values():
        if not state.held:
            out.append(Obstacle(state.model.name, state.model.geometry, state.pose))
    return out


def configuration_of(arm: Arm, state: MotionState) -> NDArray[np.float64]:
    """The arm's joints [rad, m] in ``state``.

    The path's, or where the arm complied (the pin guided by a hole or sliding) the inverse of
    the sensed hand nearest the path's. A compliance only another branch reaches keeps the
    path's joints too: the replay stops such a motion there (``ReplayMachine``'s compliance
    check), and a trace never shows the wrist turning 180° between two samples.
    """
    if state.q is not None:
        return state.q.copy()
    return complied(arm, state)[0]


def complied(arm: Arm, state: MotionState) -> tuple[NDArray[np.float64], str | None]:
    """Where the arm complied in ``state`` (its ``q`` is None), and what it would take.

    The joints are the inverse of the sensed hand nearest the path's (``state.hint``), or the
    path's where the model reaches no solution (it complied a hair beyond it). The second item
    names the joints another branch would turn (:func:`~synth.replay.reach.branch_jump`) when
    only that branch reaches: the path's joints are kept then too.
    """
    try:
        q = solve_near(arm, state.sensed, state.hint)
    except ReachProblem:
        return state.hint.copy(), None
    turned = branch_jump(arm, q, state.hint)
    return (q if turned is None else state.hint.copy()), turned
