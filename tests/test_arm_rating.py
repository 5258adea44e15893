"""Rating arm solutions the seed's way, |45° − θ5| (L2086–2100), and through the rating hook."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from synth.exceptions import UnreachableError
from synth.models.arm import (
    SEED_GRASP_RATING,
    JointAngleRating,
    JointMarginRating,
    best_solution,
    build_stanford_arm,
    rank_solutions,
)
from synth.models.manipulator import HandSpec
from synth.units import DEG


@pytest.fixture(scope="module")
def arm():
    return build_stanford_arm(HandSpec(), pin.SE3.Identity())


def test_seed_cost_is_distance_of_theta5_from_45_degrees(arm):
    q = np.array([0.3, -1.2, 0.5, -0.4, 30 * DEG, 0.2])
    assert math.isclose(SEED_GRASP_RATING(arm, q), 15 * DEG, rel_tol=1e-12)
    q[4] = -30 * DEG
    assert math.isclose(SEED_GRASP_RATING(arm, q), 75 * DEG, rel_tol=1e-12)


def test_wrist_flip_solutions_are_ranked_by_theta5(arm):
    # The two attainable solutions differ in the sign of θ5 (L961); the seed prefers θ5 near
    # +45°, so the positive one ranks first whatever order the inverse returned them in.
    q = np.array([0.4, -1.3, 0.5, -0.5, -50 * DEG, -0.3])
    solutions = arm.inverse(arm.forward(q))
    assert len(solutions) == 2
    ranked = rank_solutions(arm, solutions)
    assert ranked[0].q[4] > 0 and math.isclose(
        ranked[0].cost, abs(45 * DEG - 50 * DEG), abs_tol=1e-9
    )
    assert math.isclose(ranked[1].cost, 95 * DEG, abs_tol=1e-9)
    assert [r.index for r in rank_solutions(arm, solutions[::-1])] == [1, 0]


def test_ties_keep_input_order_and_other_ratings_plug_in(arm):
    q = np.array([0.0, -1.5, 0.5, 0.0, 45 * DEG, 0.0])
    ranked = rank_solutions(arm, [q, q.copy()])
    assert [r.index for r in ranked] == [0, 1]
    # Joint-limit margin: mid-range everywhere scores −0.5; on a stop scores 0.
    mid = (arm.limits.lower + arm.limits.upper) / 2
    margin = JointMarginRating()
    assert math.isclose(margin(arm, mid), -0.5)
    assert math.isclose(margin(arm, arm.limits.lower), 0.0)
    ranked = rank_solutions(arm, [arm.limits.lower, mid], margin)
    assert ranked[0].index == 1
    # Any joint, any preferred angle.
    assert math.isclose(JointAngleRating(joint=0, preferred=0.0)(arm, q), 0.0)


def test_best_solution_or_a_clear_unreachable_error(arm):
    q = np.array([0.4, -1.3, 0.5, -0.5, -50 * DEG, -0.3])
    best = best_solution(arm, arm.forward(q))
    assert best.q[4] > 0  # the wrist flip with θ5 = +50°, 5° from the seed's ideal
    far = pin.SE3(np.eye(3), np.array([2.0, 0.0, 0.4]))
    with pytest.raises(UnreachableError, match="unreachable") as info:
        best_solution(arm, far)
    assert info.value.translation == (2.0, 0.0, 0.4)
    assert "joint limits" in info.value.reason
