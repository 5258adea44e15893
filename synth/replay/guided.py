"""A held pin guided by a hole's bore, from its capture until it bottoms, leaves or jams.

A pin in a hole's bore follows the hole's axis (:func:`guided_motion`): the hole takes the
pin's lateral error and its tilt, the arm complies. Along the commanded path its tip depth is
the commanded tip's depth along the axis. The guided phase ends when the pin bottoms at its
seated depth (force rises), when its tip leaves the mouth (``exit_margin`` above it), or when
the commanded path drags it more than ``compliance`` sideways (the pin jams).

The pin's free flight up to the capture is :mod:`synth.replay.contact`'s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from synth.models.workcell import HoleSite
from synth.replay.bounds import PinFlight
from synth.replay.capture import tip_placement
from synth.replay.motion import PoseAt

__all__ = ["BISECTIONS", "GuidedEnd", "event_crossing", "guided_motion"]

BISECTIONS = 40
"""Bisections of an event's bracket on the reference path (the fast path's Illinois steps end
the bracket as narrow)."""


@dataclass(frozen=True)
class GuidedEnd:
    """How a guided phase ends: at ``s``, by ``kind``, with the tip ``depth`` [m] there."""

    s: float
    kind: Literal["bottom", "exit", "jam", "end"]
    depth: float
    lateral: float


def guided_motion(
    hole: HoleSite,
    pose_at: PoseAt,
    *,
    seat: float,
    start: float = 0.0,
    end: float = 1.0,
    compliance: float = 0.01,
    exit_margin: float = 1e-3,
    seated_within: float = 1e-4,
    samples: int = 64,
    flight: PinFlight | None = None,
) -> GuidedEnd:
    """The end of a pin's guided phase in ``hole`` over s ∈ [start, end] (module docstring).

    ``pose_at`` is the *commanded* pin pose (where the arm would carry it without the hole);
    ``seat`` [m] is the depth at which the pin bottoms, and a pin starting within
    ``seated_within`` [m] of it is seated (:func:`_bottom`). The commanded path is sampled at
    ``samples`` points and the first event is located by bisection.

    With a ``flight`` (the same commanded path with its motion bounds) the same first sample
    is found evaluating fewer: the tip's depth and its distance from the axis are 1-Lipschitz
    in its position, so the event margin m = min(seat − depth, compliance − lateral, depth +
    exit margin) moves no faster than the tip, by at most h·V(s) + ½Ah² from a sample at s;
    samples that close cannot hold an event and are passed over. The event between the last
    sample without one and the first with one is then located on m (Illinois), to the
    reference's bisection width.
    """
    if flight is not None:
        return _guided_flight(
            hole, flight, seat, start, end, compliance, exit_margin, seated_within, samples
        )

    def state(s: float) -> tuple[float, float]:
        p = tip_placement(hole, pose_at(s))
        return -p.axial, p.lateral

    depth0, _ = state(start)
    bottom = _bottom(depth0, seat, compliance, seated_within)

    def event(s: float) -> Literal["bottom", "exit", "jam"] | None:
        return _guided_event(*state(s), bottom, compliance, exit_margin)

    previous = start
    for s in np.linspace(start, end, max(samples, 2))[1:]:
        if event(float(s)) is None:
            previous = float(s)
            continue
        lo, hi = previous, float(s)
        for _ in range(BISECTIONS):
            mid = 0.5 * (lo + hi)
            if event(mid) is None:
                lo = mid
            else:
                hi = mid
        kind = event(hi)
        assert kind is not None
        depth, lateral = state(hi)
        return GuidedEnd(hi, kind, min(max(depth, 0.0), seat), lateral)
    depth, lateral = state(end)
    return GuidedEnd(end, "end", min(max(depth, 0.0), seat), lateral)


def _bottom(depth0: float, seat: float, compliance: float, seated_within: float) -> float:
    """The commanded depth [m] at which a guided pin starting ``depth0`` deep stalls.

    A pin above its ``seat`` stalls on reaching it. A pin already seated (within
    ``seated_within`` of the seat: a stop leaves it there up to rounding) stalls only when the
    path pushes it in by more than the arm's give, ``compliance``, the same give that bounds a
    sideways drag (:func:`_guided_event`). A joint-interpolated move bows, and a seated pin
    dragged sideways stalled on the bow's first nanometre downwards and was never seen to jam:
    a 4 cm drag of the pin seated in the rack passed as a stall at the bottom.
    """
    if depth0 < seat - seated_within:
        return seat
    return max(depth0, seat) + compliance


def _guided_event(
    depth: float, lateral: float, bottom: float, compliance: float, exit_margin: float
) -> Literal["bottom", "exit", "jam"] | None:
    """What ends a guided phase with the tip ``depth`` [m] in and ``lateral`` [m] off the axis.

    It bottoms at ``bottom``, jams past ``compliance`` sideways, leaves ``exit_margin`` above
    the mouth; None while none holds.
    """
    if depth >= bottom:
        return "bottom"
    if lateral > compliance:
        return "jam"
    if depth <= -exit_margin:
        return "exit"
    return None


def _guided_flight(
    hole: HoleSite,
    flight: PinFlight,
    seat: float,
    start: float,
    end: float,
    compliance: float,
    exit_margin: float,
    seated_within: float,
    samples: int,
) -> GuidedEnd:
    """:func:`guided_motion` along a :class:`~synth.replay.bounds.PinFlight` (its docstring)."""
    origin, axis = hole.world_from_hole.translation, hole.axis

    def state(tip: NDArray[np.float64]) -> tuple[float, float]:
        offset = tip - origin
        along = float(axis @ offset)
        radial = offset - along * axis
        return -along, math.sqrt(float(radial @ radial))

    def kind(depth: float, lateral: float) -> Literal["bottom", "exit", "jam"] | None:
        return _guided_event(depth, lateral, bottom, compliance, exit_margin)

    def margin(depth: float, lateral: float) -> float:
        return min(bottom - depth, compliance - lateral, depth + exit_margin)

    flight.at(start)
    depth0, lateral0 = state(flight.translation)
    bottom = _bottom(depth0, seat, compliance, seated_within)
    known_s, known_margin, known_speed = start, margin(depth0, lateral0), flight.speed
    curvature = flight.curvature
    previous = start
    for s in np.linspace(start, end, max(samples, 2))[1:].tolist():
        tau = s - known_s
        if known_margin > tau * known_speed + 0.5 * curvature * tau * tau:
            previous = s  # proven without an event
            continue
        flight.at(s)
        depth, lateral = state(flight.translation)
        event = kind(depth, lateral)
        if event is None:
            previous = s
            known_s, known_margin, known_speed = s, margin(depth, lateral), flight.speed
            continue
        hi = event_crossing(lambda x: margin(*state(flight.tip(x))), previous, s)
        depth, lateral = state(flight.tip(hi))
        event = kind(depth, lateral)
        if event is None:  # on the margin's zero exactly: step onto the event side
            hi = s
            depth, lateral = state(flight.tip(hi))
            event = kind(depth, lateral)
        assert event is not None
        return GuidedEnd(hi, event, min(max(depth, 0.0), seat), lateral)
    depth, lateral = state(flight.tip(end))
    return GuidedEnd(end, "end", min(max(depth, 0.0), seat), lateral)


def event_crossing(f: Callable[[float], float], lo: float, hi: float) -> float:
    """Where f falls from > 0 at ``lo`` to ≤ 0 at ``hi`` (Illinois; ``hi`` side returned).

    The bracket ends as narrow as :data:`BISECTIONS` bisections would make it.
    """
    tolerance = (hi - lo) * 2.0**-BISECTIONS
    f_lo, f_hi = f(lo), f(hi)
    if f_lo <= 0.0:
        return lo
    side = 0
    for _ in range(4 * BISECTIONS):
        if hi - lo <= tolerance or f_hi == 0.0:
            break
        mid = hi - f_hi * (hi - lo) / (f_hi - f_lo) if f_lo != f_hi else 0.5 * (lo + hi)
        if not lo < mid < hi:
            mid = 0.5 * (lo + hi)
        f_mid = f(mid)
        if f_mid > 0.0:
            lo, f_lo = mid, f_mid
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = mid, f_mid
            if side == 1:
                f_lo *= 0.5
            side = 1
    return hi
