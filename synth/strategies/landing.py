"""Where on the hole's face the pin end may come down: every attempt, less the error footprint.

The program's first attempt aims at the believed hole and each search point at an offset from
it; the pin end truly comes down at the aim less the pin's error against the hole, which lies in
the footprint ±dx × ±dy turned by ζ (:class:`~synth.strategies.records.ErrorFootprint`). The
places are those boxes, centred on each aim, in the face's own frame (its outline's), as a
shapely geometry: :mod:`~synth.strategies.beside` asks whether they leave the outline,
:mod:`~synth.strategies.wrong_hole` whether they reach another hole. Both read a pin end that
comes down there by the program's success test and by how far below the end the hand is
(:func:`hand_height_above_end`): :class:`Landing` holds what they share, made once per strategy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import coal
import numpy as np
import shapely
from numpy.typing import NDArray
from shapely import affinity

from synth.strategies.context import PlanContext, end_from_hand
from synth.strategies.fine import search_offsets
from synth.strategies.records import Grasp, PinInHoleStrategy

__all__ = [
    "Landing",
    "hand_height_above_end",
    "landing",
    "landing_region",
    "reached_places",
    "reached_region",
]


@dataclass(frozen=True)
class Landing:
    """Where a strategy's pin end may come down, and how the program reads where it stops.

    ``region``: :func:`landing_region`; ``reached``: :func:`reached_region`, the part of it
    the search goes on to reach; ``hand_height`` [m]: :func:`hand_height_above_end` at
    the strategy's grasp; ``d_f`` [m] the believed seat's depth, ``threshold`` [m] the success
    test's t and ``dz`` [m] the depth error at the test (:attr:`PinInHoleStrategy.dz_at_test`);
    ``attempts``: each attempt's offset (hole frame [m]) and its places of :func:`reached_places`
    (None where no world reaches it), in the program's order.
    """

    region: shapely.Geometry
    reached: shapely.Geometry
    hand_height: float
    d_f: float
    threshold: float
    dz: float
    strategy: PinInHoleStrategy
    attempts: tuple[tuple[tuple[float, float], shapely.Geometry | None], ...]

    def window(self) -> str:
        """The success test's window in words, for a refusal."""
        return f"the success test's {100 * self.threshold:.3g} cm (± Δz {100 * self.dz:.3g} cm)"

    def passes(self, depth: float) -> bool:
        """Whether some world reads a pin end ``depth`` [m] below the face as a seat.

        DISTANCE_OFF = d_f − depth + e with |e| ≤ Δz passes |DISTANCE_OFF| ≤ t (seed L2736).
        """
        return abs(self.d_f - depth) <= self.threshold + self.dz

    def felt(self, depth: float) -> bool:
        """Whether some world does not read a pin end ``depth`` [m] down as nothing felt.

        Nothing felt is DISTANCE_OFF < −t for every |e| ≤ Δz: depth > d_f + t + Δz.
        """
        return depth <= self.d_f + self.threshold + self.dz


def landing(ctx: PlanContext, strategy: PinInHoleStrategy) -> Landing | None:
    """The strategy's :class:`Landing`; None without a footprint or a success test."""
    region = landing_region(ctx, strategy)
    dz = strategy.dz_at_test
    if region is None or dz is None:
        return None
    attempts = reached_places(ctx, strategy, _CAPTURED * ctx.insertion.lead)
    assert attempts is not None  # a footprint gives both
    reached = shapely.union_all([p for _, p in attempts if p is not None])
    return Landing(
        region,
        reached,
        hand_height_above_end(ctx, strategy.pickup.grasp),
        ctx.insertion.d_f,
        strategy.success_threshold,
        dz,
        strategy,
        tuple(attempts),
    )


_CAPTURED = 0.9
"""The share of the parts' lead within which an attempt counts as capturing the pin, for
:func:`reached_region` (the replay captures within the lead; a tilted pin near its edge may
not)."""


def reached_region(
    ctx: PlanContext, strategy: PinInHoleStrategy, capture: float
) -> shapely.Geometry | None:
    """The places the pin end may come down at, each attempt in the worlds that reach it.

    The union of :func:`reached_places` (face frame, [m]); it lies within
    :func:`landing_region`. None for a strategy without a footprint.
    """
    attempts = reached_places(ctx, strategy, capture)
    if attempts is None:
        return None
    return shapely.union_all([p for _, p in attempts if p is not None])


def reached_places(
    ctx: PlanContext, strategy: PinInHoleStrategy, capture: float
) -> list[tuple[tuple[float, float], shapely.Geometry | None]] | None:
    """Per attempt, its offset and where its pin end may come down in the worlds reaching it.

    An attempt at offset o_k is made only when every attempt before it missed: the pin end
    against the true hole, o_j − e (e the pin's error, in the footprint F), lay farther than
    ``capture`` [m] from the axis for each j < k. Attempt k's places are o_k − E_k, E_k = F
    less the discs of radius ``capture`` about the earlier offsets (face frame, [m]); None for
    an attempt no world reaches, and None for a strategy without a footprint.
    """
    made = _attempts(ctx, strategy)
    if made is None:
        return None
    box, to_face, origin, offsets = made
    errors = shapely.Polygon(box.T)  # F, in the hole frame
    matrix = [*to_face[0], *to_face[1], *origin]
    attempts: list[tuple[tuple[float, float], shapely.Geometry | None]] = []
    for x, y in offsets:
        places = None
        if not errors.is_empty:
            # o − E: E turned half a turn about the origin, moved to o
            turned = affinity.scale(errors, -1.0, -1.0, origin=(0.0, 0.0))
            places = affinity.affine_transform(affinity.translate(turned, x, y), matrix)
        attempts.append(((x, y), places))
        errors = errors.difference(shapely.Point(x, y).buffer(capture, quad_segs=32))
    return attempts


def landing_region(ctx: PlanContext, strategy: PinInHoleStrategy) -> shapely.Geometry | None:
    """The union of the places the pin end may come down at (face frame, [m]).

    None for a strategy without a footprint.
    """
    attempts = _attempts(ctx, strategy)
    if attempts is None:
        return None
    box, to_face, origin, offsets = attempts
    places = []
    for x, y in offsets:
        corners = origin[:, None] + to_face @ (np.array([[x], [y]]) - box)
        places.append(shapely.Polygon(corners.T))
    return shapely.union_all(places)


_Attempts = tuple[
    NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], list[tuple[float, float]]
]


def _attempts(ctx: PlanContext, strategy: PinInHoleStrategy) -> _Attempts | None:
    """What the places are made of, or None without a footprint.

    The footprint's corners (columns, ±dx × ±dy turned by ζ, hole frame [m]), the hole frame's
    turn and origin in the face frame, and the attempts' offsets in order (the first attempt's,
    0, then the search's).
    """
    footprint = strategy.errors
    if footprint is None:
        return None
    face_from_hole = ctx.graph.relative(ctx.hole_shape.surface, ctx.hole_frame)
    offsets = [(0.0, 0.0), *search_offsets(strategy)]
    return (
        footprint.corners(),
        face_from_hole.rotation[:2, :2],
        face_from_hole.translation[:2],
        offsets,
    )


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
