"""Best-first selection (seed §4.6, L2445–2476) as a pure function, on synthetic candidates."""

from __future__ import annotations

from dataclasses import dataclass

from hypothesis import given, settings
from hypothesis import strategies as st

from synth.strategies.records import Rejection
from synth.strategies.select import select_strategy


@dataclass(frozen=True)
class Cand:
    name: str
    gross: float
    fine: float | None  # None: refinement rejects it


def run(cands, lower_bound, exhaustive=False):
    refined = []

    def refine(c: Cand):
        refined.append(c.name)
        if c.fine is None:
            return Rejection(c.name, "rejected")
        return (c.name, c.gross + c.fine)

    sel = select_strategy(
        cands, lambda c: c.gross, refine, lambda r: r[1], lower_bound, exhaustive=exhaustive
    )
    return sel, refined


def test_the_seeds_example_stops_after_the_best_refined() -> None:
    # §4.8: the best refined strategy costs 6.14 s; the cheapest unrefined one left costs
    # 6.64 s (L2672), more than 6.14 even before refinement: stop (L2710).
    cands = [
        Cand("a", 5.47, 1.80),
        Cand("b", 5.54, 0.60),
        Cand("c", 6.64, 0.0),
        Cand("d", 7.0, 0.0),
    ]
    sel, order = run(cands, 0.0)
    assert sel.best == ("b", 6.14)
    assert order == ["a", "b"]
    assert [c.name for c in sel.unrefined] == ["c", "d"]
    assert sel.count == 2
    full, order = run(cands, 0.0, exhaustive=True)
    assert full.best == sel.best and order == ["a", "b", "c", "d"]


def test_minimum_refinement_cost_tightens_the_cutoff() -> None:
    cands = [Cand("a", 1.0, 1.0), Cand("b", 1.5, 1.0), Cand("c", 1.9, 1.0)]
    assert run(cands, 0.0)[1] == ["a", "b", "c"]
    # With every refinement adding at least 0.6 s, b (1.5 + 0.6 ≥ 2.0) is never refined.
    assert run(cands, 0.6)[1] == ["a"]


def test_rejections_and_ties_are_deterministic() -> None:
    cands = [Cand("x", 1.0, None), Cand("y", 2.0, 1.0), Cand("z", 2.0, 1.0)]
    sel, order = run(cands, 0.0)
    assert sel.rejected == (Rejection("x", "rejected"),)
    assert sel.best == ("y", 3.0)  # equal costs: the earlier candidate (heap counter)
    assert order == ["x", "y", "z"]  # z: 2.0 < 3.0, so it must be refined; it ties and loses
    sel, _ = run([Cand("a", 1.0, None)], 0.0)
    assert sel.best is None and sel.refined == ()


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(0, 10), st.one_of(st.none(), st.floats(0, 5))),
        min_size=1,
        max_size=12,
    ),
    st.floats(0, 1),
)
def test_best_first_agrees_with_exhaustive_under_an_admissible_bound(raw, fraction) -> None:
    cands = [Cand(str(i), g, f) for i, (g, f) in enumerate(raw)]
    fines = [c.fine for c in cands if c.fine is not None]
    bound = fraction * min(fines) if fines else 0.0  # ≤ every fine time: admissible
    best_first, order = run(cands, bound)
    exhaustive, all_order = run(cands, bound, exhaustive=True)
    assert best_first.best == exhaustive.best
    assert len(order) <= len(all_order) == len(cands)
