"""Fine motions at the target hole clear of the workcell: insertion, search, tap, let-go, get-clear.

The gross motions are swept in :mod:`synth.strategies.clearance`; the moves near the hole are
where the hand comes closest to the part the pin goes into. A short pin held across its axis
(γ = 100°) puts the palm below the part's top face when the pin is seated: every insertion
and search move would stop on the palm. So each refined candidate's fine motions are checked
against the believed workcell with the hand, fingers, palm, wrist and held pin, in the nominal
configurations the program moves through (each solved nearest the one before it):

1. insertion: approach point → vias above the seat → seat (the pin end at −d_f), swept; where
   no attempt can bring the pin down off the face, the held pin below the face is in the bore
   and is swept there with what moves each solid against the bore (:func:`_guided_insertion`);
2. search: every point the search loop tries (the pattern filtered by the record's ±dx × ±dy,
   turned by ζ), with the pin end on the surface there, where a miss stops;
3. tap: tap via → the tapping place on the surface, swept;
4. let-go: the fingers opened to the let-go opening at the seat, the pin standing seated;
5. get-clear: the hand backing off from the seat, swept, the pin standing seated; and solved
   again from the seat displaced to each corner of where the hand truly stops
   (:func:`seat_displacements`), since the program backs off from there.

4 and 5 are swept again with the part (and the pin in it) turned about the seat to each
extreme of the part's rotation error: the hand follows the hole's place, not the part's turn
(:meth:`~synth.strategies.clearance.GrossMotionCheck.seat_turns`). In 4 and 5 the hand stands
off the seated pin by the grip, so the part keeps its shift and the palm and fingers its turn
(:meth:`~synth.strategies.clearance.GrossMotionCheck.seated_options`).

The hand follows the target part in these moves (the pin touches it or sits in it), so the
part and the arm keep the clearance only, the other solids their own directional margins
(:meth:`~synth.strategies.clearance.GrossMotionCheck.fine_options`); the held pin may touch the
target part, since its tip enters the hole or lands on the surface (the replay decides that
contact), and in the insertion into a hole through its part what the part stands on, where the
seated pin rests (:func:`_through_bottom`). A candidate with an obstructed fine motion is
rejected, the bodies named.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from synth.models.arm import CollisionScene, SweepOptions
from synth.models.arm.sweep import LinkDisplacement
from synth.models.spec import BoxShape
from synth.strategies.approach import Candidate, getting_clear, hand_at, pin_world
from synth.strategies.bow import pin_deviation, split_at_height
from synth.strategies.context import Configuration, PlanContext, end_from_hand
from synth.strategies.records import PinInHoleStrategy
from synth.strategies.relations import hole_frame_offset
from synth.strategies.search import inside, pattern_points

__all__ = ["fine_motion_obstruction", "search_offsets"]

_THROUGH = 1e-6  # [m]: a hole this near its box's height goes through (the loader's tolerance)


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


def _through_bottom(ctx: PlanContext, part: str) -> str | None:
    """The solid a hole through ``part`` opens onto (its support), or None for a blind hole.

    A hole as deep as its box is tall goes through it (:func:`synth.models.meshes.box_with_holes`)
    and its bottom is what the box stands on: the pin seated at d_f = depth rests there, so the
    insertion's held pin may touch it as it touches the part. The insertion goes down the bore,
    so that is the only place it can.
    """
    box = ctx.graph.node(ctx.gross.solid_frames[part]).shape
    if not isinstance(box, BoxShape) or ctx.hole_shape.depth < box.size[2] - _THROUGH:
        return None
    return ctx.gross.support_of(ctx.graph, part)


def fine_motion_obstruction(
    ctx: PlanContext, cand: Candidate, strategy: PinInHoleStrategy, beside: bool = True
) -> str | None:
    """Why one of ``strategy``'s fine motions is obstructed (module docstring), or None.

    ``beside``: whether an attempt may bring the pin down off the hole's face
    (:mod:`~synth.strategies.beside`); where none can, a pin below the face is in the hole
    and the insertion's held pin is swept there as the hole guides it
    (:func:`_guided_insertion`).
    """
    gross = ctx.gross
    grasp = strategy.pickup.grasp
    part = gross.part_of(ctx.graph, ctx.hole_frame)
    hand_seated = ctx.arm.forward(cand.q_destination).rotation
    options = gross.fine_options(part, hand_seated)
    scene = gross.fine(grasp, part)
    hole = ctx.hole_al
    d_f = ctx.insertion.d_f
    vias: list[Configuration] = []
    if cand.axis is not None:
        inner = zip(cand.axis.heights[1:-1], cand.axis.configurations[1:-1], strict=True)
        vias = [q for z, q in inner if z > -d_f]
    insertion = [cand.q_hole_approach, *vias, cand.q_destination]
    bottom = None if part is None else _through_bottom(ctx, part)
    motion = f"insertion into {hole}"
    if beside or part is None:
        inserting = scene if bottom is None else gross.fine(grasp, part, bottom)
        reason = _sweep(ctx, inserting, insertion, motion, options)
    else:
        reason = _guided_insertion(ctx, strategy, insertion, part, bottom, options)
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
        q_via = ctx.nearest(pin_world(ctx, tap.via) * pin_from_hand, cand.q_transported)
        q_tap = (
            None if q_via is None else ctx.nearest(pin_world(ctx, tap.place) * pin_from_hand, q_via)
        )
        if q_via is None or q_tap is None:
            return f"no arm solution at the tap on {tap.surface}"
        reason = _sweep(ctx, scene, [q_via, q_tap], f"tap on {tap.surface}", options)
        if reason is not None:
            return reason
    seated = pin_world(ctx, strategy.destination)
    turns = [None, *gross.seat_turns(ctx.graph, ctx.hole_frame, ctx.world_hole.translation)]
    scenes = [(t, gross.letting_go(strategy.let_go_opening, seated, part, t)) for t in turns]
    options = gross.seated_options(
        ctx.graph,
        part,
        ctx.arm.forward(cand.q_destination),
        seated_hand_displacement(ctx),
        scenes[0][1],
        cand.q_destination,
    )
    for turn, scene in scenes:
        motion = f"let-go in {hole}" + ("" if turn is None else f" ({turn.words})")
        reason = _sweep(ctx, scene, [cand.q_destination], motion, options)
        if reason is not None:
            return reason
    # the candidate's, found with its release time (refinement keeps the get-clear point)
    target, q_clear = cand.clear or getting_clear(ctx, cand.q_destination, strategy)
    if q_clear is None:
        return "no arm solution where the hand gets clear"
    spread = _unreached_get_clear(ctx, strategy, cand.q_destination, target)
    if spread is not None:
        return spread
    for turn, scene in scenes:
        motion = f"get-clear from {hole}" + ("" if turn is None else f" ({turn.words})")
        reason = _sweep(ctx, scene, [cand.q_destination, q_clear], motion, options)
        if reason is not None:
            return reason
    return None


def _guided_insertion(
    ctx: PlanContext,
    strategy: PinInHoleStrategy,
    insertion: Sequence[Configuration],
    part: str,
    bottom: str | None,
    options: SweepOptions,
) -> str | None:
    """Why the insertion is obstructed, for a pin that comes below the face only in the hole.

    The arm's bodies are swept along the whole path with the fine motions' margins, and so is
    the held pin down to where its end may still be above the true face (Δa below the believed
    one, Δa the hole's error along its axis). From Δa above the believed face on, the pin can
    be that low only in the bore (no attempt goes beside the face), which guides it: each
    solid keeps only what moves it against the pin in the bore
    (:meth:`~synth.strategies.clearance.GrossMotionCheck.in_hole_options`), and the pin on the
    planned path stands off the pin on the axis by the path's sampled deviation
    (:func:`~synth.strategies.bow.pin_deviation`).
    """
    gross = ctx.gross
    grasp = strategy.pickup.grasp
    arm_scene, pin_scene = gross.held_apart(grasp, part, bottom)
    motion = f"insertion into {ctx.hole_al}"
    reason = _sweep(ctx, arm_scene, insertion, motion, options)
    if reason is not None:
        return reason
    along = seated_hand_displacement(ctx).support(ctx.world_hole.rotation[:, 2])  # Δa
    hole_from_world = ctx.world_hole.inverse()
    hand_from_end = end_from_hand(ctx, grasp).inverse()
    above, _ = split_at_height(ctx.arm, insertion, hole_from_world, hand_from_end, -along)
    _, below = split_at_height(ctx.arm, insertion, hole_from_world, hand_from_end, along)
    if len(above) > 1:
        reason = _sweep(ctx, pin_scene, above, motion, options)
        if reason is not None:
            return reason
    if len(below) < 2:
        return None
    deviation = pin_deviation(
        ctx.arm,
        below,
        hole_from_world,
        hand_from_end,
        lambda z: hole_frame_offset(strategy.phi, (0.0, 0.0, z)),
        ctx.pin_shape.length,
        0.5 * ctx.pin_shape.diameter,
    )
    off_axis = LinkDisplacement(ctx.world_hole.rotation, np.full(3, deviation), np.zeros(3), 0.0)
    in_hole = gross.in_hole_options(ctx.graph, ctx.hole_frame, off_axis)
    return _sweep(ctx, pin_scene, below, motion, in_hole)


def seated_hand_displacement(ctx: PlanContext) -> LinkDisplacement:
    """How far the hole holding the pin may truly be from its believed place, per world axis.

    The search and the guarded move end with the pin in the true hole, so the hand stops off
    its believed seat by the hole's world error (``world⁻¹ ∘ hole``, certified, along each
    world axis; the part's turn about the seat is swept apart,
    :meth:`~synth.strategies.clearance.GrossMotionCheck.seat_turns`), and by the grip
    (:meth:`~synth.strategies.clearance.GrossMotionCheck.seated_options` adds it): the arm's
    error at the approach cancels. The hand's own turn is the wrist links' grip bound
    (:meth:`~synth.strategies.clearance.GrossMotionCheck.fine_options`); a ball about the seat
    holding the arm's bodies would charge a Panda's forearm its 49 cm at the hand's 0.5°.
    """
    bounds = ctx.hole_errors.certified
    hole = np.array([bounds.dx.magnitude, bounds.dy.magnitude, bounds.dz.magnitude])
    return LinkDisplacement(np.eye(3), hole, np.zeros(3), 0.0)


def seat_displacements(ctx: PlanContext, strategy: PinInHoleStrategy) -> list[tuple[str, pin.SE3]]:
    """Where the seated hand may truly be: world displacements C (hand = C ∘ nominal hand).

    With F the pin's error against the hole when the hand is where the program believes (the
    footprint), the search and the guarded move end with the pin in the true hole, so the hand
    stops displaced from its believed seat by its own error less F: the hole's error cancels.
    The box is the footprint (±dx × ±dy turned by ζ in the hole plane, ±Δz along its axis:
    before any tap, which corrects the program's belief, not where the true hole is) widened by
    the hand's largest translation tolerance; the hand keeps its commanded turn but for its own
    rotation error.
    Returned: the corners of the box, and a turn by the hand's largest rotation tolerance
    either way about each world axis through the seat; each with its description. Corners,
    not a certified bound: the joints vary smoothly over a box this small.
    """
    footprint = strategy.errors
    hand = {} if ctx.hand_error is None else ctx.hand_error.bounds()

    def widest(names: tuple[str, ...]) -> float:
        return max((max(-hand[n].lo, hand[n].hi) for n in names if n in hand), default=0.0)

    shift, turn = widest(("x", "y", "z")), widest(("rx", "ry", "rz"))
    half = np.full(3, shift)  # in the footprint's frame: the hole's, turned by ζ
    zeta = 0.0
    if footprint is not None:
        half = half + np.array([footprint.dx, footprint.dy, footprint.dz])
        zeta = footprint.zeta
    c, s = math.cos(zeta), math.sin(zeta)
    world_from_box = ctx.world_hole.rotation @ np.array(
        [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    )
    axes = [k for k in range(3) if half[k] > 1e-12]
    out: list[tuple[str, pin.SE3]] = []
    for signs in itertools.product((-1.0, 1.0), repeat=len(axes)):
        local = np.zeros(3)
        for k, sign in zip(axes, signs, strict=True):
            local[k] = sign * half[k]
        vector = world_from_box @ local
        words = ", ".join(f"{'xyz'[k]} {100 * vector[k]:+.2f} cm" for k in range(3))
        out.append((words, pin.SE3(np.eye(3), vector)))
    if turn > 1e-12:
        centre = ctx.world_hole.translation
        for k in range(3):
            for sign in (-1.0, 1.0):
                rotation = pin.exp3(sign * turn * np.eye(3)[k])
                about = pin.SE3(rotation, centre - rotation @ centre)  # a turn about the seat
                out.append((f"r{'xyz'[k]} {math.degrees(sign * turn):+.2f}°", about))
    return out


def _unreached_get_clear(
    ctx: PlanContext, strategy: PinInHoleStrategy, q_seat: Configuration, target: pin.SE3
) -> str | None:
    """Why the get-clear may be out of the arm's reach once the seat is displaced, or None.

    The program backs the hand off from where it truly stopped (``BMANIP*TRANS(…)``, or the
    retreat's part-relative frame), so its joint targets follow the hole's true place: the
    retreat is solved from each displaced seat (:func:`seat_displacements`) by the replay's
    rule, nearest the seat's configuration. A nominal retreat at a joint's limit fails the
    trials that push it across.
    """
    away = strategy.get_clear
    seated = ctx.arm.forward(q_seat)
    for words, displacement in seat_displacements(ctx, strategy):
        q = ctx.nearest(displacement * seated, q_seat)
        if q is None:
            return f"no arm solution at the seat in {ctx.hole_al} displaced by the errors ({words})"
        moved = (
            ctx.arm.forward(q) * away.xf if away.base == strategy.hand else displacement * target
        )
        if ctx.nearest(moved, q) is None:
            return (
                f"no arm solution where the hand gets clear from its seat in {ctx.hole_al} "
                f"displaced by the errors ({words}): the retreat is near a joint's limit"
            )
    return None
