"""Rating arm solutions: the seed's grasp quality and a hook for other ratings.

A rating maps an arm and a configuration to a cost, lower is better. The seed grades each
feasible grasping position by one joint (seed L2086–2100): "the angle of the 'elbow' (joint 5 of
the Scheinman arm) is examined; angles near 45 degrees are considered best",

    cost = |45° − θ5|   [rad].

Other ratings plug in through the :class:`SolutionRating` protocol (footnote 11 of the seed
suggests the error hypercube at the fingers or the time to reach the position). An arm without
the Stanford arm's θ5 (any URDF arm) is rated by :class:`DexterityRating`: joint-limit margin
and the Jacobian's inverse condition number, at its worst over the grasp, its approach point and
the seat (:func:`grasp_rating` picks the rating for an arm).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
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

    def describe(self, cost: float) -> str:
        """The cost as the seed states it: ``|45° − θ5| = 12.3°``."""
        return f"|45° − θ5| = {math.degrees(cost):.1f}°"


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


@lru_cache(maxsize=64)
def characteristic_length(arm: Arm) -> float:
    """L [m]: the arm's reach, summed joint-to-joint distances from joint 1 to the hand.

    Measured at the neutral configuration (the distances between consecutive joint origins do
    not depend on q). It scales the Jacobian's linear rows so that a metre of hand motion at
    full reach weighs as a radian of hand turn.
    """
    data = arm.new_data()
    q = arm.limits.clip(np.zeros(arm.nq))
    pin.forwardKinematics(arm.model, data, q)
    hand = pin.updateFramePlacement(arm.model, data, arm.hand_frame).translation
    points = [data.oMi[j].translation for j in range(1, arm.model.njoints)] + [hand]
    return float(sum(np.linalg.norm(b - a) for a, b in itertools.pairwise(points)))


def dexterity(arm: Arm, q: NDArray[np.float64]) -> float:
    """D(q) = ½·m(q) + ½·κ⁻¹(q) ∈ [0, 1]: 1 at mid-range and isotropic, 0 at a stop or singular.

    m(q) = min_j (distance of q_j to its nearer limit) / (half the range of joint j) — 1 with
    every joint mid-range, 0 at a stop. κ⁻¹(q) = σ_min/σ_max of the hand Jacobian with its
    linear rows divided by L (:func:`characteristic_length`): 0 at a singularity, where some
    hand motion needs unbounded joint speed, 1 when every hand direction is equally easy
    (Salisbury & Craig 1982; Yoshikawa's manipulability would depend on the units).
    """
    lim = arm.limits
    half = np.maximum((lim.upper - lim.lower) / 2, 1e-12)
    margin = float(np.clip(np.min(np.minimum(q - lim.lower, lim.upper - q) / half), 0.0, 1.0))
    jacobian = arm.jacobian(q).copy()
    jacobian[:3] /= characteristic_length(arm)
    sigma = np.linalg.svd(jacobian, compute_uv=False)
    conditioning = float(sigma[min(5, len(sigma) - 1)] / sigma[0]) if sigma[0] > 0 else 0.0
    return 0.5 * margin + 0.5 * conditioning


@dataclass(frozen=True)
class DexterityRating:
    """cost = −D(q) (:func:`dexterity`): the arm-agnostic rating of a configuration."""

    def __call__(self, arm: Arm, q: NDArray[np.float64]) -> float:
        """−D(q) [1], in [−1, 0]."""
        return -dexterity(arm, q)

    def describe(self, cost: float) -> str:
        """The cost as a dexterity: ``dexterity 0.41``."""
        return f"dexterity {-cost:.2f}"


class GraspRating(Protocol):
    """Cost of a grasp from its configurations (the grasp first), lower is better."""

    def __call__(self, arm: Arm, configurations: Sequence[NDArray[np.float64]]) -> float:
        """Return the cost."""
        ...

    def describe(self, cost: float) -> str:
        """The cost in words for a rejection."""
        ...


@dataclass(frozen=True)
class SeedGraspRating:
    """The seed's rule: |45° − θ5| at the grasp alone (L2096); the other configurations unused."""

    def __call__(self, arm: Arm, configurations: Sequence[NDArray[np.float64]]) -> float:
        """|45° − θ5| [rad] at ``configurations[0]``."""
        return SEED_GRASP_RATING(arm, configurations[0])

    def describe(self, cost: float) -> str:
        """``|45° − θ5| = 12.3°``."""
        return SEED_GRASP_RATING.describe(cost)


@dataclass(frozen=True)
class WorstDexterityRating:
    """cost = −min_q D(q) over the grasp, its approach point and the seat.

    A grasp is as good as the worst place the arm must hold it: one fine at the rack but near
    a wrist singularity over the hole is a poor grasp.
    """

    def __call__(self, arm: Arm, configurations: Sequence[NDArray[np.float64]]) -> float:
        """−min D(q) [1] over ``configurations``."""
        return -min(dexterity(arm, q) for q in configurations)

    def describe(self, cost: float) -> str:
        """``worst dexterity 0.41``."""
        return f"worst dexterity {-cost:.2f} (grasp, approach, seat)"


def grasp_rating(arm: Arm) -> GraspRating:
    """The grasp rating of an arm: the seed's θ5 rule where it has θ5, else worst dexterity."""
    if arm.grasp_joint is not None:
        return SeedGraspRating()
    return WorstDexterityRating()


def solution_rating(arm: Arm) -> SolutionRating:
    """Rating of a single configuration (a start, say): the seed's θ5 rule or −D(q)."""
    return SEED_GRASP_RATING if arm.grasp_joint is not None else DexterityRating()


@dataclass(frozen=True)
class RatedSolution:
    """A configuration with its cost; ``index`` is its position in the input list."""

    cost: float
    index: int
    q: NDArray[np.float64]


def best_solution(
    arm: Arm,
    world_from_hand: pin.SE3,
    rating: SolutionRating | None = None,
    hint: ArrayLike | None = None,
    rng: np.random.Generator | None = None,
) -> RatedSolution:
    """Return the best-rated configuration reaching a hand pose; raise if there is none.

    Raises :class:`~synth.exceptions.UnreachableError` with the pose and the reason (no
    attainable closed-form solution inside the joint limits, or none found by the DLS solver).
    """
    solutions = arm.inverse(world_from_hand, hint=hint, rng=rng)
    if not solutions:
        reason = (
            "no attainable solution inside the joint limits (closed form)"
            if arm.closed_form is not None
            else "the DLS solver found no solution from its starts"
        )
        t = world_from_hand.translation
        raise UnreachableError(
            (float(t[0]), float(t[1]), float(t[2])),
            tuple(float(v) for v in world_from_hand.rotation.reshape(-1)),
            reason,
        )
    return rank_solutions(arm, solutions, rating)[0]


def rank_solutions(
    arm: Arm, solutions: Sequence[ArrayLike], rating: SolutionRating | None = None
) -> list[RatedSolution]:
    """Solutions sorted by (cost, input order): deterministic ties, best first.

    ``rating`` defaults to the arm's own (:func:`solution_rating`).
    """
    rating = solution_rating(arm) if rating is None else rating
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
