"""The hand's motions: opening and closing the fingers, grasping a pin, letting it go.

``OPEN``/``CLOSE``/``CENTER`` take ``hand_time`` (50 jiffies, seed App. 2, L3854–3857; stretched
by ``WITH DURATION``), the opening changing linearly in time (:func:`hand_motion`).

**Grasp** (:func:`grasp_candidate`, :func:`grasp`). ``CENTER`` (and ``CLOSE``, whose fingers
comply the same way) grasps a free pin whose axis runs between the open pads: within
``pad_tilt`` of their plane, the axis point nearest the pads' centre line within a pad radius of
it, and the pin's section there within the opening. In the hand frame (x across the pads) with
the pin's origin o and axis a, the axis point nearest the hand's x axis is p = o + λa with

    λ = (a_x·o_x − a·o) / (1 − a_x²),

and the pin's radius there is the opening it closes on. The arm moves along the hand's x until
both pads touch (the centring offset p_x), the opening becomes the pin's diameter at the pads,
and the hand is registered on the pin: its reading becomes its true pose (the seed's hand
"holds the pin with essentially no error", L2244), so the pin's pose in the hand is known as
well as the pin's location was. A grasp that misses closes the fingers to 0.

**Release** (:func:`release`). Opening the fingers wider than the pin lets it go: a pin
standing in a hole whose axis points up drops to its seated depth; anything else stays where it
is. Opening the fingers into something is a ``collision`` (:func:`finger_collision`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from typing import Literal

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.al.motions import MonitorSpec
from synth.al.timeline import monitor_checkpoints
from synth.models.arm import HAND_BODIES, Arm, CollisionScene
from synth.replay.capture import seat_depth, seated_pose
from synth.replay.cell import PinState
from synth.replay.motion import Motion, MotionState
from synth.replay.reach import solve_continuing
from synth.replay.sweeps import pair_collisions

__all__ = ["finger_collision", "grasp", "grasp_candidate", "hand_motion", "release"]


def hand_motion(
    kind: Literal["open", "close", "center"],
    line: int,
    monitors: Sequence[MonitorSpec],
    start_time: float,
    duration: float,
    opening: tuple[float, float],
    q: NDArray[np.float64],
    sensed: pin.SE3,
    error: pin.SE3,
    finish: Callable[[], None] | None,
) -> Motion:
    """The timeline of a hand motion: the fingers go ``opening`` [m] in ``duration`` [s].

    The arm stands at ``q`` (reading ``sensed``, error ``error``) throughout.
    """
    start, final = opening
    motion = Motion(
        kind,
        line,
        tuple(monitors),
        start_time,
        duration,
        monitor_checkpoints(monitors, duration, opening=opening),
        True,
        start,
        final,
        finish=finish,
    )

    def state_at(elapsed: float) -> MotionState:
        return MotionState(q, q, sensed, error, None, None, 0.0, motion.opening_at(elapsed))

    motion.state_at = state_at
    return motion


def grasp_candidate(
    arm: Arm, pins: Iterable[PinState], true_hand: pin.SE3, opening: float, pad_tilt: float
) -> tuple[PinState, float, float] | None:
    """A free pin between the open pads: (pin, opening on it [m], centring offset [m])."""
    hand = arm.hand
    for state in pins:
        if state.held:
            continue
        local = true_hand.actInv(state.pose)
        o, a = local.translation, local.rotation[:, 2]
        if abs(a[0]) > math.sin(pad_tilt):
            continue
        lam = (a[0] * o[0] - float(a @ o)) / (1.0 - a[0] * a[0])
        p = o + lam * a
        radius = state.model.radius_at(lam)
        if (
            radius > 0.0
            and math.hypot(p[1], p[2]) <= hand.finger_pad_radius
            and abs(p[0]) + radius <= opening / 2
        ):
            return state, 2.0 * radius, float(p[0])
    return None


def grasp(
    arm: Arm, state: PinState, true_hand: pin.SE3, offset: float, q: NDArray[np.float64]
) -> tuple[pin.SE3, NDArray[np.float64]]:
    """The pads close on ``state``'s pin, the arm centring by ``offset`` [m] along hand x.

    Returns the hand's new pose (reading = truth) and the arm's configuration; the pin is
    held from now on. A centring move the arm's branch cannot make (a joint at its stop, or
    out of reach) is a :class:`ReachProblem`: the pin is not grasped. It was once absorbed,
    the joints kept while the hand moved, or set to another branch's (the wrist turned 180°
    in no time, and the trial went on to succeed).
    """
    hand = true_hand * pin.SE3(np.eye(3), np.array([offset, 0.0, 0.0]))
    q = solve_continuing(arm, hand, q, f"centring the hand {100 * offset:+.2f} cm along its x")
    state.grip = hand.actInv(state.pose)
    state.rests_on = None
    return hand, q


def release(state: PinState) -> None:
    """Let go of ``state``'s pin: in a hole whose axis points up it drops to its seat."""
    state.grip = None
    hole = state.hole
    if hole is not None and float(hole.axis[2]) > 0.5:
        state.depth = seat_depth(hole, state.model)
        state.pose = seated_pose(hole, state.depth, state.pose)


def finger_collision(scene: CollisionScene, q: NDArray[np.float64]) -> tuple[str, str] | None:
    """The first pair in contact at ``q`` with a palm or finger in it, if any."""
    hand = [k for k, (a, b) in enumerate(scene.pairs) if a in HAND_BODIES or b in HAND_BODIES]
    hits = pair_collisions(scene, q, hand)
    return hits[0] if hits else None
