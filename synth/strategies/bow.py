"""The path bow of a joint-interpolated approach, and via points along the axis that bound it.

AL moves are joint-interpolated (seed L3846): between two targets the arm moves along the
straight joint-space segment between their arm solutions, so the hand runs along a curve, not
the straight line between them. For the final approach of the first attempt (the pin end from
``hole ∘ trans(rot(ẑ, φ), (0, 0, standoff))`` down to ``(0, 0, −dtry)``) the curve bows off the
hole axis: on the Stanford arm of seed_4_8 by about 1.3 mm with every error at zero, more than a
precision fit's lead.

The bow is measured on the arm model, never assumed: for the end point ``p(s)`` of the pin,

    p(s) = T_hole⁻¹ · FK(q_k + s·(q_(k+1) − q_k)) · T_hand_end · 0,   s ∈ [0, 1],

its lateral distance from the axis, ``b(s) = √(p_x² + p_y²)`` [m], is sampled on every segment
of the approach while the end is above the seated depth (``p_z ≥ −d_f``), and the bow is the
largest sample plus half the longest chord between consecutive samples (b is 1-Lipschitz in p,
and a point between two samples is within half a chord of one of them, to first order in the
curvature). Via points at equal height steps along the axis (each solved nearest the one
before it, the replay's rule) cut the segments: a segment's bow shrinks with the square of its
length, so a few vias bound it. :func:`plan_axis_path` picks the fewest that bring the bow
within ``tolerance``; the bow that remains is added to the footprint
(:mod:`synth.strategies.refine`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.arm import Arm

__all__ = [
    "BOW_FRACTION",
    "MAX_VIAS",
    "SAMPLES",
    "AxisPath",
    "axis_heights",
    "path_bow",
    "pin_deviation",
    "plan_axis_path",
    "split_at_height",
]

BOW_FRACTION = 0.1
"""The bow is bounded by this fraction of the parts' geometric lead (or Δr_ok if smaller)."""
MAX_VIAS = 8
"""At most this many via points between the approach point and the target."""
SAMPLES = 48
"""Samples per joint-space segment [1]."""

Configuration = NDArray[np.float64]


def axis_heights(standoff: float, dtry: float, vias: int) -> tuple[float, ...]:
    """Heights [m] of the end along the axis: standoff, ``vias`` equal steps, then −dtry.

    The vias' heights are rounded to 0.1 mm, so that the program prints them exactly.
    """
    step = (standoff + dtry) / (vias + 1)
    inner = tuple(round(standoff - k * step, 4) for k in range(1, vias + 1))
    return (standoff, *inner, -dtry)


def path_bow(
    arm: Arm,
    configurations: Sequence[Configuration],
    hole_from_world: pin.SE3,
    hand_from_end: pin.SE3,
    floor: float,
    samples: int = SAMPLES,
) -> float:
    """The bow [m] of the joint-space polyline through ``configurations`` (module docstring).

    Only points with the end at or above ``floor`` [m] (hole frame z, −d_f) count.
    """
    worst = 0.0
    for end in _end_frames(arm, configurations, hole_from_world, hand_from_end, samples):
        p = np.asarray(end.translation, dtype=float)
        if p[2] >= floor:
            worst = max(worst, math.hypot(float(p[0]), float(p[1])))
    return worst


def _end_frames(
    arm: Arm,
    configurations: Sequence[Configuration],
    hole_from_world: pin.SE3,
    hand_from_end: pin.SE3,
    samples: int,
) -> Iterator[pin.SE3]:
    """The pin end's frame in the hole frame at ``samples`` + 1 points of every segment."""
    for q0, q1 in itertools.pairwise(configurations):
        delta = np.asarray(q1) - np.asarray(q0)
        for s in np.linspace(0.0, 1.0, samples + 1):
            yield hole_from_world * arm.forward(q0 + s * delta) * hand_from_end


@dataclass(frozen=True, eq=False)
class AxisPath:
    """The final approach along the hole axis.

    ``heights`` [m] of the end (approach, vias, target), the arm's ``configurations`` there and
    the measured ``bow`` [m].
    """

    heights: tuple[float, ...]
    configurations: tuple[Configuration, ...]
    bow: float

    @property
    def via_heights(self) -> tuple[float, ...]:
        """Heights [m] of the via points between the approach point and the target."""
        return self.heights[1:-1]


def plan_axis_path(
    solve: Callable[[float, Configuration], Configuration | None],
    arm: Arm,
    q_approach: Configuration,
    hole_from_world: pin.SE3,
    hand_from_end: pin.SE3,
    standoff: float,
    dtry: float,
    d_f: float,
    tolerance: float,
) -> AxisPath | None:
    """The fewest vias (0…:data:`MAX_VIAS`) whose path bows at most ``tolerance`` [m].

    ``solve(z, q)`` is the arm solution with the end at height ``z`` on the axis, nearest ``q``
    (None: unreachable). Returns the path with the smallest bow if none is within tolerance,
    None if no height has an arm solution.
    """
    best: AxisPath | None = None
    for vias in range(MAX_VIAS + 1):
        heights = axis_heights(standoff, dtry, vias)
        path: list[Configuration] = [q_approach]
        for z in heights[1:]:
            q = solve(z, path[-1])
            if q is None:
                break
            path.append(q)
        else:
            bow = path_bow(arm, path, hole_from_world, hand_from_end, -d_f)
            made = AxisPath(heights, tuple(path), bow)
            if best is None or bow < best.bow:
                best = made
            if bow <= tolerance:
                return made
    return best


def _end_height(
    arm: Arm, q: Configuration, hole_from_world: pin.SE3, hand_from_end: pin.SE3
) -> float:
    """Height [m] of the pin end along the hole axis (hole frame z) with the arm at ``q``."""
    return float((hole_from_world * arm.forward(q) * hand_from_end).translation[2])


def split_at_height(
    arm: Arm,
    configurations: Sequence[Configuration],
    hole_from_world: pin.SE3,
    hand_from_end: pin.SE3,
    height: float,
    bisections: int = 40,
) -> tuple[list[Configuration], list[Configuration]]:
    """The joint-space polyline cut where the pin end first comes down to ``height`` [m].

    Returns (the path down to the cut, the path from it on), the cut configuration ending the
    first and starting the second; the cut lies on the polyline (``q_k + s·(q_(k+1) − q_k)``,
    ``s`` bisected to 2⁻⁴⁰ on the first segment whose end is at or below ``height``). A path
    that never comes that low is all above (the second part empty); one that starts at or
    below it is all below.
    """
    path = [np.asarray(q, dtype=float) for q in configurations]
    heights = [_end_height(arm, q, hole_from_world, hand_from_end) for q in path]
    if heights[0] <= height:
        return [], path
    for k in range(1, len(path)):
        if heights[k] > height:
            continue
        q0, delta = path[k - 1], path[k] - path[k - 1]
        above, below = 0.0, 1.0
        for _ in range(bisections):
            middle = 0.5 * (above + below)
            if _end_height(arm, q0 + middle * delta, hole_from_world, hand_from_end) > height:
                above = middle
            else:
                below = middle
        cut = q0 + below * delta
        return [*path[:k], cut], [cut, *path[k:]]
    return path, []


def pin_deviation(
    arm: Arm,
    configurations: Sequence[Configuration],
    hole_from_world: pin.SE3,
    hand_from_end: pin.SE3,
    on_axis: Callable[[float], pin.SE3],
    length: float,
    radius: float,
    samples: int = SAMPLES,
) -> float:
    """How far [m] any point of the pin moves from its pose on the path to its pose on the axis.

    At each of ``samples`` + 1 points of every segment the commanded pin end frame
    ``E = hole_from_world · FK(q) · hand_from_end`` is compared with ``A = on_axis(E_z)``, the
    end frame on the hole axis at the same height (the turn the program gives it about the
    axis). A point ``x`` of the pin (end frame) moves by
    ``|E·x − A·x| ≤ |E·c − A·c| + ‖R_E − R_A‖₂·|x − c|`` for any ``c`` on its axis. With ``c``
    the end or the far end ``(0, 0, length)`` (z leaves the hole along the pin,
    :func:`~synth.strategies.context.pin_end_frame`) and ``|x − c| ≤ radius`` from the axis,
    the larger of ``|E·c − A·c|`` at the two ends (affine along the axis), plus
    ``‖R_E − R_A‖₂·radius``, bounds it; ``‖R_E − R_A‖₂ = √(3 − tr R_EᵀR_A)``. Between samples
    the pin moves continuously: as :func:`path_bow`, a sampled maximum, not a certificate.
    """
    ends = (np.zeros(3), np.array([0.0, 0.0, length]))
    worst = 0.0
    for end in _end_frames(arm, configurations, hole_from_world, hand_from_end, samples):
        axis = on_axis(float(end.translation[2]))
        turn = math.sqrt(max(0.0, 3.0 - float(np.trace(end.rotation.T @ axis.rotation))))
        moved = max(float(np.linalg.norm(end.act(c) - axis.act(c))) for c in ends)
        worst = max(worst, moved + turn * radius)
    return worst
