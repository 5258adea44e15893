"""Another hole within the search's reach: a pin seated in the wrong hole, or dragged from it.

The search tries points until the success test ``|DISTANCE_OFF| ≤ t`` passes (seed L2736). Where
the places the pin end may come down at (:func:`~synth.strategies.landing.landing_region`) come
within another open hole's lead (mouth radius − tip radius, all the replay captures) of its axis,
some world drops the pin into that hole. Seated there at depth d_o (its depth, or where the hand
lands first), DISTANCE_OFF = d_f − d_o + e with |e| ≤ Δz, and the program then

* reads a seat, |d_f − d_o| ≤ t + Δz: it reports the insertion into the wrong hole;
* reads nothing felt, d_o > d_f + t + Δz: it lifts the pin out and searches on, as for a miss
  beside the part (harmless);
* reads neither, otherwise: it moves on to the next point with the pin in the hole, dragging it.

So another open hole within reach is harmless only when it is deeper than ``d_f + t + Δz``. A
hole narrower than the pin is no safer: its mouth catches the tip (the lead is the mouth's
radius less the tip's) and the pin jams in it (a UR5 variant: PIN1, 0.748 cm, wedged in the
0.64 cm BH3 in both of its first proof trials). On
the seed's cell with the box known to ±0.6 in, ±0.4 in and ±10° and BH1 moved 3.5 cm from BH2
(d_f = 1.64 cm, BH2 1.71 cm deep), 4 of 160 proof trials put PIN1 in BH2 and passed the test.
Holes that hold another pin are not open; the pin's own start hole is, once the pin has left it.

Any open hole counts, not only those declared on the target's surface: a face split into two
surface frames, or a lower step of the part (or of another part) with a hole whose bottom is
d_f below the face, seats the pin as well (the fourth hunt: 195 of 200 where 99 % was proven,
"PIN1 is in BH2, not in BH1"). The other hole is seen from the target's surface: its centre in
that plane, and its mouth z below it, so the pin end stops at z + its depth below the face,
if its axis is within 60° of the face's normal (one farther off cannot take a falling pin).
Where an uncertain link lies between the two, its certified error (``surface⁻¹ ∘ hole``,
:func:`~synth.errors.estimate.estimate_errors`) widens the lead by the lateral bound and the
depth to an interval by the bound along the normal.
"""

from __future__ import annotations

import math

import shapely

from synth.errors.chain import chain_between
from synth.errors.estimate import estimate_errors
from synth.models.spec import HoleShape
from synth.strategies.context import PlanContext
from synth.strategies.landing import Landing

__all__ = ["wrong_hole_problem"]

_FACING = 0.5
"""cos 60°: a hole whose axis is farther than this from the face's normal takes no falling pin."""


def _occupied(ctx: PlanContext) -> set[str]:
    """Holes (frame names) another pin stands in: the parents of the other pins' frames."""
    graph = ctx.graph
    return {
        graph.parent(name)
        for name, node in graph.nodes.items()
        if node.kind == "pin" and name != ctx.pin_frame
    }


def _relative_error(ctx: PlanContext, surface: str, hole: str) -> tuple[float, float]:
    """Certified (lateral, normal) bounds [m] of ``surface⁻¹ ∘ hole``'s error.

    (0, 0) when the two are fixed to each other (no uncertain link between them).
    """
    chain = chain_between(ctx.graph, surface, hole)
    if chain.space.dim == 0:
        return 0.0, 0.0
    certified = estimate_errors(chain, surface, hole).certified
    return math.hypot(certified.dx.magnitude, certified.dy.magnitude), certified.dz.magnitude


def wrong_hole_problem(ctx: PlanContext, where: Landing) -> str | None:
    """Why the search may seat the pin in another open hole, or None (module docstring)."""
    graph, surface = ctx.graph, ctx.hole_shape.surface
    occupied = _occupied(ctx)
    pin_shape = ctx.pin_shape
    for name, node in graph.nodes.items():
        shape = node.shape
        if name == ctx.hole_frame or name in occupied or not isinstance(shape, HoleShape):
            continue
        surface_from_hole = graph.relative(surface, name)
        facing = float(surface_from_hole.rotation[2, 2])
        if facing < _FACING:
            continue
        lateral, normal = _relative_error(ctx, surface, name)
        lead = shape.diameter / 2 + shape.chamfer_width - pin_shape.tip_radius
        centre = surface_from_hole.translation[:2]
        if lead <= 0.0 or where.region.distance(shapely.Point(*centre)) >= lead + lateral:
            continue
        reach = (
            f"the search may find {node.al_name} instead of {ctx.hole_al}: the places the pin may "
            f"come down at reach within {100 * lead:.3g} cm of its axis (its lead)"
        )
        if shape.diameter <= pin_shape.diameter:
            return (
                f"{reach}, and its mouth catches the tip of a pin it does not fit (a "
                f"{100 * pin_shape.diameter:.3g} cm pin, a {100 * shape.diameter:.3g} cm hole): "
                "the pin jams there"
            )
        # the pin end stops at the hole's bottom, seen along the face's normal, or where the
        # hand lands on the face first
        below = shape.depth * facing - float(surface_from_hole.translation[2])
        shallowest = min(below - normal, where.hand_height)
        deepest = min(below + normal, where.hand_height)
        if deepest <= 0.0 or not where.felt(shallowest):
            continue  # read as nothing felt: lifted out, the search goes on
        nearest = min(max(where.d_f, shallowest), deepest)
        read = (
            "passes the success test: the program would report the wrong insertion"
            if where.passes(nearest)
            else "is read as neither a seat nor a miss: the next search move drags it"
        )
        depth = (
            f"{100 * shallowest:.3g}"
            if deepest - shallowest < 5e-5
            else (f"{100 * shallowest:.3g}–{100 * deepest:.3g}")
        )
        return (
            f"{reach}, and a pin {depth} cm deep in it, against d_f = "
            f"{100 * where.d_f:.3g} cm and {where.window()}, {read}"
        )
    return None
