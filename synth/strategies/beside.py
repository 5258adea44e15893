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

A pin beside a thin part meets what the part stands on before the hand lands: its end stops
on that floor, ``u`` below the face, the part's height (a plate 1.0 cm thick on the table, a
through hole d_f = 1.0 cm deep: u = d_f, and the test passes every such miss; 15 of 1 000
trials of a program proven 100 of 100). So does a pin over any other top beside the part: a
neighbour's, a fixture's walls, a standing pin's head (a block 0.02 cm beyond the box's edge,
its top d_f below the face: 10 of 1 000 trials, each read as the seat). The attempts that go
beside are those of :func:`~synth.strategies.landing.reached_places` that leave the face, each
counted only in the worlds whose earlier attempts missed, as the search stops at the first
capture. Such an attempt brings the pin down where the program aimed it, off by the pin's error
against the top: the hand's and the grasp's errors, and the top's own when it is uncertain, but
not the part's, which moves the face and not the aim (on the seed's fixture cell, A.1, the walls'
top lies 1.9 cm below the face, inside the test's window of d_f = 1.71 cm, yet no aim comes
over them: 1 000 of 1 000 trials succeed). The pin comes down on the highest top under it; a top
under a place the pin end reaches before the hand lands, u < h, at a depth the test passes, is
refused like the hand's landing. The tops are horizontal planes, so this is checked for an
upright box part. A tilted part's pin comes down along the tilted axis, and its depth below the
face where it meets the table depends on where it left the face (:func:`_tilted_table_landings`;
a 1.2 cm plate tilted 10° with a hole 0.9 cm from its low edge: 2 of 200 trials of a program
proven 50 of 50 read a pin on the table as seated); other tops beside a tilted part are not
checked.

The pin can go beside the part only if a place it may come down at, some attempt's offset less
the footprint (±dx × ±dy turned by ζ), lies off the face's outline; this is checked with shapely
on the outline (the face's own frame) and the attempts' footprint boxes
(:func:`~synth.strategies.landing.landing_region`).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import shapely

from synth.errors.chain import ErrorChain
from synth.errors.estimate import RelationModel
from synth.models.spec import BoxShape, FixtureShape, PinShape, SurfaceShape
from synth.models.workcell import TABLE
from synth.strategies.context import PlanContext
from synth.strategies.footprint import estimate_footprint
from synth.strategies.landing import Landing
from synth.strategies.relations import (
    SpaceBuilder,
    frame_inverse_terms,
    grasped_end_terms,
    hand_holding_end,
    hole_frame_offset,
)

__all__ = [
    "Top",
    "false_seat_problem",
    "first_attempt_may_go_beside",
    "may_go_beside",
    "solid_tops",
    "support_landing_problem",
    "support_landings",
]


_UPRIGHT = 1e-6
"""[1] 1 − cos of the tilt below which a face or a solid's top counts as horizontal."""
_AREA = 1e-12
"""[m²] places of less area than this (a shared edge) are none: no world puts the pin there."""


@dataclass(frozen=True)
class Top:
    """A horizontal top a pin end may come down on: ``outline`` (world x, y [m]) at ``z`` [m].

    ``frame``: the graph frame the top moves with (None: the world's, the table's).
    """

    name: str
    outline: shapely.Geometry
    z: float
    frame: str | None = None


def _upright(pose: pin.SE3) -> bool:
    return float(pose.rotation[2, 2]) >= 1.0 - _UPRIGHT


def _top(
    name: str,
    frame: str,
    pose: pin.SE3,
    outer: tuple[float, float],
    z: float,
    inner: tuple[float, float] = (0.0, 0.0),
) -> Top:
    """The top at height ``z`` of frame ``pose``, in the world.

    Its outline is the rectangle ``outer`` (x, y sizes, centred) less the rectangle ``inner``
    (a fixture's cavity). Turned off upright: the convex hull of the solid's corners (z from
    0 to ``z`` in its frame) at the highest of them.
    """
    corners = [
        pose.act(np.array([a * outer[0] / 2, b * outer[1] / 2, c]))
        for a in (-1, 1)
        for b in (-1, 1)
        for c in (0.0, z)
    ]
    if not _upright(pose):
        hull = shapely.MultiPoint([p[:2] for p in corners]).convex_hull
        return Top(name, hull, max(float(p[2]) for p in corners), frame)
    outline = shapely.MultiPoint([p[:2] for p in corners]).convex_hull
    if inner[0] > 0.0 and inner[1] > 0.0:
        cavity = [pose.act(np.array([a * inner[0] / 2, b * inner[1] / 2, z])) for a, b in
                  ((-1, -1), (1, -1), (1, 1), (-1, 1))]  # fmt: skip
        outline = outline.difference(shapely.Polygon([p[:2] for p in cavity]))
    return Top(name, outline, float(pose.act(np.array([0.0, 0.0, z]))[2]), frame)


def solid_tops(ctx: PlanContext) -> Iterator[Top]:
    """The believed solids' horizontal tops, but the carried pin's.

    The table's plane z = 0 (its outline: everywhere the landing can be); a box's top face; a
    fixture's wall tops and its cavity's floor; a standing pin's head. A solid turned off
    upright gives the convex hull of its corners at the highest of them (a pin end on a tilted
    top comes to rest no higher).
    """
    graph = ctx.graph
    yield Top(TABLE, shapely.box(-1e3, -1e3, 1e3, 1e3), 0.0)
    for name, node in graph.nodes.items():
        shape = node.shape
        if name == ctx.pin_frame or shape is None:
            continue
        pose = graph.world_from(name)
        if isinstance(shape, BoxShape):
            sx, sy, sz = shape.size
            yield _top(node.al_name, name, pose, (sx, sy), sz)
        elif isinstance(shape, FixtureShape):
            ix, iy, depth = shape.inside
            outer = (ix + 2 * shape.wall, iy + 2 * shape.wall)
            yield _top(node.al_name, name, pose, outer, depth, inner=(ix, iy))
            yield _top(f"{node.al_name}'s floor", name, pose, (ix, iy), 0.0)
        elif isinstance(shape, PinShape):
            yield _top(node.al_name, name, pose, (shape.diameter, shape.diameter), shape.length)


def support_landings(
    ctx: PlanContext, where: Landing, above: float
) -> tuple[list[tuple[Top, float]], bool]:
    """The tops a pin gone beside the face comes down on, if less than ``above`` [m] below.

    The attempts that go beside are those whose reached places (:attr:`Landing.attempts`) leave
    the outline grown by the pin's radius (nearer, the pin leans on the edge). Such an attempt
    puts the pin end where the program aims it, less the pin's error against the top's own
    frame (:func:`_pin_places`: the hand's and the grasp's errors, and the top's if it is
    uncertain; the part's own errors move the face, not the aim). Each top, highest first, under
    some place of an attempt not already stopped above it is given with its depth below the face
    [m]; an attempt all of whose places lie over a top stops there. The flag says whether some
    attempt is not stopped by any top within ``above`` (the pin may go deeper there). For a face
    whose normal is not vertical, or a box part turned off upright, only the table is looked for
    (:func:`_tilted_table_landings`); for a part that is not a box, none is found and every
    place may go deeper.
    """
    surface = ctx.hole_shape.surface
    shape = ctx.graph.node(surface).shape
    face = ctx.graph.world_from(surface)
    part = ctx.graph.owner(ctx.hole_frame)
    if not isinstance(shape, SurfaceShape) or not isinstance(ctx.graph.node(part).shape, BoxShape):
        return [], True
    radius = ctx.pin_shape.diameter / 2
    outline = shapely.Polygon(shape.outline).buffer(radius)
    beside = [
        offset
        for offset, places in where.attempts
        if places is not None and places.difference(outline).area > _AREA
    ]
    if not beside:
        return [], True  # only the edge is reached (the taper's case)
    if not _upright(face) or not _upright(ctx.graph.world_from(part)):
        return _tilted_table_landings(ctx, where, face, beside, above)
    level = float(face.translation[2])
    part_name = ctx.graph.node(part).al_name
    tops = [t for t in solid_tops(ctx) if t.name != part_name and level - t.z < above]
    found = []
    for top in sorted(tops, key=lambda t: -t.z):  # the pin comes down on the highest under it
        reach = top.outline.buffer(radius)
        places = _pin_places(ctx, where, top.frame, beside)
        if any(reach.intersection(p).area > _AREA for p in places):
            found.append((top, level - top.z))
        beside = [o for o, p in zip(beside, places, strict=True) if not reach.covers(p)]
    return found, bool(beside)


def _tilted_table_landings(
    ctx: PlanContext,
    where: Landing,
    face: pin.SE3,
    beside: list[tuple[float, float]],
    above: float,
) -> tuple[list[tuple[Top, float]], bool]:
    """:func:`support_landings` for a tilted face: the table, met along the hole's axis.

    A pin gone beside a tilted part comes down along the axis a (the face's outward normal,
    world) until its end meets the table, z = 0. Aimed at a point P of the believed face, it
    truly starts from P + e (e its error against the world: the hand's and the grasp's) and
    travels s = (P_z + e_z)/a_z; the program reads its depth below the believed face along a,
    u = s − e·a = P_z/a_z + c·e with c = (−a_x, −a_y, 1/a_z − a_z) (for an upright face c = 0:
    the table lies level − 0 below, whatever the error). c·e is bounded by the certified error
    model of the pin end against the world (:meth:`RelationModel.displacement_along`), so each
    attempt beside the face meets the table at a depth in [u₀ + lo, u₀ + hi]. The depth given
    for an attempt is the one of that range, short of where the hand lands (``above``),
    nearest d_f: the program's test reads it as a seat if any does (the pin's own tilt error
    turning the descent is of second order and left out). A face turned past the horizontal
    (a_z ≤ 0) meets no table along its axis. Other tops beside a tilted part are not checked.
    """
    axis = face.rotation[:, 2]
    if axis[2] <= _UPRIGHT:
        return [], True
    chain = _pin_chain(ctx, where, None)
    coefficients = np.array([-axis[0], -axis[1], 1.0 / axis[2] - axis[2]])
    lo = hi = 0.0
    if chain is not None:
        scale = float(np.linalg.norm(coefficients))
        if scale > 0.0:
            _, spread = RelationModel.of(chain).displacement_along(coefficients / scale)
            lo, hi = scale * spread.lo, scale * spread.hi
    table = next(t for t in solid_tops(ctx) if t.name == TABLE)
    found: list[tuple[Top, float]] = []
    deeper = False
    for x, y in beside:
        start = float(ctx.world_hole.act(np.array([x, y, 0.0]))[2]) / float(axis[2])
        shallowest, deepest = start + lo, start + hi
        if shallowest < above:
            found.append((table, min(max(where.d_f, shallowest), min(deepest, above))))
        deeper = deeper or deepest >= above
    return found, deeper


def _pin_chain(ctx: PlanContext, where: Landing, frame: str | None) -> ErrorChain | None:
    """The error chain of the pin end against ``frame`` (None: the world), None if exact.

    The hand's and the grasp's errors at the approach, and ``frame``'s own when uncertain: the
    relation of :mod:`synth.strategies.relations` with the hole's chain replaced by the frame's.
    """
    strategy = where.strategy
    builder = SpaceBuilder()
    terms = [] if frame is None else frame_inverse_terms(ctx.graph, frame, builder)
    end = ctx.world_hole * hole_frame_offset(strategy.phi, (0.0, 0.0, strategy.standoff))
    grasp = strategy.pickup.grasp
    hand = hand_holding_end(ctx, grasp, end)
    residual = strategy.pickup.grasp_determination
    terms += grasped_end_terms(ctx, grasp, residual, hand, builder, "hand:approach")
    if not builder.blocks:
        return None
    return ErrorChain(builder.space(), tuple(terms))


def _pin_places(
    ctx: PlanContext, where: Landing, frame: str | None, offsets: list[tuple[float, float]]
) -> list[shapely.Geometry]:
    """Where the pin end of each attempt may be, over frame ``frame`` (world x, y [m]).

    The attempt at offset o aims the end at ``hole₀ ∘ trans(o)``, the hole as believed; the end
    truly lies within the error footprint of ``frame⁻¹ ∘ end`` (:func:`estimate_footprint` of
    the relation of :mod:`synth.strategies.relations` with the hole's chain replaced by the
    frame's: ±Δx × ±Δy turned by ζ, in the frame's nominal axes) about the aim.
    """
    chain = _pin_chain(ctx, where, frame)
    corners = np.zeros((2, 4))  # no error block: the pin comes down where it is aimed
    if chain is not None:
        footprint, _ = estimate_footprint(ctx, chain)
        corners = footprint.corners()
    nominal = pin.SE3.Identity() if frame is None else ctx.graph.world_from(frame)
    turn, shift = nominal.rotation[:2, :2], nominal.translation[:2]
    out = []
    for x, y in offsets:
        aim = nominal.actInv(ctx.world_hole.act(np.array([x, y, 0.0])))[:2]
        out.append(shapely.Polygon((turn @ (aim[:, None] + corners) + shift[:, None]).T))
    return out


def support_landing_problem(ctx: PlanContext, where: Landing) -> str | None:
    """Why a pin beside the part could come down on a solid where the test reads a seat.

    A top met before the hand lands (less than ``h`` below the face) at a depth u with
    |d_f − u| ≤ t + Δz (module docstring); None if there is none.
    """
    if not may_go_beside(ctx, where):
        return None
    tops, _ = support_landings(ctx, where, where.hand_height)
    for top, depth in tops:
        if where.passes(depth):
            named = "the table" if top.name == TABLE else top.name
            return (
                f"a pin that goes down beside {ctx.hole_al}'s face (the footprint and search "
                f"reach past its edge) comes down on {named} {100 * depth:.3g} cm below the "
                f"face, within {where.window()} of d_f = {100 * where.d_f:.3g} cm: a miss "
                "would pass for an insertion"
            )
    return None


def _leaves_face(ctx: PlanContext, places: shapely.Geometry | None) -> bool:
    """Whether ``places`` (face frame) reach off the outline of the hole's face."""
    shape = ctx.graph.node(ctx.hole_shape.surface).shape
    if not isinstance(shape, SurfaceShape) or places is None:
        return False
    return not shapely.Polygon(shape.outline).covers(places)


def may_go_beside(ctx: PlanContext, where: Landing) -> bool:
    """Whether some attempt may bring the pin down off the hole's face (module docstring)."""
    return _leaves_face(ctx, where.region)


def first_attempt_may_go_beside(ctx: PlanContext, where: Landing) -> bool:
    """Whether the first attempt may bring the pin down off the hole's face.

    Its places are the whole footprint about the believed hole (the first of
    :func:`~synth.strategies.landing.reached_places`); with the seed's arrival abort such a
    world aborts though the search would find the hole (a box known to ±1 in, ±5°, BH1 0.6 cm
    from two edges: 8 of 100 trials "EXPECTED A FORCE HERE", every candidate refused).
    """
    return _leaves_face(ctx, where.attempts[0][1] if where.attempts else None)


def false_seat_problem(ctx: PlanContext, where: Landing) -> str | None:
    """Why a pin beside the part could pass the program's success test, or None.

    Two ways to stop off the face's edge (module docstring): the hand landing on the face, the
    pin end ``h`` below it; or the pin's taper resting on the edge, its axis beyond the edge by
    u with r_tip < u < r_pin, the end ``L_t (u − r_tip)/(r_pin − r_tip)`` below the face: any
    depth in [0, L_t). A depth u passes the test when |d_f − u| ≤ t + Δz, so the taper's range
    does when d_f − t − Δz < L_t (the window of a miss on the face, d_f − Δz > t, with d_f less
    the taper).
    """
    if not may_go_beside(ctx, where):
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
    if not support_landings(ctx, where, where.hand_height)[1]:
        return None  # every place off the face has a top under the pin above where the hand lands
    return (
        f"a pin that goes down beside {ctx.hole_al}'s face (the footprint and search reach past "
        f"its edge) stops when the hand lands on the face {100 * where.hand_height:.2f} cm above "
        f"the pin end, {window}"
    )
