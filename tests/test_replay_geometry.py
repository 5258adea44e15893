"""The replay's true world and contact geometry, against hand geometry.

Oracles: the seed fixture's numbers (box at (45.2, 102, 0) cm, BH1 at (3.85, 3.20, 4.90) cm in
it, hole ⌀0.64 cm × 1.71 cm with a 0.25 cm chamfer, pin ⌀0.635 cm × 2 in with a 0.34 cm taper
to a 0.13 cm tip), link errors composed with rotation matrices written out, and pins moved on
straight lines whose first contact is worked out by hand.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_TASK

from synth.exceptions import SpecError
from synth.models.arm.collision import Obstacle
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task
from synth.models.meshes import block
from synth.models.workcell import TABLE, WorkcellModel
from synth.replay.capture import captures, seat_depth, tip_placement
from synth.replay.contact import first_contact
from synth.replay.guided import guided_motion
from synth.replay.truth import HandErrors, link_error, nominal_world, sample_world
from synth.units import CM, INCH


def Rz(rad: float) -> np.ndarray:
    c, s = math.cos(rad), math.sin(rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def Rx(rad: float) -> np.ndarray:
    c, s = math.cos(rad), math.sin(rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def Ry(rad: float) -> np.ndarray:
    c, s = math.cos(rad), math.sin(rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


@pytest.fixture(scope="module")
def graph() -> AttributeGraph:
    return AttributeGraph(load_task(SEED_TASK))


@pytest.fixture(scope="module")
def model(graph: AttributeGraph) -> WorkcellModel:
    # the table reaches under the arm's base, where seed_4_8.yaml stands it: (20, 70) cm
    return WorkcellModel(graph, [np.array([0.20, 0.70, 0.0])])


# --------------------------------------------------------------------------------------------
# The true world


def test_link_error_is_translation_then_x_y_z_rotations() -> None:
    v = np.array([0.01, -0.02, 0.03, 0.1, -0.2, 0.3])
    e = link_error(("x", "y", "z", "rx", "ry", "rz"), v)
    assert np.allclose(e.rotation, Rx(0.1) @ Ry(-0.2) @ Rz(0.3), atol=1e-12)
    assert np.allclose(e.translation, [0.01, -0.02, 0.03])
    # unlisted parameters are zero
    only = link_error(("y", "rz"), np.array([0.5, 0.2]))
    assert np.allclose(only.translation, [0.0, 0.5, 0.0])
    assert np.allclose(only.rotation, Rz(0.2), atol=1e-12)


def test_nominal_world_is_the_believed_one(graph: AttributeGraph) -> None:
    world = nominal_world(graph)
    assert np.allclose(world.pose("bh1").translation, np.array([49.05, 105.2, 4.90]) * CM)
    # T_wp = trans(rot(z, 90°), (24.1, 117, .537) cm), seed L2577
    assert np.allclose(world.pose("pin1").translation, np.array([24.1, 117.0, 0.537]) * CM)
    assert np.allclose(world.pose("pin1").rotation, Rz(math.pi / 2), atol=1e-12)


def test_sampled_box_moves_its_holes_rigidly_within_the_seed_tolerances(
    graph: AttributeGraph,
) -> None:
    rng = np.random.default_rng(7)
    offsets = []
    for _ in range(200):
        world = sample_world(graph, rng)
        box = world.pose("box")
        x, y = (box.translation - np.array([45.2, 102.0, 0.0]) * CM)[:2]
        angle = math.atan2(box.rotation[1, 0], box.rotation[0, 0])
        assert abs(x) <= 0.3 * INCH + 1e-12 and abs(y) <= 0.2 * INCH + 1e-12
        assert abs(angle) <= math.radians(5) + 1e-12 and box.translation[2] == 0.0
        # BH1 = box ∘ (3.85, 3.20, 4.90) cm, composed by hand
        expected = box.translation + Rz(angle) @ (np.array([3.85, 3.20, 4.90]) * CM)
        assert np.allclose(world.pose("bh1").translation, expected, atol=1e-12)
        # the rack and its pin are exact in this task
        assert np.allclose(world.pose("pin1").translation, np.array([24.1, 117, 0.537]) * CM)
        offsets.append((x, y, angle))
    spread = np.array(offsets)
    # uniform on ±0.3 in: every quarter of the range is visited
    assert spread[:, 0].min() < -0.2 * INCH and spread[:, 0].max() > 0.2 * INCH


def test_hand_errors_stream_is_bounded_and_reproducible(graph: AttributeGraph) -> None:
    block_ = graph.spec.manipulator.hand_error  # type: ignore[union-attr]
    a = HandErrors(block_, np.random.default_rng(3))
    b = HandErrors(block_, np.random.default_rng(3))
    for _ in range(100):
        ea, eb = a.next(), b.next()
        assert np.array_equal(ea.translation, eb.translation)
        assert np.all(np.abs(ea.translation) <= 0.05 * INCH + 1e-12)
        # the rotation is rot(x̂,a)·rot(ŷ,b)·rot(ẑ,c) with |a|,|b|,|c| ≤ 0.25°: its angle is at
        # most the sum of the three
        assert np.linalg.norm(pin.log3(ea.rotation)) <= 3 * math.radians(0.25) + 1e-12
    assert HandErrors.none().next().isIdentity()


# --------------------------------------------------------------------------------------------
# The solids and the capture geometry


def test_workcell_has_table_box_and_rack_with_their_holes(
    graph: AttributeGraph, model: WorkcellModel
) -> None:
    cell = model.place(nominal_world(graph))
    names = {o.name for o in cell.obstacles}
    assert names == {TABLE, "BOX", "RACK"}
    assert {h.name for h in cell.holes_in("BOX")} == {"BH1", "BH2", "BH3", "BH4"}
    bh1 = cell.hole("bh1")
    assert math.isclose(bh1.radius, 0.32 * CM) and math.isclose(bh1.mouth_radius, 0.57 * CM)
    assert np.allclose(bh1.world_from_hole.translation, np.array([49.05, 105.2, 4.90]) * CM)
    table = next(o for o in cell.obstacles if o.name == TABLE)
    # the slab's top face is the world plane z = 0
    assert math.isclose(table.pose.translation[2] + table.geometry.halfSide[2], 0.0, abs_tol=1e-12)


def test_capture_geometry_of_the_seed_parts(graph: AttributeGraph, model: WorkcellModel) -> None:
    cell = model.place(nominal_world(graph))
    bh1, pin1 = cell.hole("bh1"), cell.pins["pin1"]
    # the shaft (⌀0.635) fits the bore (⌀0.64): the pin bottoms at the hole's depth
    assert math.isclose(seat_depth(bh1, pin1), 1.71 * CM)
    # lead: the upright tip circle (r 0.13) inside the mouth (r 0.32 + 0.25) up to 0.44 cm off
    # axis lands on the chamfer; beyond, its flat face lands on the top face
    mouth = bh1.world_from_hole
    for offset, inside in ((0.43, True), (0.45, False)):
        pose = mouth * pin.SE3(np.eye(3), np.array([offset * CM, 0.0, 0.0]))
        placement = tip_placement(bh1, pose)
        assert math.isclose(placement.lateral, offset * CM) and abs(placement.axial) < 1e-12
        assert captures(bh1, pin1, placement) is inside


# --------------------------------------------------------------------------------------------
# First contact along a path (conservative advancement on Coal distances)


def straight_down(start: pin.SE3, depth: float):
    """The pin moved straight down by ``depth`` [m] over s ∈ [0, 1]."""

    def pose(s: float) -> pin.SE3:
        return pin.SE3(start.rotation, start.translation - np.array([0.0, 0.0, s * depth]))

    return pose


@pytest.mark.parametrize(
    ("offset_cm", "kind", "stop_z_cm"),
    [
        (1.0, "surface", 4.90),  # lands on the flat top face
        (0.50, "surface", 4.90),  # tip circle over the mouth's rim: the flat face stops it
        (0.40, "capture", 4.90),  # tip circle inside the mouth: captured at the mouth plane
        (0.0, "capture", 4.90),
    ],
)
def test_pin_falling_on_the_box_near_bh1(
    graph: AttributeGraph, model: WorkcellModel, offset_cm: float, kind: str, stop_z_cm: float
) -> None:
    cell = model.place(nominal_world(graph))
    bh1, pin1 = cell.hole("bh1"), cell.pins["pin1"]
    # towards the box's centre (BH1 is 0.64 cm from the +x edge)
    above = bh1.world_from_hole * pin.SE3(np.eye(3), np.array([-offset_cm * CM, 0.0, 2 * CM]))
    path = straight_down(above, 4 * CM)
    found = first_contact(pin1, path, 4 * CM, cell.obstacles, cell.holes, clearance=2e-5)
    assert found is not None and found.kind == kind and found.obstacle == "BOX"
    tip_z = path(found.s).translation[2]
    if kind == "capture":
        assert found.hole is bh1
        assert math.isclose(tip_z, stop_z_cm * CM, abs_tol=1e-9)
    else:
        # stopped between half the clearance and the clearance above the top face
        assert stop_z_cm * CM + 1e-5 - 1e-9 <= tip_z <= stop_z_cm * CM + 2e-5 + 1e-9
        assert np.allclose(found.normal, [0.0, 0.0, 1.0], atol=1e-6)


def test_a_thin_plate_is_never_stepped_over(graph: AttributeGraph, model: WorkcellModel) -> None:
    cell = model.place(nominal_world(graph))
    pin1 = cell.pins["pin1"]
    # a 0.2 mm plate 10 cm above the table, the pin falls 30 cm onto it from 20 cm above it
    plate = Obstacle.of(
        "plate", block((0.05, 0.05, 0.0002)), pin.SE3(np.eye(3), np.array([0.3, 0.3, 0.1]))
    )
    start = pin.SE3(np.eye(3), np.array([0.3, 0.3, 0.3]))
    path = straight_down(start, 0.3)
    found = first_contact(pin1, path, 0.3, [plate], [], clearance=2e-5)
    assert found is not None and found.obstacle == "plate"
    assert 0.1002 < path(found.s).translation[2] <= 0.1002 + 2e-5 + 1e-9


def test_guided_pin_bottoms_at_its_seat(graph: AttributeGraph, model: WorkcellModel) -> None:
    cell = model.place(nominal_world(graph))
    bh1, pin1 = cell.hole("bh1"), cell.pins["pin1"]
    # commanded 4.25 cm below the mouth from the mouth plane: bottoms at 1.71/4.25 of the way
    start = bh1.world_from_hole * pin.SE3(np.eye(3), np.array([0.1 * CM, 0.0, 0.0]))
    end = guided_motion(bh1, straight_down(start, 4.25 * CM), seat=seat_depth(bh1, pin1))
    assert end.kind == "bottom"
    assert math.isclose(end.s, 1.71 / 4.25, abs_tol=1e-9)

    # dragged sideways by more than the compliance: jams
    def sideways(s: float) -> pin.SE3:
        return start * pin.SE3(np.eye(3), np.array([s * 2 * CM, 0.0, -s * 1 * CM]))

    jam = guided_motion(bh1, sideways, seat=seat_depth(bh1, pin1), compliance=1 * CM)
    assert jam.kind == "jam" and math.isclose(jam.lateral, 1 * CM, abs_tol=1e-8)


def test_a_seated_pin_dragged_sideways_jams_and_pushed_in_stalls_after_the_give(
    graph: AttributeGraph, model: WorkcellModel
) -> None:
    cell = model.place(nominal_world(graph))
    bh1, pin1 = cell.hole("bh1"), cell.pins["pin1"]
    seat = seat_depth(bh1, pin1)
    # The tip at the seat up to rounding, as a stop leaves it (1e-15 m short of it).
    seated = bh1.world_from_hole * pin.SE3(np.eye(3), np.array([0.0, 0.0, -(seat - 1e-15)]))

    def bowed(s: float) -> pin.SE3:
        # 4 cm sideways with a joint-interpolated move's bow, up to 0.5 mm deeper mid-way
        return seated * pin.SE3(
            np.eye(3), np.array([4 * CM * s, 0.0, -0.05 * CM * 4 * s * (1 - s)])
        )

    # The bore stops the drag 1 cm off the axis, the bow having pushed 0.5·4·¼·(3/4) = 0.375 mm
    # into the bottom at s = ¼, within the arm's 1 cm give (it stalled at s ≈ 0 as "bottom").
    drag = guided_motion(bh1, bowed, seat=seat, compliance=1 * CM)
    assert drag.kind == "jam" and math.isclose(drag.s, 0.25, abs_tol=1e-6)

    def pushed(s: float) -> pin.SE3:
        return seated * pin.SE3(np.eye(3), np.array([0.0, 0.0, -2 * CM * s]))

    # Pushed 2 cm further in: the arm gives 1 cm, then stalls (half-way), the pin at its seat.
    push = guided_motion(bh1, pushed, seat=seat, compliance=1 * CM)
    assert push.kind == "bottom" and math.isclose(push.s, 0.5, abs_tol=1e-6)
    assert push.depth == seat


def test_a_hole_below_its_boxs_face_is_refused_at_its_translation(tmp_path) -> None:
    # BH1's mouth 3 cm up a 4.9 cm box: the field named is the hole's translation, with the
    # line of the task's text where it is written
    text = SEED_TASK.read_text(encoding="utf-8")
    written = "translation: [3.85 cm, 3.20 cm, 4.90 cm]"
    assert written in text
    changed = text.replace(written, "translation: [3.85 cm, 3.20 cm, 3.00 cm]", 1)
    path = tmp_path / "sunk.yaml"
    path.write_text(changed, encoding="utf-8")
    spec = load_task(path)
    with pytest.raises(SpecError) as refused:
        WorkcellModel(AttributeGraph(spec)).place(nominal_world(AttributeGraph(spec)))
    index = next(i for i, f in enumerate(spec.frames) if f.name == "bh1")
    assert refused.value.path == f"frames[{index}].pose.translation"
    assert "3 cm up" in str(refused.value) and "4.9 cm up" in str(refused.value)
    assert "3.00 cm]" in changed.splitlines()[refused.value.line - 1]
