"""Motion time: the quintic rule against the quintic's own derivatives, ruckig durations against
the closed-form bang-coast-bang profiles, via points, limits along the trajectory, and the
seed's rule (L3846) worked by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from synth.exceptions import TrajectoryError
from synth.models.arm import (
    JIFFY,
    SEED_GRACE,
    JointLimits,
    TimingOptions,
    build_stanford_arm,
    motion_time,
    plan_trajectory,
    quintic_motion_time,
    seed_motion_time,
)
from synth.models.manipulator import HandSpec
from synth.replay.motion import quintic


@pytest.fixture(scope="module")
def limits() -> JointLimits:
    return build_stanford_arm(HandSpec()).limits


def rest_to_rest(distance: float, v: float, a: float) -> float:
    """Time-optimal rest-to-rest time under |q̇| ≤ v, |q̈| ≤ a (no jerk limit).

    Trapezoid when the distance allows reaching v (D ≥ v²/a): T = D/v + v/a; else triangle
    T = 2·√(D/a).
    """
    return distance / v + v / a if distance >= v * v / a else 2 * math.sqrt(distance / a)


def _derivatives(delta: np.ndarray, duration: float) -> list[np.ndarray]:
    """Peak |q′|, |q″|, |q‴| per joint of q0 + Δq·quintic(t/T), by finite differences of the
    replay's own time law on 20 001 points (the closed forms are not used)."""
    t = np.linspace(0.0, duration, 20_001)
    h = t[1] - t[0]
    q = np.array([quintic(x / duration) for x in t])[:, None] * delta[None, :]
    peaks = []
    for _ in range(3):
        q = np.diff(q, axis=0) / h
        peaks.append(np.max(np.abs(q), axis=0))
    return peaks


@pytest.mark.parametrize("jerk", [None, [40.0, 20.0, 10.0, 40.0, 40.0, 60.0]])
def test_the_quintic_rule_keeps_every_joint_within_its_limits_and_meets_one(limits, jerk):
    # What the replay plays: each segment Δq over its duration with s(τ) = 10τ³ − 15τ⁴ + 6τ⁵.
    lim = limits if jerk is None else limits.replace(jerk=jerk)
    rng = np.random.default_rng(11)
    q0 = np.array([0.0, -1.5, 0.3, 0.0, 0.5, 0.0])
    for scale in (0.002, 0.02, 0.3):  # jerk-, acceleration- and speed-bound moves
        delta = rng.uniform(-1.0, 1.0, 6) * scale * (lim.upper - lim.lower) / 4
        q1 = np.clip(q0 + delta, lim.lower, lim.upper)
        duration = motion_time(lim, [q0, q1]).duration
        assert duration == quintic_motion_time(lim, [q0, q1]).duration
        bounds = (lim.velocity, lim.acceleration, lim.jerk)
        peaks = _derivatives(q1 - q0, duration)
        ratios = [p / b for p, b in zip(peaks, bounds, strict=True) if b is not None]
        # within its limits and the shortest such quintic: some joint reaches one of them
        # (third differences on steps of T/20 000 carry a rounding of a few 1e-4)
        worst = max(float(np.max(r)) for r in ratios)
        assert 1.0 - 2e-3 < worst <= 1.0 + 1e-3


def test_single_joint_moves_match_the_closed_form(limits):
    q0 = np.array([0.0, -1.5, 0.3, 0.0, 0.5, 0.0])
    for joint, delta in [(0, 1.2), (0, 0.1), (2, 0.4), (2, 0.02), (5, -2.0)]:
        q1 = q0.copy()
        q1[joint] += delta
        expected = rest_to_rest(abs(delta), limits.velocity[joint], limits.acceleration[joint])
        assert math.isclose(
            motion_time(limits, [q0, q1], rule="ruckig").duration, expected, rel_tol=1e-9
        )


def test_multi_joint_move_takes_the_slowest_joint(limits):
    q0 = np.array([0.0, -1.5, 0.3, 0.0, 0.5, 0.0])
    q1 = np.array([0.8, -1.0, 0.5, 1.0, -0.5, 2.0])
    expected = max(
        rest_to_rest(abs(d), v, a)
        for d, v, a in zip(q1 - q0, limits.velocity, limits.acceleration, strict=True)
    )
    assert math.isclose(
        motion_time(limits, [q0, q1], rule="ruckig").duration, expected, rel_tol=1e-9
    )


def test_jerk_limited_move_matches_closed_form():
    # One joint reaching both v and a: T = D/v + v/a + a/j (jerk-limited S-curve).
    lim = JointLimits(
        ("j",),
        ("revolute",),
        np.array([-10.0]),
        np.array([10.0]),
        np.array([1.0]),
        np.array([2.0]),
        np.array([8.0]),
    )
    t = motion_time(lim, [np.array([0.0]), np.array([3.0])], rule="ruckig").duration
    assert math.isclose(t, 3.0 / 1.0 + 1.0 / 2.0 + 2.0 / 8.0, rel_tol=1e-9)


def test_via_points_blend_and_stopping_is_the_sum_of_rest_to_rest_moves(limits):
    q0 = np.array([0.0, -1.6, 0.3, 0.0, 1.0, 0.0])
    q1 = np.array([0.5, -1.2, 0.5, 0.3, 0.5, 1.0])
    q2 = np.array([1.0, -1.0, 0.7, 0.6, 0.2, 2.0])
    stopped = motion_time(
        limits, [q0, q1, q2], rule="ruckig", options=TimingOptions(blend_vias=False)
    )
    for (a, b), seg in zip([(q0, q1), (q1, q2)], stopped.segments, strict=True):
        assert math.isclose(seg, motion_time(limits, [a, b], rule="ruckig").duration, rel_tol=1e-9)
    blended = motion_time(limits, [q0, q1, q2], rule="ruckig")
    assert blended.duration < stopped.duration  # every joint keeps its direction through q1


def test_trajectory_passes_vias_and_respects_limits(limits):
    q0 = np.array([0.0, -1.6, 0.3, 0.0, 1.0, 0.0])
    q1 = np.array([0.5, -1.2, 0.5, 0.3, 0.5, 1.0])
    q2 = np.array([0.2, -1.0, 0.7, 0.6, 0.2, 2.0])  # θ1 reverses at q1
    trajectory = plan_trajectory(limits, [q0, q1, q2])
    first = trajectory.durations[0]
    assert np.allclose(trajectory.position(first), q1, atol=1e-9)
    assert np.allclose(trajectory.position(trajectory.duration), q2, atol=1e-9)
    assert trajectory.via_velocities[0][0] == 0.0  # reversing joint stops at the via
    times, qs = trajectory.sample(0.002)
    speeds = np.abs(np.diff(qs, axis=0)) / np.diff(times)[:, None]
    assert np.all(speeds <= limits.velocity * (1 + 1e-6))
    assert np.all(qs >= limits.lower - 1e-9) and np.all(qs <= limits.upper + 1e-9)


def test_seed_rule_by_hand(limits):
    # Per joint |Δq|/v̄ with v̄ = (8/15)·v_max, the slowest joint, plus 20 jiffies (L3846).
    q0 = np.array([0.0, -1.5, 0.3, 0.0, 0.5, 0.0])
    q1 = np.array([0.6, -1.2, 0.5, 0.0, 0.5, 0.0])
    # θ1: 0.6 rad at (8/15)·2 rad/s = 0.5625 s; θ2: 0.3 at 8/15 = 0.5625 s; S3: 0.2 m at
    # (8/15)·0.5 m/s = 0.75 s → the boom is the slowest joint.
    expected = 0.2 / (0.5 * 8 / 15) + 20 / 60
    assert math.isclose(seed_motion_time(limits, [q0, q1]).duration, expected, rel_tol=1e-12)
    assert math.isclose(
        motion_time(limits, [q0, q1], rule="seed").duration, expected, rel_tol=1e-12
    )
    assert math.isclose(SEED_GRACE, 20 * JIFFY) and math.isclose(JIFFY, 1 / 60)
    # Via points: segment times add, the grace is paid once per move.
    mid = (q0 + q1) / 2
    assert math.isclose(seed_motion_time(limits, [q0, mid, q1]).duration, expected, rel_tol=1e-12)


def test_bad_moves_are_reported(limits):
    q0 = np.array([0.0, -1.5, 0.3, 0.0, 0.5, 0.0])
    outside = q0.copy()
    outside[1] = 0.2  # θ2 above its −5° stop
    with pytest.raises(TrajectoryError, match="outside the joint limits"):
        motion_time(limits, [q0, outside])
    with pytest.raises(TrajectoryError, match="expected 6"):
        motion_time(limits, [q0, q0[:3]])
    assert motion_time(limits, [q0]).duration == 0.0
