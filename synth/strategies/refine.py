"""Accuracy refinement of a candidate (seed §4.5, L2203–2440) and the cutoff's lower bound.

For one basic strategy, in its own world:

1. the pin-hole relation at the approach point and its certified footprint
   (:mod:`synth.strategies.footprint`), widened by the approach's measured path bow;
2. tilt (§4.5.1): ``Δθ > Δθ_ok`` rejects the strategy (L2290);
3. the guarded moves must work whatever Δz: ``Δz < standoff`` (the approach point stays above
   the surface) and ``Δz < dtry − d_f`` (a full insertion stops on force, not on arrival) —
   the "principal constraint" on dtry and standoff of L2186;
4. along the axis (§4.5.2): ``Δz > τ·(d_f − d_s)/(1 + τ)`` asks for a tap (the seed's
   τ·(d_f − d_s), L2289, corrected in :func:`axial_limit`)
   (:mod:`synth.strategies.tapping`); no tapping place, or a corrected Δz still too large,
   rejects;
5. in the plane (§4.5.3): ``Δr = max(Δx, Δy) > Δr_ok`` asks for a search
   (:mod:`synth.strategies.search`);
6. the fine motions (insertion, search points, tap, let-go, get-clear) must be clear of the
   workcell (:mod:`synth.strategies.fine`);
7. ``fine_time`` = tap time + search time; the success test's threshold is ``Δz/τ`` with the
   tap-corrected Δz (the programs of §4.8 test ``|DISTANCE_OFF| > .169`` = .127/.75, L2738,
   and ``> .239`` ≈ .180/.75, L2836), and at least Δz plus the arm's reading resolution
   (:func:`success_threshold`).

:func:`minimum_refinement_cost` is the lower bound on fine-motion time of L2459/L2476.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

from synth.al.interpreter import MAX_TIME
from synth.errors.estimate import RelationModel
from synth.models.world import World
from synth.strategies.approach import Candidate
from synth.strategies.beside import (
    false_seat_problem,
    first_attempt_may_go_beside,
    may_go_beside,
    support_landing_problem,
)
from synth.strategies.context import PlanContext
from synth.strategies.fine import fine_motion_obstruction
from synth.strategies.footprint import estimate_footprint, footprint_tables
from synth.strategies.hypotheses import Accuracy, Tapped
from synth.strategies.landing import landing
from synth.strategies.records import ErrorFootprint, PinInHoleStrategy, Rejection
from synth.strategies.relations import approach_relation, hole_only_relation
from synth.strategies.search import (
    plan_search,
    points_within_box,
    search_size_problem,
    search_time_problem,
)
from synth.strategies.tapping import plan_tap
from synth.strategies.wrong_hole import wrong_hole_problem
from synth.units import DEG


@dataclass(frozen=True, eq=False)
class Refined:
    """A refined strategy and the world it was planned in."""

    strategy: PinInHoleStrategy
    world: World
    candidate: Candidate


def _cm(x: float) -> str:
    return f"{100 * x:.3f} cm"


def _deg(x: float) -> str:
    return f"{x / DEG:.3f}°"


def success_threshold(dz: float, tau: float, floor: float) -> float:
    """The success test's threshold t [m] for a depth error ``dz``: max(Δz/τ, Δz + floor).

    The seed's programs test ``|DISTANCE_OFF| > Δz/τ`` (L2738: .169 = .127/.75; L2836: .239 ≈
    .180/.75). A seated pin reads within Δz of 0, so t must exceed Δz by at least the arm's
    reading resolution, ``floor`` (:attr:`~synth.strategies.options.PlanOptions.reading_floor`);
    Δz/τ does for Δz ≥ floor·τ/(1 − τ) (0.076 cm at τ = 0.75), the floor below that. The seed's
    figures are above it: their thresholds are Δz/τ.
    """
    return max(dz / tau, dz + floor)


def axial_limit(tau: float, d_f: float, d_s: float, floor: float = 0.0) -> float:
    """Largest Δz [m] the success test can live with: τ·(d_f − d_s)/(1 + τ), or less by ``floor``.

    That is min(τ·(d_f − d_s)/(1 + τ), (d_f − d_s − floor)/2).

    The programs test ``|DISTANCE_OFF| > t`` against the seated position (L2738), t =
    :func:`success_threshold`. A seated pin reads at most Δz; a pin that missed stops on the
    same surface, shifted by the same height error, and reads at least (d_f − d_s) − Δz. The
    two are told apart only when t < (d_f − d_s) − Δz: with t = Δz/τ, Δz < τ·(d_f − d_s)/(1 +
    τ); with t = Δz + floor, Δz < (d_f − d_s − floor)/2 (binding only for d_f − d_s below
    floor·(1 + τ)/(1 − τ), 0.18 cm at the defaults). The seed's rule (L2289, |Δz| ≤ τ·(d_f −
    d_s)) leaves out the miss's own shift: on the generality task tap_and_search (Δz 0.727 cm,
    d_f − d_s 1.2 cm, within the seed's 0.90 cm) 19 % of trials read a pin resting on the plate
    as seated. The seed's own figures pass either rule (seed_4_8: Δz 0.18 cm against 0.73 cm).
    """
    span = d_f - d_s
    return min(tau * span / (1.0 + tau), (span - floor) / 2.0)


def hole_tilt_problem(ctx: PlanContext) -> Rejection | None:
    """Refuse a task whose hole alone may tilt more than Δθ_ok (seed §4.5.1, L2290).

    The pin's tilt at the hole composes the hand's tilt with the hole's own, and a
    candidate's §4.5.1 test compares the certified bound of that composition, which is at
    least the certified tilt of ``world⁻¹ ∘ hole`` (the same relation with every hand error
    at zero, a point of the candidate's larger error box). No grasp, tap or search reduces a
    part's rotation error, so when that tilt exceeds Δθ_ok every candidate would fail; saying
    so before any motion is swept names the real cause (a leaning part's margins would
    otherwise block every transport first), and quotes the figure ``synth errors`` prints.
    """
    tilt = ctx.hole_errors.certified.tilt
    if tilt <= ctx.insertion.dtheta_ok:
        return None
    return Rejection(
        "task",
        f"tilt: the hole {ctx.hole_al} itself may tilt {_deg(tilt)} off its nominal axis (its "
        f"part's rotation error), more than Δθ_ok = {_deg(ctx.insertion.dtheta_ok)}; no grasp, "
        "tap or search corrects it (seed §4.5.1)",
        cause="tilt",
        stage="refine",
    )


def refine(ctx: PlanContext, cand: Candidate) -> Refined | Rejection:
    """Apply §4.5 to one candidate: a refined strategy or the reason it fails."""
    opts, ins = ctx.options, ctx.insertion
    phi = cand.strategy.phi
    standoff = cand.strategy.standoff
    fp, _ = estimate_footprint(ctx, approach_relation(ctx, cand.world, phi), bow=cand.strategy.bow)
    decisions: list[str] = []
    if fp.dtheta > ins.dtheta_ok:
        return Rejection(
            cand.name,
            f"tilt Δθ = {_deg(fp.dtheta)} exceeds Δθ_ok = {_deg(ins.dtheta_ok)} "
            "(seed §4.5.1: grounds for rejection)",
        )
    decisions.append(f"tilt Δθ = {_deg(fp.dtheta)} ≤ Δθ_ok = {_deg(ins.dtheta_ok)}")
    decisions.extend(ins.notes)  # a given Δθ_ok clipped to the wedging limit
    for detour, motion in (
        (cand.pickup.detour, f"the move from {ctx.start_words} to the grasp"),
        (cand.transport_detour, f"the transport to {ctx.hole_al}"),
    ):
        if detour is not None:
            decisions.append(
                f"{motion} is lifted {detour.describe()}: a straight joint-interpolated "
                "move would sweep into it"
            )
    if fp.dz >= standoff:
        return Rejection(
            cand.name,
            f"Δz = {_cm(fp.dz)} ≥ standoff {_cm(standoff)}: the approach point could lie "
            "in the object (seed L2186)",
        )
    if fp.dz >= cand.strategy.dtry - ins.d_f:
        return Rejection(
            cand.name,
            f"Δz = {_cm(fp.dz)} ≥ dtry − d_f = {_cm(cand.strategy.dtry - ins.d_f)}: the "
            "guarded move could arrive without a force (seed L2186)",
        )
    z_limit = axial_limit(opts.tau, ins.d_f, ins.d_s, opts.reading_floor)
    if z_limit < opts.tau * (ins.d_f - ins.d_s) / (1.0 + opts.tau):
        z_words = f"(d_f − d_s − {_cm(opts.reading_floor)} arm reading)/2 = {_cm(z_limit)}"
    else:
        z_words = f"τ·(d_f − d_s)/(1 + τ) = {_cm(z_limit)}"
    world = cand.world.with_facts(
        Accuracy(ctx.pin_al, ctx.hole_al, fp.dx, fp.dy, fp.dz, fp.zeta, fp.dtheta)
    )
    made, beside = _fine_motions(ctx, cand, fp, world, decisions, (z_limit, z_words), None)
    if not beside:
        return made
    # a miss beside the face, or a pin in another hole, would pass the success test: a tap
    # narrows Δz, and the test with it
    assert isinstance(made, Rejection)
    where = (
        f"a pin gone down beside {ctx.hole_al}'s face"
        if made.cause == "depth"
        else f"a pin in another hole than {ctx.hole_al}"
    )
    why = f"without one, Δz = {_cm(fp.dz)} lets {where} pass the success test"
    tapped, _ = _fine_motions(ctx, cand, fp, world, decisions, (z_limit, z_words), why)
    if isinstance(tapped, Refined):
        return tapped
    return dataclasses.replace(made, reason=f"{made.reason}; with a tap: {tapped.reason}")


def _fine_motions(
    ctx: PlanContext,
    cand: Candidate,
    fp: ErrorFootprint,
    world: World,
    decisions: list[str],
    axial: tuple[float, str],
    tap_reason: str | None,
) -> tuple[Refined | Rejection, bool]:
    """The tap and search of §4.5.2–4.5.3, and the checks of the fine motions they make.

    A tap when Δz exceeds the ``axial`` limit (:func:`axial_limit`, and its formula in words),
    or when ``tap_reason`` asks for one. Returns the refined strategy or the rejection, and
    whether the rejection is one a tap may lift, in a strategy without one: a false seat beside
    the face (:mod:`~synth.strategies.beside`) or in another hole
    (:mod:`~synth.strategies.wrong_hole`).
    """
    opts, ins = ctx.options, ctx.insertion
    z_limit, z_words = axial
    decisions = list(decisions)
    tap = None
    dz = fp.dz
    if fp.dz > z_limit or tap_reason is not None:
        made = plan_tap(ctx, cand, fp)
        if isinstance(made, Rejection):
            return made, False
        if made.dz_after >= fp.dz:
            # the tap's reading carries the hand's error at the tap as well as at the hole: a
            # face whose height is known better than the hand places it gains nothing
            return Rejection(
                cand.name,
                f"a tap would not narrow Δz: {_cm(made.dz_after)} after it against {_cm(fp.dz)} "
                "without (the hand's own error at the tap)",
            ), False
        tap = made
        dz = tap.dz_after
        if dz > z_limit:
            rejection = Rejection(
                cand.name,
                f"even after tapping, Δz = {_cm(dz)} exceeds {z_words}",
            )
            return rejection, False
        because = f"Δz = {_cm(fp.dz)} exceeds {z_words}" if tap_reason is None else tap_reason
        decisions.append(
            f"tap: {because}; tapping place "
            f"({100 * tap.offset[0]:.2f}, {100 * tap.offset[1]:.2f}) cm from {ctx.hole_al} on "
            f"{tap.surface}, {_cm(tap.clearance)} clear of holes and edges; Δz after the tap "
            f"{_cm(dz)} (LP), extra time {tap.time:.2f} s"
        )
        world = world.with_facts(Tapped(tap.surface, tap.offset))
    else:
        decisions.append(
            f"no tap: Δz = {_cm(fp.dz)} ≤ {z_words}, small enough to tell an insertion from a miss"
        )
    search = None
    if fp.dr > ins.dr_ok:
        step = opts.search_step_fraction * ins.dr_ok
        too_large = search_size_problem(fp.dx, fp.dy, ins.dr_ok, step)  # before enumerating
        if too_large is not None:
            return Rejection(cand.name, too_large), False
        search = plan_search(fp.dx, fp.dy, fp.zeta, ins.dr_ok, cand.try_time, opts)
        other_time = cand.strategy.gross_time + (0.0 if tap is None else tap.time)
        too_long = search_time_problem(search, cand.try_time, other_time, MAX_TIME)
        if too_long is not None:
            return Rejection(cand.name, too_long), False
        decisions.append(
            f"search: error footprint ±{_cm(fp.dx)} × ±{_cm(fp.dy)} (ζ = {_deg(fp.zeta)}) "
            f"exceeds Δr_ok = {_cm(ins.dr_ok)}; {search.rings} rings of {_cm(search.step)}, "
            f"{search.expected_points} points within Δx/2, Δy/2 expected at "
            f"{cand.try_time:.2f} s each = {search.time:.2f} s"
        )
        if ins.dr_ok > ins.lead + 1e-9:
            decisions.append(
                f"note: the task's Δr_ok = {_cm(ins.dr_ok)} (measured, seed L1963) exceeds the "
                f"parts' geometric lead {_cm(ins.lead)} (chamfer + hole radius − tip radius); "
                "the search spacing follows Δr_ok, the replay captures within the lead"
            )
    else:
        decisions.append(
            f"no search: error footprint ±{_cm(fp.dx)} × ±{_cm(fp.dy)} is within Δr_ok = "
            f"{_cm(ins.dr_ok)}"
        )
    fine_time = (0.0 if tap is None else tap.time) + (0.0 if search is None else search.time)
    strategy = dataclasses.replace(
        cand.strategy,
        errors=fp,
        tap=tap,
        search=search,
        fine_time=fine_time,
        dr_ok=ins.dr_ok,  # the lead's, when refined at the lead
        dtheta_ok=ins.dtheta_ok,  # the wedging limit's, when tighter than the task's
        success_threshold=success_threshold(dz, opts.tau, opts.reading_floor),
        decisions=tuple(decisions),
    )
    where = landing(ctx, strategy)
    beside = where is None or may_go_beside(ctx, where)
    obstructed = fine_motion_obstruction(ctx, cand, strategy, beside)
    if obstructed is not None:
        return Rejection(cand.name, obstructed), False
    if where is not None:
        false_seat = false_seat_problem(ctx, where)
        if false_seat is not None:
            return Rejection(cand.name, false_seat, cause="depth"), tap is None
        landed = support_landing_problem(ctx, where)
        if landed is not None:
            return Rejection(cand.name, landed, cause="footprint"), tap is None
        wrong_hole = wrong_hole_problem(ctx, where)
        if wrong_hole is not None:
            return Rejection(cand.name, wrong_hole, cause="footprint"), tap is None
        if (
            search is not None
            and search.off_surface == "retract"
            and first_attempt_may_go_beside(ctx, where)
        ):
            strategy = dataclasses.replace(
                strategy,
                search=dataclasses.replace(search, first_off_surface="retract"),
                decisions=(
                    *strategy.decisions,
                    f"the first attempt may come down beside {ctx.hole_al}'s face (the "
                    "footprint reaches past its edge): felt nothing, it backs out and searches",
                ),
            )
    return Refined(strategy, world, cand), False


def minimum_refinement_cost(ctx: PlanContext, candidates: Sequence[Candidate]) -> float:
    """A lower bound [s] on every candidate's fine-motion time (L2459, L2476).

    "Assuming that there is no error in the arm or grasp, so that all error between pin and
    hole comes from errors in the hole location": the first-order footprint ξ_k^h of
    :func:`~synth.strategies.relations.hole_only_relation`. Every candidate's relation adds
    hand (and grasp) blocks to the same box terms, so its support in each direction is at least
    ξ_k^h (a Minkowski sum of sets holding 0), and its certified values are larger still. Hence
    if ``max_k ξ_k^h > Δr_ok`` every candidate searches, with ``Δx = max_k ξ_k ≥ max_k ξ_k^h``
    and ``Δy = ξ_(k+3) ≥ min_k ξ_k^h``; the count of pattern points with ``|x| ≤ Δx/2``,
    ``|y| ≤ Δy/2`` (the pattern is fixed in the footprint frame) is monotone in both, so it is at
    least the count for ``(max ξ^h/2, min ξ^h/2)``, each point costing at least the smallest
    retry time. Tapping gets no bound (0 s): its time depends on a place only refinement finds.
    """
    if not candidates:
        return 0.0
    first, _ = footprint_tables(ctx, RelationModel.of(hole_only_relation(ctx)))
    if float(first.max()) <= ctx.insertion.dr_ok:
        return 0.0
    step = ctx.options.search_step_fraction * ctx.insertion.dr_ok
    count = points_within_box(step, float(first.max()) / 2, float(first.min()) / 2)
    return count * min(c.try_time for c in candidates)
