"""Fit and wedging of a round pin in a round hole: the planner's tilt limit [Whitney1982].

[Whitney1982] D. E. Whitney, "Quasi-static assembly of compliantly supported rigid parts",
ASME J. Dyn. Sys., Meas., Control 104 (1982) 65–77.

With hole diameter D, pin (shaft) diameter d and friction coefficient μ:

* fit: the pin enters only if ``d < D``;
* clearance ratio ``c = (D − d) / D`` [1];
* two-point contact (the mouth's rim on one side of the pin, the pin's leading edge on the
  other wall) of a pin tilted by θ happens at the insertion depth ℓ with
  ``ℓ sin θ + d cos θ = D``, for small angles ``ℓ ≈ c·D / θ``;
* wedging (the two contact forces balance inside their friction cones, so the pin sticks
  whatever the arm does) is possible when that contact is shallow, ``ℓ / D < μ``; with the
  small-angle ℓ this is a tilt at two-point contact above

      θ_wedge = c / μ   [rad].

The arm holds the pin's orientation stiffly, so the tilt at two-point contact is the tilt at
entry: an insertion whose tilt bound stays below θ_wedge cannot wedge. Jamming proper (a pin
that stops because the applied force and moment leave Whitney's jamming diagram) depends on the
applied forces, not on the geometry alone; the planner leaves it to the replay's compliance model.

The replay checks wedging with its own, exact two-point geometry
(:mod:`synth.replay.wedging`); it is not this module's arithmetic.
"""

from __future__ import annotations

import math

__all__ = ["clearance_ratio", "fit_problem", "wedging_tilt"]


def clearance_ratio(hole_diameter: float, pin_diameter: float) -> float:
    """``c = (D − d) / D`` [1] for hole diameter D and pin diameter d [m] (Whitney1982)."""
    return (hole_diameter - pin_diameter) / hole_diameter


def wedging_tilt(hole_diameter: float, pin_diameter: float, friction: float) -> float:
    """``θ_wedge = c / μ`` [rad], capped at 90° (a frictionless pair never wedges).

    0 when the pin does not fit (``c ≤ 0``).
    """
    c = clearance_ratio(hole_diameter, pin_diameter)
    if c <= 0.0:
        return 0.0
    if friction <= 0.0:
        return math.pi / 2
    return min(c / friction, math.pi / 2)


def fit_problem(pin: str, pin_diameter: float, hole: str, hole_diameter: float) -> str | None:
    """Why pin ``pin`` cannot go into hole ``hole`` (diameters [m]), or None if it fits."""
    if pin_diameter < hole_diameter:
        return None
    return (
        f"pin {pin} ({100 * pin_diameter:.2f} cm) does not fit hole {hole} "
        f"({100 * hole_diameter:.2f} cm): a pin must be thinner than its hole"
    )
