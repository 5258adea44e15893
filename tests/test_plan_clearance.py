"""Gross motions swept by the planner (synth/strategies/clearance.py), judged by the replay.

The referee for "is this move clear" is the replay ("every emitted program must parse
and replay successfully in the nominal world"); the sweep's own correctness is checked against
dense sampling of the same joint-space segment with Coal's exact distances.

The obstructed case is the seed_4_8 workcell with the arm at (20, 80) cm, yaw 225°, where it first
stood: the joint-interpolated move from BPARK to the approach point of the grasp ω = 180°,
γ = 100° swings the hand about the column through the box's sector, at ~5.7 cm above the table
(BPARK 10.7 cm, box top 4.90 cm), and finger_left enters BOX. That is the collision the replay
reported on the planner's program before the sweep existed (AL line 10, hand at (47.94, 95.80,
5.66) cm).
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_TASK, TASKS
from _tasks import plannable, synthesized, with_base, without_lifts

from synth.codegen.emitter import emit_program
from synth.models.arm import Obstacle
from synth.models.believed import believed_graph
from synth.models.loader import load_task
from synth.models.spec import TaskSpec
from synth.replay import replay_program
from synth.strategies import plan_task
from synth.strategies.context import plan_context
from synth.strategies.grasp import (
    generate_pickups,
    pin_from_approach,
    reached_grasp,
)
from synth.strategies.options import hand_openings
from synth.strategies.records import Grasp, Rejection
from synth.units import DEG

OBSTRUCTED = "ω=180° γ=100° d=3.54 cm"


@pytest.fixture(scope="module")
def old_base() -> TaskSpec:
    return with_base(load_task(SEED_TASK), 20, 80, 225)


def test_the_sweep_finds_the_pickup_whose_move_from_park_hits_the_box(
    old_base, monkeypatch
) -> None:
    # Straight moves only (as before lifts): the sweep refuses the pickup
    without_lifts(monkeypatch)
    ctx = plan_context(old_base)
    pickups, rejected = generate_pickups(ctx)
    reasons = [r.reason for r in rejected if r.candidate == OBSTRUCTED]
    assert len(reasons) == 1 and "BPARK" in reasons[0]
    assert "finger_left into BOX" in reasons[0]
    assert OBSTRUCTED not in {p.name for p in pickups}
    assert ctx.counters.sweeps >= len(pickups) + 1
    # Independent: sample the same straight joint segment densely with exact Coal distances,
    # at least 8 samples per mm of hand travel (finer than the 1 mm clearance).
    distance = pickups[0].strategy.grasp.distance  # the single grasp distance (L2595)
    grasp = Grasp(math.pi, 100 * DEG, distance)
    found = reached_grasp(ctx, grasp)
    assert not isinstance(found, Rejection)
    q_app = found[0]
    scene = ctx.gross.empty_hand(hand_openings(ctx.pin_shape.diameter, ctx.options)[0])
    travel = np.linalg.norm(
        ctx.arm.forward(q_app).translation - ctx.arm.forward(ctx.q_park).translation
    )
    path = [ctx.q_park + s * (q_app - ctx.q_park) for s in np.linspace(0, 1, int(8e3 * travel))]
    hits = {pair for q in path for pair in scene.collisions(q)}
    assert ("finger_left", "BOX") in hits


def test_the_pickup_whose_move_from_park_hits_the_box_is_lifted_over_it(old_base) -> None:
    # With lifts the same pickup is kept: the hand rises over BOX and comes down above the pin
    ctx = plan_context(old_base)
    pickups, _ = generate_pickups(ctx)
    (lifted,) = [p for p in pickups if p.name == OBSTRUCTED]
    detour = lifted.detour
    assert detour is not None and detour.over == ("BOX",)
    # BPARK's hand is 10.7 cm high, above the lift: only the via above the pin is needed
    assert len(detour.configurations) == 1
    assert detour.describe().endswith(", 1 via point)")  # the decision said "two" here
    # the lift clears the box's top (4.90 cm) by the distance the sweep asked of the pair and
    # the hand's reach below its origin (the finger pads' radius, 0.25 in), and 1 cm
    assert detour.height >= 0.049 + 0.25 * 0.0254 + 0.01
    assert [d.label for d in lifted.strategy.approach_detour] == ["lift 1"]
    # Independent: the lifted path sampled densely (8 per mm of hand travel) with Coal's exact
    # distances keeps the sweep's clearance from BOX at its nominal pose, and touches nothing
    # with BOX at each corner of its error box (±0.3 in, ±0.2 in, ±5° about its vertical axis:
    # the extreme displacements of its corners), sampled at 2 per mm
    q_app = lifted.q_approach
    scene = ctx.gross.empty_hand(lifted.strategy.approach_opening)
    points = [ctx.q_park, *detour.configurations, q_app]
    box = [k for k, pair in enumerate(scene.pairs) if "BOX" in pair]

    def path(per_mm: float) -> list[np.ndarray]:
        out = []
        for a, b in itertools.pairwise(points):
            travel = np.linalg.norm(ctx.arm.forward(b).translation - ctx.arm.forward(a).translation)
            out += [a + u * (b - a) for u in np.linspace(0, 1, max(2, int(per_mm * 1e3 * travel)))]
        return out

    closest = min(float(np.min(scene.distances(q)[box])) for q in path(8))
    assert closest > ctx.gross.options_for(scene).clearance
    nominal = {o.name: o for o in scene.environment}
    for x, y, rz in itertools.product((-0.3, 0.3), (-0.2, 0.2), (-5.0, 5.0)):
        error = pin.SE3(pin.utils.rotate("z", math.radians(rz)), np.array([x, y, 0.0]) * 0.0254)
        moved = [
            Obstacle(o.name, o.geometry, o.pose * error if o.name == "BOX" else o.pose)
            for o in nominal.values()
        ]
        scene.reposition(moved, scene.held)
        assert not any(scene.collisions(q) for q in path(2)), (x, y, rz)


def test_without_the_sweep_the_replay_catches_the_collision(old_base, monkeypatch) -> None:
    # The planner's choice with the sweep disabled is the program the replay refused.
    from synth.strategies.clearance import GrossMotionCheck

    monkeypatch.setattr(GrossMotionCheck, "obstructed", lambda *a, **k: None)  # every sweep
    # γ = 100° also puts the fingers 1.96 cm above the pin end, where a pin gone beside the
    # box would pass the success test (test_plan_beside.py): that check is left out too, so
    # the sweep alone is what tells the two plans apart
    monkeypatch.setattr("synth.strategies.refine.false_seat_problem", lambda *a, **k: None)
    unchecked = plan_task(old_base).strategy
    monkeypatch.undo()
    checked = plan_task(old_base).strategy
    assert unchecked.name.startswith(OBSTRUCTED) and not checked.name.startswith(OBSTRUCTED)
    graph = believed_graph(old_base)
    refused = replay_program(emit_program(unchecked, graph), old_base, base_dir=TASKS)
    assert refused.nominal.outcome == "violation"
    kinds = {(v.kind, v.line) for v in refused.nominal.violations}
    assert ("collision", 9) in kinds and "BOX" in refused.nominal.message  # the first MOVE
    accepted = replay_program(emit_program(checked, graph), old_base, base_dir=TASKS)
    assert accepted.nominal.outcome == "success", accepted.nominal.message


@pytest.mark.parametrize("path", plannable(), ids=lambda p: p.stem)
def test_every_planned_program_replays_in_the_nominal_world(path: Path) -> None:
    # The pipeline writes only what replays, so the test is that the planner's first choice is
    # the one proven (no candidate rejected by its nominal replay) and the replay agrees.
    synthesis = synthesized(path)
    assert [a.candidate for a in synthesis.attempts] == [synthesis.strategy.name]
    report = replay_program(synthesis.program, path)
    assert report.nominal.outcome == "success", (synthesis.strategy.name, report.nominal.message)
    assert report.nominal.violations == ()


def test_box_margin_bounds_every_sampled_displacement_of_its_corners() -> None:
    # BOX under ±0.3 in, ±0.2 in, ±5° (L2566): its margin is |t|max + 2 sin(θmax/2)·λ with λ
    # the lever of its corners about the z axis (sweep.LinkDisplacement), √(4.45² + 3.80²) cm;
    # the ball about its origin (radius 8.79 cm) said 1.68 cm. Sampled: the corners' largest
    # displacement over 20 000 uniform errors (the extreme points of a box are its corners).
    spec = load_task(SEED_TASK)
    ctx = plan_context(spec)
    displacement = ctx.gross.empty.displacements["BOX"]
    margin = displacement.bound()
    t_max = math.hypot(0.3 * 0.0254, 0.2 * 0.0254)
    lever = math.hypot(0.0445, 0.0380)
    assert margin == pytest.approx(t_max + 2 * math.sin(math.radians(2.5)) * lever, rel=1e-12)
    radius = math.hypot(4.45, 3.80, 4.90 / 2) * 0.01 + 4.90 / 2 * 0.01  # |aabb centre| + ρ
    assert margin < t_max + math.radians(5) * radius - 0.0025
    rng = np.random.default_rng(0)
    x, y = (rng.uniform(-b, b, 20_000) * 0.0254 for b in (0.3, 0.2))
    rz = rng.uniform(-math.radians(5), math.radians(5), 20_000)
    hx, hy, h = 0.0445, 0.0380, 0.049
    corners = np.array([[sx * hx, sy * hy] for sx in (-1, 1) for sy in (-1, 1)])  # z unmoved
    c, s = np.cos(rz)[:, None], np.sin(rz)[:, None]
    moved_x = x[:, None] + c * corners[:, 0] - s * corners[:, 1]
    moved_y = y[:, None] + s * corners[:, 0] + c * corners[:, 1]
    worst = float(np.max(np.hypot(moved_x - corners[:, 0], moved_y - corners[:, 1])))
    assert h > 0 and worst <= margin
    # The bound adds the translation and the turn's chord at their largest. The worst error,
    # at a corner of the error box (x, y, rz at their bounds, enumerated), reaches 1.4175 cm:
    # within 0.01 cm of the bound, where the ball's radius left 0.26 cm. The uniform draws
    # come within 0.05 cm of that corner.
    extreme = 0.0
    for sx, sy, sr in itertools.product((-1, 1), repeat=3):
        turn = sr * math.radians(5)
        cos_t, sin_t = math.cos(turn), math.sin(turn)
        for cx, cy in corners:
            dx = sx * 0.3 * 0.0254 + cos_t * cx - sin_t * cy - cx
            dy = sy * 0.2 * 0.0254 + sin_t * cx + cos_t * cy - cy
            extreme = max(extreme, math.hypot(dx, dy))
    assert worst <= extreme <= margin
    assert margin - extreme < 0.0001
    assert extreme - worst < 0.0005
    # Per direction (SweepOptions.displacements): the sampled corner displacements along n never
    # exceed the support D(n); no error of the block moves it vertically, so D(ẑ) = 0.
    for n in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.6, 0.8, 0.0]):
        along = n[0] * (moved_x - corners[:, 0]) + n[1] * (moved_y - corners[:, 1])
        support = displacement.support(np.array(n))
        assert float(np.max(np.abs(along))) <= support <= margin
    assert displacement.support(np.array([0.0, 0.0, 1.0])) == pytest.approx(0.0, abs=1e-15)


def test_with_margins_no_sampled_world_hits_the_box_on_the_gross_motions(old_base) -> None:
    # Before the margins, the program planned here hit BOX with wrist_body on the move from
    # BPARK in 56 of 300 sampled worlds (it passed 1 mm from the believed box). Now no trial may
    # collide anywhere; with p = 56/300, 0 of 60 would have chance
    # (1 − 0.187)^60 ≈ 4e-6.
    program = emit_program(plan_task(old_base).strategy, believed_graph(old_base))
    report = replay_program(program, old_base, trials=60, seed=1, workers=1, base_dir=TASKS)
    hits = [v for run in report.trials for v in run.violations if v.kind == "collision"]
    assert report.nominal.outcome == "success" and hits == []


@pytest.mark.parametrize("task", ["seed_4_8", "seed_4_8_tap", "seed_4_8_fixture"])
def test_swept_configurations_are_the_ones_the_replay_moves_through(task: str) -> None:
    # The sweep is only as good as its path: the planner's configurations (the best-rated grasp,
    # then nearest by motion time) must be those the replay reaches, solving each MOVE target
    # nearest its current configuration from the park on (synth/replay/reach.py).
    from synth.replay.reach import solve_near
    from synth.strategies.approach import hand_at, hole_frame_offset, plan_approach
    from synth.strategies.records import Rejection

    ctx = plan_context(load_task(TASKS / f"{task}.yaml"))
    pickups, _ = generate_pickups(ctx, try_harder=True)
    assert pickups
    for p in pickups:
        grasp = p.strategy.grasp
        approach = ctx.world_pin * pin_from_approach(grasp, ctx.options.grasp_approach_distance)
        q = solve_near(ctx.arm, approach, ctx.q_park)
        np.testing.assert_allclose(q, p.q_approach, atol=1e-9)
        q = solve_near(ctx.arm, ctx.world_pin * grasp.pin_from_hand(), q)
        np.testing.assert_allclose(q, p.q_grasp, atol=1e-9)
        departure = ctx.world_pin * p.strategy.departure_point.xf * grasp.pin_from_hand()
        q = solve_near(ctx.arm, departure, q)
        np.testing.assert_allclose(q, p.q_departure, atol=1e-9)
        made = plan_approach(ctx, p)
        if isinstance(made, Rejection):
            continue
        above = hand_at(
            ctx, grasp, hole_frame_offset(made.strategy.phi, (0, 0, ctx.options.standoff))
        )
        np.testing.assert_allclose(solve_near(ctx.arm, above, q), made.q_hole_approach, atol=1e-9)
