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

import math

import coal
import numpy as np
import shapely

from synth.models.spec import SurfaceShape
from synth.strategies.context import PlanContext, end_from_hand
from synth.strategies.landing import landing_region
from synth.strategies.records import Grasp, PinInHoleStrategy

__all__ = ["false_seat_problem", "hand_height_above_end"]


def hand_height_above_end(ctx: PlanContext, grasp: Grasp) -> float:
    """Height [m] of the hand's lowest point above the pin end, along the end's axis.

    The end frame's z points out of the hole once inserted; the hand holds the pin by ``grasp``,
    fingers closed on it. Coal's distance from each of the arm's hand bodies (the parametric
    hand's plates and palm, or a URDF hand's own meshes) to the half-space z ≤ 0 of the end
    frame: the height of the body's lowest point. For the parametric hand this is the closed
    form ``d − r_pad (sin γ + |cos γ|)`` (its plates reach one pad radius past the pads' centre
    along the approach and across it); a Panda's palm sits 1 cm higher than that form says.
    """
    scene = ctx.gross.holding(grasp)
    q = ctx.q_park  # the bodies' placements in the hand frame do not depend on the joints
    hand = ctx.arm.forward(q)
    end_hand = end_from_hand(ctx, grasp)
    below = coal.Halfspace(np.array([0.0, 0.0, 1.0]), 0.0)
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    lowest = math.inf
    for body in scene.bodies:
        if body.role != "hand":
            continue
        placed = end_hand * hand.actInv(scene.body_pose(q, body.name))
        result.clear()
        height = coal.distance(
            body.geometry,
            coal.Transform3s(placed.rotation, placed.translation),
            below,
            coal.Transform3s(),
            request,
            result,
        )
        lowest = min(lowest, float(height))
    return lowest


def _can_go_beside(ctx: PlanContext, strategy: PinInHoleStrategy) -> bool:
    """Whether some attempt may bring the pin down off the hole's face (module docstring)."""
    shape = ctx.graph.node(ctx.hole_shape.surface).shape
    region = landing_region(ctx, strategy)
    if region is None or not isinstance(shape, SurfaceShape):
        return False
    return not shapely.Polygon(shape.outline).covers(region)


def false_seat_problem(ctx: PlanContext, strategy: PinInHoleStrategy) -> str | None:
    """Why a pin beside the part could pass the program's success test, or None.

    Two ways to stop off the face's edge (module docstring): the hand landing on the face, the
    pin end ``h`` below it; or the pin's taper resting on the edge, its axis beyond the edge by
    u with r_tip < u < r_pin, the end ``L_t (u − r_tip)/(r_pin − r_tip)`` below the face: any
    depth in [0, L_t). A depth u passes the test when |d_f − u| ≤ t + Δz, so the taper's range
    does when d_f − t − Δz < L_t (the window of a miss on the face, d_f − Δz > t, with d_f less
    the taper).
    """
    dz = strategy.dz_at_test
    if dz is None or not _can_go_beside(ctx, strategy):
        return None
    h = hand_height_above_end(ctx, strategy.pickup.grasp)
    d_f, threshold = ctx.insertion.d_f, strategy.success_threshold
    taper = ctx.pin_shape.tip_taper_length
    window = (
        f"within the success test's {100 * threshold:.3g} cm (± Δz {100 * dz:.3g} cm) of "
        f"d_f = {100 * d_f:.3g} cm: a miss would pass for an insertion"
    )
    tapered = ctx.pin_shape.tip_radius < ctx.pin_shape.diameter / 2
    if tapered and taper > 0.0 and d_f - threshold - dz < taper:
        return (
            f"a pin that comes down just past {ctx.hole_al}'s face's edge (the footprint and "
            f"search reach past it) rests its taper on the edge with its end up to "
            f"{100 * taper:.3g} cm below the face, {window}"
        )
    if d_f + threshold + dz < h:
        return None
    return (
        f"a pin that goes down beside {ctx.hole_al}'s face (the footprint and search reach past "
        f"its edge) stops when the hand lands on the face {100 * h:.2f} cm above the pin end, "
        f"{window}"
    )
