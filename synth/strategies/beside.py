"""A pin gone beside the part whose hand stops on the part's face: a miss the success test passes.

Where the error footprint and the search reach past the edge of the hole's face, an attempt can
send the pin down beside the part. It feels nothing until the hand itself comes down on the
face, and then it stops with the pin end ``h`` below the face, ``h`` the height of the hand's
lowest point above the pin end (the hand closed on the pin at its grasp). The program's test
``|DISTANCE_OFF| ≤ t`` (seed L2736) compares the pin end with the believed seat, ``d_f`` below the
believed face: DISTANCE_OFF = d_f − h + e, with e the face's height error against the belief
(|e| ≤ Δz, after the tap when there is one). If ``|d_f − h| ≤ t + Δz`` some such world passes the
test with the pin beside the hole: the program reports an insertion that did not happen (a
box known to ±0.2 in in height on the Stanford arm, a 0.635 cm pin held straight down, h = 2.9
cm, d_f = 1.71 cm, t = 0.85 cm, Δz = 0.64 cm: 3 of 300 trials). Such a candidate is refused.

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

import numpy as np
import pinocchio as pin
import shapely

from synth.models.arm.hand import finger_placement
from synth.models.spec import HandSpec, SurfaceShape
from synth.strategies.context import PlanContext, end_from_hand
from synth.strategies.landing import landing_region
from synth.strategies.records import PinInHoleStrategy

__all__ = ["false_seat_problem", "hand_height_above_end"]


def _box_corners(size: tuple[float, float, float], placement: pin.SE3) -> np.ndarray:
    """The 8 corners (3 × 8) of a box of full sides ``size`` placed at ``placement``."""
    half = 0.5 * np.asarray(size)
    signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1)
    return placement.rotation @ (half[:, None] * signs) + placement.translation[:, None]


def hand_height_above_end(hand: HandSpec, end_from_hand_: pin.SE3, opening: float) -> float:
    """Height [m] of the hand's lowest point above the pin end, along the end's axis.

    The hand of :func:`synth.models.arm.hand.hand_bodies`: two finger plates (thickness ×
    2·pad radius × finger length + pad radius) at ``opening`` and the palm behind them, their
    corners seen from the end frame (z out of the hole once inserted).
    """
    finger = (
        hand.finger_thickness,
        2 * hand.finger_pad_radius,
        hand.finger_length + hand.finger_pad_radius,
    )
    palm = pin.SE3(np.eye(3), np.array([0.0, 0.0, -hand.finger_length - hand.palm_size[2] / 2]))
    corners = [_box_corners(hand.palm_size, end_from_hand_ * palm)]
    for side in (-1, 1):
        placed = end_from_hand_ * finger_placement(hand, side, opening)  # type: ignore[arg-type]
        corners.append(_box_corners(finger, placed))
    return float(np.min(np.concatenate(corners, axis=1)[2]))


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
    footprint = strategy.errors
    if footprint is None or not _can_go_beside(ctx, strategy):
        return None
    grasp = strategy.pickup.grasp
    h = hand_height_above_end(ctx.hand, end_from_hand(ctx, grasp), ctx.pin_shape.diameter)
    dz = footprint.dz if strategy.tap is None else strategy.tap.dz_after
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
    if abs(d_f - h) > threshold + dz:
        return None
    return (
        f"a pin that goes down beside {ctx.hole_al}'s face (the footprint and search reach past "
        f"its edge) stops when the hand lands on the face {100 * h:.2f} cm above the pin end, "
        f"{window}"
    )
