"""True worlds of objects located by contacts: drawn from the contacts, a referee of locate.

Oracles, all independent of :mod:`synth.replay.located` (and of ``synth.errors``):

* Coal's signed distances between the box and the fixture's floor and walls as primitives at
  the drawn poses (touching where the contacts say, nowhere inside);
* the closed forms of seed A.1 (``tests/test_locate_seed.py``; box half-sizes a = 4.45,
  b = 3.80 cm between walls x = ±4, y = ±5 cm): second problem X ∈ [0, 4 − b], Y ∈ ±(5 − a),
  W ∈ [−90° − δ*, −90°] with δ* = asin(4/√(a² + b²)) − atan(b/a) = 2.6274°; final problem
  X = 0, Y = 5 − a cos δ* − b sin δ* = .3805 cm, W = −90° − δ* (L3151–3154);
* the planner's own derived block (``synth.errors.locate``), which the drawn truths must fill
  and not leave: that checks locate by the referee, not the other way round;
* Monte Carlo: a planner fed a deliberately wrong locate result plans a wrong program, and the
  replay fails it, while sampling around the planner's belief (the referee as it was)
  passes every trial.

Acceptance rates of the proposal (w on the circle, the free slide on the floor's extent),
measured on 200 000 candidates with seed 0: box1 (floor only, two gross orientations)
7.5·10⁻⁵, box2 and seed_4_8_fixture's box (plus an edge on a wall) 6.85·10⁻⁴, box3 (three
edges: w fixed at two roots, one feasible) 0.50.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import coal
import numpy as np
import pinocchio as pin
import pytest
from _paths import BOX_FIXTURE_TASK, TASKS

import synth.errors.locate as locate
import synth.replay.located as located
from synth.codegen.emitter import emit_program
from synth.errors.parameters import ParameterBlock, ParameterSpace
from synth.exceptions import SpecError
from synth.models.believed import believed_graph
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task
from synth.models.uncertainty import Uncertainty
from synth.replay.located import ContactPlacement, located_objects
from synth.replay.run import replay_context, replay_graph, replay_program, run_world, trial_seed
from synth.replay.truth import HandErrors, error_parameters, sample_world
from synth.strategies.planner import plan_task

SEED_FIXTURE = TASKS / "seed_4_8_fixture.yaml"
CM = 0.01
A, B = 4.45 * CM, 3.80 * CM
DELTA = math.asin(4 * CM / math.hypot(A, B)) - math.atan2(B, A)


def seed_w(pose: pin.SE3) -> float:
    """The seed's W [rad]: the rotation about −ẑ (R = ROTN(−ZHAT, W), L3024)."""
    return -math.atan2(pose.rotation[1, 0], pose.rotation[0, 0])


def poses(placement: ContactPlacement, seed: int, wanted: int) -> list[pin.SE3]:
    rng = np.random.default_rng(seed)
    out: list[pin.SE3] = []
    while len(out) < wanted:
        out += placement.draw(rng, 100_000)
    return out[:wanted]


# --------------------------------------------------------------------------------------------
# The drawn poses against Coal and the seed's closed forms


def fixture_parts(shape: Any) -> dict[str, tuple[coal.Box, pin.SE3]]:
    """Floor slab and walls of a fixture as Coal boxes in its frame (by the wall they hold)."""
    lx, ly, depth = shape.inside
    wall, floor = shape.wall, shape.floor
    parts = {
        "floor": ((lx + 2 * wall, ly + 2 * wall, floor), (0.0, 0.0, -floor / 2)),
        "xpos": ((wall, ly + 2 * wall, depth), (lx / 2 + wall / 2, 0.0, depth / 2)),
        "xneg": ((wall, ly + 2 * wall, depth), (-lx / 2 - wall / 2, 0.0, depth / 2)),
        "ypos": ((lx, wall, depth), (0.0, ly / 2 + wall / 2, depth / 2)),
        "yneg": ((lx, wall, depth), (0.0, -ly / 2 - wall / 2, depth / 2)),
    }
    return {
        k: (coal.Box(*size), pin.SE3(np.eye(3), np.array(centre)))
        for k, (size, centre) in parts.items()
    }


def signed_distance(
    box: coal.Box, box_pose: pin.SE3, part: coal.Box, part_pose: pin.SE3
) -> tuple[float, np.ndarray]:
    request = coal.DistanceRequest()
    request.enable_signed_distance = True
    result = coal.DistanceResult()
    d = coal.distance(
        box,
        coal.Transform3s(box_pose.rotation, box_pose.translation),
        part,
        coal.Transform3s(part_pose.rotation, part_pose.translation),
        request,
        result,
    )
    return float(d), box_pose.actInv(np.asarray(result.getNearestPoint1(), dtype=float))


@pytest.mark.parametrize(
    ("task", "obj", "fixture", "touching", "edges"),
    [
        (BOX_FIXTURE_TASK, "box2", "fixture2", {"xpos"}, {"xpos": (-1, -1)}),
        (
            BOX_FIXTURE_TASK,
            "box3",
            "fixture3",
            {"xpos", "ypos", "xneg"},
            {"xpos": (-1, -1), "ypos": (1, -1)},
        ),
        (SEED_FIXTURE, "box", "fixture", {"xpos"}, {"xpos": (-1, -1)}),
    ],
    ids=["A1-second", "A1-final", "seed_4_8_fixture"],
)
def test_drawn_poses_touch_the_fixture_where_the_contacts_say_by_coal(
    task: Path,
    obj: str,
    fixture: str,
    touching: set[str],
    edges: dict[str, tuple[int, int]],
) -> None:
    graph = AttributeGraph(load_task(task))
    shape = graph.nodes[obj].shape
    assert shape is not None and shape.type == "box"
    sx, sy, sz = shape.size
    box = coal.Box(sx, sy, sz)
    parts = fixture_parts(graph.nodes[fixture].shape)
    for pose in poses(located_objects(graph)[obj], 0, 60):
        centre = pose * pin.SE3(np.eye(3), np.array([0.0, 0.0, sz / 2]))  # Coal boxes are centred
        for name, (part, part_pose) in parts.items():
            d, on_box = signed_distance(box, centre, part, part_pose)
            if name == "floor" or name in touching:
                assert abs(d) < 1e-7, (name, d)
            else:
                assert d > -1e-7, (name, d)
            if name in edges:  # the box touches that wall along its vertical edge
                sign_x, sign_y = edges[name]
                assert on_box[:2] == pytest.approx([sign_x * sx / 2, sign_y * sy / 2], abs=1e-6)


def test_drawn_poses_span_the_seeds_second_and_final_estimates() -> None:
    graph = AttributeGraph(load_task(BOX_FIXTURE_TASK))
    places = located_objects(graph)
    second = poses(places["box2"], 1, 300)
    xs = np.array([p.translation[0] for p in second])
    ys = np.array([p.translation[1] for p in second])
    ws = np.array([seed_w(p) for p in second])
    assert xs.min() >= -1e-9 and xs.max() <= 4 * CM - B + 1e-9
    assert np.all(np.abs(ys) <= 5 * CM - A + 1e-9)
    assert ws.min() >= -math.pi / 2 - DELTA - 1e-9 and ws.max() <= -math.pi / 2 + 1e-9
    # and they fill those ranges (300 uniform draws come within 15 % of every end)
    assert xs.max() - xs.min() > 0.85 * (4 * CM - B)
    assert ys.max() - ys.min() > 0.85 * 2 * (5 * CM - A)
    assert ws.max() - ws.min() > 0.85 * DELTA
    # the final problem leaves a single pose (L3151–3154)
    for p in poses(places["box3"], 2, 20):
        assert p.translation == pytest.approx(
            [0.0, 5 * CM - A * math.cos(DELTA) - B * math.sin(DELTA), 0.0], abs=1e-12
        )
        assert seed_w(p) == pytest.approx(-math.pi / 2 - DELTA, abs=1e-12)


def test_locate_block_holds_and_is_filled_by_the_truths() -> None:
    # the referee checks locate: every drawn truth lies in the block the planner derived, and
    # the truths reach out to its bounds (none of them is loose by more than 15 %)
    graph = replay_graph(load_task(SEED_FIXTURE))
    block = graph.links["box"].uncertainty
    assert block is not None
    space = ParameterSpace((ParameterBlock.from_uncertainty("box", block),))
    names = ParameterBlock.from_uncertainty("box", block).names
    assert names == ("x", "y", "rz")
    belief = graph.links["box"].parent_from_child
    values = []
    for truth in poses(located_objects(graph)["box"], 3, 300):
        e = error_parameters(belief.actInv(truth))
        assert abs(e["z"]) < 1e-12 and abs(e["rx"]) < 1e-12 and abs(e["ry"]) < 1e-12
        values.append([e[n] for n in names])
    v = np.array(values)
    assert np.all(space.feasible(v, tol=1e-9))
    width = space.hi - space.lo
    assert np.all(v.min(axis=0) - space.lo < 0.15 * width)
    assert np.all(space.hi - v.max(axis=0) < 0.15 * width)


def test_draws_are_reproducible_and_bounded(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    graph = AttributeGraph(load_task(SEED_FIXTURE))
    a = sample_world(graph, np.random.default_rng(7)).pose("box")
    b = sample_world(graph, np.random.default_rng(7)).pose("box")
    c = sample_world(graph, np.random.default_rng(8)).pose("box")
    assert a.isApprox(b, 0.0) and not a.isApprox(c, 1e-9)
    # a box that barely fits its cavity leaves a set too thin to draw from: a clear error
    text = BOX_FIXTURE_TASK.read_text(encoding="utf-8").replace(
        "inside: [8.0 cm, 10.0 cm", "inside: [8.9001 cm, 7.6001 cm"
    )
    thin = tmp_path / "thin.yaml"
    thin.write_text(text, encoding="utf-8")
    monkeypatch.setattr(located, "MAX_CANDIDATES", 1 << 14)
    placement = located_objects(AttributeGraph(load_task(thin)))["box1"]
    with pytest.raises(SpecError, match="too thin"):
        placement.sample(np.random.default_rng(0))


# --------------------------------------------------------------------------------------------
# A wrong locate result fails the replay


def shifted(link: locate.DerivedLink) -> locate.DerivedLink:
    """The box believed 1 cm off along its own y: a locate that mis-centres its Y interval."""
    nominal = link.nominal * pin.SE3(np.eye(3), np.array([0.0, 1.0 * CM, 0.0]))
    pose = link.pose.model_copy(update={"translation": tuple(map(float, nominal.translation))})
    return dataclasses.replace(link, nominal=nominal, pose=pose)


def narrowed(link: locate.DerivedLink) -> locate.DerivedLink:
    """The box believed known to ±0.5 mm and ±0.1° (the contacts allow ±5.5 mm and ±1.3°)."""
    block = Uncertainty.model_validate({"x": "0.5 mm", "y": "0.5 mm", "rz": "0.1 deg"})
    return dataclasses.replace(link, uncertainty=block)


# seed 0, 40 trials: moved, 37 fail (the search pattern lies 1 cm off); narrowed, no search
# is planned and 5 abort; the correct locate passes all 40 (also with the old referee)
@pytest.mark.parametrize(
    ("wrong", "at_least_failing"),
    [(shifted, 30), pytest.param(narrowed, 4, marks=pytest.mark.slow)],
    ids=["shifted", "narrowed"],
)
def test_a_wrong_locate_result_fails_the_replay(
    monkeypatch: pytest.MonkeyPatch, wrong: Any, at_least_failing: int
) -> None:
    derive = locate.derive_link
    monkeypatch.setattr(locate, "derive_link", lambda *args, **kw: wrong(derive(*args, **kw)))
    # believing the box 1 cm towards FIX's wall, the planner finds its aims over the wall's top,
    # 1.9 cm below the face, and refuses every candidate: the referee is what is tested here
    monkeypatch.setattr("synth.strategies.refine.support_landing_problem", lambda *a, **k: None)
    spec = load_task(SEED_FIXTURE)
    program = emit_program(plan_task(spec).strategy, believed_graph(spec))
    trials = 40
    report = replay_program(program, spec, trials=trials, seed=0)
    assert report.nominal.success  # the program does what its (wrong) beliefs say
    failing = trials - report.monte_carlo.outcomes.get("success", 0)
    assert failing >= at_least_failing
    # the referee as it was drew the truth around the belief: it passed them all
    context = replay_context(program, spec)
    around_belief = AttributeGraph(context.graph.spec.model_copy(update={"contacts": ()}))
    manipulator = spec.manipulator
    assert manipulator is not None
    for index in range(trials):
        world_seed, hand_seed = trial_seed(0, index).spawn(2)
        world = sample_world(around_belief, np.random.default_rng(world_seed))
        hand = HandErrors(manipulator.hand_error, np.random.default_rng(hand_seed))
        assert run_world(context, world, hand).success
