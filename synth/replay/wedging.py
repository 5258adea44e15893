"""Whether a pin entering a hole at a tilt can wedge: the replay's exact two-point test.

The referee's own model, written from the geometry and not from the planner's
:mod:`synth.models.jamming` (which uses Whitney's small-angle limit c/μ). In the plane of the
tilt, a pin of diameter d tilted by θ in a bore of diameter D touches at two points
[Whitney1982, D. E. Whitney, ASME J. Dyn. Sys. Meas. Control 104 (1982) 65–77]:

* A, the mouth's rim, against the pin's side: the contact normal is the pin's side normal,
  tilted by θ from the horizontal;
* B, the pin's leading edge, against the far bore wall: the normal is horizontal.

The pin has gone in ``ℓ = (D − d cos θ) / sin θ`` along its side past A, and B lies
``h = ℓ cos θ − d sin θ`` below the mouth. The pin wedges (stays stuck with no applied load:
the two contact forces are equal and opposite along AB, each within its friction cone of half
angle φ = atan μ) when the line AB, at ``atan(h / D)`` below the horizontal, is within φ of both
normals; the binding one is A's:

    θ + atan(h / D) ≤ atan μ.

:func:`wedging_onset` is the least tilt that satisfies it (bisection); :func:`wedges` counts a
sampled true tilt at or above the onset as wedged where its two-point contact comes before the
pin seats (h ≤ seat depth).
"""

from __future__ import annotations

import math
from functools import lru_cache

__all__ = ["two_point_depth", "wedges", "wedging_onset"]

_BISECTIONS = 60


def two_point_depth(tilt: float, bore: float, shaft: float) -> float:
    """Depth h [m] below the mouth of the pin's leading edge at two-point contact (inf at 0)."""
    if tilt <= 0.0:
        return math.inf
    along = (bore - shaft * math.cos(tilt)) / math.sin(tilt)
    return along * math.cos(tilt) - shaft * math.sin(tilt)


def _margin(tilt: float, bore: float, shaft: float, friction: float) -> float:
    """``atan μ − θ − atan(h / D)`` [rad]: ≥ 0 where the two contact forces can balance."""
    h = two_point_depth(tilt, bore, shaft)
    return math.atan(friction) - tilt - math.atan2(h, bore)


@lru_cache(maxsize=256)
def wedging_onset(bore: float, shaft: float, friction: float, samples: int = 512) -> float:
    """The least tilt [rad] at which a pin (diameter ``shaft``) can wedge in ``bore`` [m].

    ``inf`` if it never can (a large clearance, or no friction); 0 if the pin does not fit.
    A property of the fit alone, asked at every capture of a replay (~200 evaluations of the
    margin each): kept for the fits last asked.
    """
    if shaft >= bore:
        return 0.0
    top = math.atan(friction)
    if top <= 0.0:
        return math.inf
    previous = 0.0
    for k in range(1, samples + 1):
        tilt = top * (k / samples) ** 2  # fine near 0, where the onset of a close fit lies
        if _margin(tilt, bore, shaft, friction) >= 0.0:
            lo, hi = previous, tilt
            for _ in range(_BISECTIONS):
                mid = 0.5 * (lo + hi)
                if _margin(mid, bore, shaft, friction) >= 0.0:
                    hi = mid
                else:
                    lo = mid
            return hi
        previous = tilt
    return math.inf


def wedges(tilt: float, bore: float, shaft: float, friction: float, seat: float) -> bool:
    """Whether a pin entering at ``tilt`` [rad] wedges before it reaches ``seat`` [m] deep."""
    if shaft >= bore:
        return True
    if tilt < wedging_onset(bore, shaft, friction):
        return False
    return 0.0 <= two_point_depth(tilt, bore, shaft) <= seat
