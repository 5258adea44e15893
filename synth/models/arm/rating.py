"""Rating arm solutions: the seed's grasp quality and a hook for other ratings.

A rating maps an arm and a configuration to a cost, lower is better. The seed grades each
feasible grasping position by one joint (seed L2086–2100): "the angle of the 'elbow' (joint 5 of
the Scheinman arm) is examined; angles near 45 degrees are considered best",

    cost = |45° − θ5|   [rad].

Other ratings plug in through the :class:`SolutionRating` protocol (footnote 11 of the seed
suggests the error hypercube at the fingers or the time to reach the position); the joint-limit
margin below is one such alternative.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from synth.exceptions import UnreachableError
from synth.models.arm.arm import Arm


class SolutionRating(Protocol):
    """Cost of reaching a pose with configuration ``q`` (lower is better)."""

    def __call__(self, arm: Arm, q: NDArray[np.float64]) -> float:
        """Return the cost of ``q``."""
        ...


@dataclass(frozen=True)
class JointAngleRating:
    """cost = |preferred − q[joint]| [rad]; the seed's rule with joint θ5 and 45° (L2096)."""

    joint: int | None = None
    """Index of the rated joint; None: the arm's ``grasp_joint`` (θ5 for the Stanford arm)."""
    preferred: float = math.radians(45.0)
    """[rad] the best angle."""

    def __call__(self, arm: Arm, q: NDArray[np.float64]) -> float:
        """|preferred − q[joint]| [rad]."""
        joint = self.joint if self.joint is not None else arm.grasp_joint
        if joint is None:
            raise ValueError(
                f"arm {arm.name!r} has no grasp joint; give JointAngleRating(joint=...)"
            )
        return abs(self.preferred - float(q[joint]))


SEED_GRASP_RATING = JointAngleRating()
"""The seed's grasp rating: |45° − θ5| (L2096)."""


@dataclass(frozen=True)
class JointMarginRating:
    """cost = −min_j (distance to the nearer limit of joint j) / (range of joint j) [1].

    Prefers configurations far from every joint stop; 0 at a stop, −0.5 at mid-range.
    """

    def __call__(self, arm: Arm, q: NDArray[np.float64]) -> float:
        """Negative smallest normalised margin to the joint limits."""
        lim = arm.limits
        span = np.maximum(lim.upper - lim.lower, 1e-12)
        margin = np.minimum(q - lim.lower, lim.upper - q) / span
        return -float(np.min(margin))


@dataclass(frozen=True)
class RatedSolution:
    """A configuration with its cost; ``index`` is its position in the input list."""

    cost: float
    index: int
    q: NDArray[np.float64]


def best_solution(
    arm: Arm,
    transform_world_hand: pin.SE3,
    rating: SolutionRating = SEED_GRASP_RATING,
    hint: ArrayLike | None = None,
    rng: np.random.Generator | None = None,
) -> RatedSolution:
    """Return the best-rated configuration reaching a hand pose; raise if there is none.

    Raises :class:`~synth.exceptions.UnreachableError` with the pose and the reason (no
    attainable closed-form solution inside the joint limits, or none found by the DLS solver).
    """
    solutions = arm.inverse(transform_world_hand, hint=hint, rng=rng)
    if not solutions:
        reason = (
            "no attainable solution inside the joint limits (closed form)"
            if arm.closed_form is not None
            else "the DLS solver found no solution from its starts"
        )
        t = transform_world_hand.translation
        raise UnreachableError(
            (float(t[0]), float(t[1]), float(t[2])),
            tuple(float(v) for v in transform_world_hand.rotation.reshape(-1)),
            reason,
        )
    return rank_solutions(arm, solutions, rating)[0]


def rank_solutions(
    arm: Arm, solutions: Sequence[ArrayLike], rating: SolutionRating = SEED_GRASP_RATING
) -> list[RatedSolution]:
    """Solutions sorted by (cost, input order): deterministic ties, best first."""
    rated = []
    for i, s in enumerate(solutions):
        q = np.array(s, dtype=float)
        rated.append(RatedSolution(float(rating(arm, q)), i, q))
    return sorted(rated, key=lambda r: (r.cost, r.index))


def nearest_solution(
    arm: Arm, solutions: Sequence[ArrayLike], q_from: ArrayLike
) -> NDArray[np.float64] | None:
    """The solution with the smallest largest joint change from ``q_from``: min max_j |Δq_j|.

    How a program's targets become configurations, for the planner and the replay alike, so
    consecutive targets of a move stay on one arm branch; ties keep the input order. Not
    weighted by joint speed: the wrist joints are the fastest, and a speed-weighted rule can
    prefer flipping the wrist (θ4, θ6 by π) to a small shoulder move, which swings the hand and
    the pin through the work (the seed's tap listing, L2831, pushed the pin into the box top
    that way). None when there is no solution.
    """
    start = np.asarray(q_from, dtype=float)
    best: NDArray[np.float64] | None = None
    best_change = math.inf
    for s in solutions:
        q = np.array(s, dtype=float)
        change = float(np.max(np.abs(q - start)))
        if change < best_change:
            best, best_change = q, change
    return best
