"""Moving the pin to the hole (seed §4.4, L2141–2200): φ, dtry, standoff and the basic motions.

The guarded move of the first attempt is (L2146–2148)::

    move pin to hole*trans(rot(zhat,phi),vector(0,0,-dtry))
      via hole*trans(rot(zhat,phi),vector(0,0,standoff))
      on force(pin*zhat)>8*oz do ...

φ is chosen like ω: every 45°, an arm solution at the approach and destination points,
"a single value of ϕ is picked to minimize the expected motion time" (L2155–2160) of the move
departure → approach → destination, among the φ whose transport (departure → approach) is clear
of the workcell (:mod:`synth.strategies.clearance`).

Heights (L2186–2190: "the principal constraint" is that the approach point stays above the
surface and a full insertion stops on force whatever Δz): the seed takes ``standoff = 1 in``
and ``dtry = d_f + 1 in``; here they are at least that and at least the certified Δz along the
axis at the approach point plus :data:`APPROACH_CLEARANCE`, ``standoff ≥ Δz + m + c`` (m the
held pin's margin in the gross-motion sweep, which ends there), at least what that sweep asks
of the pin and the hole's part along the axis plus c, and ``dtry − d_f ≥ Δz + c``, so
a part whose height is poorly known gets a higher approach instead of a rejection. The final
approach runs through via points along the axis that bound the bow of the joint-interpolated
move (:mod:`synth.strategies.bow`). The result is the "embryo" pin-in-hole strategy (L2201)
whose cost is the pickup time plus the transport time: the candidate that best-first selection
refines.

Poses are those of the pin end that enters the hole (the tip, or the head when the pin is
turned over): ``end = hole ∘ trans(rot(ẑ, φ), (0, 0, z))``; the hand is then at
``end ∘ T_end_hand`` with ``T_end_hand = T_pin_end⁻¹ ∘ T_pin_hand``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from synth.errors.estimate import RelationModel
from synth.models.arm import SweepResult
from synth.models.world import World
from synth.strategies.bow import BOW_FRACTION, AxisPath, plan_axis_path
from synth.strategies.context import Configuration, PlanContext, end_from_hand, hand_at
from synth.strategies.detour import Detour, lift_over
from synth.strategies.grasp import Pickup
from synth.strategies.hypotheses import ApproachPhi, ApproachStandoff
from synth.strategies.records import Destination, PinInHoleStrategy, Rejection
from synth.strategies.relations import approach_relation, hole_frame_offset

__all__ = [
    "APPROACH_CLEARANCE",
    "Candidate",
    "approach_heights",
    "end_from_hand",
    "hand_at",
    "hole_frame_offset",
    "pin_destination",
    "plan_approach",
]

APPROACH_CLEARANCE = 1e-3
"""[m] the approach point stays this far above the surface, and the guarded insertion aims
this far past the seat, beyond the certified Δz (the gross-motion sweeps' clearance)."""


def pin_destination(ctx: PlanContext, label: str, hole_from_end: pin.SE3) -> Destination:
    """``PIN1 = BH1 * xf`` with ``xf = hole_from_end ∘ T_pin_end⁻¹`` (seed L1912–1925)."""
    return Destination(label, ctx.pin_al, ctx.hole_al, hole_from_end * ctx.pin_from_end.inverse())


@dataclass(frozen=True, eq=False)
class Candidate:
    """A basic pin-in-hole strategy (L2201) with its arm configurations and its world.

    ``q_hole_approach``, ``q_destination`` reach the approach point and the pin at depth d_f;
    ``q_surface`` the pin end on the hole's plane (where a miss stops). ``transport_time`` [s]
    is departure → approach → (vias above the seat) → destination; ``try_time`` [s] one retry:
    surface → approach → surface, the unit of search time. ``phi_times`` is the φ table of
    L2170–2180 (None: no arm solution). ``axis`` is the final approach with its vias and bow.
    """

    strategy: PinInHoleStrategy
    pickup: Pickup
    q_hole_approach: Configuration
    q_destination: Configuration
    q_surface: Configuration
    transport_time: float
    try_time: float
    phi_times: tuple[tuple[float, float | None], ...]
    world: World
    axis: AxisPath | None = None
    counter: int = 0
    transport_detour: Detour | None = None
    """The transport lifted over the workcell (:mod:`synth.strategies.detour`), if it is."""
    clear: tuple[pin.SE3, Configuration | None] | None = None
    """Where the hand gets clear after letting go and the arm there (:func:`getting_clear`),
    found once with the release time and swept at refinement."""

    @property
    def name(self) -> str:
        """Label: grasp and φ."""
        return self.strategy.name

    @property
    def q_transported(self) -> Configuration:
        """Where the departure move ends: its detour's last via point, or the departure point.

        The tap or the first attempt starts there.
        """
        return self.transport_vias[-1] if self.transport_vias else self.pickup.q_departure

    @property
    def transport_vias(self) -> tuple[Configuration, ...]:
        """The arm at the transport detour's via points, in order (none: a straight move)."""
        return () if self.transport_detour is None else self.transport_detour.configurations

    @property
    def cost(self) -> float:
        """The best-first priority [s]: the gross motion time (pickup + transport, L2455).

        And the release after the insertion, known before refinement as the gross motions are.
        """
        return self.strategy.gross_time + self.strategy.release_time


def pin_world(ctx: PlanContext, destination: Destination) -> pin.SE3:
    """The world pose [m] of a destination point (its base frame as believed, then ``xf``)."""
    return ctx.graph.world_from(ctx.graph.resolve(destination.base)) * destination.xf


def getting_clear(
    ctx: PlanContext, q_destination: Configuration, strategy: PinInHoleStrategy
) -> tuple[pin.SE3, Configuration | None]:
    """Where the hand goes to get clear after letting go (seed L2844), and the arm there."""
    away = strategy.get_clear
    if away.base == strategy.hand:
        target = ctx.arm.forward(q_destination) * away.xf
    else:
        target = pin_world(ctx, away) * strategy.pickup.grasp.pin_from_hand()
    return target, ctx.nearest(target, q_destination)


def release_time(
    ctx: PlanContext, q_destination: Configuration, q_clear: Configuration | None
) -> float:
    """[s] The let-go and get-clear the program ends with (seed L2839–2844).

    OPEN (50 jiffies, L3854) and the move back to where the hand is clear, ``q_clear`` (none
    where it has no arm solution, which :func:`~synth.strategies.fine.fine_motion_obstruction`
    refuses).
    """
    move = 0.0 if q_clear is None else ctx.motion([q_destination, q_clear])
    return ctx.options.open_time + move


def approach_heights(ctx: PlanContext, pickup: Pickup) -> tuple[float, float, float]:
    """``(standoff, dtry, Δz)`` [m] for a pickup (module docstring).

    Δz is the certified bound on the pin end's error along the hole axis at the approach point
    of the option's standoff, φ = 0 (one bound): a change of height or of φ moves the hand
    error's lever by centimetres and Δz by θ_hand·Δl, far below the clearance.
    """
    opts = ctx.options
    world = pickup.world.with_facts(ApproachStandoff(ctx.pin_al, ctx.hole_al, opts.standoff))
    model = RelationModel.of(approach_relation(ctx, world, 0.0))
    ctx.counters.count_bounds(model.space)
    _, certified = model.displacement_along(np.array([0.0, 0.0, 1.0]))
    dz = float(certified.magnitude)
    # The transport ends at the approach point: its sweep keeps the held pin its ball margin
    # under the hand error (clearance.GrossMotionCheck) from the part, which Δz alone omits,
    # and charges the part the displacement of its farthest point along the axis, where Δz is
    # that of the hole: a plate tilting about a far origin rises more at its corners.
    held = ctx.gross.carrying.margins.get(ctx.pin_al, 0.0)
    part = ctx.gross.part_of(ctx.graph, ctx.hole_frame)
    swept = 0.0
    if part is not None:
        axis = ctx.world_hole.rotation[:, 2]
        carrying = ctx.gross.carrying
        swept = carrying.clearance + carrying.pair_margin_along((ctx.pin_al, part), axis)
    standoff = max(opts.standoff, dz + held + APPROACH_CLEARANCE, swept + APPROACH_CLEARANCE)
    dtry = ctx.insertion.d_f + max(opts.dtry_extra, dz + APPROACH_CLEARANCE)
    return standoff, dtry, dz


def plan_approach(
    ctx: PlanContext, pickup: Pickup, skip: frozenset[float] = frozenset()
) -> Candidate | Rejection:
    """The φ with the shortest transport time for one pickup, or why there is none.

    ``skip``: φ values [rad] already tried (their fine motions obstructed, at refinement).
    """
    opts = ctx.options
    grasp = pickup.strategy.grasp
    d_f = ctx.insertion.d_f
    standoff, dtry, _ = approach_heights(ctx, pickup)
    steps = round(2 * math.pi / opts.phi_step)
    table: list[tuple[float, float | None]] = []
    timed: list[tuple[float, float, Configuration, Configuration]] = []
    for k in range(steps):
        phi = k * opts.phi_step
        if phi in skip:
            continue
        q_app = ctx.nearest(
            hand_at(ctx, grasp, hole_frame_offset(phi, (0.0, 0.0, standoff))),
            pickup.q_departure,
        )
        q_dest = (
            None
            if q_app is None
            else ctx.nearest(hand_at(ctx, grasp, hole_frame_offset(phi, (0.0, 0.0, -d_f))), q_app)
        )
        if q_app is None or q_dest is None:
            table.append((phi, None))
            continue
        t = ctx.motion([pickup.q_departure, q_app, q_dest])
        table.append((phi, t))
        timed.append((t, phi, q_app, q_dest))
    if not timed:
        return Rejection(
            pickup.name,
            f"no φ in 0°…315° has arm solutions at the approach and destination points of "
            f"{ctx.hole_al}",
        )
    # The quickest φ (L2160) whose transport is clear of the workcell; failing every one, the
    # quickest whose transport lifted over the workcell is
    carrying = ctx.gross.holding(grasp)
    best: tuple[float, float, Configuration, Configuration] | None = None
    first_reason: str | None = None
    ordered = sorted(timed, key=lambda e: (e[0], e[1]))
    straight: list[SweepResult] = []  # the sweeps of the obstructed φ, in that order
    for entry in ordered:
        blocked = ctx.obstructed(
            carrying,
            [pickup.q_departure, entry[2]],
            f"transport to the approach point of {ctx.hole_al} at φ={math.degrees(entry[1]):.0f}°",
        )
        if blocked is None:
            best = entry
            break
        first_reason = first_reason or blocked[0]
        straight.append(blocked[1])
    # An obstructed φ quicker than that one may be quicker still lifted over what is in the
    # way (a lift only adds time, so the φ no quicker straight are not tried)
    detour: Detour | None = None
    lifted_reason = ""
    best_time = math.inf if best is None else best[0]
    for entry, sweep in zip(ordered, straight, strict=False):
        if entry[0] >= best_time:
            break
        lifted = lift_over(ctx, carrying, pickup.q_departure, entry[2], sweep)
        if isinstance(lifted, str):
            lifted_reason = lifted_reason or lifted
            continue
        lifted_time = ctx.motion([pickup.q_departure, *lifted.configurations, entry[2], entry[3]])
        if lifted_time < best_time:
            best, detour, best_time = entry, lifted, lifted_time
    if best is None:
        return Rejection(
            pickup.name,
            f"every φ is obstructed; the quickest: {first_reason}; lifted: {lifted_reason}",
        )
    _, phi, q_app, q_dest = best
    vias = () if detour is None else detour.configurations
    q_surface = ctx.nearest(hand_at(ctx, grasp, hole_frame_offset(phi, (0.0, 0.0, 0.0))), q_dest)
    if q_surface is None:
        return Rejection(pickup.name, f"no arm solution with the pin on the surface at φ={phi}")

    def solve(z: float, q_from: Configuration) -> Configuration | None:
        return ctx.nearest(hand_at(ctx, grasp, hole_frame_offset(phi, (0.0, 0.0, z))), q_from)

    tolerance = BOW_FRACTION * min(ctx.insertion.lead, ctx.insertion.dr_ok)
    axis = plan_axis_path(
        solve,
        ctx.arm,
        q_app,
        ctx.world_hole.inverse(),
        end_from_hand(ctx, grasp).inverse(),
        standoff,
        dtry,
        d_f,
        tolerance,
    )
    if axis is None:
        return Rejection(pickup.name, f"no arm solution along the axis of {ctx.hole_al} at φ={phi}")
    above_seat = [
        q for z, q in zip(axis.heights[1:-1], axis.configurations[1:-1], strict=True) if z > -d_f
    ]
    transport = ctx.motion([pickup.q_departure, *vias, q_app, *above_seat, q_dest])
    try_time = ctx.motion([q_surface, q_app, q_surface])
    name = f"{pickup.name} φ={math.degrees(phi):.0f}°"
    strategy = PinInHoleStrategy(
        pin=ctx.pin_al,
        hole=ctx.hole_al,
        hand=ctx.hand_al,
        pickup=pickup.strategy,
        phi=phi,
        dtry=dtry,
        standoff=standoff,
        approach=pin_destination(ctx, "approach", hole_frame_offset(phi, (0, 0, standoff))),
        destination=pin_destination(ctx, "destination", hole_frame_offset(phi, (0, 0, -d_f))),
        target=pin_destination(ctx, "target", hole_frame_offset(phi, (0.0, 0.0, -dtry))),
        d_f=d_f,
        d_s=ctx.insertion.d_s,
        dr_ok=ctx.insertion.dr_ok,
        lead=ctx.insertion.lead,
        success_threshold=opts.tau * (d_f - ctx.insertion.d_s),
        force_threshold=opts.force_threshold,
        gross_time=pickup.strategy.pickup_time + transport,
        name=name,
        approach_vias=tuple(
            pin_destination(ctx, f"approach via {k + 1}", hole_frame_offset(phi, (0.0, 0.0, z)))
            for k, z in enumerate(axis.via_heights)
        ),
        bow=axis.bow,
        transport_detour=()
        if detour is None
        else detour.destinations(ctx.pin_al, grasp.pin_from_hand().inverse()),
    )
    clear = getting_clear(ctx, q_dest, strategy)
    strategy = dataclasses.replace(strategy, release_time=release_time(ctx, q_dest, clear[1]))
    world = pickup.world.with_facts(
        ApproachPhi(ctx.pin_al, ctx.hole_al, round(phi, 12)),
        ApproachStandoff(ctx.pin_al, ctx.hole_al, standoff),
    )
    return Candidate(
        strategy,
        pickup,
        q_app,
        q_dest,
        q_surface,
        transport,
        try_time,
        tuple(table),
        world,
        axis,
        transport_detour=detour,
        clear=clear,
    )
