"""Grasp generation (seed §4.3, L2011–2140): where and how the hand takes the pin.

The hand takes the pin at ``hand = pin ∘ trans(rot(ẑ, ω)·rot(x̂, γ), (0, 0, d))`` (L2020):
γ is the angle between the pin axis and the hand's approach vector, d the distance from the tip
along the pin axis, ω the turn of the hand about the pin axis. The method (L2090–2100):

1. limits on d from the pin's depth in its start hole d_i and target hole d_f
   (:func:`grasp_distance_limits`), then "significantly distinct" d and γ values
   (:func:`grasp_distances`, :func:`grasp_angles`);
2. geometric filters with the hand "moved by levitation" (:func:`geometry_problem`): fingers
   not below either hole plane, approach vector at least 90° from the holes' outward normals,
   palm clear of the pin shaft;
3. ω every 45°, an arm solution at each grasping position, graded by the seed's rating
   |45° − θ5| and pruned to the best three (L2122) unless ``try_harder``;
4. approach point 2 in back along the hand's approach vector, departure point 2 in above the
   start hole (L2128), hand openings by L2139, and the pickup's expected time.

Before the arm is asked (step 3), each grasp's ``center`` is checked against where the pin may
really be (§4.3.1: "the pin's position be known with sufficient accuracy for the centering
operation to succeed"): :func:`centering_bounds` bounds the pin's grasp point relative to the
hand through the start part's uncertainty and the hand's error, and :func:`centering_problem`
applies the hand's geometry. ``center`` registers the hand on the pin along the fingers' closing
direction only; what the start location leaves along the pin axis and across the pads is the
grasp determination (``GRASP DETERM``) that the insertion's footprint then carries.

Each surviving pickup plans on in its own child world of the assertion base, in which the pin
is affixed to the hand with its grasp.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import shapely

from synth.errors.bounds import bound_linear
from synth.errors.chain import ErrorChain, Fixed, Perturbation, Term
from synth.errors.estimate import RelationModel, estimate_errors
from synth.errors.parameters import ParameterBlock
from synth.models.arm import grasp_rating
from synth.models.manipulator import HandSpec
from synth.models.spec import PinShape
from synth.models.world import World
from synth.strategies.context import Configuration, PinEnd, PlanContext, hand_at
from synth.strategies.detour import Detour, lift_over
from synth.strategies.hypotheses import Affixed, At, GraspDetermination, Holding
from synth.strategies.options import PlanOptions, hand_openings
from synth.strategies.records import Destination, Grasp, GraspStrategy, Rejection, grasp_remarks

"""World atom for a grasp determination of NILTRANS: ``center`` holds the pin exactly (L2630)."""

PAD_TILT = math.radians(10.0)
"""[rad] largest angle between the pin's axis and the pads' plane at which ``center`` still
closes both pads on the shaft [est: the rubber pads' give]."""
OPENING_MARGIN = 1e-3
"""[m] added to each side of a widened approach opening, so the fingers' descent along the
approach clears the farthest place the pin may be."""
OPENING_ROUNDING = 1e-3
"""[m] a widened approach opening is rounded up to a whole number of these."""


def grasp_distance_limits(
    pin_length: float,
    taper_length: float,
    d_i: float,
    d_f: float,
    pad_radius: float,
    kappa: float,
    *,
    same_end: bool,
) -> tuple[float, float]:
    """``(d_min, d_max)`` [m] of the grasp distance (seed L2032–2044, L2076).

    Same end into both holes: ``d_min = max(d_i, d_f) + r_fp + κ``,
    ``d_max = l_pin − (l_taper + κ)``. Turned over: ``d_i + r_fp + κ ≤ d ≤ l_pin − (d_f + r_fp
    + κ)``. The interval is empty when ``d_min > d_max``.
    """
    if same_end:
        return max(d_i, d_f) + pad_radius + kappa, pin_length - (taper_length + kappa)
    return d_i + pad_radius + kappa, pin_length - (d_f + pad_radius + kappa)


def grasp_distances(d_min: float, d_max: float, options: PlanOptions) -> tuple[float, ...]:
    """The d values tried [m]: the midpoint of a short interval, else three (L2050–2060).

    Short (``d_max − d_min < 2.5 in``): ``(d_min + d_max)/2``. Long: ``d_max − 0.6 in``,
    ``d_min + 0.6 in`` and the midpoint. Empty when ``d_min > d_max``.
    """
    if d_min > d_max:
        return ()
    middle = (d_min + d_max) / 2
    if d_max - d_min < options.short_interval:
        return (middle,)
    return (d_max - options.distance_offset, d_min + options.distance_offset, middle)


def grasp_angles(same_end: bool, options: PlanOptions) -> tuple[float, ...]:
    """The γ values tried [rad]: 180°, 135°, 100° (L2064–2068), or 90° turned over (L2078)."""
    return options.same_end_gammas if same_end else (options.turn_over_gamma,)


def _inverse_terms(terms: list[Term]) -> list[Term]:
    """Terms of the inverse product: reversed, each fixed pose and perturbation inverted."""
    out: list[Term] = []
    for t in reversed(terms):
        if isinstance(t, Fixed):
            out.append(Fixed(t.pose.inverse()))
        else:
            out.append(Perturbation(t.block, inverse=not t.inverse))
    return out


@dataclass(frozen=True)
class CenteringBounds:
    """Certified errors of the pin relative to the hand at the grasp point (seed §4.3.1).

    In the hand frame (x the fingers' closing direction, z the approach vector) the pin's axis
    should cross the x axis at the pads' centre with the grasp point, ``d`` up the pin from the
    tip, at the origin. ``closing`` [m] bounds where along x the axis crosses (``center`` closes
    the fingers and moves the arm by that much); ``across`` [m] the axis's distance from the x
    axis (the pads reach ``r_fp``); ``axial`` [m] the grasp point's shift along the pin axis;
    ``tilt`` [rad] the axis's angle to its nominal direction, which bounds its angle to the pads'
    plane. ``residual`` is the grasp determination: ``(param, lo, hi)`` bounds [m, rad] of the
    pin's error in the hand after ``center`` (a perturbation in the pin frame, the form of
    :func:`synth.strategies.relations.held_end_terms`), from the start location's errors only;
    empty when the start location is exact (NILTRANS).
    """

    closing: float
    across: float
    axial: float
    tilt: float
    residual: tuple[tuple[str, float, float], ...] = ()

    def to_json(self) -> dict[str, object]:
        """JSON form (SI)."""
        return {
            "closing": self.closing,
            "across": self.across,
            "axial": self.axial,
            "tilt": self.tilt,
            "grasp_determination": [list(r) for r in self.residual],
        }


def grasp_relation(ctx: PlanContext, grasp: Grasp, *, hand_error: bool = True) -> ErrorChain:
    """``hand⁻¹ ∘ pin ∘ trans(0, 0, d)``: the pin's grasp point seen from the hand at the grasp.

    ``E_hand(v)⁻¹ ∘ hand₀⁻¹ ∘ pin(v) ∘ trans(0, 0, d)``, ``hand₀ = pin₀ ∘ T_pin_hand`` the
    nominal grasp (L2020) and ``pin(v)`` the pin's chain from the world through the start part's
    uncertainty blocks (the same ``link:<frame>`` blocks the insertion's relations use). Without
    ``hand_error`` the relation is the start location's share only.
    """
    from synth.strategies.relations import SpaceBuilder, frame_inverse_terms  # imports grasp

    builder = SpaceBuilder()
    to_pin = _inverse_terms(frame_inverse_terms(ctx.graph, ctx.pin_frame, builder))
    terms: list[Term] = []
    unc = ctx.hand_error
    if hand_error and unc is not None and unc.bounds():
        owner = f"{ctx.hand_al}@grasp"
        index = builder.block("hand:grasp", lambda: ParameterBlock.from_uncertainty(owner, unc))
        terms.append(Perturbation(index, inverse=True))
    world_from_hand = ctx.world_pin * grasp.pin_from_hand()
    terms.append(Fixed(world_from_hand.inverse()))
    terms += to_pin
    terms.append(Fixed(_translation(grasp.distance)))
    return ErrorChain(builder.space(), tuple(terms))


def _support(rel: RelationModel, position: np.ndarray, axis: np.ndarray) -> float:
    """Certified max |ℓ_p·Δp + ℓ_a·Δa| of the displacement Δp and axis change Δa [m]."""
    first = bound_linear(rel.displacement.linear @ position + rel.axis.linear @ axis, rel.space)
    slack = float(np.abs(position) @ rel.displacement.remainder)
    slack += float(np.abs(axis) @ rel.axis.remainder)
    return first.magnitude + slack


def centering_bounds(ctx: PlanContext, grasp: Grasp) -> CenteringBounds:
    """Bound where the pin may be between the fingers at the grasp (:class:`CenteringBounds`).

    With q the grasp point's displacement and a = a₀ + Δa the pin axis in the hand frame,
    a₀ = (0, sin γ, cos γ): the axis crosses the fingers' line at distance
    ``|q_y a_z − q_z a_y| / |a_yz| ≤ (|n·q| + |q| sin t) / cos t`` from it, n = (0, cos γ,
    −sin γ), and at ``x = q_x + μ a_x``, |μ a_x| ≤ |q| tan t, t the certified tilt. Each linear
    support is the certified bound of :mod:`synth.errors.estimate` over the relation of
    :func:`grasp_relation`.
    """
    chain = grasp_relation(ctx, grasp)
    if chain.space.dim == 0:
        return CenteringBounds(0.0, 0.0, 0.0, 0.0)
    rel = RelationModel.of(chain)
    tilt = estimate_errors(chain, ctx.hand_al, ctx.pin_al).certified.tilt
    s, c = math.sin(grasp.gamma), math.cos(grasp.gamma)
    zero = np.zeros(3)
    qx = _support(rel, np.array([1.0, 0.0, 0.0]), zero)
    qn = _support(rel, np.array([0.0, c, -s]), zero)
    qa = _support(rel, np.array([0.0, s, c]), zero)
    q_norm = math.sqrt(qx**2 + qn**2 + qa**2)
    closing = qx + q_norm * math.tan(tilt)
    across = (qn + q_norm * math.sin(tilt)) / math.cos(tilt)
    return CenteringBounds(closing, across, qa, tilt, grasp_determination(ctx, grasp))


def grasp_determination(ctx: PlanContext, grasp: Grasp) -> tuple[tuple[str, float, float], ...]:
    """The pin's error in the hand after ``center``, from the start location (GRASP DETERM).

    ``center`` moves the arm along the fingers' closing direction c = rot(ẑ, ω)x̂ (the hand's
    x̂ in the pin frame) until the axis passes between the pads' centres, so the grasp point's
    displacement along c is taken out: the tip is left at ``Δp − c (c·(Δp + d Δa))`` in the pin
    frame, the axis keeps its tilt. Rotation about the pin's own axis is left out (the pin is a
    solid of revolution). Empty when the start is exact: the seed's NILTRANS, "the hand holds
    the pin with essentially no error" (L2244), and the program AFFIXes the pin where it
    believed it.

    Otherwise the program re-derives the pin from the hand after ``center``
    (``PIN ← BMANIP*TRANS(grasp⁻¹)``, :mod:`synth.codegen.views`): the believed grip is then the
    nominal one, and the true grip is where the hand truly closed on the true pin, so the hand's
    own error at the grasp (its ``hand:grasp`` block) stays in the residual along every
    direction but the closing one. Left out, a pin from a rack known to ±0.5 mm under a
    ±0.05 in hand was believed up to 0.18 cm higher than it was: seated pins read as misses
    and the program aborted in 4 of 1 000 trials.
    """
    if grasp_relation(ctx, grasp, hand_error=False).space.dim == 0:
        return ()
    rel = RelationModel.of(grasp_relation(ctx, grasp, hand_error=True))
    hand_from_pin = grasp.pin_from_hand().rotation.T
    closing = np.array([1.0, 0.0, 0.0])  # the fingers' direction, in the hand frame
    out: list[tuple[str, float, float]] = []
    for k, name in enumerate(("x", "y", "z")):
        e = hand_from_pin[:, k]  # the pin frame's axis k in the hand frame
        # Δp_tip = q − d Δa; the residual along e is e·Δp_tip − (e·c)(c·q)
        position = e - float(e @ closing) * closing
        bound = _support(rel, position, -grasp.distance * e)
        if bound > 1e-12:
            out.append((name, -bound, bound))
    # a small turn θ of the pin moves its axis by θ × ẑ = (θ_y, −θ_x, 0) in the pin frame
    zero = np.zeros(3)
    for name, e, sign in (("rx", hand_from_pin[:, 1], -1.0), ("ry", hand_from_pin[:, 0], 1.0)):
        sine = _support(rel, zero, sign * e)
        if sine > 1e-12:
            angle = math.asin(min(1.0, sine))
            out.append((name, -angle, angle))
    return tuple(out)


def centering_opening(
    bounds: CenteringBounds,
    grasp: Grasp,
    pin_shape: PinShape,
    hand: HandSpec,
    d_i: float,
    default_opening: float,
) -> float | str:
    """The approach opening [m] at which ``center`` takes the pin wherever it may be, or why not.

    The geometry of the pads (:class:`CenteringBounds`): the axis must pass between the open
    fingers, ``closing + r_pin ≤ opening / 2``, so the half-gap (opening − diameter)/2 must
    cover ``closing`` — the seed's opening, pin diameter + 1 in (L2139), or wider up to the
    hand's largest opening; it must cross the pads, ``across ≤ r_fp``, since ``center`` only
    moves along the closing direction; it must lie within ``PAD_TILT`` of the pads' plane; the
    grasp point must stay on the full-diameter shaft, ``l_taper ≤ d ± axial ≤ l_pin``; and the
    fingers must stay above the start hole's plane (condition a, L2030) with the pin ``axial``
    lower than believed.
    """
    r_pin = pin_shape.diameter / 2
    r_fp = hand.finger_pad_radius
    if bounds.across > r_fp:
        return (
            f"pin may be {100 * bounds.across:.2f} cm across from the finger pads' centres, the "
            f"pads reach {100 * r_fp:.2f} cm (CENTER registers the hand along the fingers only)"
        )
    if bounds.tilt > PAD_TILT:
        return (
            f"pin axis may lie {math.degrees(bounds.tilt):.1f}° out of the finger pads' plane, "
            f"CENTER takes {math.degrees(PAD_TILT):.0f}°"
        )
    shaft = pin_shape.tip_taper_length
    d = grasp.distance
    if d - bounds.axial < shaft or d + bounds.axial > pin_shape.length:
        return (
            f"the fingers may close {100 * bounds.axial:.2f} cm off the grasp distance "
            f"{100 * d:.2f} cm, off the pin's shaft ({100 * shaft:.2f}–"
            f"{100 * pin_shape.length:.2f} cm from the tip)"
        )
    lo, _ = finger_span(grasp, hand)
    if lo - bounds.axial < d_i - 1e-12:
        return (
            f"with the pin {100 * bounds.axial:.2f} cm off along its axis the fingers reach "
            f"{100 * (d_i - lo + bounds.axial):.2g} cm below the start hole's plane "
            "(seed §4.3.2 condition a)"
        )
    needed = pin_shape.diameter + 2 * bounds.closing
    if needed <= default_opening:
        return default_opening
    widened = pin_shape.diameter + 2 * (bounds.closing + OPENING_MARGIN)
    widened = math.ceil(widened / OPENING_ROUNDING - 1e-9) * OPENING_ROUNDING
    if widened > hand.max_opening:
        return (
            f"pin may be {100 * bounds.closing:.2f} cm from the fingers' centre, the approach "
            f"opening leaves {100 * (default_opening / 2 - r_pin):.2f} cm and the hand's "
            f"largest opening {100 * hand.max_opening:.2f} cm leaves "
            f"{100 * (hand.max_opening / 2 - r_pin):.2f} cm"
        )
    return widened


def finger_span(grasp: Grasp, hand: HandSpec) -> tuple[float, float]:
    """Lowest and highest pin-axis coordinate [m] of the finger plates.

    A hand-frame point p lies at ``s = d + p_y sin γ + p_z cos γ`` along the pin axis (the third
    row of ``rot(ẑ, ω)·rot(x̂, γ)`` is ``(0, sin γ, cos γ)``). The plates span
    ``|p_y| ≤ r_fp`` and ``−L_f ≤ p_z ≤ r_fp`` (:mod:`synth.models.arm.hand`).
    """
    s, c = math.sin(grasp.gamma), math.cos(grasp.gamma)
    across = hand.finger_pad_radius * abs(s)
    along = sorted((-hand.finger_length * c, hand.finger_pad_radius * c))
    return grasp.distance - across + along[0], grasp.distance + across + along[1]


def palm_clearance(grasp: Grasp, pin_shape: PinShape, hand: HandSpec) -> float:
    """Distance [m] between the pin shaft and the palm (negative: they overlap).

    In the hand frame the pin axis is the segment ``(s − d)·(0, sin γ, cos γ)``, ``0 ≤ s ≤
    l_pin``, in the y–z plane through the middle of the palm box ``|y| ≤ p_y/2``,
    ``−L_f − p_z ≤ z ≤ −L_f``; the distance in that plane less the pin radius. For γ = 180° it
    is the seed's check l_pin − d < L_f (L2070), with the pin's radius added.
    """
    u = np.array([math.sin(grasp.gamma), math.cos(grasp.gamma)])
    ends = [(s - grasp.distance) * u for s in (0.0, pin_shape.length)]
    shaft = shapely.LineString([tuple(ends[0]), tuple(ends[1])])
    half_y = hand.palm_size[1] / 2
    palm = shapely.box(
        -half_y, -hand.finger_length - hand.palm_size[2], half_y, -hand.finger_length
    )
    return float(shaft.distance(palm)) - pin_shape.diameter / 2


def geometry_problem(
    grasp: Grasp,
    pin_shape: PinShape,
    hand: HandSpec,
    d_i: float,
    d_f: float,
    target_end: PinEnd,
) -> str | None:
    """Why a grasp would do "something bad with the hand" (L2086–2090), or None.

    (a) fingers not below the start hole's plane (pin-axis coordinate ``d_i``) nor the target
    hole's (``d_f`` for the tip, ``l_pin − d_f`` for the head); (b) approach vector at least
    90° from each hole's outward normal: ``cos γ ≤ 0`` at the start hole (tip in, normal = pin
    ẑ) and at a tip-first target, ``cos γ ≥ 0`` at a head-first target; (c) palm clear of the
    pin (:func:`palm_clearance`).
    """
    lo, hi = finger_span(grasp, hand)
    cos_gamma = math.cos(grasp.gamma)
    if lo < d_i - 1e-12:
        return (
            f"fingers reach {100 * (d_i - lo):.2f} cm below the start hole's plane "
            "(seed §4.3.2 condition a)"
        )
    if target_end == "tip" and lo < d_f - 1e-12:
        return (
            f"fingers reach {100 * (d_f - lo):.2f} cm below the target hole's plane "
            "(seed §4.3.2 condition a)"
        )
    if target_end == "head" and hi > pin_shape.length - d_f + 1e-12:
        return (
            f"fingers reach {100 * (hi - pin_shape.length + d_f):.2f} cm below the target "
            "hole's plane (seed §4.3.2 condition a)"
        )
    if cos_gamma > 1e-9 or (target_end == "head" and cos_gamma < -1e-9):
        return "the approach vector is less than 90° from a hole's outward normal (condition b)"
    clearance = palm_clearance(grasp, pin_shape, hand)
    if clearance < 0:
        return f"the pin pokes {100 * -clearance:.2f} cm into the palm (seed L2070)"
    return None


@dataclass(frozen=True, eq=False)
class Pickup:
    """A pickup strategy with its arm configurations and its own hypothetical world.

    ``q_approach``, ``q_grasp``, ``q_departure`` reach the approach, grasp and departure
    points; ``move_time`` [s] is park → approach → grasp, ``lift_time`` [s] grasp → departure.
    """

    strategy: GraspStrategy
    q_approach: Configuration
    q_grasp: Configuration
    q_departure: Configuration
    move_time: float
    lift_time: float
    world: World
    detour: Detour | None = None
    """The move from the park lifted over the workcell (:mod:`synth.strategies.detour`)."""

    @property
    def name(self) -> str:
        """The grasp's label (``ω=90° γ=135° d=3.54 cm``)."""
        return grasp_label(self.strategy.grasp)


def grasp_label(grasp: Grasp) -> str:
    """Human label of a grasp, in degrees and centimetres."""
    return (
        f"ω={math.degrees(grasp.omega):.0f}° γ={math.degrees(grasp.gamma):.0f}° "
        f"d={100 * grasp.distance:.2f} cm"
    )


def _translation(z: float) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([0.0, 0.0, z]))


def pin_from_approach(grasp: Grasp, distance: float) -> pin.SE3:
    """The grasp's approach point in the pin frame: ``T_pin_hand ∘ trans(0, 0, −a)`` [m].

    The hand backs off ``a`` along its own approach vector (Fig. 4.2): for ω = 90°, γ = 135°,
    d = 3.54 cm and a = 2 in the seed prints ``VECTOR(−3.59, 0, 7.13)`` (L2609).
    """
    return grasp.pin_from_hand() * _translation(-distance)


def generate_pickups(
    ctx: PlanContext, *, try_harder: bool = False
) -> tuple[list[Pickup], list[Rejection]]:
    """Every feasible pickup strategy of seed §4.3 and the reasons the others were dropped."""
    opts = ctx.options
    ins = ctx.insertion
    same_end = ctx.target_end == "tip"
    d_min, d_max = grasp_distance_limits(
        ctx.pin_shape.length,
        ctx.pin_shape.tip_taper_length,
        ctx.d_i,
        ins.d_f,
        ctx.hand.finger_pad_radius,
        opts.kappa,
        same_end=same_end,
    )
    rejected: list[Rejection] = []
    distances = grasp_distances(d_min, d_max, opts)
    if not distances:
        rejected.append(
            Rejection(
                "grasp",
                f"no grasp distance: d_min = {100 * d_min:.2f} cm exceeds d_max = "
                f"{100 * d_max:.2f} cm (seed L2032–2044)",
            )
        )
    approach_opening, grasp_opening = hand_openings(ctx.pin_shape.diameter, opts)
    if approach_opening > ctx.hand.max_opening:
        rejected.append(
            Rejection(
                "grasp",
                f"approach opening {100 * approach_opening:.2f} cm exceeds the hand's "
                f"{100 * ctx.hand.max_opening:.2f} cm (seed L2139)",
            )
        )
        return [], rejected
    pickups: list[Pickup] = []
    rate = grasp_rating(ctx.arm)
    omegas = [k * opts.omega_step for k in range(round(2 * math.pi / opts.omega_step))]
    for gamma in grasp_angles(same_end, opts):
        for d in distances:
            problem = geometry_problem(
                Grasp(0.0, gamma, d), ctx.pin_shape, ctx.hand, ctx.d_i, ins.d_f, ctx.target_end
            )
            if problem is not None:
                label = f"γ={math.degrees(gamma):.0f}° d={100 * d:.2f} cm"
                rejected.append(Rejection(label, problem))
                continue
            rated: list[
                tuple[float, int, Grasp, Configuration, Configuration, CenteringBounds, float]
            ] = []
            for k, omega in enumerate(omegas):
                grasp = Grasp(omega, gamma, d)
                centering = centering_bounds(ctx, grasp)
                opening = centering_opening(
                    centering, grasp, ctx.pin_shape, ctx.hand, ctx.d_i, approach_opening
                )
                if isinstance(opening, str):
                    rejected.append(Rejection(grasp_label(grasp), opening))
                    continue
                found = reached_grasp(ctx, grasp)
                if isinstance(found, Rejection):
                    rejected.append(found)
                    continue
                q_approach, q_grasp = found
                rating = float(
                    rate(ctx.arm, [q_grasp, q_approach, *seat_configuration(ctx, grasp, q_grasp)])
                )
                rated.append((rating, k, grasp, q_approach, q_grasp, centering, opening))
            # Ratings equal to 1e-9 rad are ties (γ = 180°: θ5 does not depend on ω); ties keep
            # the ω order, so float noise cannot decide which ω survive the pruning.
            rated.sort(key=lambda r: (round(r[0], 9), r[1]))
            keep = rated if try_harder else rated[: opts.keep_omegas]
            for cost, _, grasp, *_ in rated[len(keep) :]:
                rejected.append(
                    Rejection(
                        grasp_label(grasp),
                        f"pruned: rating {rate.describe(cost)}, only the best "
                        f"{opts.keep_omegas} ω are kept (seed L2122; --try-harder keeps all)",
                    )
                )
            for cost, _, grasp, q_approach, q_grasp, centering, opening in keep:
                made = _pickup(
                    ctx, grasp, cost, q_approach, q_grasp, opening, grasp_opening, centering
                )
                if isinstance(made, Rejection):
                    rejected.append(made)
                else:
                    pickups.append(made)
    return pickups, rejected


def seat_configuration(
    ctx: PlanContext, grasp: Grasp, q_grasp: Configuration
) -> list[Configuration]:
    """The arm with the pin seated d_f deep in the target hole at φ = 0, if it reaches there.

    For a grasp rating over the whole motion (the approach strategy chooses φ later): [] when
    the arm has no configuration there.
    """
    seat = hand_at(ctx, grasp, _translation(-ctx.insertion.d_f))
    q = ctx.nearest(seat, q_grasp)
    return [] if q is None else [q]


def reached_grasp(
    ctx: PlanContext, grasp: Grasp
) -> tuple[Configuration, Configuration] | Rejection:
    """The configurations the program reaches at the grasp's approach point and at the grasp.

    The pickup is the program's first motion, ``MOVE hand TO grasp VIA approach`` from the park
    (L2723–2724); each target is solved nearest the configuration before it
    (:meth:`PlanContext.nearest`), as the arm will move. The seed rates "the" arm solution at
    the grasp (L2096); with several solutions (wrist flips) the one rated here is the one the
    arm will be in, so the rating, the timing and the swept path agree with the program.
    """
    approach_xf = pin_from_approach(grasp, ctx.options.grasp_approach_distance)
    q_approach = ctx.nearest(ctx.world_pin * approach_xf, ctx.q_park)
    if q_approach is None:
        return Rejection(grasp_label(grasp), "no arm solution at the grasp's approach point")
    q_grasp = ctx.nearest(ctx.world_pin * grasp.pin_from_hand(), q_approach)
    if q_grasp is None:
        return Rejection(grasp_label(grasp), "no arm solution at the grasp point")
    return q_approach, q_grasp


def _pickup(
    ctx: PlanContext,
    grasp: Grasp,
    rating: float,
    q_approach: Configuration,
    q_grasp: Configuration,
    approach_opening: float,
    grasp_opening: float,
    centering: CenteringBounds,
) -> Pickup | Rejection:
    """Departure point, the gross-motion check and the pickup's time (§4.3.3)."""
    opts = ctx.options
    pin_from_hand = grasp.pin_from_hand()
    approach_xf = pin_from_approach(grasp, opts.grasp_approach_distance)
    lift = opts.departure_lift + ctx.d_i
    q_departure = ctx.nearest(ctx.world_pin * _translation(lift) * pin_from_hand, q_grasp)
    if q_departure is None:
        return Rejection(grasp_label(grasp), "no arm solution at the departure point")
    empty_hand = ctx.gross.empty_hand(approach_opening)
    motion = f"move from {ctx.start_words} to the grasp's approach point"
    blocked = ctx.obstructed(empty_hand, [ctx.q_park, q_approach], motion)
    detour: Detour | None = None
    if blocked is not None:
        reason, straight = blocked
        lifted = lift_over(ctx, empty_hand, ctx.q_park, q_approach, straight)
        if isinstance(lifted, str):
            return Rejection(grasp_label(grasp), f"{reason}; lifted: {lifted}")
        detour = lifted
    vias = [] if detour is None else list(detour.configurations)
    move_time = ctx.motion([ctx.q_park, *vias, q_approach, q_grasp])
    lift_time = ctx.motion([q_grasp, q_departure])
    goodness = opts.open_time + move_time + opts.center_time + lift_time
    pin_al, hand_al = ctx.pin_al, ctx.hand_al
    strategy = GraspStrategy(
        object=pin_al,
        grasp=grasp,
        approach_point=Destination("approach", hand_al, pin_al, approach_xf),
        grasp_point=Destination("grasp", hand_al, pin_al, pin_from_hand),
        departure_point=Destination("departure", pin_al, pin_al, _translation(lift)),
        approach_opening=approach_opening,
        grasp_opening=grasp_opening,
        pickup_time=goodness,
        rating=rating,
        joint_solution=tuple(float(x) for x in q_grasp),
        grasp_determination=centering.residual or None,
        remarks=grasp_remarks(grasp),
        centering=centering,
        approach_detour=() if detour is None else detour.destinations(hand_al),
    )
    world = ctx.base_world.child(grasp_label(grasp)).with_facts(
        Holding(hand_al, pin_al),
        Affixed(pin_al, hand_al, grasp),
        GraspDetermination(pin_al, centering.residual),
        At(pin_al, "departure"),
    )
    return Pickup(strategy, q_approach, q_grasp, q_departure, move_time, lift_time, world, detour)
