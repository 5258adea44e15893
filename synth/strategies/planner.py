"""``plan_task``: the pin-in-hole planner of seed chapter IV, §4.2–4.6, end to end.

1. initial computations (§4.2): :func:`~synth.strategies.context.build_context`;
2. pickup strategies (§4.3): :func:`~synth.strategies.grasp.generate_pickups`, each in its own
   child world of the assertion base;
3. basic motions (§4.4): the best φ per pickup, :func:`~synth.strategies.approach.plan_approach`;
4. best-first refinement (§4.5–4.6): :func:`~synth.strategies.select.select_strategy` with
   :func:`~synth.strategies.refine.refine` and the minimum refinement cost.

A pure function of the task and the options, except for ``planning_time`` (wall clock).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from synth.exceptions import NoStrategyError
from synth.models.insertion import at_lead, exceeds_lead
from synth.models.spec import TaskSpec
from synth.strategies.approach import Candidate, plan_approach
from synth.strategies.causes import root_cause
from synth.strategies.context import PlanContext, plan_context
from synth.strategies.grasp import generate_pickups
from synth.strategies.options import PlanOptions
from synth.strategies.records import PinInHoleStrategy, PlanResult, Rejection
from synth.strategies.refine import (
    Refined,
    hole_tilt_problem,
    minimum_refinement_cost,
    refine,
)
from synth.strategies.select import select_strategy

Accept = Callable[[PinInHoleStrategy], Rejection | None]
"""A last check of a chosen strategy (the pipeline's proof): ``None`` accepts it, a
:class:`Rejection` sends the search on to the next best candidate."""


def _at_stage(rejection: Rejection, stage: str) -> Rejection:
    return rejection if rejection.stage else dataclasses.replace(rejection, stage=stage)


AT_THE_LEAD = "at the lead"
"""Suffix of a candidate's name once it is refined at the parts' lead (:func:`_at_the_lead`)."""


def _renamed(made: Refined | Rejection, name: str) -> Refined | Rejection:
    if isinstance(made, Rejection):
        return dataclasses.replace(made, candidate=name)
    return dataclasses.replace(made, strategy=dataclasses.replace(made.strategy, name=name))


def _at_the_lead(ctx: PlanContext, missed: str) -> PlanContext:
    """``ctx`` with Δr_ok and Δθ_ok at the parts' lead (:func:`~synth.models.insertion.at_lead`).

    ``missed`` names the proof a trial of which missed the hole.
    """
    ins = ctx.insertion
    why = (
        f"note: a trial of {missed} missed the hole, refuting the task's Δr_ok = "
        f"{100 * ins.dr_ok:.3g} cm (measured, seed L1963), wider than the parts' geometric lead "
        f"{100 * ins.lead:.3g} cm (chamfer + hole radius − tip radius, all the replay "
        "captures); re-planned at the lead"
    )
    return dataclasses.replace(ctx, insertion=at_lead(ins, why))


def _made_name(made: Refined | Rejection) -> str:
    """The name of what a refinement made: its strategy's, or the rejected candidate's."""
    return made.candidate if isinstance(made, Rejection) else made.strategy.name


def _refined_at_some_phi(
    ctx: PlanContext, candidate: Candidate, passed_over: list[Rejection]
) -> Refined | Rejection:
    """``candidate`` refined, or else its pickup at the next quickest φ whose fine motions clear.

    §4.4 keeps the quickest φ of each pickup (L2160), but a let-go or an insertion swept into a
    neighbour is a property of that φ, found only at refinement: the pickup's next quickest φ
    (:func:`plan_approach` without the φ tried) may clear it. (A wall beside the seat refused
    every pickup once the quintic timing made φ = 315° quicker than φ = 0°, which clears it.)
    The φ passed over go to ``passed_over``, to be shown with the other rejections. The
    candidate's gross time is a lower bound on the others', so best-first order holds.
    """
    made = refine(ctx, candidate)
    tried = {candidate.strategy.phi}
    obstructed: list[Rejection] = []
    last = made
    while isinstance(last, Rejection) and last.kind == "collision":
        obstructed.append(last)
        other = plan_approach(ctx, candidate.pickup, skip=frozenset(tried))
        if isinstance(other, Rejection):
            break
        tried.add(other.strategy.phi)
        last = refine(ctx, other)
        if isinstance(last, Refined):
            passed_over.extend(obstructed)
            return last
    return made  # every φ tried failed: the quickest one's reason stands for the pickup


def plan_task(
    spec: TaskSpec,
    *,
    options: PlanOptions | None = None,
    base_dir: Path | str | None = None,
    accept: Accept | None = None,
    q_start: NDArray[np.float64] | None = None,
) -> PlanResult:
    """Plan a pin-in-hole task; raise :class:`~synth.exceptions.NoStrategyError` if none works.

    ``options.try_harder`` keeps every ω with an arm solution instead of the best three
    (L2122); ``options.exhaustive`` refines every candidate instead of stopping at the
    best-first cutoff (L2463). ``base_dir`` resolves a URDF arm's relative paths (the task
    file's directory).

    ``accept`` is asked about the best refined strategy; when it rejects it, that candidate
    is dropped and best-first selection runs again over the rest (refinements are kept, so a
    candidate is refined at most once). The planner stays a pure function: what ``accept``
    checks (the pipeline emits and proves the program) is not the planner's business. A
    rejection with ``refuted="dr_ok"`` (a trial missed: Δr_ok wider than the capture) sends
    every candidate to be refined once more at the parts' lead; one marked ``proven`` (its
    proof passed all the same) is kept, and chosen if nothing planned at the lead is accepted.
    ``q_start`` is the arm's first configuration (default: at the park frame).
    """
    start = time.perf_counter()
    ctx = plan_context(spec, options, base_dir, q_start)
    hopeless = hole_tilt_problem(ctx)
    if hopeless is not None:
        raise NoStrategyError(spec.name, (hopeless,), root_cause([hopeless]))
    pickups, dropped = generate_pickups(ctx, try_harder=ctx.options.try_harder)
    rejected = [_at_stage(r, "pickup") for r in dropped]
    candidates: list[Candidate] = []
    for pickup in pickups:
        made = plan_approach(ctx, pickup)
        if isinstance(made, Rejection):
            rejected.append(_at_stage(made, "approach"))
        else:
            candidates.append(made)
    refinements: dict[int, Refined | Rejection] = {}
    refining = [ctx]  # the context refinements use: replaced once, by the lead's
    if ctx.options.at_lead and exceeds_lead(ctx.insertion):
        refining[0] = _at_the_lead(ctx, "a replay proof of the sequence")
    lower_bound = minimum_refinement_cost(refining[0], candidates)

    passed_over: list[Rejection] = []  # a pickup's quicker φ whose fine motions are obstructed

    def refine_once(candidate: Candidate) -> Refined | Rejection:
        key = id(candidate)
        if key not in refinements:
            made = _refined_at_some_phi(refining[0], candidate, passed_over)
            if refining[0] is not ctx:  # named apart from its refuted first refinement
                made = _renamed(made, f"{_made_name(made)} {AT_THE_LEAD}")
            refinements[key] = made
        return refinements[key]

    exhaustive = ctx.options.exhaustive
    remaining = list(candidates)
    refused: list[Rejection] = []  # by ``accept``, in the order it refused them
    fallback: Refined | None = None  # proven, but with a miss that refuted Δr_ok
    accept_time = 0.0  # [s] spent in ``accept``: not planning time
    while True:
        selection = select_strategy(
            remaining,
            cost=lambda c: c.cost,
            refine=refine_once,
            refined_cost=lambda r: r.strategy.expected_time,
            minimum_refinement_cost=lower_bound,
            exhaustive=exhaustive,
        )
        best: Refined | None = selection.best
        if best is None or accept is None:
            break
        checked = time.perf_counter()
        verdict = accept(best.strategy)
        accept_time += time.perf_counter() - checked
        if verdict is None:
            break
        replan = verdict.refuted == "dr_ok" and refining[0] is ctx and exceeds_lead(ctx.insertion)
        if verdict.proven and not replan:
            break  # nothing is planned without the refuted belief: the passed proof stands
        if verdict.proven:
            fallback = best
        else:
            refused.append(_at_stage(verdict, "proof"))
        remaining = [c for c in remaining if refinements.get(id(c)) is not best]
        if replan:
            # A trial missed: the proof refuted the task's Δr_ok (measured on the seed's real
            # arm, L1963; the replay captures within the parts' lead). Every candidate is refined
            # once more with its search spaced, and its tilt bounded, by the lead.
            rejected.extend(
                _at_stage(r, "refine") for r in refinements.values() if isinstance(r, Rejection)
            )
            refinements.clear()
            refining[0] = _at_the_lead(ctx, f"the replay proof of {best.strategy.name}")
            lower_bound = minimum_refinement_cost(refining[0], candidates)
            remaining = list(candidates)
    rejected.extend(
        _at_stage(r, "refine") for r in refinements.values() if isinstance(r, Rejection)
    )
    rejected.extend(_at_stage(r, "refine") for r in passed_over)
    rejected.extend(refused)
    if best is None and fallback is not None:
        # Every candidate planned at the lead was refused (their reasons are in ``rejected``):
        # the program proven with a miss is the best synth has, and its proof passed.
        best = fallback
    if best is None:
        raise NoStrategyError(spec.name, tuple(rejected), root_cause(rejected))
    refined = [r for r in refinements.values() if isinstance(r, Refined)]
    refused_names = {r.candidate for r in refused}
    listed: list[PinInHoleStrategy] = [
        r.strategy for r in refined if r.strategy.name not in refused_names
    ]
    listed += [c.strategy for c in selection.unrefined]
    if best is fallback:  # its refinement was dropped with the refuted Δr_ok's
        listed.append(best.strategy)
    listed.sort(key=lambda s: (not s.refined, s.expected_time))
    return PlanResult(
        strategy=best.strategy,
        candidates=tuple(listed),
        rejected=tuple(rejected),
        refined=len(refinements),
        planning_time=time.perf_counter() - start - accept_time,
        counters=ctx.counters.as_dict(),
        mode="exhaustive" if exhaustive else "best-first",
        minimum_refinement_cost=lower_bound,
    )
