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
"""

from __future__ import annotations

import shapely

from synth.models.spec import HoleShape
from synth.strategies.context import PlanContext
from synth.strategies.landing import Landing

__all__ = ["wrong_hole_problem"]


def _occupied(ctx: PlanContext) -> set[str]:
    """Holes (frame names) another pin stands in: the parents of the other pins' frames."""
    graph = ctx.graph
    return {
        graph.parent(name)
        for name, node in graph.nodes.items()
        if node.kind == "pin" and name != ctx.pin_frame
    }


def wrong_hole_problem(ctx: PlanContext, where: Landing) -> str | None:
    """Why the search may seat the pin in another hole of the face, or None (module docstring)."""
    graph, surface = ctx.graph, ctx.hole_shape.surface
    occupied = _occupied(ctx)
    pin_shape = ctx.pin_shape
    for name, node in graph.nodes.items():
        shape = node.shape
        if name == ctx.hole_frame or name in occupied or not isinstance(shape, HoleShape):
            continue
        if shape.surface != surface:
            continue
        lead = shape.diameter / 2 + shape.chamfer_width - pin_shape.tip_radius
        centre = graph.relative(surface, name).translation[:2]
        if lead <= 0.0 or where.region.distance(shapely.Point(*centre)) >= lead:
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
        depth = min(shape.depth, where.hand_height)
        if not where.felt(depth):
            continue  # read as nothing felt: lifted out, the search goes on
        read = (
            "passes the success test: the program would report the wrong insertion"
            if where.passes(depth)
            else "is read as neither a seat nor a miss: the next search move drags it"
        )
        return (
            f"{reach}, and a pin {100 * depth:.3g} cm deep in it, against d_f = "
            f"{100 * where.d_f:.3g} cm and {where.window()}, {read}"
        )
    return None
