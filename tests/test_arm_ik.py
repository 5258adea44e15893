"""Damped-least-squares IK: Jacobian vs finite differences, solutions checked against the Stanford
closed form and forward kinematics, joint limits, failures carrying problem and result."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from synth.exceptions import NoSolutionFound
from synth.models.arm import IKOptions, build_ik, build_stanford_arm, solve_ik, solve_ik_all
from synth.models.manipulator import HandSpec


@pytest.fixture(scope="module")
def stanford():
    return build_stanford_arm(HandSpec())


def test_hand_jacobian_matches_finite_differences(stanford):
    # Column j of the LOCAL Jacobian is the hand twist per unit q_j: log6(T(q)⁻¹·T(q + h·e_j))/h.
    rng = np.random.default_rng(11)
    lim = stanford.limits
    h = 1e-6
    for _ in range(20):
        q = rng.uniform(lim.lower + 0.01, lim.upper - 0.01)
        jac = stanford.jacobian(q)
        base = stanford.forward(q)
        numeric = np.column_stack(
            [pin.log6(base.actInv(stanford.forward(q + h * e))).vector / h for e in np.eye(6)]
        )
        assert np.allclose(jac, numeric, atol=1e-5)


def test_dls_solutions_are_closed_form_solutions(stanford):
    # Independent oracle: every DLS solution must be one of the closed form's (L895: ≤ 2).
    rng = np.random.default_rng(12)
    lim = stanford.limits
    found_any = 0
    for _ in range(6):
        q = rng.uniform(lim.lower, lim.upper)
        target = stanford.forward(q)
        exact = stanford.inverse(target)
        problem = build_ik(stanford, target, IKOptions(starts=16))
        solutions = solve_ik_all(problem, rng)
        found_any += bool(solutions)
        for s in solutions:
            assert lim.contains(s)
            assert min(np.max(np.abs(s - e)) for e in exact) < 1e-7
            err = pin.log6(stanford.forward(s).actInv(target)).vector
            assert np.linalg.norm(err[:3]) < 1e-9 and np.linalg.norm(err[3:]) < 1e-9
    assert found_any >= 5


def test_hint_converges_to_the_nearby_solution(stanford):
    q = np.array([0.3, -1.4, 0.55, 0.2, 0.7, -0.4])
    target = stanford.forward(q)
    problem = build_ik(stanford, target, IKOptions(starts=1), hint=q + 0.05)
    result = solve_ik(problem, np.random.default_rng(0))
    assert np.max(np.abs(result.solutions[0] - q)) < 1e-8
    assert result.best.converged and result.best.iterations < 20


def test_joint_limits_are_respected_when_the_target_needs_them_violated(stanford):
    # A target reached only with S3 beyond its 35 in stop: the solver stays inside the limits
    # and reports failure with the problem and its closest attempt.
    q = np.array([0.0, -1.5, 0.95, 0.0, 0.5, 0.0])  # S3 = 0.95 m > 0.889 m
    data = stanford.model.createData()
    pin.framesForwardKinematics(stanford.model, data, q)  # forward kinematics ignores limits
    target = data.oMf[stanford.hand_frame].copy()
    problem = build_ik(stanford, target, IKOptions(starts=6))
    with pytest.raises(NoSolutionFound) as info:
        solve_ik(problem, np.random.default_rng(1))
    assert info.value.problem is problem
    best = info.value.result.best
    assert stanford.limits.contains(best.q)
    assert not best.converged and best.position_error + best.rotation_error > 1e-3
    assert stanford.inverse(target) == []
