"""The pickup's CENTER checked against the start hole's uncertainty (seed §4.3.1, L1980)."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from _paths import DATA_TASKS, TASKS

from synth.exceptions import NoStrategyError
from synth.models.loader import load_task
from synth.strategies.context import plan_context
from synth.strategies.grasp import centering_bounds
from synth.strategies.planner import plan_task
from synth.strategies.records import Grasp


def _error(x: float, y: float, rz: float) -> pin.SE3:
    return pin.SE3(pin.exp3(np.array([0.0, 0.0, rz])), np.array([x, y, 0.0]))


def test_bound_covers_the_exact_chain_and_is_tight() -> None:
    """Closing offset of the pin at the grasp: certified bound vs the exact chain's corners."""
    spec = load_task(DATA_TASKS / "uncertain_rack.yaml")
    ctx = plan_context(spec, None, TASKS)
    grasp = Grasp(math.radians(90), math.pi, 0.035425)
    bounds = centering_bounds(ctx, grasp)
    world_rack = ctx.graph.world_from("rack")
    rack_pin = ctx.graph.relative("rack", ctx.pin_frame)
    hand0 = ctx.world_pin * grasp.pin_from_hand()
    h = 0.05 * 0.0254
    r = 0.25 * 0.0254
    worst_closing = worst_across = 0.0
    for sx in (-1, 1):
        for sy in (-1, 1):
            for srz in (-1, 1):
                for hx in (-1, 1):
                    for hy in (-1, 1):
                        true_pin = world_rack * _error(sx * r, sy * r, srz * math.radians(4))
                        true_pin = true_pin * rack_pin
                        hand = hand0 * pin.SE3(np.eye(3), np.array([hx * h, hy * h, 0.0]))
                        local = hand.actInv(true_pin)
                        worst_closing = max(worst_closing, abs(local.translation[0]))
                        worst_across = max(worst_across, abs(local.translation[1]))
    assert worst_closing <= bounds.closing
    assert worst_across <= bounds.across
    assert bounds.closing <= 1.05 * worst_closing  # hand rotations add the rest


def test_rack_known_to_a_quarter_inch_is_refused_at_the_pads() -> None:
    """±0.25 in in x and y: no ω puts the pin within the pads' 0.25 in radius across."""
    spec = load_task(DATA_TASKS / "uncertain_rack.yaml")
    with pytest.raises(NoStrategyError) as caught:
        plan_task(spec, base_dir=TASKS)
    assert "finger pads" in str(caught.value)


def test_rail_rack_plans_with_a_wider_opening() -> None:
    """±0.75 in along the rail: the opening widens past the seed's 1 in + diameter (L2139)."""
    spec = load_task(DATA_TASKS / "uncertain_rack_rail.yaml")
    result = plan_task(spec, base_dir=TASKS)
    pickup = result.strategy.pickup
    assert pickup.approach_opening > 0.00635 + 0.0254
    assert pickup.approach_opening <= 4.5 * 0.0254  # the hand's largest opening (L1984)
    assert pickup.grasp_determination is not None


def test_rack_beyond_the_hands_opening_is_refused_naming_the_opening() -> None:
    """±2.25 in along the rail: the hand's 4.5 in opening leaves 5.40 cm, too little."""
    spec = load_task(DATA_TASKS / "uncertain_rack_wide.yaml")
    with pytest.raises(NoStrategyError) as caught:
        plan_task(spec, base_dir=TASKS)
    assert "largest opening" in str(caught.value)


@pytest.mark.parametrize("trials", [40, pytest.param(200, marks=pytest.mark.slow)])
def test_rail_rack_program_grasps_in_every_sampled_world(trials: int) -> None:
    """The replay (the referee) never reports GRASP FAILED in the sampled rack poses.

    The planner opens the hand for the rack's whole error block, so no sampled pose may miss
    the fingers: any GRASP FAILED is a planner bug, however few the trials (200 in the slow
    suite, 40 by default: ~60 ms a trial).
    """
    from synth.codegen.emitter import emit_program
    from synth.models.believed import believed_graph
    from synth.replay.run import replay_program

    spec = load_task(DATA_TASKS / "uncertain_rack_rail.yaml")
    result = plan_task(spec, base_dir=TASKS)
    program = emit_program(result.strategy, believed_graph(spec))
    report = replay_program(program, spec, trials=trials, seed=0)
    assert report.nominal.outcome == "success"
    assert not [r for r in report.trials if r.message == "GRASP FAILED"]
