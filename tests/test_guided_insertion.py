"""Below the face the hole guides the pin: a solid on the hole's part keeps no margin against it.

Where no attempt can bring the pin down off the face, a pin end below the face is in the bore,
which guides it along the hole's axis (:mod:`synth.replay.guided`): the pin moves with every
uncertain link above the hole, and a solid sharing those links moves with it
(:func:`synth.strategies.clearance.in_hole_displacement`). The insertion's held pin is swept
there with those margins, the arm's bodies with the fine motions' as before
(``synth.strategies.fine._guided_insertion``).
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from _paths import DATA_TASKS

from synth.codegen.emitter import emit_program
from synth.exceptions import NoStrategyError
from synth.models.believed import believed_graph
from synth.models.loader import load_task
from synth.models.spec import TaskSpec
from synth.replay.run import replay_context, run_trial
from synth.replay.truth import link_error
from synth.strategies import refine
from synth.strategies.bow import pin_deviation, split_at_height
from synth.strategies.clearance import in_hole_displacement, solid_displacement
from synth.strategies.context import end_from_hand, hand_at, plan_context
from synth.strategies.planner import plan_task
from synth.strategies.relations import hole_frame_offset
from synth.units import CM, DEG, INCH

TASK = DATA_TASKS / "step_beside_the_hole.yaml"
NAMES = ("x", "y", "z", "rx", "ry", "rz")


@pytest.fixture(scope="module")
def planned():
    spec = load_task(TASK)
    return spec, plan_task(spec).strategy


def _corner_world(tmp_path: Path, sx: int, srz: int) -> TaskSpec:
    """The task's worlds with the plate at 0.9 of its x and rz tolerances, signs ``sx``, ``srz``."""
    data = yaml.safe_load(TASK.read_text(encoding="utf-8"))
    plate = next(f for f in data["frames"] if f["name"] == "plate")
    x = {"terms": {"x": 1}, ("min" if sx > 0 else "max"): f"{sx * 0.045} in"}
    rz = {"terms": {"rz": 1}, ("min" if srz > 0 else "max"): f"{srz * 0.45} deg"}
    plate["uncertainty"]["constraints"] = [x, rz]
    path = tmp_path / f"corner_{sx}_{srz}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return load_task(path)


def test_the_step_beside_the_hole_is_planned_and_replays_at_the_plates_corners(
    planned, tmp_path: Path, monkeypatch
) -> None:
    spec, strategy = planned
    # Charged the plate's error against the pin (as where an attempt may go beside the face,
    # the behaviour before), NB refuses every insertion: 0.23 cm of plate between the bore and
    # NB against 0.10 cm clearance + the plate's ±0.05 in and 0.5° at NB's far corner
    monkeypatch.setattr(refine, "may_go_beside", lambda ctx, where: True)
    with pytest.raises(NoStrategyError, match=r"the insertion into BH1 sweeps PIN1 into NB"):
        plan_task(spec)
    monkeypatch.undo()
    graph = believed_graph(spec)
    program = emit_program(strategy, graph)
    # the referee at the corners where NB stands nearest and farthest, turned either way: the
    # pin never touches NB (it is in the bore, the plate between), every trial succeeds
    for sx, srz in ((1, 1), (-1, -1), (1, -1)):
        context = replay_context(program, _corner_world(tmp_path, sx, srz))
        outcomes = [run_trial(context, 5, trial).outcome for trial in range(12)]
        assert outcomes == ["success"] * 12, (sx, srz)


def test_a_solid_on_the_holes_part_keeps_no_margin_a_fixed_one_the_holes_error() -> None:
    spec = load_task(TASK)
    ctx = plan_context(spec)
    graph, gross = ctx.graph, ctx.gross
    nb = next(o for o in gross.solids if o.name == "NB")
    rack = next(o for o in gross.solids if o.name == "RACK")
    r, length, depth = ctx.pin_shape.diameter / 2, ctx.pin_shape.length, ctx.hole_shape.depth
    pin_box = np.array(
        [[sx * r, sy * r, z] for sx in (-1, 1) for sy in (-1, 1) for z in (-depth, length)]
    )
    # NB shares the plate's link with BH1, whose error (x, y, rz) never moves the hole along
    # its axis: nothing is left. Against the plate's believed pose NB is off by the whole error
    assert in_hole_displacement(graph, "nb", nb.geometry, "bh1", pin_box).links == ()
    assert solid_displacement(graph, "nb", nb.geometry).support(np.array([1.0, 0, 0])) > 0.05 * INCH
    # The rack is fixed. Monte Carlo through the exact motion: the plate moved by its error at
    # its box's corners and 400 draws inside; the pin on the moved axis, its end where the
    # believed end projects onto it (the command keeps the depth); every point of the pin,
    # its end anywhere down the bore, moves along each direction within the rack's support
    shifted = in_hole_displacement(graph, "rack", rack.geometry, "bh1", pin_box)
    world_plate, world_hole = graph.world_from("plate"), graph.world_from("bh1")
    rng = np.random.default_rng(7)
    bounds = np.array([0.05 * INCH, 0.05 * INCH, 0.0, 0.0, 0.0, 0.5 * DEG])
    corners = [np.array(c) * bounds for c in itertools.product((-1, 0, 1), repeat=6)]
    errors = [link_error(NAMES, v) for v in [*corners, *rng.uniform(-bounds, bounds, (400, 6))]]
    angles = rng.uniform(0, 2 * math.pi, 40)
    local = np.array(
        [[r * math.cos(a), r * math.sin(a), h] for a in angles for h in (0.0, length / 2, length)]
    )
    displaced = []
    for e in errors:
        true_hole = world_plate * e * world_plate.inverse() * world_hole
        axis, mouth = true_hole.rotation[:, 2], true_hole.translation
        for z_end in (0.0, -depth / 2, -depth):
            believed_end = world_hole.act(np.array([0.0, 0.0, z_end]))
            true_end = mouth + axis * float((believed_end - mouth) @ axis)
            believed = believed_end + local @ world_hole.rotation.T
            true = true_end + local @ true_hole.rotation.T
            displaced.append(true - believed)
    moved = np.vstack(displaced)
    directions = rng.normal(size=(60, 3))
    directions = np.vstack([directions / np.linalg.norm(directions, axis=1)[:, None], np.eye(3)])
    for n in directions:
        assert float(np.max(moved @ n)) <= shifted.support(n) + 1e-12
    # the command keeps the depth: along the axis only the turn's share is charged (0.5° at the
    # pin box's corners' levers about the plate's vertical axis: none)
    assert shifted.support(np.array([0.0, 0.0, 1.0])) == pytest.approx(0.0, abs=1e-12)
    assert shifted.support(np.array([1.0, 0.0, 0.0])) >= 0.05 * INCH


def _insertion_path(planned) -> tuple[object, list[np.ndarray], pin.SE3, pin.SE3]:
    """The plan's context and a joint path of the pin end from 2 cm above BH1 to its seat."""
    spec, strategy = planned
    ctx = plan_context(spec)
    grasp = strategy.pickup.grasp
    path = [ctx.q_park]
    for z in (2 * CM, 1 * CM, -ctx.insertion.d_f):
        q = ctx.nearest(
            hand_at(ctx, grasp, hole_frame_offset(strategy.phi, (0.0, 0.0, z))), path[-1]
        )
        assert q is not None
        path.append(q)
    return ctx, path[1:], ctx.world_hole.inverse(), end_from_hand(ctx, grasp).inverse()


def test_the_path_is_cut_where_the_pin_end_comes_down_to_a_height(planned) -> None:
    ctx, path, hole_from_world, hand_from_end = _insertion_path(planned)

    def height(q: np.ndarray) -> float:
        return float((hole_from_world * ctx.arm.forward(q) * hand_from_end).translation[2])

    for z in (0.5 * CM, 0.0, -0.3 * CM):
        above, below = split_at_height(ctx.arm, path, hole_from_world, hand_from_end, z)
        assert np.array_equal(above[-1], below[0])
        assert height(below[0]) == pytest.approx(z, abs=1e-9)
        assert all(height(q) > z for q in above[:-1])
        assert np.array_equal(below[-1], path[-1]) and np.array_equal(above[0], path[0])
    # a height the path never reaches leaves it all above; one above its start, all below
    assert split_at_height(ctx.arm, path, hole_from_world, hand_from_end, -5 * CM)[1] == []
    assert split_at_height(ctx.arm, path, hole_from_world, hand_from_end, 5 * CM)[0] == []


def test_the_pins_deviation_from_the_axis_bounds_every_point_of_it(planned) -> None:
    # Independent: points on the pin's surface (end frame: the shaft of radius r from the end
    # to the far end), moved from the pose on the path to the pose on the axis at the same
    # height, at the same samples of the path
    _, strategy = planned
    ctx, path, hole_from_world, hand_from_end = _insertion_path(planned)
    r, length = ctx.pin_shape.diameter / 2, ctx.pin_shape.length

    def on_axis(z: float) -> pin.SE3:
        return hole_frame_offset(strategy.phi, (0.0, 0.0, z))

    bound = pin_deviation(ctx.arm, path, hole_from_world, hand_from_end, on_axis, length, r)
    angles = np.linspace(0.0, 2 * math.pi, 24, endpoint=False)
    heights = np.linspace(0.0, length, 13)
    points = np.array(
        [[r * math.cos(a), r * math.sin(a), h] for a in angles for h in heights]
        + [[0.0, 0.0, h] for h in heights]
    )
    worst = 0.0
    for q0, q1 in itertools.pairwise(path):
        for s in np.linspace(0.0, 1.0, 49):
            end = hole_from_world * ctx.arm.forward(q0 + s * (q1 - q0)) * hand_from_end
            axis = on_axis(float(end.translation[2]))
            moved = (
                points @ end.rotation.T
                + end.translation
                - (points @ axis.rotation.T + axis.translation)
            )
            worst = max(worst, float(np.max(np.linalg.norm(moved, axis=1))))
    assert worst <= bound + 1e-12
    # the triangle inequality gives away at most the turn's share, ‖R_E − R_A‖·r
    assert bound - worst < 1e-4
    assert worst > 0.0  # a joint-interpolated path bows off the axis (bow.py)
