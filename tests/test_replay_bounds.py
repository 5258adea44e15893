"""The fast path's proven bounds (issue 14), checked by Monte Carlo through the real kinematics.

:mod:`synth.replay.bounds` and :mod:`synth.replay.advance` step a conservative advancement by
bounds on how far points move along a joint-space segment: |p(s+h) − p(s)| ≤ h·V(s) + ½·A·h²
with V(s) from the joint velocities at s and A a second-order bound. Each test samples the
motion itself (Pinocchio's forward kinematics at many s, points of the bodies, Coal's distances
densely along a segment) and checks the bound against what it sampled, never against the
bound's own formulas.
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_PROGRAM, SEED_TASK

from synth.models.arm import SweepOptions
from synth.replay import machine_for, replay_context
from synth.replay.advance import PairMotion, fast_sweep
from synth.replay.bounds import ArmChain, PinExtent, PinFlight, safe_step
from synth.replay.contact import GJK_MARGIN, PinGeometry, Target, pin_points
from synth.replay.motion import Segment
from synth.replay.truth import HandErrors, nominal_world


@pytest.fixture(scope="module")
def cell():  # type: ignore[no-untyped-def]
    context = replay_context(SEED_PROGRAM.read_text(encoding="utf-8"), SEED_TASK)
    machine = machine_for(context, nominal_world(context.graph), HandErrors.none())
    return context, machine


def random_error(rng: np.random.Generator, size: float) -> pin.SE3:
    return pin.SE3(pin.exp3(rng.normal(scale=size, size=3)), rng.normal(scale=size, size=3))


def random_segment(rng: np.random.Generator, limits, spread: float) -> Segment:  # type: ignore[no-untyped-def]
    q0 = rng.uniform(limits.lower, limits.upper)
    q1 = np.clip(q0 + rng.normal(scale=spread, size=q0.size), limits.lower, limits.upper)
    return Segment(q0, q1, random_error(rng, 2e-3), random_error(rng, 2e-3), 0.0, 1.0)


def pin_setup(cell):  # type: ignore[no-untyped-def]
    """The context, the arm's chain and the pin's vertices (pin frame, columns)."""
    context, machine = cell
    state = next(iter(machine.pins.values()))
    return context, ArmChain.of(context.arm), pin_points(state.model)


def test_safe_step_is_the_quadratics_root() -> None:
    # gap − r·τ − ½Aτ² = 0 at τ = (−r + √(r² + 2Ag))/A
    for gap, rate, curvature in [(0.01, 0.07, 0.05), (0.002, -0.03, 0.4), (0.5, 1.2, 2.7)]:
        tau = (-rate + np.sqrt(rate * rate + 2 * curvature * gap)) / curvature
        assert safe_step(gap, rate, curvature) == pytest.approx(tau, rel=1e-12)
    assert safe_step(0.01, 0.1, 0.0) == pytest.approx(0.1)
    assert safe_step(0.01, -0.1, 0.0) == np.inf  # moving away, no curvature: never
    assert safe_step(0.0, 0.1, 1.0) == 0.0


def test_the_pins_points_move_no_faster_than_its_bound(cell) -> None:  # type: ignore[no-untyped-def]
    # every vertex of the pin, at 40 instants of 200 random segments, against the motion
    # sampled with Pinocchio: displacement over h ≤ h·V(s) + ½Ah², and along random unit
    # directions n, −n·(displacement) ≤ h·a(n) + ½Ah² (the approach rate)
    context, chain, points = pin_setup(cell)
    rng = np.random.default_rng(1)
    worst = worst_along = -np.inf
    tightest = np.inf
    for _ in range(200):
        seg = random_segment(rng, context.arm.limits, 0.3)
        grip = pin.SE3(pin.exp3(rng.normal(scale=0.5, size=3)), rng.normal(scale=0.02, size=3))
        flight = PinFlight(chain, seg, PinExtent.of(chain, grip, points))
        for s in rng.uniform(0.0, 0.9, 40):
            h = float(rng.uniform(0.0, 1.0 - s))
            flight.at(s)
            here = flight.rotation @ points + flight.translation[:, None]
            speed, normals = flight.speed, rng.normal(size=(4, 3))
            normals /= np.linalg.norm(normals, axis=1, keepdims=True)
            rates = flight.approach(normals)
            flight.at(s + h)
            there = flight.rotation @ points + flight.translation[:, None]
            moved = np.linalg.norm(there - here, axis=0)
            bound = h * speed + 0.5 * flight.curvature * h * h
            worst = max(worst, float(np.max(moved) - bound))
            if h > 1e-3:
                tightest = min(tightest, bound / max(float(np.max(moved)), 1e-12))
            approach = -(normals @ (there - here))  # along −n, per vertex
            bound_along = h * rates + 0.5 * flight.curvature * h * h
            worst_along = max(worst_along, float(np.max(approach - bound_along[:, None])))
    assert worst <= 1e-12
    assert worst_along <= 1e-12
    assert tightest < 1.5  # the bound is not vacuous: somewhere it is within 50 % of the motion


def test_the_pins_second_derivative_is_within_its_curvature(cell) -> None:  # type: ignore[no-untyped-def]
    # central second differences of the vertices' positions, step 1e-3, against A
    context, chain, points = pin_setup(cell)
    rng = np.random.default_rng(2)
    ratio = 0.0
    for _ in range(100):
        seg = random_segment(rng, context.arm.limits, 0.6)
        grip = pin.SE3(np.eye(3), np.array([0, 0, 0.03]))
        flight = PinFlight(chain, seg, PinExtent.of(chain, grip, points))
        step = 1e-3
        for s in rng.uniform(step, 1.0 - step, 10):
            y = []
            for x in (s - step, s, s + step):
                flight.at(x)
                y.append(flight.rotation @ points + flight.translation[:, None])
            second = np.linalg.norm(y[0] - 2 * y[1] + y[2], axis=0) / step**2
            ratio = max(ratio, float(np.max(second)) / flight.curvature)
    assert ratio <= 1.0 + 1e-3  # finite differences of a C² path: within rounding of A
    assert ratio > 0.05


def test_pair_rates_bound_the_bodies_relative_motion(cell) -> None:  # type: ignore[no-untyped-def]
    # points in each body's ball, fixed in its joint frame, moved along the segment with only
    # the pair's joints (the distance depends on nothing else): their displacement over h is
    # within the sum of both bodies' bounds h·a + ½Ah²
    from synth.replay.advance import _measure_pairs, closing_rates
    from synth.replay.bounds import curvatures

    context, machine = cell
    scene = machine.scene()
    chain = ArmChain.of(context.arm)
    motion = PairMotion.of(scene)
    model, data = context.arm.model, context.arm.model.createData()
    rng = np.random.default_rng(3)
    worst = -np.inf
    exact_below = np.full(len(scene.pairs), 1e-3)
    for _ in range(80):
        seg = random_segment(rng, context.arm.limits, 0.4)
        delta = seg.q1 - seg.q0
        levers = chain.levers(motion.supports, motion.radii, seg.q0, seg.q1)
        k = int(rng.integers(len(scene.pairs)))
        sides = motion.sides[[k]]
        signed = delta[None, None, :] * motion.masks[[k]]
        curvature = sum(
            float(curvatures(chain.revolute, levers[[p]], np.abs(signed[:, i]))[0])
            for i, p in enumerate(sides[0])
        )
        s = float(rng.uniform(0.0, 0.8))
        h = float(rng.uniform(0.0, 0.2))
        here = _measure_pairs(scene, seg.q0 + s * delta, exact_below, np.array([k]))
        rate = float(closing_rates(here, motion, sides, signed)[0])
        moved = 0.0
        for side, body in enumerate(sides[0]):
            direction = rng.normal(size=(3, 50))
            radius = motion.radii[body] * rng.uniform(0, 1, 50) ** (1 / 3)
            local = direction / np.linalg.norm(direction, axis=0) * radius
            ends = []
            for x in (0.0, h):
                pin.forwardKinematics(model, data, seg.q0 + s * delta + x * signed[0, side])
                frame = data.oMi[int(motion.joints[body])]
                ends.append(frame.rotation @ local + frame.translation[:, None])
            moved += float(np.max(np.linalg.norm(ends[1] - ends[0], axis=0)))
        worst = max(worst, moved - (h * rate + 0.5 * curvature * h * h))
    assert worst <= 1e-12


def test_the_two_ended_floor_is_the_least_of_the_larger_bound() -> None:
    # against a dense grid of τ: min over τ of max(f0(τ), f1(τ))
    from synth.replay.advance import two_ended_floor

    rng = np.random.default_rng(6)
    d0, d1 = rng.uniform(0, 0.05, 200), rng.uniform(0, 0.05, 200)
    a0, a1 = rng.uniform(0, 0.3, 200), rng.uniform(0, 0.3, 200)
    curvature = rng.uniform(0, 2.0, 200)
    for length in (1.0, 0.3):
        tau = np.linspace(0.0, length, 20001)[:, None]
        f0 = d0 - a0 * tau - 0.5 * curvature * tau**2
        f1 = d1 - a1 * (length - tau) - 0.5 * curvature * (length - tau) ** 2
        grid = np.min(np.maximum(f0, f1), axis=0)
        floor = two_ended_floor(d0, a0, d1, a1, curvature, length)
        assert np.all(floor <= grid + 1e-12)
        assert np.all(floor >= grid - 2e-4)  # the grid's spacing times the slopes


def test_plane_and_witness_bounds_stay_below_coals_distances(cell) -> None:  # type: ignore[no-untyped-def]
    # the half-space separations of a box or a mesh's hull are lower bounds on Coal's
    # distance, and the separation along Coal's witness direction nearly equals it
    _, machine = cell
    state = next(iter(machine.pins.values()))
    pin_ = PinGeometry(state.model)
    points = pin_points(state.model)
    rng = np.random.default_rng(4)
    for obstacle in machine.workcell.obstacles:
        target = Target(obstacle)
        assert target.normals is not None and target.offsets is not None
        hull_gaps = []
        witnessed = 0
        for _ in range(300):
            rotation = pin.exp3(rng.normal(size=3))
            place = obstacle.pose.translation + rng.uniform(-0.15, 0.15, 3) + [0, 0, 0.03]
            pose = pin.SE3(rotation, place)
            world = rotation @ points + place[:, None]
            planes = float(np.max(np.min(target.normals @ world, axis=1) - target.offsets))
            d, normal = pin_.separation(pose, target, exact=False)
            assert planes <= d + 1e-9
            hull_gaps.append(d - planes)
            if d <= 1e-4:
                continue
            # the separation along Coal's witness direction, computed from the vertices, is a
            # lower bound on the true distance and Coal's d an upper one (two points of the
            # solids): they agree within GJK_MARGIN·d, the margin the fast path takes off d
            n = -normal / np.linalg.norm(normal)  # from the obstacle towards the pin
            support = _support(target.hull, target, -n)  # max over the obstacle of n·x
            separation = float(np.min(n @ world)) - support
            # (the upper side in rounding: Coal's d is the distance of two witness points it
            # forms from barycentric weights, and a run failed a 1e-12 m allowance by 2.5e-12;
            # 1e-9 m is still 10⁻⁵ of the smallest d checked here, 1e-4 m)
            assert d * (1.0 - GJK_MARGIN) <= separation <= d + 1e-9
            witnessed += 1
        assert min(hull_gaps) < 1e-6  # the planes are exact where a face is nearest
        assert witnessed > 100


def _support(hull: coal.CollisionGeometry, target: Target, direction: np.ndarray) -> float:
    """max over the obstacle of −direction·x, from its hull's points (a box: its corners)."""
    if isinstance(hull, coal.Box):
        half = np.asarray(hull.halfSide)
        corners = np.array(np.meshgrid(*[[-h, h] for h in half])).reshape(3, -1)
    else:
        corners = np.asarray(hull.points()).T
    pose = target.obstacle.pose
    world = pose.rotation @ corners + pose.translation[:, None]
    return float(np.max(-direction @ world))


def test_fast_sweeps_never_step_over_half_the_clearance(cell) -> None:  # type: ignore[no-untyped-def]
    # Coal's distances at 400 points of each random segment are the truth: a segment whose
    # pairs all stay beyond c is free, one whose closest pair comes within c/2 is not, and a
    # hit is within c there
    context, machine = cell
    scene = machine.scene()
    chain = ArmChain.of(context.arm)
    limits = context.arm.limits
    rng = np.random.default_rng(5)
    clearance = 1e-3
    options = SweepOptions(clearance=clearance)
    free = hit = 0
    for _ in range(40):
        q0 = rng.uniform(limits.lower, limits.upper)
        q1 = rng.uniform(limits.lower, limits.upper)
        if np.min(scene.distances(q0)) <= clearance:
            continue  # starts in contact: the relaxed clearance applies, tested elsewhere
        result = fast_sweep(scene, chain, q0, q1, options)
        # distance_bounds is exact wherever a pair is within the clearance (meshes), a lower
        # bound elsewhere, so `truth` decides both tests below as the exact minimum would
        truth = min(
            float(np.min(scene.distance_bounds(q0 + x * (q1 - q0), exact_below=clearance)))
            for x in np.linspace(0, 1, 400)
        )
        if truth > clearance + 1e-6:
            assert result.free
            free += 1
        if truth < 0.5 * clearance - 1e-6:
            assert not result.free
            hit += 1
        if not result.free:
            assert result.distance <= clearance
            k = scene.pairs.index(result.pair)
            assert scene.distances(result.q)[k] == pytest.approx(result.distance, abs=2e-6)
    assert free >= 3 and hit >= 3
