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

import time
from pathlib import Path

from synth.exceptions import NoStrategyError
from synth.models.spec import TaskSpec
from synth.strategies.approach import Candidate, plan_approach
from synth.strategies.context import build_context
from synth.strategies.grasp import generate_pickups
from synth.strategies.options import PlanOptions
from synth.strategies.records import PinInHoleStrategy, PlanResult, Rejection
from synth.strategies.refine import Refined, minimum_refinement_cost, refine
from synth.strategies.select import select_strategy


def plan_task(
    spec: TaskSpec,
    *,
    try_harder: bool = False,
    exhaustive: bool = False,
    options: PlanOptions | None = None,
    base_dir: Path | str | None = None,
) -> PlanResult:
    """Plan a pin-in-hole task; raise :class:`~synth.exceptions.NoStrategyError` if none works.

    ``try_harder`` keeps every ω with an arm solution instead of the best three (L2122);
    ``exhaustive`` refines every candidate instead of stopping at the best-first cutoff
    (L2463). ``base_dir`` resolves a URDF arm's relative paths (the task file's directory).
    """
    start = time.perf_counter()
    ctx = build_context(spec, options, base_dir)
    pickups, rejected = generate_pickups(ctx, try_harder=try_harder)
    candidates: list[Candidate] = []
    for pickup in pickups:
        made = plan_approach(ctx, pickup)
        if isinstance(made, Rejection):
            rejected.append(made)
        else:
            candidates.append(made)
    lower_bound = minimum_refinement_cost(ctx, candidates)
    selection = select_strategy(
        candidates,
        cost=lambda c: c.cost,
        refine=lambda c: refine(ctx, c),
        refined_cost=lambda r: r.strategy.goodness,
        minimum_refinement_cost=lower_bound,
        exhaustive=exhaustive,
    )
    rejected.extend(selection.rejected)
    if selection.best is None:
        raise NoStrategyError(spec.name, tuple((r.candidate, r.reason) for r in rejected))
    best: Refined = selection.best
    listed: list[PinInHoleStrategy] = [r.strategy for r in selection.refined]
    listed += [c.strategy for c in selection.unrefined]
    listed.sort(key=lambda s: (not s.refined, s.goodness))
    return PlanResult(
        strategy=best.strategy,
        candidates=tuple(listed),
        rejected=tuple(rejected),
        refined=selection.count,
        planning_time=time.perf_counter() - start,
        counters=ctx.counters.as_dict(),
        mode="exhaustive" if exhaustive else "best-first",
        minimum_refinement_cost=lower_bound,
    )
