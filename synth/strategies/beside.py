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

The pin can go beside the part only if a place it may come down at, some attempt's offset less
the footprint (±dx × ±dy turned by ζ), lies off the face's outline; this is checked with shapely
on the outline (the face's own frame) and the attempts' footprint boxes.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import shapely

from synth.models.arm.hand import finger_placement
from synth.models.spec import HandSpec, SurfaceShape
from synth.strategies.context import PlanContext, end_from_hand
from synth.strategies.fine import search_offsets
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
    footprint = strategy.errors
    surface = ctx.hole_shape.surface
    shape = ctx.graph.node(surface).shape
    if footprint is None or not isinstance(shape, SurfaceShape):
        return False
    face_from_hole = ctx.graph.relative(surface, ctx.hole_frame)
    c, s = math.cos(footprint.zeta), math.sin(footprint.zeta)
    turn = np.array([[c, -s], [s, c]])
    box = turn @ np.array(
        [[-footprint.dx, footprint.dx, footprint.dx, -footprint.dx],
         [-footprint.dy, -footprint.dy, footprint.dy, footprint.dy]]
    )  # fmt: skip
    to_face = face_from_hole.rotation[:2, :2]
    origin = face_from_hole.translation[:2]
    places = []
    for x, y in [(0.0, 0.0), *search_offsets(strategy)]:
        corners = origin[:, None] + to_face @ (np.array([[x], [y]]) - box)
        places.append(shapely.Polygon(corners.T))
    return not shapely.Polygon(shape.outline).covers(shapely.union_all(places))


def false_seat_problem(ctx: PlanContext, strategy: PinInHoleStrategy) -> str | None:
    """Why a pin beside the part could pass the program's success test, or None."""
    footprint = strategy.errors
    if footprint is None or not _can_go_beside(ctx, strategy):
        return None
    grasp = strategy.pickup.grasp
    h = hand_height_above_end(ctx.hand, end_from_hand(ctx, grasp), ctx.pin_shape.diameter)
    dz = footprint.dz if strategy.tap is None else strategy.tap.dz_after
    d_f, threshold = ctx.insertion.d_f, strategy.success_threshold
    if abs(d_f - h) > threshold + dz:
        return None
    return (
        f"a pin that goes down beside {ctx.hole_al}'s face (the footprint and search reach past "
        f"its edge) stops when the hand lands on the face {100 * h:.2f} cm above the pin end, "
        f"within the success test's {100 * threshold:.3g} cm (± Δz {100 * dz:.3g} cm) of "
        f"d_f = {100 * d_f:.3g} cm: a miss would pass for an insertion"
    )
