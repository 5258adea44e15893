"""Gross motions lifted over the workcell (synth/strategies/detour.py), judged by the replay.

The task: the seed's cell with a tower 4 × 4 × 14 cm between the rack and the box
(tests/data/tasks/tower_between.yaml). Straight joint-interpolated moves from BPARK to the pin
and from the rack to the box sweep into it; lifted, both clear it, and the program replays.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from _paths import DATA_TASKS
from _tasks import without_lifts

from synth.codegen.emitter import emit_program
from synth.exceptions import NoStrategyError
from synth.models.believed import believed_graph
from synth.models.loader import load_task
from synth.replay import replay_program
from synth.strategies import plan_task
from synth.strategies.approach import Candidate, plan_approach
from synth.strategies.context import PlanContext, plan_context
from synth.strategies.detour import SLACK
from synth.strategies.grasp import generate_pickups

TOWER = DATA_TASKS / "tower_between.yaml"
TOWER_TOP = 0.14  # [m]


@pytest.fixture(scope="module")
def planned():
    spec = load_task(TOWER)
    return spec, plan_task(spec).strategy


def _candidate(ctx: PlanContext, name: str) -> Candidate:
    pickups, _ = generate_pickups(ctx)
    for pickup in pickups:
        made = plan_approach(ctx, pickup)
        if isinstance(made, Candidate) and made.name == name:
            return made
    raise AssertionError(f"no candidate {name}")


def _path(ctx: PlanContext, points: list[np.ndarray], per_mm: float) -> list[np.ndarray]:
    out = []
    for a, b in itertools.pairwise(points):
        travel = np.linalg.norm(ctx.arm.forward(b).translation - ctx.arm.forward(a).translation)
        out += [a + u * (b - a) for u in np.linspace(0, 1, max(2, int(per_mm * 1e3 * travel)))]
    return out


def test_the_pickup_and_the_transport_are_lifted_over_the_tower(planned) -> None:
    _, strategy = planned
    lifted = [d for d in strategy.decisions if "lifted over TOWER" in d]
    assert len(lifted) == 2, strategy.decisions
    assert all(", 2 via points)" in d for d in lifted)
    # both via points of each are world poses (AL's NILTRANS base), the pin's for the transport
    assert [d.what for d in strategy.pickup.approach_detour] == ["BMANIP", "BMANIP"]
    assert [d.what for d in strategy.transport_detour] == ["PIN1", "PIN1"]
    assert {d.base for d in (*strategy.pickup.approach_detour, *strategy.transport_detour)} == {
        "NILTRANS"
    }
    # The held pin hangs below the hand: its tip is the grasp distance d below the hand's
    # origin, so the hand crosses at least d + the clearance + SLACK above the tower's top
    # (the pin's via is the hand's less d along the vertical pin)
    d = strategy.pickup.grasp.distance
    for via in strategy.transport_detour:
        tip = via.xf.translation[2]  # the pin frame is at its tip
        assert tip >= TOWER_TOP + SLACK
        assert tip == pytest.approx(strategy.transport_detour[0].xf.translation[2])
    # … and the empty hand only its finger pads' radius (0.25 in)
    for via in strategy.pickup.approach_detour:
        assert via.xf.translation[2] >= TOWER_TOP + 0.25 * 0.0254 + SLACK
    assert d == pytest.approx(0.03542, abs=1e-5)


def test_the_straight_transport_hits_the_tower_and_the_lifted_one_clears_it(planned) -> None:
    # Independent of the sweep: the chosen φ's straight transport sampled densely (8 per mm of
    # hand travel) with Coal's exact distances touches TOWER; the lifted one keeps the sweep's
    # clearance from every solid
    spec, strategy = planned
    ctx = plan_context(spec)
    cand = _candidate(ctx, strategy.name)
    assert cand.transport_detour is not None and cand.transport_detour.over == ("TOWER",)
    scene = ctx.gross.holding(cand.pickup.strategy.grasp)
    start, end = cand.pickup.q_departure, cand.q_hole_approach
    hits = {pair for q in _path(ctx, [start, end], 8) for pair in scene.collisions(q)}
    assert any("TOWER" in pair for pair in hits), hits
    clearance = ctx.gross.options_for(scene).clearance
    lifted = [start, *cand.transport_vias, end]
    closest = min(float(np.min(scene.distances(q))) for q in _path(ctx, lifted, 8))
    assert closest > clearance
    # the tap or the first attempt starts where the lift comes down
    assert np.array_equal(cand.q_transported, cand.transport_vias[-1])


def test_the_lifted_program_replays(planned) -> None:
    spec, strategy = planned
    text = emit_program(strategy, believed_graph(spec))
    # one unguarded MOVE of the pin: to the second lift, via the departure and the first lift
    move = text[text.index("MOVE PIN1 TO TRANS(") :].split(";")[0]
    assert "VIA PIN1*TRANS(NILROTN,VECTOR(0,0,6.79)*CM)" in move and "ON FORCE" not in move
    report = replay_program(text, spec, trials=20, seed=5, base_dir=DATA_TASKS)
    assert report.nominal.outcome == "success", report.nominal.message
    assert report.monte_carlo.outcomes == {"success": 20}


def test_without_lifts_the_tower_leaves_one_slow_transport(monkeypatch) -> None:
    # Straight moves only: the quick grasps' pickups sweep into the tower, and the transport's
    # one clear φ (270°) swings the hand over it in 2.13 s; lifted, the plan is quicker
    without_lifts(monkeypatch)
    spec = load_task(TOWER)
    try:
        straight = plan_task(spec).strategy
    except NoStrategyError:
        return
    monkeypatch.undo()
    lifted = plan_task(spec).strategy
    assert straight.phi == pytest.approx(math.radians(270))
    assert lifted.expected_time < straight.expected_time
