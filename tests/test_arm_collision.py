"""Collision scene: pair rules (adjacent links, static bodies, explicit allowed contacts), distances
checked against closed-form geometry, trimesh environments, the Stanford arm's self-collision."""

from __future__ import annotations

import itertools
import math

import coal
import numpy as np
import pinocchio as pin
import pytest
import trimesh

from synth.exceptions import ArmModelError
from synth.models.arm import CollisionScene, HeldObject, build_stanford_arm, grasp_contacts
from synth.models.manipulator import HandSpec
from synth.units import CM

HAND = HandSpec()
DOWN = pin.utils.rotate("y", math.pi)  # hand z (approach) pointing down, as BPARK (L2578)


@pytest.fixture(scope="module")
def arm():
    return build_stanford_arm(HAND)  # at the default base for the seed's workcell


def table():
    # 2 m × 2 m slab whose top face is the plane z = 0 (the world frame's table top).
    return ("table", coal.Box(2.0, 2.0, 0.05), pin.SE3(np.eye(3), np.array([0.4, 0.9, -0.025])))


def seed_box():
    # The seed's box (fixture seed_4_8): 8.90 × 7.60 × 4.90 cm, bottom centre at (45.2, 102, 0) cm.
    return (
        "BOX",
        coal.Box(0.0890, 0.0760, 0.0490),
        pin.SE3(np.eye(3), np.array([0.452, 1.02, 0.0245])),
    )


def hand_down_at(arm, x: float, y: float, z: float, spin: float = 0.0) -> np.ndarray:
    target = pin.SE3(DOWN @ pin.utils.rotate("z", spin), np.array([x, y, z]))
    solutions = arm.inverse(target)
    assert solutions, (x, y, z)
    return solutions[0]


def test_no_adjacent_pair_is_checked_and_static_pairs_are_skipped(arm):
    scene = CollisionScene(arm, [table(), seed_box()])
    parents = arm.model.parents
    joint = {b.name: b.joint for b in scene.bodies}
    role = {b.name: b.role for b in scene.bodies}
    for a, b in scene.pairs:
        ja, jb = joint[a], joint[b]
        assert not (ja == 0 and jb == 0), (a, b)
        if role[a] in ("arm", "hand") and role[b] in ("arm", "hand"):
            assert not (ja == jb or parents[ja] == jb or parents[jb] == ja), (a, b)
    assert scene.excluded[frozenset(("column", "table"))] == "static"
    assert scene.excluded[frozenset(("boom", "sleeve"))] == "adjacent"


def test_adjacent_links_would_be_false_positives(arm):
    # The boom slides inside its sleeve, so the two overlap at every configuration: checking
    # all pairs naively reports a "collision" the arm cannot avoid. The scene must not.
    naive = pin.GeometryModel()
    for body in arm.bodies:
        naive.addGeometryObject(body.geometry_object(arm.model))
    naive.addAllCollisionPairs()
    naive_data = naive.createData()
    data = arm.model.createData()
    scene = CollisionScene(arm)
    rng = np.random.default_rng(41)
    boom, sleeve = naive.getGeometryId("boom"), naive.getGeometryId("sleeve")
    k = naive.findCollisionPair(pin.CollisionPair(min(boom, sleeve), max(boom, sleeve)))
    for _ in range(50):
        q = rng.uniform(arm.limits.lower, arm.limits.upper)
        pin.computeCollisions(arm.model, data, naive, naive_data, q, False)
        assert naive_data.collisionResults[k].isCollision()
        assert ("boom", "sleeve") not in scene.collisions(q) and (
            "sleeve",
            "boom",
        ) not in scene.collisions(q)


def test_stanford_self_collisions_are_only_the_hand_hitting_the_column(arm):
    # Sampling the whole joint box, the only self-contacts are the hand swinging into the
    # column (a real collision of the arm); links never touch their non-adjacent neighbours.
    scene = CollisionScene(arm)
    real = {frozenset(("column", b)) for b in ("wrist_body", "palm", "finger_left", "finger_right")}
    rng = np.random.default_rng(42)
    for _ in range(3000):
        q = rng.uniform(arm.limits.lower, arm.limits.upper)
        for pair in scene.collisions(q):
            assert frozenset(pair) in real, pair


def test_wrist_never_collides_with_itself_even_at_the_theta5_stops(arm):
    scene = CollisionScene(arm)
    wrist = {
        "boom",
        "wrist_roll",
        "wrist_pitch",
        "wrist_body",
        "palm",
        "finger_left",
        "finger_right",
    }
    grid = np.radians([-165, -120, -60, 0, 60, 120, 165])
    for t4, t5, t6 in itertools.product(grid, np.radians([-110, -90, -45, 0, 45, 90, 110]), grid):
        q = np.array([0.0, -1.5, 0.1524, t4, t5, t6])  # boom fully retracted (6 in stop)
        for pair in scene.collisions(q):
            assert not set(pair) <= wrist, (pair, np.degrees([t4, t5, t6]))


def test_clearance_above_the_table_is_height_minus_pad_radius(arm):
    # Hand pointing down with its origin h above the table top: the finger boxes reach one pad
    # radius past the origin, so the nearest body is a finger at distance h − r_p (exact).
    scene = CollisionScene(arm, [table()])
    on_table = [i for i, p in enumerate(scene.pairs) if "table" in p]
    for h in (0.03, 0.05, 0.10):
        q = hand_down_at(arm, 0.40, 0.95, h)
        d = scene.distances(q)
        k = min(on_table, key=lambda i: d[i])
        assert math.isclose(d[k], h - HAND.finger_pad_radius, abs_tol=1e-6)
        assert set(scene.pairs[k]) & {"finger_left", "finger_right"}
    q = hand_down_at(arm, 0.40, 0.95, 0.003)  # pads 3.35 mm into the table
    assert set(scene.collisions(q)) >= {("finger_left", "table"), ("finger_right", "table")}
    assert scene.in_collision(q)


def test_box_obstacle_and_trimesh_environment_agree(arm):
    mesh = trimesh.creation.box(extents=(0.0898, 0.0760, 0.0490))  # centred like coal.Box
    name, _box, pose = seed_box()
    # Fingers 1 cm apart, so both stay over the box top whatever the hand's spin.
    primitive = CollisionScene(arm, [table(), seed_box()], opening=0.01)
    meshed = CollisionScene(arm, [table(), (name, mesh, pose)], opening=0.01)
    top = 0.049
    q = hand_down_at(arm, 0.452, 1.02, top + 0.02)  # 2 cm above the box's top face
    for scene in (primitive, meshed):
        d = scene.distances(q)
        k = next(i for i, p in enumerate(scene.pairs) if "BOX" in p and "finger_left" in p)
        assert math.isclose(d[k], 0.02 - HAND.finger_pad_radius, abs_tol=1e-6)
    q_in = hand_down_at(arm, 0.452, 1.02, top - 0.005)
    assert ("finger_left", "BOX") in primitive.collisions(q_in)
    assert ("finger_left", "BOX") in meshed.collisions(q_in)


def pin_between_fingers() -> HeldObject:
    # PIN1 (seed fixture): 2 in long, 0.635 cm diameter, held with γ = 180° at d = 3.54 cm from
    # its tip: its axis is the hand's −z, its tip 3.54 cm ahead of the hand origin.
    length, radius = 2 * 0.0254, 0.635 * CM / 2
    centre = 3.54 * CM - length / 2  # along the hand z, from the origin towards the tip
    return HeldObject.of(
        "PIN1", coal.Cylinder(radius, length), pin.SE3(np.eye(3), np.array([0, 0, centre]))
    )


def test_allowed_contacts_are_explicit(arm):
    held = pin_between_fingers()
    squeezed = 0.635 * CM - 0.0004  # pads close 0.4 mm past the pin surface (rubber pads)
    q = hand_down_at(arm, 0.40, 0.95, 0.10)
    plain = CollisionScene(arm, held=held, opening=squeezed)
    assert {("finger_left", "PIN1"), ("finger_right", "PIN1")} <= set(plain.collisions(q))
    grasped = CollisionScene(arm, held=held, opening=squeezed, allowed=grasp_contacts("PIN1"))
    assert grasped.collisions(q) == []
    assert grasped.excluded[frozenset(("finger_left", "PIN1"))] == "allowed"
    # Pin in its hole: the pin's tip enters the box; only the declared pair is exempt.
    inserted = hand_down_at(arm, 0.452, 1.02, 0.049 + 3.54 * CM - 1.71 * CM)
    scene = CollisionScene(
        arm, [seed_box()], held=held, opening=squeezed, allowed=grasp_contacts("PIN1")
    )
    assert ("PIN1", "BOX") in scene.collisions(inserted)
    allowed = set(grasp_contacts("PIN1")) | {frozenset(("PIN1", "BOX"))}
    assert scene.with_held(held, allowed).collisions(inserted) == []
    # The fingers would still be caught if they hit the box.
    too_low = hand_down_at(arm, 0.452, 1.02, 0.049 - 0.005)
    assert ("finger_left", "BOX") in scene.with_held(held, allowed).collisions(too_low)


def test_bad_scenes_are_reported(arm):
    with pytest.raises(ArmModelError, match="used twice"):
        CollisionScene(arm, [("palm", coal.Sphere(0.1), pin.SE3.Identity())])
    with pytest.raises(ArmModelError, match="unknown bodies"):
        CollisionScene(arm, [table()], allowed=[("finger_left", "PIN9")])
    with pytest.raises(ArmModelError, match="opening"):
        CollisionScene(arm, opening=1.0)


def test_finger_opening_moves_the_fingers(arm):
    # Fingers open by w: the inner faces sit at x = ±w/2 in the hand frame (module hand).
    q = np.array([0.0, -1.5, 0.4, 0.0, 1.0, 0.0])
    for w in (0.0, 0.02, HAND.max_opening):
        scene = CollisionScene(arm, opening=w)
        hand = arm.forward(q)
        left = hand.actInv(scene.body_pose(q, "finger_left")).translation
        right = hand.actInv(scene.body_pose(q, "finger_right")).translation
        assert math.isclose(right[0] - left[0], w + HAND.finger_thickness, abs_tol=1e-12)


def test_hull_bounds_underestimate_and_are_exact_near_contact(arm):
    # A box with a drilled hole (concave mesh) and the pin held inside the hole, 1.8 mm from
    # the wall: the hole's convex hull is solid, so the hull distance is ≤ 0, yet the exact
    # mesh distance is the radial clearance, 5.0 − 3.175 mm (minus the mesh's polygon sag).
    block = trimesh.creation.box(extents=(0.06, 0.06, 0.04))
    drill = trimesh.creation.cylinder(radius=0.005, height=0.1, sections=64)
    drilled = block.difference(drill)
    pose = pin.SE3(np.eye(3), np.array([0.45, 1.0, 0.02]))  # top face at z = 4 cm
    held = pin_between_fingers()
    q = hand_down_at(arm, 0.45, 1.0, 0.04 + 3.54 * CM - 1.0 * CM)  # tip 1 cm down the hole
    scene = CollisionScene(
        arm, [("BLOCK", drilled, pose)], held=held, opening=0.0, allowed=grasp_contacts("PIN1")
    )
    k = scene.pairs.index(("PIN1", "BLOCK"))
    exact = scene.distances(q)
    loose = scene.distance_bounds(q, exact_below=-1.0)  # hulls only
    assert loose[k] <= 0.0 < exact[k]
    sag = 0.005 * (1 - math.cos(math.pi / 64))  # chord inset of a 64-gon
    assert math.isclose(exact[k], 0.005 - 0.003175 - sag, abs_tol=2e-5)
    assert np.all(loose <= exact + 1e-5)  # up to Coal's GJK tolerance (~1e-6 m)
    tight = scene.distance_bounds(q, exact_below=0.001)
    assert math.isclose(tight[k], exact[k], rel_tol=1e-9)
    assert not scene.in_collision(q)
