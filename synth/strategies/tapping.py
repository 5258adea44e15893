"""Tapping (seed §4.5.2, L2283–2365): measure the surface near the hole to pin down Δz.

When ``|Δz| > τ·(d_f − d_s)`` the success test could mistake a miss for an insertion, so the
program first taps the hole's surface: a guarded move of the pin from 2 in above the nominal
surface to 2 in below it (L2852), whose stopping height ``CORR`` (L2826) corrects the test.

**Where** (L2300–2330, :func:`find_tapping_place`): rings of radius ``r = r_td + Δr_td, r +
Δr_td, …`` about the hole in the surface frame, ``Δr_td = max(0.3 in, Δx, Δy)``, points every
``Δr_td/r`` rad; each point scores the signed distance to the nearest hole or edge of the
surface (negative off the surface or over a hole, footnote 15), computed with shapely on the
outline, the hole mouths (bore radius + chamfer) as circles. The best point of the first ring whose
best score beats the in-plane error is the tapping place. We require ``d > Δr + r_tip`` (the
tip's flat must land on the surface whatever the in-plane error); the seed asked ``d > Δx``.

**How much it helps** (:func:`build_tap_lp`, :func:`solve_tap_lp`): a genuine LP. The tap reads
``m``, the believed height of the pin end at contact above the nominal tap point. With the
relations of :func:`synth.strategies.relations.tap_relations` over one parameter space (box
errors shared, hand errors at the tap and at the insertion, m),

* contact: ``z_c(v, m) = a·v + q_c = 0`` with ``|q_c| ≤ R_c`` (Taylor remainder), i.e. the two
  rows ``±a·v ≤ R_c`` added to the space's constraints;
* the corrected error of the success test is ``Δz_hp(v) + m = c·v + q_i``, ``|q_i| ≤ R_i``
  (the program subtracts CORR from the distance it reads, L2835);

so ``Δz_tap = max |c·v + m| over the constrained polytope + R_i`` (HiGHS). The first-order figure
(the seed's) takes ``R_c = R_i = 0``.

**Cost** (:func:`tap_time`): the extra time of departure → tap via → contact → approach →
destination over departure → approach → destination.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from synth.errors.bounds import ErrorLP, Interval, build_error_lp, solve_error_lp
from synth.errors.estimate import RelationModel, certified_tilt
from synth.errors.parameters import ParameterSpace
from synth.models.graph import AttributeGraph
from synth.models.spec import HoleShape, SurfaceShape
from synth.strategies.approach import Candidate, hand_at, hole_frame_offset, pin_destination
from synth.strategies.context import PlanContext
from synth.strategies.hypotheses import TapAt
from synth.strategies.records import ErrorFootprint, Rejection, Tap
from synth.strategies.relations import TapRelations, hole_only_relation, tap_relations

TIE = 1e-9
"""[m] clearances closer than this are equal: the first point of the ring keeps the place."""


@dataclass(frozen=True, eq=False)
class SurfaceRegion:
    """A surface in its own frame: the outline polygon and the hole mouths ``(x, y, r)`` [m]."""

    outline: shapely.Polygon
    holes: tuple[tuple[float, float, float], ...]

    def signed_distance(self, x: float, y: float) -> float:
        """Distance [m] to the nearest hole or edge; negative off the surface or over a hole.

        Edges by shapely (any simple outline); hole mouths as exact circles, ``|p − c| − r``.
        """
        point = shapely.Point(x, y)
        if not self.outline.covers(point):
            return -float(self.outline.distance(point))
        d = float(self.outline.exterior.distance(point))
        for cx, cy, r in self.holes:
            d = min(d, math.hypot(x - cx, y - cy) - r)
        return d


def surface_region(graph: AttributeGraph, surface: str) -> SurfaceRegion:
    """The tappable part of a surface: its outline less the mouths of the holes drilled in it.

    Each hole of :meth:`AttributeGraph.holes_in` is a disc of its bore radius plus chamfer
    width about its centre (in the surface frame).
    """
    shape = graph.node(surface).shape
    assert isinstance(shape, SurfaceShape)
    holes = []
    for node in graph.holes_in(surface):
        hole = node.shape
        assert isinstance(hole, HoleShape)
        centre = graph.relative(surface, node.name).translation
        holes.append((float(centre[0]), float(centre[1]), hole.diameter / 2 + hole.chamfer_width))
    return SurfaceRegion(shapely.Polygon(shape.outline), tuple(holes))


@dataclass(frozen=True)
class TappingPlace:
    """A tapping place in surface coordinates ``(x, y)`` [m].

    ``clearance`` [m] to the nearest hole or edge, ``radius`` [m] of the ring it came from, and
    the scored points of that ring ``((x, y, d), …)`` (the table at L2345).
    """

    x: float
    y: float
    clearance: float
    radius: float
    ring: tuple[tuple[float, float, float], ...]


def find_tapping_place(
    region: SurfaceRegion,
    hole_xy: tuple[float, float],
    r_td: float,
    dr_td: float,
    need: float,
    r_max: float,
) -> TappingPlace | None:
    """The seed's search (L2300–2330): nearest ring whose best clearance exceeds ``need``.

    ``r_td`` = bore radius + tip radius, ``dr_td`` the ring spacing, ``r_max`` the farthest
    point of the surface from the hole [m]. None when no ring qualifies.
    """
    xh, yh = hole_xy
    best: tuple[float, float, float] | None = None
    r = r_td + dr_td
    while r <= r_max + 1e-12:
        ring = []
        for xi in np.arange(0.0, 2 * math.pi, dr_td / r):
            x, y = xh + r * math.cos(xi), yh + r * math.sin(xi)
            d = region.signed_distance(x, y)
            ring.append((x, y, d))
            if d > (0.0 if best is None else best[2] + TIE):
                best = (x, y, d)
        if best is not None and best[2] > need:
            return TappingPlace(best[0], best[1], best[2], r, tuple(ring))
        r += dr_td
    return None


def measurement_bound(ctx: PlanContext, relations: TapRelations) -> float:
    """Bound [m] of the tap's reading |m|: ``B₀ / cos θ_s``; give relations built with m ≡ 0.

    ``B₀`` is the certified |z| of the contact relation with m = 0 (how far the true surface
    may be from where the believed pin end is) and θ_s the certified tilt of the hole's frame:
    moving the believed pin by m along the nominal normal moves it ``m·cos(tilt)`` along the
    true one, so contact needs ``|m| ≤ B₀ / cos θ_s``.
    """
    model = RelationModel.of(relations.contact)
    linear = model.displacement.linear[:, 2]
    b0 = ctx.bound(linear, model.space).magnitude + float(model.displacement.remainder[2])
    hole = RelationModel.of(hole_only_relation(ctx))
    ctx.counters.count_bounds(hole.space, 6)
    tilt = certified_tilt(hole.tilt_table()[1])
    return b0 / math.cos(tilt) + 1e-12


@dataclass(frozen=True, eq=False)
class TapProblem:
    """The corrected-Δz LP: objective ``c`` (with m), the measurement rows, the remainders.

    ``lp`` is certified (rows ``±a·v ≤ R_c``); ``first_order_lp`` the seed's linearisation
    (``a·v = 0``). ``insertion_remainder`` R_i [m] is added to the certified optimum.
    """

    lp: ErrorLP
    first_order_lp: ErrorLP
    insertion_remainder: float
    contact_remainder: float
    space: ParameterSpace


def build_tap_lp(relations: TapRelations) -> TapProblem:
    """Build the LPs of the tap-corrected Δz (module docstring)."""
    insertion = RelationModel.of(relations.insertion)
    contact = RelationModel.of(relations.contact)
    space = relations.contact.space
    c = insertion.displacement.linear[:, 2].copy()
    c[relations.measurement] += 1.0
    a = contact.displacement.linear[:, 2]
    r_c = float(contact.displacement.remainder[2])
    rows = np.vstack([a, -a])
    certified = space.constrain(rows, np.array([r_c, r_c]))
    linearised = space.constrain(rows, np.zeros(2))
    return TapProblem(
        lp=build_error_lp(c, certified),
        first_order_lp=build_error_lp(c, linearised),
        insertion_remainder=float(insertion.displacement.remainder[2]),
        contact_remainder=r_c,
        space=certified,
    )


def solve_tap_lp(ctx: PlanContext, problem: TapProblem) -> tuple[float, float]:
    """``(first-order, certified)`` corrected |Δz| [m] (two HiGHS LPs, both senses each)."""
    ctx.counters.bounds += 2
    ctx.counters.lp += 2
    first: Interval = solve_error_lp(problem.first_order_lp)
    cert: Interval = solve_error_lp(problem.lp)
    return first.magnitude, cert.magnitude + problem.insertion_remainder


def plan_tap(ctx: PlanContext, cand: Candidate, footprint: ErrorFootprint) -> Tap | Rejection:
    """Find a tapping place, bound the corrected Δz by LP and price the extra motion."""
    opts = ctx.options
    hole_shape = ctx.hole_shape
    surface = ctx.graph.resolve(hole_shape.surface)
    region = surface_region(ctx.graph, surface)
    surface_from_hole = ctx.graph.relative(surface, ctx.hole_frame)
    hole_xy = (
        float(surface_from_hole.translation[0]),
        float(surface_from_hole.translation[1]),
    )
    r_td = hole_shape.diameter / 2 + ctx.pin_shape.tip_radius
    dr_td = max(opts.tap_ring_min, footprint.dx, footprint.dy)
    shape = ctx.graph.node(surface).shape
    assert isinstance(shape, SurfaceShape)
    r_max = max(math.hypot(x - hole_xy[0], y - hole_xy[1]) for x, y in shape.outline)
    need = footprint.dr + ctx.pin_shape.tip_radius
    place = find_tapping_place(region, hole_xy, r_td, dr_td, need, r_max)
    if place is None:
        return Rejection(
            cand.name,
            f"Δz = {100 * footprint.dz:.3f} cm needs a tap but no place on "
            f"{ctx.graph.al_names[surface]} is {100 * need:.3f} cm clear of holes and edges "
            "(seed L2363)",
        )
    in_hole = surface_from_hole.inverse().act(np.array([place.x, place.y, 0.0]))
    offset = (float(in_hole[0]), float(in_hole[1]), 0.0)
    phi = cand.strategy.phi
    world = cand.world.with_facts(TapAt(ctx.pin_al, ctx.graph.al_names[surface], offset))
    bound = measurement_bound(ctx, tap_relations(ctx, world, phi, offset, 0.0))
    if bound >= opts.tap_travel:
        return Rejection(
            cand.name,
            f"the surface may lie {100 * bound:.2f} cm from nominal, beyond the tap's "
            f"±{100 * opts.tap_travel:.2f} cm travel (L2852)",
        )
    relations = tap_relations(ctx, world, phi, offset, bound)
    first, dz_after = solve_tap_lp(ctx, build_tap_lp(relations))
    grasp = cand.pickup.strategy.grasp
    q_via = ctx.nearest(
        hand_at(ctx, grasp, hole_frame_offset(phi, (offset[0], offset[1], opts.tap_travel))),
        cand.q_transported,
    )
    q_contact = (
        None
        if q_via is None
        else ctx.nearest(hand_at(ctx, grasp, hole_frame_offset(phi, offset)), q_via)
    )
    if q_via is None or q_contact is None:
        at = f"({100 * offset[0]:.2f}, {100 * offset[1]:.2f}) cm from {ctx.hole_al}"
        return Rejection(cand.name, f"no arm solution at the tapping place {at}")
    blocked = ctx.obstruction(
        ctx.gross.holding(grasp),
        [cand.q_transported, q_via],
        f"transport to the tap's via point above {ctx.graph.al_names[surface]}",
    )
    if blocked is not None:
        return Rejection(cand.name, blocked)
    extra = (
        ctx.motion([cand.pickup.q_departure, *cand.transport_vias, q_via, q_contact])
        + ctx.motion([q_contact, cand.q_hole_approach, cand.q_destination])
        - cand.transport_time
    )
    return Tap(
        offset=offset,
        surface=ctx.graph.al_names[surface],
        clearance=place.clearance,
        place=pin_destination(ctx, "tap", hole_frame_offset(phi, offset)),
        via=pin_destination(
            ctx, "tap via", hole_frame_offset(phi, (offset[0], offset[1], opts.tap_travel))
        ),
        target=pin_destination(
            ctx, "tap target", hole_frame_offset(phi, (offset[0], offset[1], -opts.tap_travel))
        ),
        dz_after=dz_after,
        time=max(extra, 0.0),
        dz_first_order=first,
        ring_radius=place.radius,
        ring=place.ring,
        measurement_bound=bound,
    )
