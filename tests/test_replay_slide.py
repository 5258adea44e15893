"""A held pin sliding along a solid (synth.replay.motion.Slide, synth.replay.scrape).

The seed's pin (0.604 cm shaft, tapered tip; its convex hull, as the replay uses it) slides
along a 3 cm box standing on a table slab. Oracles: the closed forms below, from the pin's
hull vertices; none of them calls Coal.

* A face: the contact point stays on the plane it touched, so the yield is the plane's,
  δ = −n·(P x − x₀), exactly as before edges were told apart.
* An edge: a pin beside the box's top edge, its contact normal tilted up from the wall by the
  edge (as Coal reports it at an edge), clears the box once shifted along n by
  δ* = min(Δx / n_x, Δz / n_z): Δx its overlap with the wall, Δz how far its tip is below the
  top. The tangent plane's yield grows by n_z per unit of descent instead, and jammed the pin
  in the air beside the box (four-pin Stanford cell, hand ±0.1 in: trial 40 of seed 1 stalled
  1.8 cm down and 1.15 cm clear of the wall, and the program read a seat).
"""

from __future__ import annotations

import math

import coal
import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_TASK

from synth.models.arm.collision import Obstacle
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task
from synth.models.workcell import PinModel, WorkcellModel
from synth.replay.motion import Slide
from synth.replay.scrape import scrape
from synth.replay.truth import nominal_world

CM = 0.01
WALL = 2.0 * CM  # the box's +x face
TOP = 3.0 * CM  # its top face, on the table's top at z = 0
BOX = Obstacle("BOX", coal.Box(4 * CM, 4 * CM, TOP), pin.SE3(np.eye(3), np.array([0, 0, TOP / 2])))
TABLE = Obstacle(
    "TABLE", coal.Box(40 * CM, 40 * CM, 2 * CM), pin.SE3(np.eye(3), np.array([0, 0, -CM]))
)


@pytest.fixture(scope="module")
def pin_model() -> PinModel:
    graph = AttributeGraph(load_task(SEED_TASK))
    cell = WorkcellModel(graph, [np.array([0.2, 0.7, 0.0])]).place(nominal_world(graph))
    return cell.pins["pin1"]


def hull_points(model: PinModel) -> np.ndarray:
    """The vertices of the pin's hull, pin frame (tip centre at 0, z up the pin) [m]."""
    return np.asarray(model.geometry.points(), dtype=float).reshape(-1, 3)


def upright(x: float, z: float) -> pin.SE3:
    """The pin standing upright with its tip centre at (x, 0, z)."""
    return pin.SE3(np.eye(3), np.array([x, 0.0, z]))


def test_along_a_face_the_yield_is_the_planes(pin_model: PinModel) -> None:
    points = hull_points(pin_model)
    inner = points[np.argmin(points[:, 0])]  # the pin's point nearest the wall
    normal = np.array([1.0, 0.0, 0.0])
    origin = np.array([WALL, 0.0, 2.0 * CM])
    slide = Slide(BOX, normal, inner, origin, pin_model.geometry)
    for overlap in (0.0, 2e-5, 0.05 * CM, 0.4 * CM):
        for tip in (2.5 * CM, 1.0 * CM):
            pose = upright(WALL - inner[0] - overlap, tip)
            plane = max(0.0, -float(normal @ (pose.act(inner) - origin)))
            assert slide.deflection(pose) == plane
            assert plane == pytest.approx(overlap, abs=1e-12)


@pytest.mark.parametrize("tilt_deg", [70.0, 80.0])
def test_past_an_edge_the_yield_is_the_least_shift_that_clears_the_box(
    pin_model: PinModel, tilt_deg: float
) -> None:
    points = hull_points(pin_model)
    reach = -float(points[:, 0].min())  # the hull's reach towards −x from its axis
    tilt = math.radians(tilt_deg)  # from the vertical: the edge's normal, tilted off the top
    normal = np.array([math.sin(tilt), 0.0, math.cos(tilt)])
    axis_x = WALL + reach - 0.05 * CM  # the pin overlaps the wall by 0.05 cm
    # it touched the edge with its taper, 0.2 cm above where the tip is when the test starts
    start = upright(axis_x, TOP - 0.1 * CM)
    touching = points[np.argmin(points[:, 0] + 10 * points[:, 2])]
    slide = Slide(BOX, normal, touching, start.act(touching), pin_model.geometry)
    # (past the plane's trusted 2 mm: 1.5 cm down the plane's yield is 0.26 cm at 80°)
    for depth in (1.5 * CM, 2.0 * CM, 2.9 * CM):
        pose = upright(axis_x, TOP - depth)
        overlap_x = WALL - (axis_x - reach)
        below = depth
        expected = min(overlap_x / normal[0], below / normal[2])
        plane = -float(normal @ (pose.act(touching) - slide.origin))
        assert slide.deflection(pose) == pytest.approx(expected, abs=2e-6)
        assert slide.deflection(pose) <= plane + 1e-12
    # the plane's yield grows by n_z per unit of descent: 2.9 cm down, 0.99 cm (70°) or 0.50 cm
    # (80°), where the pin needs 0.05 cm / n_x
    deepest = -float(normal @ (upright(axis_x, 0.0).act(touching) - slide.origin))
    assert deepest == pytest.approx(2.9 * CM * normal[2], abs=1e-12)
    assert deepest > 9 * 0.05 * CM / normal[0]


def test_a_pin_lowered_along_the_wall_stops_on_the_table(pin_model: PinModel) -> None:
    # commanded 0.05 cm into the wall, from 2.5 cm above the table to 1 cm below its top
    points = hull_points(pin_model)
    inner = points[np.argmin(points[:, 0])]
    axis_x = WALL - inner[0] - 0.05 * CM
    top, bottom = 2.5 * CM, -1.0 * CM
    slide = Slide(
        BOX, np.array([1.0, 0.0, 0.0]), inner, np.array([WALL, 0.0, top]), pin_model.geometry
    )

    def pose_at(s: float) -> pin.SE3:
        return upright(axis_x, top + s * (bottom - top))

    end = scrape(pin_model, pose_at, top - bottom, slide, [TABLE], start=0.0)
    assert end.kind == "touch" and end.touched is TABLE
    # stopped where the pin comes within the contact clearance (2e-5 m) of the table
    tip = pose_at(end.s).translation[2]
    assert 1e-5 <= tip <= 2e-5 + 1e-9
    assert end.deflection == pytest.approx(0.05 * CM, abs=1e-12)
    assert end.point is not None and abs(end.point[2]) < 1e-6


def test_a_pin_lowered_over_the_edge_goes_down_beside_the_box(pin_model: PinModel) -> None:
    # the commanded pin's shaft stays 0.05 cm into the wall all the way down (its tip starts
    # 0.5 cm below the top, past the 0.34 cm taper); the edge's normal is 70° from the vertical,
    # so the plane's yield would reach 1.07 cm, past the 1 cm compliance, 3.1 cm further down
    points = hull_points(pin_model)
    reach = -float(points[:, 0].min())
    tilt = math.radians(70.0)
    normal = np.array([math.sin(tilt), 0.0, math.cos(tilt)])
    axis_x = WALL + reach - 0.05 * CM
    top, bottom = TOP - 0.5 * CM, -1.0 * CM
    touching = points[np.argmin(points[:, 0] + 10 * points[:, 2])]
    slide = Slide(BOX, normal, touching, upright(axis_x, top).act(touching), pin_model.geometry)

    def pose_at(s: float) -> pin.SE3:
        return upright(axis_x, top + s * (bottom - top))

    end = scrape(pin_model, pose_at, top - bottom, slide, [TABLE], start=0.0)
    assert end.kind == "touch" and end.touched is TABLE
    # held off the wall by the overlap along n: 0.05 cm / sin 70°, far inside the compliance
    assert end.deflection == pytest.approx(0.05 * CM / math.sin(tilt), abs=2e-6)
    assert 1e-5 <= slide.yielded(pose_at(end.s)).translation[2] <= 2e-5 + 1e-9
