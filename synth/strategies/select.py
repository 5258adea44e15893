"""Best-first selection of a strategy (seed §4.6, L2445–2476).

"All candidate strategies are sorted according to gross motion time, and then considered in
'best first' order. If we reach a point where the next best unrefined strategy is more
expensive than a fully planned strategy, then we can stop searching" (L2447)::

    for each s in strategies (cheapest first):
        if cost(s) + minimum_refinement_cost ≥ shortest_time: done
        refine s; if cost(s) < shortest_time: best ← s

A pure function over callables: heap entries ``(priority, counter, candidate)`` with the
counter breaking ties deterministically (input order); the best refined strategy is the least
``(refined cost, counter)``. ``exhaustive=True`` refines every candidate and picks by the same
key, so when ``minimum_refinement_cost`` is a true lower bound (refinement adds at least that
much time) both modes choose the same strategy.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Generic, TypeVar

from synth.strategies.records import Rejection

C = TypeVar("C")
R = TypeVar("R")


@dataclass(frozen=True, eq=False)
class Selection(Generic[C, R]):
    """Outcome of selection.

    ``best`` is the chosen refined strategy (None when every refined candidate was rejected);
    ``refined`` the refined strategies in refinement order; ``rejected`` the candidates refinement
    rejected; ``unrefined`` the candidates the cutoff skipped; ``order`` the refinement order
    of all candidates that were refined (as input indices).
    """

    best: R | None
    refined: tuple[R, ...]
    rejected: tuple[Rejection, ...]
    unrefined: tuple[C, ...]
    order: tuple[int, ...]

    @property
    def count(self) -> int:
        """Number of candidates refined."""
        return len(self.order)


def select_strategy(
    candidates: Sequence[C],
    cost: Callable[[C], float],
    refine: Callable[[C], R | Rejection],
    refined_cost: Callable[[R], float],
    minimum_refinement_cost: float,
    *,
    exhaustive: bool = False,
) -> Selection[C, R]:
    """Refine candidates cheapest first until the cutoff; return the cheapest refined one.

    ``cost`` [s] is a candidate's gross motion time, ``refined_cost`` [s] a refined strategy's
    total; ``minimum_refinement_cost`` [s] a lower bound on what refinement adds.
    """
    heap = [(cost(c), i, c) for i, c in enumerate(candidates)]
    heapq.heapify(heap)
    best: tuple[float, int, R] | None = None
    refined: list[R] = []
    rejected: list[Rejection] = []
    order: list[int] = []
    while heap:
        priority, counter, candidate = heap[0]
        # Everything left costs at least priority + bound once refined; ties go to the counter.
        if (
            not exhaustive
            and best is not None
            and (priority + minimum_refinement_cost, counter) >= (best[0], best[1])
        ):
            break
        heapq.heappop(heap)
        order.append(counter)
        result = refine(candidate)
        if isinstance(result, Rejection):
            rejected.append(result)
            continue
        refined.append(result)
        key = (refined_cost(result), counter)
        if best is None or key < best[:2]:
            best = (key[0], counter, result)
    unrefined = tuple(c for _, _, c in sorted(heap, key=lambda e: (e[0], e[1])))
    return Selection(
        best=None if best is None else best[2],
        refined=tuple(refined),
        rejected=tuple(rejected),
        unrefined=unrefined,
        order=tuple(order),
    )
