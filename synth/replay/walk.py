"""The held pin's walk along one segment of a motion: free flight, capture, guidance, sliding.

Along a segment the arm carries the pin on the commanded pose P(s) = F(q(s))·E(s)·G (the arm's
forward kinematics, the hand positioning error blending between its two targets, the grip).
The walk splits the segment into phases (:class:`~synth.replay.motion.Phase`) and finds where
the pin is stopped, if it is (:class:`~synth.replay.motion.Stop`):

* *free*: :func:`~synth.replay.contact.first_contact` finds the first contact. A capture by a
  hole starts a guided phase; a wedge is a ``wedged`` violation; a grazing push (less than
  ``slide_angle`` into the surface) starts a slide; any other contact stops the pin there;
* *guided* by a hole (:func:`~synth.replay.guided.guided_motion`): until it bottoms (a stop
  at the seat), leaves the mouth (free again) or is dragged sideways past the compliance (a
  ``collision`` violation: jammed);
* *sliding* (:func:`~synth.replay.scrape.scrape`): until the path clears the surface (free
  again), the arm would have to yield more than the compliance (a stop: jammed) or the pin
  meets another solid (a stop there).

:func:`pin_speed` bounds how fast any point of the pin moves along a segment: the constant
the contact search's conservative advancement divides distances by.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.arm import Arm, JointLimits, Obstacle
from synth.models.arm.bodies import Body
from synth.models.arm.sweep import body_motion_bounds
from synth.models.workcell import HoleSite, Workcell
from synth.replay.bounds import ArmChain, PinExtent, PinFlight
from synth.replay.capture import seat_depth, seated_pose, tip_placement
from synth.replay.cell import PinState, ReplayOptions
from synth.replay.contact import first_contact, pin_points
from synth.replay.guided import guided_motion
from synth.replay.motion import Phase, PoseAt, Segment, Slide, Stop, point_on, push_reaction
from synth.replay.report import Violation
from synth.replay.scrape import scrape
from synth.replay.wedging import wedging_onset
from synth.vec3 import norm3

__all__ = ["Walk", "WalkContext", "commanded_pose", "pin_speed", "walk_segment"]


@dataclass(frozen=True)
class WalkContext:
    """What the walk of one motion needs: the arm, the true workcell and the motion's facts.

    ``obstacles``: what the held pin can touch (the static solids and the free pins);
    ``line``: the motion's AL line; ``start_time`` [s]: the clock when the motion started;
    ``chain``: the arm's chain for the fast path's motion bounds.
    """

    arm: Arm
    workcell: Workcell
    options: ReplayOptions
    obstacles: Sequence[Obstacle]
    line: int
    start_time: float
    chain: ArmChain


@dataclass(frozen=True)
class Walk:
    """How the pin's walk along one segment ended.

    ``stop``: where the pin was stopped (None: it ran to the segment's end); ``hole`` and
    ``slide``: the phase it is in at the end (guided by a hole, sliding, or free), which the
    next segment starts in.
    """

    stop: Stop | None
    hole: HoleSite | None
    slide: Slide | None


def commanded_pose(arm: Arm, seg: Segment, grip: pin.SE3) -> PoseAt:
    """The pin pose the arm commands along ``seg``, s ↦ F(q(s))·E(s)·G [m]."""
    r_g, t_g = np.array(grip.rotation), np.array(grip.translation)

    def commanded(x: float) -> pin.SE3:
        # reading ∘ error ∘ grip, composed as matrices
        reading = arm.forward(seg.q(x))
        r_r, t_r = reading.rotation, reading.translation
        r_e, t_e = seg.error_rt(x)
        rotation = r_r @ r_e @ r_g
        return pin.SE3(rotation, r_r @ (r_e @ t_g + t_e) + t_r)

    return commanded


def pin_speed(arm: Arm, state: PinState, segment: Segment) -> float:
    """Bound [m per unit s] on the speed of every point of the held pin along ``segment``.

    Σ_j (ρ_j + m_j)·|Δq_j| + b: ρ_j bounds a pin point's lever about joint j over the
    segment's joint box (:func:`~synth.models.arm.sweep.body_motion_bounds`), m_j = 2(|t_e| +
    |θ_e|·r) the hand error's shift of the pin (r its reach from the hand) on revolute joints,
    and b = |Δt_e| + |Δθ_e|·(r + |t_e|) the error's own blend between its two targets.
    """
    assert state.grip is not None
    hand_frame = arm.model.frames[arm.hand_frame]
    body = Body(
        state.model.name,
        int(hand_frame.parentJoint),
        state.model.name,
        hand_frame.placement * state.grip,
        state.model.geometry,
        "held",
    )
    # the levers of the bound only need the prismatic extensions this segment passes through
    limits = arm.limits
    low, high = np.minimum(segment.q0, segment.q1), np.maximum(segment.q0, segment.q1)
    swept = JointLimits(limits.names, limits.kinds, low, high, limits.velocity, limits.acceleration)
    rho = body_motion_bounds(arm.model, swept, [body])[0]
    reach = state.model.reach(state.grip)
    t_e = float(max(norm3(segment.e0.translation), norm3(segment.e1.translation)))
    r_e = float(
        max(
            norm3(pin.log3(segment.e0.rotation)),
            norm3(pin.log3(segment.e1.rotation)),
        )
    )
    margin = np.where(rho > 0, 2.0 * (t_e + r_e * reach), 0.0)
    margin = np.where(np.array(limits.kinds) == "prismatic", 0.0, margin)
    dq = np.abs(segment.q1 - segment.q0)
    d_error = segment.e0.inverse() * segment.e1
    blend = norm3(segment.e1.translation - segment.e0.translation)
    blend += norm3(pin.log3(d_error.rotation)) * (reach + t_e)
    return float((rho + margin) @ dq) + blend


def _extent(chain: ArmChain, held: PinState) -> PinExtent:
    """The held pin's :class:`PinExtent`, kept on the pin while its grip stays the same."""
    assert held.grip is not None
    extent = held.extent
    if extent is None or extent.grip is not held.grip:
        extent = PinExtent.of(chain, held.grip, pin_points(held.model))
        held.extent = extent
    return extent


def _violation(context: WalkContext, kind: str, detail: str, seg: Segment, s: float) -> Violation:
    return Violation(kind, context.line, detail, context.start_time + seg.time(s))  # type: ignore[arg-type]


def _wedged(
    context: WalkContext, held: PinState, hole: HoleSite, pose: pin.SE3, seg: Segment, s: float
) -> Stop:
    """The stop of a pin that enters ``hole`` at a wedging tilt (a ``wedged`` violation)."""
    friction = context.workcell.friction
    tilt = tip_placement(hole, pose).tilt
    onset = wedging_onset(2.0 * hole.radius, 2.0 * held.model.radius, friction)
    detail = (
        f"{held.model.name} wedged in {hole.name}: it entered tilted "
        f"{math.degrees(tilt):.2f}°, "
        f"beyond the {math.degrees(onset):.2f}° at which its two-point contact sticks "
        f"(μ = {friction:g})"
    )
    violation = _violation(context, "wedged", detail, seg, s)
    return Stop(s, "violation", held.model.name, hole.name, violation=violation)


def walk_segment(
    context: WalkContext,
    held: PinState,
    seg: Segment,
    hole: HoleSite | None,
    slide: Slide | None,
) -> Walk:
    """Walk the held pin along ``seg``, starting guided by ``hole`` or sliding (``slide``).

    Sets ``seg.phases``; see the module docstring.
    """
    options = context.options
    obstacles = context.obstacles
    seg.phases = [Phase(0.0, hole, slide)]
    pin_stop: Stop | None = None
    s = 0.0
    grip = held.grip
    assert grip is not None
    commanded = commanded_pose(context.arm, seg, grip)
    speeds: list[float] = []

    def speed() -> float:
        """:func:`pin_speed` of this segment (the reference's search and the slide's steps)."""
        if not speeds:
            speeds.append(pin_speed(context.arm, held, seg))
        return speeds[0]

    flight = None
    if not options.reference:
        flight = PinFlight(context.chain, seg, _extent(context.chain, held))
    while s < 1.0 and pin_stop is None:
        if hole is not None:
            end = guided_motion(
                hole,
                commanded,
                seat=seat_depth(hole, held.model),
                start=s,
                compliance=options.compliance,
                exit_margin=options.exit_margin,
                seated_within=options.seat_tolerance,
                flight=flight,
            )
            if end.kind == "exit":
                hole, s = None, end.s
                seg.phases.append(Phase(s))
            elif end.kind == "bottom":
                tip = seated_pose(hole, end.depth, commanded(end.s)).translation
                pin_stop = Stop(end.s, "seat", held.model.name, hole.name, tip, hole.axis)
            elif end.kind == "jam":
                detail = (
                    f"{held.model.name} jammed in {hole.name}: the motion drags it "
                    f"{100 * end.lateral:.2f} cm sideways while it is in the hole"
                )
                violation = _violation(context, "collision", detail, seg, end.s)
                pin_stop = Stop(end.s, "violation", held.model.name, hole.name, violation=violation)
            else:
                s = 1.0
            continue
        if slide is not None:
            current = slide
            slid = scrape(
                held.model,
                commanded,
                speed(),
                current,
                [o for o in obstacles if o is not current.obstacle],
                start=s,
                compliance=options.compliance,
                clearance=options.contact_clearance,
            )
            if slid.kind == "free":
                slide, s = None, slid.s
                seg.phases.append(Phase(s))
            elif slid.kind == "jam":
                pin_point = current.pin_point
                pin_stop = Stop(
                    slid.s,
                    "surface",
                    held.model.name,
                    current.obstacle.name,
                    commanded(slid.s).act(pin_point),
                    push_reaction(partial(point_on, commanded, pin_point), slid.s),
                    note=f"slid along it and jammed, {100 * slid.deflection:.2f} cm in",
                )
            elif slid.kind == "touch":
                assert slid.touched is not None and slid.point is not None
                pin_stop = Stop(
                    slid.s,
                    "surface",
                    held.model.name,
                    slid.touched.name,
                    slid.point,
                    push_reaction(partial(point_on, commanded, current.pin_point), slid.s),
                    note=f"met it sliding along {current.obstacle.name}",
                )
            else:
                s = 1.0
            continue
        found = first_contact(
            held.model,
            commanded,
            speed() if flight is None else 0.0,
            obstacles,
            context.workcell.holes,
            start=s,
            clearance=options.contact_clearance,
            friction=context.workcell.friction,
            flight=flight,
        )
        if found is None:
            s = 1.0
        elif found.kind == "wedge":
            assert found.hole is not None
            pin_stop = _wedged(context, held, found.hole, commanded(found.s), seg, found.s)
        elif found.kind == "capture":
            assert found.hole is not None
            hole, s = found.hole, found.s
            seg.phases.append(Phase(s, hole))
        else:
            local: NDArray[np.float64] = found.pin_point
            reaction = push_reaction(partial(point_on, commanded, local), found.s)
            into = float(reaction @ found.normal)  # the push's component into the surface
            if into < math.sin(options.slide_angle):
                # a grazing push: the pin slides along the surface, the arm yields
                touched = next(o for o in obstacles if o.name == found.obstacle)
                origin = commanded(found.s).act(local)
                slide = Slide(touched, found.normal, local, origin, held.model.geometry)
                s = found.s
                seg.phases.append(Phase(s, slide=slide))
            else:
                pin_stop = Stop(
                    found.s, "surface", held.model.name, found.obstacle, found.point, reaction
                )
    return Walk(pin_stop, hole, slide)
