"""Swept checks: the Lipschitz bounds against finite differences, a 1 mm plate that a fixed-count
check steps over but conservative advancement cannot, and free paths confirmed by dense sampling."""

from __future__ import annotations

import itertools
import math

import coal
import numpy as np
import pinocchio as pin
import pytest

from synth.models.arm import (
    CollisionScene,
    SweepOptions,
    build_stanford_arm,
    plan_trajectory,
    swept_path,
    swept_segment,
    swept_trajectory,
)
from synth.models.manipulator import HandSpec

DOWN = pin.utils.rotate("y", math.pi)
SPIN = pin.utils.rotate("z", math.pi / 2)  # fingers side by side across the motion


@pytest.fixture(scope="module")
def arm():
    return build_stanford_arm(HandSpec())


def plate(x: float):
    # 1 mm thick (along x), 30 cm wide, 12 cm tall, standing on the table at x.
    return ("plate", coal.Box(0.001, 0.3, 0.12), pin.SE3(np.eye(3), np.array([x, 1.0, 0.06])))


@pytest.fixture(scope="module")
def path(arm):
    """Hand pointing down at 8 cm, carried 25 cm along world x (same arm branch at both ends)."""
    q0 = arm.inverse(pin.SE3(DOWN @ SPIN, np.array([0.40, 1.0, 0.08])))[0]
    ends = arm.inverse(pin.SE3(DOWN @ SPIN, np.array([0.65, 1.0, 0.08])))
    q1 = min(ends, key=lambda s: float(np.max(np.abs(s - q0))))
    return q0, q1


def shape_points(body) -> np.ndarray:
    """Extreme points of a shape (box corners, cylinder rims, sphere surface) in its joint frame."""
    g = body.geometry
    if isinstance(g, coal.Box):
        local = np.array(list(itertools.product(*[(-h, h) for h in g.halfSide])))
    elif isinstance(g, coal.Cylinder):
        a = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        rim = np.column_stack([g.radius * np.cos(a), g.radius * np.sin(a)])
        local = np.vstack(
            [np.column_stack([rim, np.full(16, z)]) for z in (-g.halfLength, g.halfLength)]
        )
    elif isinstance(g, coal.Sphere):
        u = np.random.default_rng(0).normal(size=(32, 3))
        local = g.radius * u / np.linalg.norm(u, axis=1, keepdims=True)
    else:
        raise AssertionError(type(g))
    return (body.placement.rotation @ local.T).T + body.placement.translation


def test_point_speed_bounds_hold_against_finite_differences(arm):
    # |∂p/∂q_j| ≤ ρ_bj for the extreme points of every body, at random configurations.
    scene = CollisionScene(arm)
    data = arm.model.createData()
    rng = np.random.default_rng(51)
    h = 1e-6
    for _ in range(40):
        q = rng.uniform(arm.limits.lower + 1e-3, arm.limits.upper - 1e-3)
        pin.forwardKinematics(arm.model, data, q)
        base = [data.oMi[j].copy() for j in range(arm.model.njoints)]
        for j in range(6):
            pin.forwardKinematics(arm.model, data, q + h * np.eye(6)[j])
            for b, body in enumerate(scene.bodies):
                if body.joint == 0:
                    continue
                pts = shape_points(body)
                moved = (data.oMi[body.joint].rotation @ pts.T).T + data.oMi[body.joint].translation
                before = (base[body.joint].rotation @ pts.T).T + base[body.joint].translation
                speed = np.max(np.linalg.norm(moved - before, axis=1)) / h
                assert speed <= scene.body_bounds[b, j] * (1 + 1e-6) + 1e-6, (body.name, j)


def test_pair_distance_is_lipschitz_with_the_pair_bound(arm, path):
    # |d(q') − d(q)| ≤ m·|q' − q| over finite steps, for every checked pair (self and table).
    table = ("table", coal.Box(2.0, 2.0, 0.05), pin.SE3(np.eye(3), np.array([0.4, 0.9, -0.025])))
    scene = CollisionScene(arm, [table, plate(0.50)])
    rng = np.random.default_rng(52)
    for _ in range(60):
        q = rng.uniform(arm.limits.lower, arm.limits.upper)
        dq = rng.normal(size=6) * 0.05
        q2 = np.clip(q + dq, arm.limits.lower, arm.limits.upper)
        d1, d2 = scene.distances(q), scene.distances(q2)
        bound = scene.pair_bounds @ np.abs(q2 - q)
        positive = (d1 > 0) & (d2 > 0)  # penetration depths are not distances
        assert np.all(np.abs(d2 - d1)[positive] <= bound[positive] + 1e-6)


def test_thin_plate_is_not_stepped_over(arm, path):
    q0, q1 = path
    scene = CollisionScene(arm, [plate(0.50)])
    assert not scene.in_collision(q0) and not scene.in_collision(q1)
    # Ground truth by dense sampling: the fingers cross the plate on a short stretch of the path.
    s = np.linspace(0.0, 1.0, 4001)
    hits = s[[scene.in_collision(q0 + t * (q1 - q0)) for t in s]]
    assert hits.size and hits.max() - hits.min() < 0.08
    # A fixed count of 11 samples (every 0.1) steps right over it ...
    assert not any(scene.in_collision(q0 + k / 10 * (q1 - q0)) for k in range(11))
    # ... conservative advancement cannot: it stops before the first contact.
    result = swept_segment(scene, q0, q1)
    assert not result.free
    assert result.s <= hits.min() and "plate" in result.pair
    assert result.distance <= SweepOptions().clearance


def test_free_path_is_confirmed_by_dense_sampling(arm, path):
    q0, q1 = path
    scene = CollisionScene(arm, [plate(0.75)])  # beyond the end of the move
    result = swept_segment(scene, q0, q1)
    assert result.free and result.s == 1.0
    on_plate = [i for i, p in enumerate(scene.pairs) if "plate" in p]
    dense = min(
        scene.distances(q0 + t * (q1 - q0))[on_plate].min() for t in np.linspace(0, 1, 1001)
    )
    assert dense > 0
    # The step count follows the clearance, not a fixed number: a plate just past the end of
    # the move (fingers stop 1 cm short of it) takes more checks than one far away.
    near = swept_segment(CollisionScene(arm, [plate(0.67)]), q0, q1)
    far = swept_segment(CollisionScene(arm, [plate(1.5)]), q0, q1)
    assert near.free and far.free and far.checks < near.checks


def test_polyline_and_timed_trajectory_checks(arm, path):
    q0, q1 = path
    mid = q0 + 0.5 * (q1 - q0)  # a via on the straight line: the polyline equals the segment
    scene = CollisionScene(arm, [plate(0.50)])
    hit = swept_path(scene, [q0, mid, q1])
    assert not hit.free and hit.s < 1.0  # in the first half (s = segment index + fraction)
    trajectory = plan_trajectory(arm.limits, [q0, q1])
    timed = swept_trajectory(scene, trajectory.position, trajectory.duration, arm.limits.velocity)
    # The timed path runs along the same joint-space line, its rest-to-rest profile symmetric
    # in time (half way at T/2), so it hits in its first half, where the straight segment does:
    # at the same fraction of the line to within the 1 mm clearance over the 25 cm carry.
    assert not timed.free and 0.0 < timed.s < trajectory.duration / 2
    along = trajectory.position(timed.s) - q0
    fraction = float(along @ (q1 - q0) / ((q1 - q0) @ (q1 - q0)))
    assert np.allclose(along, fraction * (q1 - q0), atol=1e-12)
    assert abs(fraction - swept_segment(scene, q0, q1).s) < 0.001 / 0.25
    free = swept_trajectory(
        CollisionScene(arm, [plate(0.75)]),
        trajectory.position,
        trajectory.duration,
        arm.limits.velocity,
    )
    assert free.free and math.isclose(free.s, trajectory.duration)


def test_margins_widen_the_clearance_of_named_bodies(arm, path):
    # A body believed where it may not be (an uncertain obstacle) must be passed by its margin
    # too. Ground truth: the closest approach to a plate 2 cm past the move's end, densely sampled.
    q0, q1 = path
    scene = CollisionScene(arm, [plate(0.67)])
    on_plate = [i for i, p in enumerate(scene.pairs) if "plate" in p]
    closest = min(
        scene.distances(q0 + t * (q1 - q0))[on_plate].min() for t in np.linspace(0, 1, 2001)
    )
    clearance = SweepOptions().clearance
    assert closest > clearance + 0.004
    roomy = SweepOptions(margins={"plate": closest - clearance - 0.002})
    assert swept_segment(scene, q0, q1, roomy).free
    tight = SweepOptions(margins={"plate": closest - clearance + 0.001})
    result = swept_segment(scene, q0, q1, tight)
    assert not result.free and "plate" in result.pair
    # The stop is where the pair first comes within clearance + margin, found in few steps:
    # each step covers at least clearance/M (no Zeno approach to the margin).
    assert result.distance <= clearance + tight.margins["plate"] + 1e-9
    assert result.checks < 2_000
    # Margins of both bodies add: split over the closest pair, the same stop.
    body = next(name for name in result.pair if name != "plate")
    half = tight.margins["plate"] / 2
    split = swept_segment(scene, q0, q1, SweepOptions(margins={"plate": half, body: half}))
    assert not split.free and split.s == pytest.approx(result.s, abs=1e-6)
    assert tight.required([("plate", "palm")])[0] == pytest.approx(
        clearance + tight.margins["plate"]
    )
