"""Where on the hole's face the pin end may come down: every attempt, less the error footprint.

The program's first attempt aims at the believed hole and each search point at an offset from
it; the pin end truly comes down at the aim less the pin's error against the hole, which lies in
the footprint ±dx × ±dy turned by ζ (:class:`~synth.strategies.records.ErrorFootprint`). The
places are those boxes, centred on each aim, in the face's own frame (its outline's), as a
shapely geometry: :mod:`~synth.strategies.beside` asks whether they leave the outline,
:mod:`~synth.strategies.wrong_hole` whether they reach another hole.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from synth.strategies.context import PlanContext
from synth.strategies.fine import search_offsets
from synth.strategies.records import PinInHoleStrategy

__all__ = ["landing_region"]


def landing_region(ctx: PlanContext, strategy: PinInHoleStrategy) -> shapely.Geometry | None:
    """The union of the places the pin end may come down at (face frame, [m]).

    None for a strategy without a footprint.
    """
    footprint = strategy.errors
    if footprint is None:
        return None
    face_from_hole = ctx.graph.relative(ctx.hole_shape.surface, ctx.hole_frame)
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
    return shapely.union_all(places)
