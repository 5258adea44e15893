"""The search pattern's size is bounded before it is enumerated."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _paths import SEED_TASK
from scipy.spatial import cKDTree

from synth.al.interpreter import MAX_TIME
from synth.exceptions import NoStrategyError, SpecError
from synth.models.loader import parse_task
from synth.strategies.causes import classify
from synth.strategies.options import PlanOptions
from synth.strategies.planner import plan_task
from synth.strategies.search import (
    MAX_POINTS,
    coverage,
    pattern_points,
    pattern_size,
    plan_search,
    points_within_box,
    search_extent,
    search_size_problem,
    search_time_problem,
    tried_points,
)
from synth.units import CM


def test_a_tiny_dr_ok_is_refused_without_summing_its_rings() -> None:
    # Δr_ok = 1e-9 cm: step 7.5e-12 m, 2·10⁹ rings for a 1.58 cm footprint, ~10¹⁹ points.
    dr_ok = 1e-9 * CM
    reason = search_size_problem(1.58 * CM, 1.15 * CM, dr_ok, 0.75 * dr_ok)
    assert reason is not None and "more than 20000" in reason and "1e-09 cm" in reason
    assert classify(reason) == "footprint"
    assert "no spacing" in (search_size_problem(1.58 * CM, 1.15 * CM, 0.0, 0.0) or "")
    assert points_within_box(0.75 * dr_ok, 0.79 * CM, 0.57 * CM) == 0  # the lower bound stays 0


def test_the_size_bound_agrees_with_the_exact_count_near_the_limit() -> None:
    # 80 rings hold Σ⌈2πk⌉ = 20 397 > MAX_POINTS points; 79 hold 19 894. π·R(R+1) ≤ the count,
    # so the O(1) bound never refuses a pattern the exact count would accept.
    assert pattern_size(1.0, 80) == 20_397 and pattern_size(1.0, 79) == 19_894
    for rings in range(1, 120):
        exact = pattern_size(1.0, rings) > MAX_POINTS
        refused = search_size_problem(rings - 1.0, 0.0, 1.0, 1.0) is not None  # R = rings
        assert refused == exact, rings


def test_plan_refuses_a_tiny_dr_ok_naming_the_footprint() -> None:
    text = SEED_TASK.read_text().replace("dr_ok: 0.762 cm", "dr_ok: 1e-9 cm")
    assert "1e-9 cm" in text
    with pytest.raises(NoStrategyError) as info:
        plan_task(parse_task(text))
    assert info.value.root.cause == "footprint"
    assert any("needs a search of about" in r for _, r in info.value.reasons)


def test_plan_refuses_a_zero_dr_ok_instead_of_dividing_by_it() -> None:
    # A task file with dr_ok 0 is refused at load, naming the field; a spec built in code that
    # bypasses the schema still gets the planner's refusal, never a division by zero.
    text = SEED_TASK.read_text().replace("dr_ok: 0.762 cm", "dr_ok: 0 cm")
    with pytest.raises(SpecError, match=r"insertion\.dr_ok.*must be > 0"):
        parse_task(text)
    spec = parse_task(SEED_TASK.read_text())
    assert spec.insertion is not None
    zero = spec.model_copy(update={"insertion": spec.insertion.model_copy(update={"dr_ok": 0.0})})
    with pytest.raises(NoStrategyError) as info:
        plan_task(zero)
    assert info.value.root.cause == "footprint"


def _seed_loop_points(step: float, rings: int, dx: float, dy: float) -> list[tuple[float, float]]:
    """The offsets the generated loop tries, as the AL of L2743–2770 runs it: R from step while
    R ≤ rings·step; W from 0 while W < 2π, DW = step/R; kept when |x| ≤ dx and |y| ≤ dy."""
    kept = []
    for ring in range(1, rings + 1):
        r, w = ring * step, 0.0
        while w < 2 * math.pi:
            x, y = r * math.cos(w), r * math.sin(w)
            if abs(x) <= dx and abs(y) <= dy:
                kept.append((x, y))
            w += step / r
    return kept


def test_a_hand_placed_plate_gets_a_search_pattern_that_covers_it() -> None:
    # ±3 in of hand placement gave the certified footprint ±10.6 cm × ±10.6 cm against
    # Δr_ok = 0.525 cm (a 1 cm pin, 1.05 cm hole, 0.3 cm chamfer): the 41 × 41 check added a
    # grid half-diagonal of 0.37 cm to a coverage of ≈ 0.35 cm, no pattern passed, and
    # search_extent raised (synth plan exited 70).
    dx = dy = 10.6 * CM
    dr_ok = 0.525 * CM
    step = 0.75 * dr_ok
    rings, margin = search_extent(dx, dy, dr_ok, step)
    tried = np.vstack([[0.0, 0.0], _seed_loop_points(step, rings, dx + margin, dy + margin)])
    # Monte Carlo over the footprint, apart from the cells the check uses: every point within
    # Δr_ok of a tried offset, and the check's bound above the largest distance found.
    probe = np.random.default_rng(3).uniform([-dx, -dy], [dx, dy], size=(20_000, 2))
    nearest, _ = cKDTree(tried).query(probe)
    assert nearest.max() <= dr_ok
    points = pattern_points(step, rings)
    assert coverage(points, dx, dy, margin, within=dr_ok) >= nearest.max()


def test_coverage_fails_where_a_footprint_point_is_far_from_every_offset() -> None:
    # One ring of radius 1 about the origin, filter ±2 × ±2: the corner (2, 2) is 2√2 from the
    # origin, so at least 2√2 − 1 = 1.83 from the origin's ring: the bound is at least that, and
    # coverage within 1 is never proven.
    points = pattern_points(1.0, 1)
    bound = coverage(points, 2.0, 2.0, within=1.0)
    assert bound >= 2 * math.sqrt(2) - 1 > 1.0


def test_a_search_longer_than_a_replayed_run_is_refused_with_the_footprint_cause() -> None:
    dx, dy, dr_ok = 10.6 * CM, 10.6 * CM, 0.525 * CM
    search = plan_search(dx, dy, 0.0, dr_ok, 0.5, PlanOptions())
    tried = len(_seed_loop_points(search.step, search.rings, search.dx, search.dy))
    assert tried_points(search) == tried
    # A pin at the footprint's corner tries every point: (tried + 1)·0.5 s, plus 7 s of pickup
    # and transport, against the referee's 600 s budget for one run.
    worst = (tried + 1) * 0.5 + 7.0
    assert worst > MAX_TIME
    reason = search_time_problem(search, 0.5, 7.0, MAX_TIME)
    assert reason is not None and f"{tried} points" in reason and f"{worst:.0f} s" in reason
    assert classify(reason) == "footprint"
    fast = (MAX_TIME - 7.0) / (tried + 1)  # [s] per retry: the worst case just fits
    assert search_time_problem(search, 0.999 * fast, 7.0, MAX_TIME) is None
    assert search_time_problem(search, 1.001 * fast, 7.0, MAX_TIME) is not None
