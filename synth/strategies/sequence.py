"""Assembly sequences: several insertions planned together (seed IV ch. 5, L2870–2890).

"In selecting a grasping method for the first pin, we should remember that our choice will also
affect how much time will be required to pick up the second pin … Inserting the first pin gives
us information about the box location." A sequence is planned step by step, each step by the
single-insertion planner (:func:`synth.strategies.planner.plan_task`) in the world the steps
before it leave:

* the arm starts where the last step ended (the first step: at the park), so a step's pickup
  time depends on the choices before it;
* the pins already inserted stand in their holes (solids of the gross-motion check);
* with ``reuse``, every part a seat located carries its reduced block
  (:func:`synth.errors.seat.after_seat`), so the next footprint, tap and search are planned from
  what the program will know then (the program corrects the part's frame after the seat).
  The correction is a reading at the seat, and a hole far from it on the other side of the
  part's origin can be known worse after it (the turn's error over the longer lever): when the
  next hole may cost more to find after the correction than before (:func:`correction_may_hurt`:
  a larger x-y box, a wider Δz or tilt), the next step is planned both ways and the correction
  kept only if that step is then no slower (``declined`` on the step that seated the pin).

Order (``insertions.order``): ``fixed`` runs the listed order; ``free`` searches every order
best-first. A node is a prefix of steps with its cost g = Σ expected step times (each step's
``expected_time``: pickup + transport + fine motion); the frontier is expanded cheapest first
and the first complete sequence taken. The heuristic is h = 0, which is admissible (no step takes
negative time), so the first complete sequence popped has the least expected total time of all
orders, given each step's best-first plan (a step's time is not bounded below usefully without
planning it: it depends on where the arm comes from and on what the earlier seats taught).

A step's best plan may leave every next step without one (the arm ends where no pickup of the
next pin is clear, say). A prefix whose every next step is refused is then tried again with its
last step's strategy given up, up to :data:`STEP_ALTERNATIVES` times: the next-best plan of
that step, from the same start, joins the frontier as a sibling.

Where a step ends is not the planner's to guess: ``check`` (the pipeline's nominal replay of the
step's program from its start) accepts a step's strategy and returns the arm's final
configuration, the next step's start. The planner emits nothing.
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from synth.errors.chain import chain_between
from synth.errors.estimate import ErrorBounds, estimate_errors
from synth.errors.seat import SeatKnowledge, after_seat, seated
from synth.exceptions import NoStrategyError
from synth.models.graph import AttributeGraph
from synth.models.spec import WORLD, InsertionSpec, TaskSpec
from synth.strategies.causes import root_cause
from synth.strategies.options import PlanOptions
from synth.strategies.planner import plan_task
from synth.strategies.records import PinInHoleStrategy, PlanResult, Rejection

__all__ = ["STEP_ALTERNATIVES", "SequencePlan", "StepCheck", "StepPlan", "plan_sequence"]

STEP_ALTERNATIVES = 2
"""Strategies a step gives up, one at a time, when each left every next step without a plan."""

StepCheck = Callable[
    [int, TaskSpec, NDArray[np.float64] | None, PinInHoleStrategy],
    tuple[Rejection | None, NDArray[np.float64] | None],
]
"""``check(step, step_task, q_start, strategy)`` → (None, q_end) to accept a strategy for
step ``step`` (its index in ``insertions``), or (a rejection, None): the pipeline emits the
step's program and replays it nominally."""


@dataclass(frozen=True, eq=False)
class StepPlan:
    """One planned step: its insertion, the task it was planned in, and what its seat teaches.

    ``alone`` is the same step planned without the earlier steps' knowledge (same start, same
    pins standing), for the report of what reuse saved: its plan, or the first line of its
    refusal; None when not compared. ``declined`` is the knowledge of this step's seat whose
    correction the program leaves out, since the next step planned ``declined_saving`` [s]
    faster without it (``knowledge`` is then None).
    """

    index: int
    insertion: InsertionSpec
    task: TaskSpec
    plan: PlanResult
    knowledge: SeatKnowledge | None
    q_start: NDArray[np.float64] | None
    q_end: NDArray[np.float64]
    alone: PlanResult | str | None = None
    declined: SeatKnowledge | None = None
    declined_saving: float = 0.0

    @property
    def strategy(self) -> PinInHoleStrategy:
        """The step's chosen strategy."""
        return self.plan.strategy

    @property
    def time(self) -> float:
        """Expected time of the step [s]."""
        return self.plan.strategy.expected_time

    @property
    def saved(self) -> float | None:
        """Expected time reuse saved on this step [s] (None: not compared, or refused alone)."""
        if not isinstance(self.alone, PlanResult):
            return None
        return self.alone.strategy.expected_time - self.time


@dataclass(frozen=True, eq=False)
class SequencePlan:
    """The chosen sequence: steps in execution order, and how the order search went."""

    task: TaskSpec
    steps: tuple[StepPlan, ...]
    order: str
    expanded: int
    planned: int
    reuse: bool
    rejected: tuple[Rejection, ...] = ()

    @property
    def expected_time(self) -> float:
        """Σ step times [s]."""
        return sum(s.time for s in self.steps)

    @property
    def planning_time(self) -> float:
        """Σ of the step plans' planning times [s] (the chosen steps')."""
        return sum(s.plan.planning_time for s in self.steps)


@dataclass(order=True)
class _Node:
    cost: float
    tie: int
    done: tuple[int, ...] = field(compare=False)
    steps: tuple[StepPlan, ...] = field(compare=False)
    believed: TaskSpec = field(compare=False)
    q: NDArray[np.float64] | None = field(compare=False)
    parent: _Node | None = field(default=None, compare=False)
    banned: frozenset[str] = field(default=frozenset(), compare=False)
    """Strategies its last step gave up (each left every next step without a plan)."""
    plain: TaskSpec | None = field(default=None, compare=False)
    """``believed`` without the last step's correction (None: it made none)."""


def plan_sequence(
    spec: TaskSpec,
    check: StepCheck,
    *,
    options: PlanOptions | None = None,
    base_dir: Path | str | None = None,
    reuse: bool = True,
    compare: bool = True,
) -> SequencePlan:
    """Plan every insertion of ``spec`` (module docstring); NoStrategyError when none works.

    ``compare`` also plans each chosen step without the earlier seats' knowledge (``alone``).
    """
    steps = spec.steps
    order = spec.insertions.order if spec.insertions is not None else "fixed"
    counter = itertools.count()
    frontier = [_Node(0.0, next(counter), (), (), spec, None)]
    rejected: list[Rejection] = []
    expanded = 0
    plans = _Plans()
    while frontier:
        node = heapq.heappop(frontier)
        if len(node.done) == len(steps):
            chosen = node.steps
            if compare and reuse:
                chosen = tuple(_compared(s, spec, node, options, base_dir) for s in chosen)
            return SequencePlan(spec, chosen, order, expanded, plans.made, reuse, tuple(rejected))
        expanded += 1
        remaining = [i for i in range(len(steps)) if i not in node.done]
        grown = False
        for i in remaining if order == "free" else remaining[:1]:
            child = _grown(node, i, steps[i], check, options, base_dir, reuse, next(counter), plans)
            if isinstance(child, Rejection):
                rejected.append(child)
            else:
                heapq.heappush(frontier, child)
                grown = True
        parent = node.parent
        if grown or parent is None or len(node.banned) >= STEP_ALTERNATIVES:
            continue
        last = node.steps[-1]
        banned = node.banned | {last.strategy.name}
        sibling = _grown(
            parent,
            last.index,
            last.insertion,
            check,
            options,
            base_dir,
            reuse,
            next(counter),
            plans,
            banned,
        )
        if isinstance(sibling, Rejection):
            rejected.append(sibling)
        else:
            heapq.heappush(frontier, sibling)
    # a step refused alike from two nodes (its sibling, another order) is said once
    distinct: dict[tuple[str, str, str], Rejection] = {}
    for r in rejected:
        distinct.setdefault((r.candidate, r.reason, r.kind), r)
    kept = list(distinct.values())
    raise NoStrategyError(spec.name, tuple(kept), root_cause(kept))


@dataclass
class _Plans:
    made: int = 0
    """Step plans made (a step planned with and without the last correction counts two)."""


@dataclass(frozen=True, eq=False)
class _Made:
    plan: PlanResult
    q_end: NDArray[np.float64]

    @property
    def strategy(self) -> PinInHoleStrategy:
        return self.plan.strategy

    @property
    def time(self) -> float:
        return self.plan.strategy.expected_time


def _grown(
    node: _Node,
    index: int,
    insertion: InsertionSpec,
    check: StepCheck,
    options: PlanOptions | None,
    base_dir: Path | str | None,
    reuse: bool,
    tie: int,
    plans: _Plans,
    banned: frozenset[str] = frozenset(),
) -> _Node | Rejection:
    """``node`` with step ``index`` planned next (its ``banned`` strategies refused).

    When the last step's correction may leave this step's hole known worse
    (:func:`correction_may_hurt`), the step is planned without it too, and the faster plan
    taken (the corrected one on a tie): without, the last step is marked ``declined``.
    """
    base, earlier = node.believed, node.steps
    task = base.step(insertion)
    made = _plan_step(task, insertion, index, node.q, check, options, base_dir, banned)
    plans.made += 1
    if node.plain is not None and correction_may_hurt(base, node.plain, insertion):
        plans.made += 1
        plain_task = node.plain.step(insertion)
        other = _plan_step(plain_task, insertion, index, node.q, check, options, base_dir, banned)
        if isinstance(other, _Made) and (isinstance(made, Rejection) or other.time < made.time):
            last = earlier[-1]
            saving = math.inf if isinstance(made, Rejection) else made.time - other.time
            declined = replace(
                last, knowledge=None, declined=last.knowledge, declined_saving=saving
            )
            base, earlier, task, made = node.plain, (*earlier[:-1], declined), plain_task, other
    if isinstance(made, Rejection):
        return made
    pickup = made.strategy.pickup
    knowledge = (
        after_seat(task, insertion, pickup.grasp.distance, pickup.grasp_determination or ())
        if reuse
        else None
    )
    plain = seated(base, insertion)
    step = StepPlan(index, insertion, task, made.plan, knowledge, node.q, made.q_end)
    return _Node(
        node.cost + step.time,
        tie,
        (*node.done, index),
        (*earlier, step),
        plain if knowledge is None else knowledge.spec,
        made.q_end,
        node,
        banned,
        None if knowledge is None else plain,
    )


def correction_may_hurt(corrected: TaskSpec, plain: TaskSpec, insertion: InsertionSpec) -> bool:
    """Whether the hole may cost more to find corrected (world to hole, certified bounds).

    What a step's fine motion costs grows with the hole's footprint (the search's points) and
    with its height error and tilt (the tap, the approach): the corrected hole may cost more
    when its x-y box is larger in area, or its Δz or tilt wider. A correction that trades a
    wider y for a narrower x (the seed's box, the other hole 7.7 cm from the seat) is kept
    without planning the step twice. On a free-order sequence of three pins from one rack
    (a UR10's), where no correction hurt, comparing every axis planned 41 steps (50 s); this
    rule plans 27 (35 s), against 22 (30 s) without the comparison.
    """
    a, b = (_hole_bounds(spec, insertion) for spec in (corrected, plain))

    def width(bounds: ErrorBounds, name: str) -> float:
        interval = getattr(bounds, name)
        return float(interval.hi - interval.lo)

    def area(bounds: ErrorBounds) -> float:
        return width(bounds, "dx") * width(bounds, "dy")

    wider = 1.0 + 1e-9
    return (
        area(a) > area(b) * wider
        or width(a, "dz") > width(b, "dz") * wider
        or a.tilt > b.tilt * wider
    )


def _hole_bounds(spec: TaskSpec, insertion: InsertionSpec) -> ErrorBounds:
    graph = AttributeGraph(spec)
    hole = graph.resolve(insertion.hole)
    return estimate_errors(chain_between(graph, WORLD, hole)).certified


def _plan_step(
    task: TaskSpec,
    insertion: InsertionSpec,
    index: int,
    q_start: NDArray[np.float64] | None,
    check: StepCheck,
    options: PlanOptions | None,
    base_dir: Path | str | None,
    banned: frozenset[str] = frozenset(),
) -> _Made | Rejection:
    ends: dict[str, NDArray[np.float64]] = {}

    def accept(strategy: PinInHoleStrategy) -> Rejection | None:
        if strategy.name in banned:
            # a search limit, like the seed's ω pruning: never the root cause of a refusal
            reason = "pruned: it left every next step of the sequence without a plan"
            return Rejection(strategy.name, reason, cause="pruned")
        rejection, q_end = check(index, task, q_start, strategy)
        if rejection is None and q_end is not None:
            ends[strategy.name] = q_end
        return rejection

    label = f"step {index + 1} ({insertion.pin} into {insertion.hole})"
    try:
        plan = plan_task(task, options=options, base_dir=base_dir, accept=accept, q_start=q_start)
    except NoStrategyError as exc:
        first = str(exc).splitlines()[0]
        return Rejection(label, first, cause=exc.root.cause if exc.root else None)
    return _Made(plan, ends[plan.strategy.name])


def _compared(
    step: StepPlan,
    spec: TaskSpec,
    node: _Node,
    options: PlanOptions | None,
    base_dir: Path | str | None,
) -> StepPlan:
    """``step`` with ``alone``: planned from the same start with the task's own blocks.

    Only where an earlier seat taught something (its correction is in the program): else the
    two plans differ only by what the comparison leaves out (the nominal replay's check), and
    the difference was printed as a saving, negative ones included.
    """
    before = list(itertools.takewhile(lambda e: e.index != step.index, node.steps))
    if not any(e.knowledge is not None and e.knowledge.corrected for e in before):
        return step  # nothing earlier seats taught (the first step too): nothing to compare
    plain = spec
    for earlier in before:
        plain = seated(plain, earlier.insertion)
    alone: PlanResult | str
    try:
        alone = plan_task(
            plain.step(step.insertion), options=options, base_dir=base_dir, q_start=step.q_start
        )
    except NoStrategyError as exc:
        alone = str(exc).splitlines()[0]
    return replace(step, alone=alone)
