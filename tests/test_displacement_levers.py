"""The gross-motion sweep's displacement bound of an uncertain solid, at its hull's levers.

:class:`~synth.models.arm.sweep.LinkDisplacement` bounds how far a point of a solid moves along
a direction under its link's error. The bound is checked here against the error applied as the
replay applies it (:func:`synth.replay.truth.link_error`, the seed's trans ∘ rot_x ∘ rot_y ∘
rot_z) to the solid's points, and against the corner lever's closed form.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest
from _paths import DATA_TASKS

from synth.codegen.emitter import emit_program
from synth.models.arm.bodies import hull_points
from synth.models.arm.sweep import LinkDisplacement
from synth.models.believed import believed_graph
from synth.models.loader import load_task
from synth.models.spec import TaskSpec
from synth.replay.run import replay_context, run_trial
from synth.replay.truth import link_error
from synth.strategies.approach import APPROACH_CLEARANCE
from synth.strategies.context import plan_context
from synth.strategies.planner import plan_task

NAMES = ("x", "y", "z", "rx", "ry", "rz")


def _annulus_mesh() -> coal.BVHModelOBBRSS:
    """A 6 × 4 × 1 cm block with a 1 cm hole (a mesh, like a plate with its hole)."""
    import trimesh

    block = trimesh.creation.box(extents=[0.06, 0.04, 0.01])
    hole = trimesh.creation.cylinder(radius=0.005, height=0.02, sections=16)
    plate = block.difference(hole) if trimesh.boolean.engines_available else block
    bvh = coal.BVHModelOBBRSS()
    bvh.beginModel(len(plate.faces), len(plate.vertices))
    bvh.addVertices(np.asarray(plate.vertices, dtype=float))
    bvh.addTriangles(np.asarray(plate.faces, dtype=np.int64))
    bvh.endModel()
    return bvh


def _errors(bounds: np.ndarray, rng: np.random.Generator, n: int) -> list[pin.SE3]:
    """Every corner of the error box and ``n`` draws inside it."""
    corners = [np.array(s) * bounds for s in itertools.product((-1, 1), repeat=6)]
    inside = list(rng.uniform(-bounds, bounds, size=(n, 6)))
    return [link_error(NAMES, v) for v in corners + inside]


@pytest.mark.parametrize(
    ("geometry", "placement"),
    [
        (coal.Box(0.16, 0.12, 0.015), pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.0075]))),
        (
            coal.Box(0.05, 0.02, 0.03),
            pin.SE3(pin.exp3(np.array([0.3, -0.2, 0.9])), np.array([0.07, -0.04, 0.02])),
        ),
        (
            _annulus_mesh(),
            pin.SE3(pin.exp3(np.array([0.0, 0.4, 0.0])), np.array([0.03, 0.01, 0.0])),
        ),
    ],
    ids=["plate", "offset-block", "mesh"],
)
def test_no_sampled_point_moves_farther_than_the_bound(
    geometry: coal.CollisionGeometry, placement: pin.SE3
) -> None:
    # Soundness: for every sampled error (the corners of the error box included) and direction,
    # n·δ(p) of every vertex and of points inside the hull stays within support(n), |δ(p)|
    # within bound(); δ is affine in p, so the hull's vertices are the worst points.
    rng = np.random.default_rng(11)
    bounds = np.array([0.002, 0.001, 0.01, math.radians(4), math.radians(3), math.radians(5)])
    radius = float(np.linalg.norm(placement.translation)) + 0.2  # a loose ball: levers decide
    points = hull_points(geometry, placement)
    assert points is not None
    inside = rng.dirichlet(np.ones(len(points)), size=200) @ points
    solid = np.vstack([points, inside])
    link_rotation = pin.exp3(np.array([0.1, 0.2, -0.7]))
    bound = LinkDisplacement(link_rotation, bounds[:3], bounds[3:], radius, points)
    moved = np.stack([e.act(p) - p for e in _errors(bounds, rng, 400) for p in solid])
    directions = rng.normal(size=(60, 3))
    directions = np.vstack([directions / np.linalg.norm(directions, axis=1)[:, None], np.eye(3)])
    for n_world in directions:
        n_link = link_rotation.T @ n_world
        assert float(np.max(moved @ n_link)) <= bound.support(n_world) + 1e-12
    assert float(np.max(np.linalg.norm(moved, axis=1))) <= bound.bound() + 1e-12


def test_a_tilted_plate_rises_by_its_corners_levers() -> None:
    # Closed form: a 16 × 12 × 1.5 cm plate on its link's origin, ±1 cm in z, ±4° about x and
    # y. Along the vertical the corner (8, 6, 1.5) cm is charged κ·(ρ_x + κ·|p|) about x (ρ_x
    # = √(6² + 1.5²) cm, the y turn applied first moves it by κ|p|) and κ·ρ_y about y (ρ_y =
    # √(8² + 1.5²) cm), κ = 2 sin 2°. The ball of radius r charged κ·r about both axes.
    kappa = 2 * math.sin(math.radians(2))
    box = coal.Box(0.16, 0.12, 0.015)
    placement = pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.0075]))
    corner = np.array([0.08, 0.06, 0.015])
    rho_x, rho_y = math.hypot(0.06, 0.015), math.hypot(0.08, 0.015)
    expected = 0.01 + kappa * (rho_x + kappa * float(np.linalg.norm(corner)) + rho_y)
    radius = float(np.linalg.norm(corner))
    angles = np.array([math.radians(4), math.radians(4), 0.0])
    lever = LinkDisplacement(
        np.eye(3), np.array([0.0, 0.0, 0.01]), angles, radius, hull_points(box, placement)
    )
    ball = LinkDisplacement(np.eye(3), np.array([0.0, 0.0, 0.01]), angles, radius)
    up = np.array([0.0, 0.0, 1.0])
    assert lever.support(up) == pytest.approx(expected, rel=1e-12)
    assert ball.support(up) == pytest.approx(0.01 + 2 * kappa * radius, rel=1e-12)
    # First order, the corner rises 1 cm + 4°·(8 + 6) cm = 1.977 cm: the bound is within 6 % of
    # it, where the ball said 2.40 cm
    first_order = 0.01 + math.radians(4) * (0.08 + 0.06)
    assert first_order <= lever.support(up) <= 1.06 * first_order
    assert ball.support(up) > 1.2 * first_order


def test_curved_solids_keep_the_ball() -> None:
    # A cylinder has no vertices whose hull holds it: the ball bound, unchanged
    assert hull_points(coal.Cylinder(0.01, 0.05), pin.SE3.Identity()) is None
    bounds = np.array([0.001, 0.002, 0.003, 0.01, 0.02, 0.03])
    ball = LinkDisplacement(np.eye(3), bounds[:3], bounds[3:], 0.05)
    assert ball.bound() == pytest.approx(
        float(np.linalg.norm(bounds[:3])) + float(np.sum(bounds[3:])) * 0.05
    )


def _plate_rise(z: float, tilt_deg: float) -> float:
    """The plate's rise [m] along the vertical at its corners' levers (the closed form above)."""
    kappa = 2 * math.sin(math.radians(tilt_deg) / 2)
    corner = np.array([0.08, 0.06, 0.015])
    levers = (
        math.hypot(0.06, 0.015) + kappa * float(np.linalg.norm(corner)) + math.hypot(0.08, 0.015)
    )
    return z + kappa * levers


def _variant(
    tmp_path: Path, name: str, z: str, tilt: str, corner: tuple[int, int] | None
) -> TaskSpec:
    """The task with the plate's height and tilt bounds replaced; ``corner``: the plate forced
    to that tilted corner (rx, ry signs), raised at least 90 % of its height bound."""
    text = (DATA_TASKS / "tilted_plate_far_corners.yaml").read_text(encoding="utf-8")
    block = "      z: 1 cm\n      rx: 4 deg\n      ry: 4 deg\n"
    assert text.count(block) == 1
    height, angle = float(z.split()[0]), float(tilt.split()[0])
    lines = f"      z: {z}\n      rx: {tilt}\n      ry: {tilt}\n"
    if corner is not None:
        lines += (
            "      constraints:\n"
            f"        - {{terms: {{z: 1}}, min: {0.9 * height} cm}}\n"
            f"        - {{terms: {{rx: {corner[0]}, ry: {corner[1]}}}, min: {1.75 * angle} deg}}\n"
        )
    path = tmp_path / f"{name}.yaml"
    path.write_text(text.replace(block, lines), encoding="utf-8")
    return load_task(path)


@pytest.mark.parametrize(
    ("z", "tilt", "standoff"),
    [
        # the fourth hunt's task as it is: the transport had to keep PIN1 2.87 cm above PLATE,
        # over the 2.54 cm standoff; at the corners' levers it asks 2.44 cm: 1 in stands
        ("1 cm", "4 deg", None),
        # 2 cm high, ±2.5°: the hole's Δz asked a 2.8 cm standoff, the sweep 3.17 cm at the
        # ball, 3.12 cm at the corners; the standoff now meets the sweep's need (+1 mm)
        ("2 cm", "2.5 deg", "swept"),
    ],
    ids=["hunt", "higher"],
)
def test_the_tilted_plate_is_planned_and_its_corners_replay(
    tmp_path: Path, z: str, tilt: str, standoff: str | None
) -> None:
    # tests/data/tasks/tilted_plate_far_corners.yaml was refused, "every motion the task needs
    # is obstructed", the transport's end within the plate's displacement bound
    spec = _variant(tmp_path, "nominal", z, tilt, None)
    ctx = plan_context(spec)
    planned = plan_task(spec)
    strategy = planned.strategy
    options = ctx.gross.options_for(ctx.gross.holding(strategy.pickup.grasp))
    up = np.array([0.0, 0.0, 1.0])
    need = options.clearance + options.pair_margin_along(("PIN1", "PLATE"), up)
    plate = _plate_rise(float(z.split()[0]) / 100, float(tilt.split()[0]))
    assert need == pytest.approx(options.clearance + options.margins["PIN1"] + plate, rel=1e-9)
    if standoff is None:
        assert need < strategy.standoff == pytest.approx(0.0254)
    else:
        assert strategy.standoff == pytest.approx(need + APPROACH_CLEARANCE, rel=1e-9)
    # The program, replayed in the worlds at the plate's four tilted corners, raised high
    program = emit_program(strategy, believed_graph(spec))
    for corner in itertools.product((-1, 1), repeat=2):
        context = replay_context(program, _variant(tmp_path, "corner", z, tilt, corner))
        outcomes = [run_trial(context, 5, i).outcome for i in range(4)]
        assert outcomes == ["success"] * 4, (corner, outcomes)
