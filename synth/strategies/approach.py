"""Moving the pin to the hole (seed §4.4, L2141–2200): φ, dtry, standoff and the basic motions.

The guarded move of the first attempt is (L2146–2148)::

    move pin to hole*trans(rot(zhat,phi),vector(0,0,-dtry))
      via hole*trans(rot(zhat,phi),vector(0,0,standoff))
      on force(pin*zhat)>8*oz do ...

φ is chosen like ω: every 45°, an arm solution at the approach and destination points,
"a single value of ϕ is picked to minimize the expected motion time" (L2155–2160) of the move
departure → approach → destination, among the φ whose transport (departure → approach) is clear
of the workcell (:mod:`synth.strategies.clearance`). ``dtry = d_f + 1 in`` and
``standoff = 1 in`` (L2188–2190). The result is the "embryo" pin-in-hole strategy (L2201) whose
cost is the pickup time plus the transport time: the candidate that best-first selection
refines.

Poses are those of the pin end that enters the hole (the tip, or the head when the pin is
turned over): ``end = hole ∘ trans(rot(ẑ, φ), (0, 0, z))``; the hand is then at
``end ∘ T_end_hand`` with ``T_end_hand = T_pin_end⁻¹ ∘ T_pin_hand``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from synth.models.world import World
from synth.strategies.context import Configuration, PlanContext
from synth.strategies.grasp import Pickup
from synth.strategies.records import Destination, Grasp, PinInHoleStrategy, Rejection


def hole_frame_offset(phi: float, offset: tuple[float, float, float]) -> pin.SE3:
    """``trans(rot(ẑ, φ), offset)``: a frame in the hole frame [rad, m]."""
    return pin.SE3(pin.exp3(np.array([0.0, 0.0, phi])), np.array(offset, dtype=float))


def transform_end_hand(ctx: PlanContext, grasp: Grasp) -> pin.SE3:
    """The hand in the frame of the inserted pin end: ``T_pin_end⁻¹ ∘ T_pin_hand``."""
    return ctx.transform_pin_end.inverse() * grasp.pin_from_hand()


def hand_at(ctx: PlanContext, grasp: Grasp, transform_hole_end: pin.SE3) -> pin.SE3:
    """World pose of the hand when the pin end is at ``transform_hole_end`` (hole frame)."""
    return ctx.world_hole * transform_hole_end * transform_end_hand(ctx, grasp)


def pin_destination(ctx: PlanContext, label: str, transform_hole_end: pin.SE3) -> Destination:
    """``PIN1 = BH1 * xf`` with ``xf = transform_hole_end ∘ T_pin_end⁻¹`` (seed L1912–1925)."""
    return Destination(
        label, ctx.pin_al, ctx.hole_al, transform_hole_end * ctx.transform_pin_end.inverse()
    )


@dataclass(frozen=True, eq=False)
class Candidate:
    """A basic pin-in-hole strategy (L2201) with its arm configurations and its world.

    ``q_hole_approach``, ``q_destination`` reach the approach point and the pin at depth d_f;
    ``q_surface`` the pin end on the hole's plane (where a miss stops). ``transport_time`` [s]
    is departure → approach → destination; ``try_time`` [s] one retry: surface → approach →
    surface, the unit of search time. ``phi_times`` is the φ table of L2170–2180 (None: no arm
    solution).
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
    counter: int = 0

    @property
    def name(self) -> str:
        """Label: grasp and φ."""
        return self.strategy.name

    @property
    def cost(self) -> float:
        """Gross motion time [s] (pickup + transport), the best-first priority (L2455)."""
        return self.strategy.ttime


def _z(z: float) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([0.0, 0.0, z]))


def plan_approach(ctx: PlanContext, pickup: Pickup) -> Candidate | Rejection:
    """The φ with the shortest transport time for one pickup, or why there is none."""
    opts = ctx.options
    grasp = pickup.strategy.grasp
    d_f = ctx.insertion.d_f
    steps = round(2 * math.pi / opts.phi_step)
    table: list[tuple[float, float | None]] = []
    timed: list[tuple[float, float, Configuration, Configuration]] = []
    for k in range(steps):
        phi = k * opts.phi_step
        q_app = ctx.nearest(
            hand_at(ctx, grasp, hole_frame_offset(phi, (0.0, 0.0, opts.standoff))),
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
    # The quickest φ (L2160) whose transport is clear of the workcell.
    carrying = ctx.gross.holding(grasp)
    best: tuple[float, float, Configuration, Configuration] | None = None
    first_reason: str | None = None
    for entry in sorted(timed, key=lambda e: (e[0], e[1])):
        reason = ctx.obstruction(
            carrying,
            [pickup.q_departure, entry[2]],
            f"transport to the approach point of {ctx.hole_al} at φ={math.degrees(entry[1]):.0f}°",
        )
        if reason is None:
            best = entry
            break
        first_reason = first_reason or reason
    if best is None:
        return Rejection(pickup.name, f"every φ is obstructed; the quickest: {first_reason}")
    transport, phi, q_app, q_dest = best
    q_surface = ctx.nearest(hand_at(ctx, grasp, hole_frame_offset(phi, (0.0, 0.0, 0.0))), q_dest)
    if q_surface is None:
        return Rejection(pickup.name, f"no arm solution with the pin on the surface at φ={phi}")
    try_time = ctx.motion([q_surface, q_app, q_surface])
    dtry = d_f + opts.dtry_extra
    name = f"{pickup.name} φ={math.degrees(phi):.0f}°"
    strategy = PinInHoleStrategy(
        pin=ctx.pin_al,
        hole=ctx.hole_al,
        hand=ctx.hand_al,
        pickup=pickup.strategy,
        phi=phi,
        dtry=dtry,
        standoff=opts.standoff,
        approach=pin_destination(ctx, "approach", hole_frame_offset(phi, (0, 0, opts.standoff))),
        destination=pin_destination(ctx, "destination", hole_frame_offset(phi, (0, 0, -d_f))),
        target=pin_destination(ctx, "target", hole_frame_offset(phi, (0.0, 0.0, -dtry))),
        d_f=d_f,
        d_s=ctx.insertion.d_s,
        dr_ok=ctx.insertion.dr_ok,
        success_threshold=opts.tau * (d_f - ctx.insertion.d_s),
        force_threshold=opts.force_threshold,
        ttime=pickup.strategy.goodness + transport,
        name=name,
    )
    world = pickup.world.set_value("approach-phi", ctx.pin_al, ctx.hole_al, round(phi, 12))
    return Candidate(
        strategy, pickup, q_app, q_dest, q_surface, transport, try_time, tuple(table), world
    )
