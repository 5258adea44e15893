"""Extrema of a linear functional ``c·v`` over the feasible parameter set.

Seed A.2 (L3260–3275): the errors are objective functions of linear programs over the
constraint set. With coupled constraints ``A v ≤ b`` that is an LP (scipy's HiGHS); when the set
is just the bounds, the closed form ``max c·v = Σ max(c_i lo_i, c_i hi_i)`` gives the same
numbers without a solver. Problems are built (:func:`build_error_lp`) apart from being solved
(:func:`solve_error_lp`) so tests can inspect the matrices and failures carry the problem.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from synth.errors.parameters import ParameterSpace
from synth.exceptions import EstimationError


@dataclass(frozen=True)
class Interval:
    """A closed interval [lo, hi] in SI units."""

    lo: float
    hi: float

    @property
    def magnitude(self) -> float:
        """``max(|lo|, |hi|)``."""
        return max(abs(self.lo), abs(self.hi))

    def widened(self, r: float) -> Interval:
        """``[lo − r, hi + r]``."""
        return Interval(self.lo - r, self.hi + r)

    def as_list(self) -> list[float]:
        """``[lo, hi]`` for JSON."""
        return [self.lo, self.hi]


@dataclass(frozen=True, eq=False)
class ErrorLP:
    """``min / max c·v`` subject to ``A v ≤ b``, ``lo ≤ v ≤ hi``."""

    objective: np.ndarray
    a_ub: np.ndarray
    b_ub: np.ndarray
    lo: np.ndarray
    hi: np.ndarray


class LPFailure(EstimationError):
    """HiGHS did not return an optimum; carries the problem and scipy's result."""

    def __init__(self, problem: ErrorLP, result: object) -> None:
        self.problem = problem
        self.result = result
        super().__init__(f"error LP failed: {getattr(result, 'message', result)}")


def build_error_lp(objective: np.ndarray, space: ParameterSpace) -> ErrorLP:
    """The LP for the extrema of ``objective · v`` over ``space``."""
    a, b = space.constraint_matrix()
    return ErrorLP(np.asarray(objective, dtype=float).copy(), a, b, space.lo, space.hi)


def solve_error_lp(lp: ErrorLP) -> Interval:
    """Solve both senses with HiGHS; ``[min c·v, max c·v]``."""
    if not np.any(lp.objective):
        return Interval(0.0, 0.0)
    bounds = list(zip(lp.lo, lp.hi, strict=True))
    a = lp.a_ub if lp.a_ub.shape[0] else None
    b = lp.b_ub if lp.a_ub.shape[0] else None
    out = []
    for sense in (1.0, -1.0):
        res = linprog(sense * lp.objective, A_ub=a, b_ub=b, bounds=bounds, method="highs")
        if res.status != 0:
            raise LPFailure(lp, res)
        out.append(sense * res.fun)
    return Interval(float(out[0]), float(out[1]))


def closed_form_bound(objective: np.ndarray, space: ParameterSpace) -> Interval:
    """Extrema of ``c·v`` over the box ``lo ≤ v ≤ hi``: ``Σ min/max(c_i lo_i, c_i hi_i)``."""
    c = np.asarray(objective, dtype=float)
    ends = np.stack([c * space.lo, c * space.hi])
    return Interval(float(ends.min(axis=0).sum()), float(ends.max(axis=0).sum()))


def bound_linear(objective: np.ndarray, space: ParameterSpace) -> Interval:
    """Closed form when the feasible set is a box, otherwise the LP."""
    if space.is_box:
        return closed_form_bound(objective, space)
    return solve_error_lp(build_error_lp(objective, space))
