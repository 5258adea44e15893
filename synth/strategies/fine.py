"""Fine motions at the target hole clear of the workcell: insertion, search, tap, let-go, get-clear.

The gross motions are swept in :mod:`synth.strategies.clearance`; the moves near the hole are
where the hand comes closest to the part the pin goes into. A short pin held across its axis
(γ = 100°) puts the palm below the part's top face when the pin is seated: every insertion
and search move would stop on the palm. So each refined candidate's fine motions are checked
against the believed workcell with the hand, fingers, palm, wrist and held pin, in the nominal
configurations the program moves through (each solved nearest the one before it):

1. insertion: approach point → vias above the seat → seat (the pin end at −d_f), swept;
2. search: every point the search loop tries (the pattern filtered by the record's ±dx × ±dy,
   turned by ζ), with the pin end on the surface there, where a miss stops;
3. tap: tap via → the tapping place on the surface, swept;
4. let-go: the fingers opened to the let-go opening at the seat, the pin standing seated;
5. get-clear: the hand backing off from the seat, swept, the pin standing seated.

The hand follows the target part in these moves (the pin touches it or sits in it), so the
part and the arm keep the clearance only, the other solids their own directional margins
(:meth:`~synth.strategies.clearance.GrossMotionCheck.fine_options`); the held pin may touch the
target part, since its tip enters the hole or lands on the surface (the replay decides that
contact). A candidate with an obstructed fine motion is rejected, the bodies named.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from synth.models.arm import CollisionScene, SweepOptions
from synth.strategies.approach import Candidate, hand_at
from synth.strategies.context import Configuration, PlanContext
from synth.strategies.records import Destination, PinInHoleStrategy
from synth.strategies.relations import hole_frame_offset
from synth.strategies.search import inside, pattern_points

__all__ = ["fine_motion_obstruction", "search_offsets"]


def search_offsets(strategy: PinInHoleStrategy) -> list[tuple[float, float]]:
    """The search loop's offsets (x, y) [m] in the hole frame (the view's SETPNT, turned by ζ)."""
    search = strategy.search
    if search is None:
        return []
    points = pattern_points(search.step, search.rings)
    kept = points[inside(points, search.dx, search.dy)]
    c, s = math.cos(search.zeta), math.sin(search.zeta)
    return [(c * x - s * y, s * x + c * y) for x, y in kept]


def _sweep(
    ctx: PlanContext,
    scene: CollisionScene,
    path: Sequence[Configuration],
    motion: str,
    options: SweepOptions,
) -> str | None:
    ctx.counters.sweeps += 1
    points = list(path) if len(path) > 1 else [path[0], path[0]]
    return ctx.gross.obstruction(scene, points, motion, options)


def _pin_world(ctx: PlanContext, destination: Destination) -> pin.SE3:
    return ctx.graph.world_from(ctx.graph.resolve(destination.base)) * destination.xf


def fine_motion_obstruction(
    ctx: PlanContext, cand: Candidate, strategy: PinInHoleStrategy
) -> str | None:
    """Why one of ``strategy``'s fine motions is obstructed (module docstring), or None."""
    gross = ctx.gross
    grasp = strategy.pickup.grasp
    part = gross.part_of(ctx.graph, ctx.hole_frame)
    options = gross.fine_options(part)
    scene = gross.fine(grasp, part)
    hole = ctx.hole_al
    d_f = ctx.insertion.d_f
    vias: list[Configuration] = []
    if cand.axis is not None:
        inner = zip(cand.axis.heights[1:-1], cand.axis.configurations[1:-1], strict=True)
        vias = [q for z, q in inner if z > -d_f]
    insertion = [cand.q_hole_approach, *vias, cand.q_destination]
    reason = _sweep(ctx, scene, insertion, f"insertion into {hole}", options)
    if reason is not None:
        return reason
    for x, y in search_offsets(strategy):
        shift = pin.SE3(np.eye(3), np.array([x, y, 0.0]))
        offset = shift * hole_frame_offset(strategy.phi, (0.0, 0.0, 0.0))
        q = ctx.nearest(hand_at(ctx, grasp, offset), cand.q_surface)
        if q is None:
            return f"no arm solution at the search point ({100 * x:.2f}, {100 * y:.2f}) cm"
        motion = f"search point ({100 * x:.2f}, {100 * y:.2f}) cm from {hole}"
        reason = _sweep(ctx, scene, [q], motion, options)
        if reason is not None:
            return reason
    tap = strategy.tap
    if tap is not None:
        pin_from_hand = grasp.pin_from_hand()
        q_via = ctx.nearest(_pin_world(ctx, tap.via) * pin_from_hand, cand.pickup.q_departure)
        q_tap = (
            None
            if q_via is None
            else ctx.nearest(_pin_world(ctx, tap.place) * pin_from_hand, q_via)
        )
        if q_via is None or q_tap is None:
            return f"no arm solution at the tap on {tap.surface}"
        reason = _sweep(ctx, scene, [q_via, q_tap], f"tap on {tap.surface}", options)
        if reason is not None:
            return reason
    seated = _pin_world(ctx, strategy.destination)
    open_scene = gross.letting_go(strategy.let_go_opening, seated, part)
    reason = _sweep(ctx, open_scene, [cand.q_destination], f"let-go in {hole}", options)
    if reason is not None:
        return reason
    away = strategy.get_clear
    if away.base == strategy.hand:
        target = ctx.arm.forward(cand.q_destination) * away.xf
    else:
        target = _pin_world(ctx, away) * grasp.pin_from_hand()
    q_clear = ctx.nearest(target, cand.q_destination)
    if q_clear is None:
        return "no arm solution where the hand gets clear"
    return _sweep(ctx, open_scene, [cand.q_destination, q_clear], f"get-clear from {hole}", options)
