"""Damped-least-squares inverse kinematics for any arm, multi-start, inside the joint limits.

Used when an arm has no closed form. Each start runs Levenberg–Marquardt steps on the pose error
e(q) = log6(T_target⁻¹·T_hand(q)) ∈ se(3) (hand frame, [m] and [rad] weighted alike). A hand
motion J_hand·dq (``pin.LOCAL``) changes it by J_e·dq with J_e = Jlog6(T_target⁻¹·T_hand)·J_hand, so

    Δq = −J_eᵀ·(J_e·J_eᵀ + λ·I)⁻¹·e,   λ = c·‖e‖² + w̄          [Sugihara 2011]

clipped to ``max_step`` and then into the joint limits. Sugihara takes c = ½; c = 0.01
converged faster on the Stanford arm and the UR5 (more starts converge, in fewer iterations).
A start is abandoned when its error has not halved over ``stall_iterations`` iterations.
Starts are the hint (if any) and configurations drawn uniformly inside the limits from the
caller's ``np.random.Generator``. With a hint the descent from the hint runs first, and when it
converges its solution is the answer (``hint_first``): a move's next target is a small step
from where the arm is, the descent stays on the arm's branch (for a redundant arm such as the
Panda, on the nearby part of its self-motion manifold), and the nearest-solution rule would
pick it anyway. The random starts run only when it fails, or without a hint (the park).
:func:`build_ik` returns the problem; :func:`solve_ik` solves it and raises
:class:`~synth.exceptions.NoSolutionFound` carrying problem and result when no start converges.

[Sugihara 2011] T. Sugihara, "Solvability-unconcerned inverse kinematics by the
Levenberg–Marquardt method", IEEE Trans. Robotics 27(5), 2011.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from synth.exceptions import NoSolutionFound
from synth.models.arm.arm import Arm
from synth.models.arm.limits import JointLimits


@dataclass(frozen=True)
class IKOptions:
    """Solver options; units in brackets."""

    starts: int = 24
    """Number of starts, the hint included."""
    max_iterations: int = 100
    """Iterations per start."""
    position_tolerance: float = 1e-10
    """[m] converged when the hand position error is below this."""
    rotation_tolerance: float = 1e-10
    """[rad] and the hand rotation error below this."""
    damping: float = 1e-6
    """w̄ [m² ≡ rad²]: constant part of the damping λ = c·‖e‖² + w̄."""
    error_damping: float = 0.01
    """c [1]: weight of the squared error in the damping."""
    stall_iterations: int = 10
    """Abandon a start whose error has not halved over this many iterations."""
    max_solutions: int | None = None
    """Stop after this many distinct solutions (None: run every start)."""
    max_step: float = 0.5
    """[rad | m] largest joint change per iteration (∞-norm)."""
    distinct: float = 1e-6
    """[rad | m] converged configurations closer than this (∞-norm) are one solution."""
    hint_first: bool = True
    """With a hint, return the hint's own converged descent without running the other starts."""


@dataclass(frozen=True, eq=False)
class IKProblem:
    """A built IK problem: reach ``target`` (T_world_hand) with ``frame`` of ``model``."""

    model: pin.Model
    frame: int
    target: pin.SE3
    limits: JointLimits
    options: IKOptions
    hint: NDArray[np.float64] | None


@dataclass(frozen=True)
class IKAttempt:
    """One start's outcome: final configuration, pose error norms [m], [rad], iterations."""

    q: NDArray[np.float64]
    position_error: float
    rotation_error: float
    iterations: int
    converged: bool


@dataclass(frozen=True)
class IKResult:
    """All distinct converged solutions, the attempt that came closest, and the starts run."""

    solutions: tuple[NDArray[np.float64], ...]
    best: IKAttempt
    attempts: int


def build_ik(
    arm: Arm,
    target: pin.SE3,
    options: IKOptions | None = None,
    hint: ArrayLike | None = None,
) -> IKProblem:
    """Build the problem of reaching T_world_hand = ``target`` with ``arm`` (not solved)."""
    h = None if hint is None else arm.limits.clip(np.asarray(hint, dtype=float))
    return IKProblem(
        arm.model, arm.hand_frame, target.copy(), arm.limits, options or IKOptions(), h
    )


def _run(problem: IKProblem, data: pin.Data, q0: NDArray[np.float64]) -> IKAttempt:
    opts, model, frame, lim = problem.options, problem.model, problem.frame, problem.limits
    target_inv = problem.target.inverse()
    q = q0.copy()
    eye6 = np.eye(6)
    history: list[float] = []
    for it in range(opts.max_iterations + 1):
        # One kinematics pass gives both the pose and the Jacobian (joint Jacobians include FK).
        pin.computeJointJacobians(model, data, q)
        current = pin.updateFramePlacement(model, data, frame)
        error_pose = target_inv * current  # T_target⁻¹·T_hand
        e = pin.log6(error_pose).vector
        ep, er = math.sqrt(float(e[:3] @ e[:3])), math.sqrt(float(e[3:] @ e[3:]))
        if ep < opts.position_tolerance and er < opts.rotation_tolerance:
            return IKAttempt(q, ep, er, it, True)
        history.append(ep + er)
        if it == opts.max_iterations or (
            it >= opts.stall_iterations and history[-1] > 0.5 * history[-1 - opts.stall_iterations]
        ):
            return IKAttempt(q, ep, er, it, False)
        jac = pin.getFrameJacobian(model, data, frame, pin.LOCAL)
        je = pin.Jlog6(error_pose) @ jac
        lam = opts.error_damping * float(e @ e) + opts.damping
        dq = -je.T @ np.linalg.solve(je @ je.T + lam * eye6, e)
        biggest = float(np.abs(dq).max())
        if biggest > opts.max_step:
            dq *= opts.max_step / biggest
        q = np.minimum(np.maximum(q + dq, lim.lower), lim.upper)
    raise AssertionError("unreachable")


def solve_ik(problem: IKProblem, rng: np.random.Generator) -> IKResult:
    """Solve from every start; raise :class:`NoSolutionFound` when none converges."""
    opts, lim = problem.options, problem.limits
    starts = [] if problem.hint is None else [problem.hint]
    n_random = max(opts.starts - len(starts), 0)
    starts += list(rng.uniform(lim.lower, lim.upper, size=(n_random, lim.n)))
    data = problem.model.createData()
    if problem.hint is not None and opts.hint_first:
        first = _run(problem, data, problem.hint)
        if first.converged:
            return IKResult((first.q,), first, 1)
    solutions: list[NDArray[np.float64]] = []
    best: IKAttempt | None = None
    runs = 0
    for q0 in starts:
        runs += 1
        attempt = _run(problem, data, np.asarray(q0, dtype=float))
        if best is None or (attempt.position_error + attempt.rotation_error) < (
            best.position_error + best.rotation_error
        ):
            best = attempt
        if attempt.converged and all(
            np.max(np.abs(attempt.q - s)) > opts.distinct for s in solutions
        ):
            solutions.append(attempt.q)
            if opts.max_solutions is not None and len(solutions) >= opts.max_solutions:
                break
    assert best is not None
    if problem.hint is not None:
        hint = problem.hint
        solutions.sort(key=lambda s: float(np.max(np.abs(s - hint))))
    result = IKResult(tuple(solutions), best, runs)
    if not solutions:
        raise NoSolutionFound(
            problem,
            result,
            f"no IK solution from {runs} starts; closest: "
            f"{best.position_error * 1000:.3g} mm, {np.degrees(best.rotation_error):.3g} deg",
        )
    return result


def solve_ik_all(problem: IKProblem, rng: np.random.Generator) -> list[NDArray[np.float64]]:
    """Return the distinct solutions (empty when none): :func:`solve_ik` without raising."""
    try:
        return list(solve_ik(problem, rng).solutions)
    except NoSolutionFound:
        return []
