"""A pin gone beside the part whose hand stops on the part's face: a miss the success test passes.

Where the error footprint and the search reach past the edge of the hole's face, an attempt can
send the pin down beside the part. It feels nothing until the hand itself comes down on the
face, and then it stops with the pin end at least ``h`` below the face, ``h`` the height of the
hand's lowest point above the pin end (the hand closed on the pin at its grasp): deeper when
that point hangs past the edge and a higher one lands (:func:`hand_height_above_end`). The
program's test ``|DISTANCE_OFF| ≤ t`` (seed L2736) compares the pin end with the believed seat,
``d_f`` below the believed face: DISTANCE_OFF = d_f − u + e for a pin end u ≥ h below the face,
with e the face's height error against the belief (|e| ≤ Δz, after the tap when there is one).
If ``d_f + t + Δz ≥ h`` some such world passes the test with the pin beside the hole: the
program reports an insertion that did not happen (a box known to ±0.2 in in height on the
Stanford arm, a 0.635 cm pin held straight down, h = 2.9 cm, d_f = 1.71 cm, t = 0.85 cm,
Δz = 0.64 cm: 3 of 300 trials; a Panda whose palm, 2.01 cm above the pin end, hangs past the
box's edge at the seat, d_f = 2.03 cm: its pin stopped 2.35 cm down beside the box in the
first trial). Such a candidate is refused.

Nearer the edge the pin does not go beside at all: its axis beyond the edge by less than its
radius, it rests its taper on the edge, the end anywhere from the face down to the taper's
length below it (0.2 cm in a world of a 0.63 cm pin whose program had d_f = 0.9 cm, t = 0.48
cm, Δz = 0.36 cm: the test passed a pin leaning on the box's edge). That range must lie outside
the test's window too, as a miss on the face does (d_f − Δz > t) with d_f less the taper.

The pin can go beside the part only if a place it may come down at, some attempt's offset less
the footprint (±dx × ±dy turned by ζ), lies off the face's outline; this is checked with shapely
on the outline (the face's own frame) and the attempts' footprint boxes
(:func:`~synth.strategies.landing.landing_region`).
"""

from __future__ import annotations

import shapely

from synth.models.spec import SurfaceShape
from synth.strategies.context import PlanContext
from synth.strategies.landing import Landing

__all__ = ["false_seat_problem"]


def _can_go_beside(ctx: PlanContext, where: Landing) -> bool:
    """Whether some attempt may bring the pin down off the hole's face (module docstring)."""
    shape = ctx.graph.node(ctx.hole_shape.surface).shape
    if not isinstance(shape, SurfaceShape):
        return False
    return not shapely.Polygon(shape.outline).covers(where.region)


def false_seat_problem(ctx: PlanContext, where: Landing) -> str | None:
    """Why a pin beside the part could pass the program's success test, or None.

    Two ways to stop off the face's edge (module docstring): the hand landing on the face, the
    pin end ``h`` below it; or the pin's taper resting on the edge, its axis beyond the edge by
    u with r_tip < u < r_pin, the end ``L_t (u − r_tip)/(r_pin − r_tip)`` below the face: any
    depth in [0, L_t). A depth u passes the test when |d_f − u| ≤ t + Δz, so the taper's range
    does when d_f − t − Δz < L_t (the window of a miss on the face, d_f − Δz > t, with d_f less
    the taper).
    """
    if not _can_go_beside(ctx, where):
        return None
    window = (
        f"within {where.window()} of d_f = {100 * where.d_f:.3g} cm: a miss would pass for an "
        "insertion"
    )
    taper = ctx.pin_shape.tip_taper_length
    tapered = ctx.pin_shape.tip_radius < ctx.pin_shape.diameter / 2
    if tapered and taper > 0.0 and where.d_f - where.threshold - where.dz < taper:
        return (
            f"a pin that comes down just past {ctx.hole_al}'s face's edge (the footprint and "
            f"search reach past it) rests its taper on the edge with its end up to "
            f"{100 * taper:.3g} cm below the face, {window}"
        )
    if not where.felt(where.hand_height):
        return None
    return (
        f"a pin that goes down beside {ctx.hole_al}'s face (the footprint and search reach past "
        f"its edge) stops when the hand lands on the face {100 * where.hand_height:.2f} cm above "
        f"the pin end, {window}"
    )
