"""Swept collision checks that cannot step over a thin obstacle: conservative advancement.

Motion bound. A point p of a body carried by joint k moves, when joint j ≤ k moves, at

    |∂p/∂q_j| = |ω_j × (p − o_j)| ≤ |p − o_j| ≤ ρ_kj    (revolute j)
    |∂p/∂q_j| = |a_j| = 1                               (prismatic j)

where o_j is a point on joint j's axis (its frame origin). A bound on |p − o_j| valid in every
configuration follows from the triangle inequality along the chain j → k:

    ρ_kj = Σ_{i ∈ (j, k]} (|t_i| + e_i) + |t_g + R_g·c_g| + r_g

with t_i the placement translation of joint i in its parent, e_i = max(|q_i,min|, |q_i,max|)
for a prismatic joint i (0 otherwise), and (t_g, R_g) the body's placement in joint k and
(c_g, r_g) the ball around its bounding box. Along a path, |dp/ds| ≤ Σ_j ρ_kj·|dq_j/ds|.

For a pair of bodies a, b the distance can only change through joints moving one relative to
the other; a joint carrying both moves them rigidly and leaves the distance unchanged, so

    |d(s') − d(s)| ≤ M·|s' − s|,   M = Σ_{j ∉ S_b} ρ_aj·|Δq_j| + Σ_{j ∉ S_a} ρ_bj·|Δq_j|,

S_a being the joints supporting a (an environment body has none). From a configuration with
distance d > 0 the pair therefore cannot touch before s + d/M. The check steps to
s + min over pairs of d/M (conservative advancement), so every step is bounded by a distance
argument, never by a fixed count, and no obstacle, however thin, is stepped over. A pair closer
than ``clearance`` (plus the bodies' ``margins``) counts as a collision, which also bounds the
number of steps. Distances come
from :meth:`CollisionScene.distance_bounds`: convex hulls of meshes give lower bounds (steps can
only shrink), and a pair is re-measured on its meshes before it is declared too close. Coal's
distances are accurate to its GJK tolerance (about 1 µm), far below the default clearance.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from synth.models.arm.bodies import Body, bounding_radius
from synth.models.arm.limits import JointLimits

if TYPE_CHECKING:
    from synth.models.arm.collision import CollisionScene


def body_motion_bounds(
    model: pin.Model,
    limits: JointLimits,
    bodies: Sequence[Body],
    *,
    rows: Sequence[int] | None = None,
    base: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """ρ [m/rad | 1]: bound on |∂p/∂q_j| over every point p of each body and every q.

    Shape (bodies, joints); zero for joints not supporting the body. See the module docstring.
    ``rows`` and ``base``: only those bodies' rows anew, the others copied from ``base`` (a
    reposition moves only the held object; its rows are computed as a full call would).
    """
    reach = np.array(
        [
            max(abs(lo), abs(hi)) if kind == "prismatic" else 0.0
            for lo, hi, kind in zip(limits.lower, limits.upper, limits.kinds, strict=True)
        ]
    )
    if rows is None or base is None:
        rho = np.zeros((len(bodies), model.nv))
        rows = range(len(bodies))
    else:
        rho = np.array(base, dtype=float)
    for row in rows:
        rho[row] = _body_row(model, limits, reach, bodies[row])
    return rho


def _body_row(
    model: pin.Model, limits: JointLimits, reach: NDArray[np.float64], body: Body
) -> NDArray[np.float64]:
    """One body's row of :func:`body_motion_bounds`."""
    row = np.zeros(model.nv)
    if body.joint == 0:
        return row
    radius = bounding_radius(body.geometry, body.placement)
    chain = [j for j in model.supports[body.joint] if j != 0]
    for pos, j in enumerate(chain):
        col = model.joints[j].idx_v
        if limits.kinds[col] == "prismatic":
            row[col] = 1.0
            continue
        lever = radius
        for i in chain[pos + 1 :]:
            lever += (
                float(np.linalg.norm(model.jointPlacements[i].translation))
                + reach[model.joints[i].idx_v]
            )
        row[col] = lever
    return row


def pair_motion_bounds(
    model: pin.Model,
    bodies: Sequence[Body],
    pairs: Sequence[tuple[int, int]],
    rho: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Per pair, the row m with |Δd| ≤ m·|Δq|: joints moving one body but not the other."""
    support = np.zeros((len(bodies), model.nv), dtype=bool)
    for p, body in enumerate(bodies):
        for j in model.supports[body.joint]:
            if j != 0:
                support[p, model.joints[j].idx_v] = True
    if not pairs:
        return np.zeros((0, model.nv))
    a, b = np.array(pairs, dtype=np.int64).reshape(-1, 2).T
    return rho[a] * ~support[b] + rho[b] * ~support[a]


@dataclass(frozen=True)
class LinkDisplacement:
    """How far one uncertain link's error moves a solid under it, direction by direction.

    The link's error is ``trans(t) ∘ rot_x(θ_x) ∘ rot_y(θ_y) ∘ rot_z(θ_z)`` in the link frame
    (seed A.2), ``|t_i| ≤ translation_i`` [m], ``|θ_i| ≤ angles_i`` [rad]; ``rotation`` is the
    link frame's orientation in the world and ``radius`` [m] that of a ball about the link's
    origin holding the solid. A point p of the solid moves by δ = t + (R − I)p, and

        R − I = (R_x − I)R_yR_z + (R_y − I)R_z + (R_z − I),

    where (R_a − I)w is perpendicular to the axis a with length 2 sin(θ_a/2)·ρ_a(w), ρ_a(w) the
    distance of w from the axis. Since |R_yR_z p − p| ≤ (κ_y + κ_z)|p| (κ = 2 sin(θ/2)),
    ρ_x(R_yR_z p) ≤ ρ_x(p) + (κ_y + κ_z)|p|, likewise ρ_y(R_z p) ≤ ρ_y(p) + κ_z|p|: the lever
    of axis a at p is λ_a(p) = ρ_a(p) + c_a|p| with c = (κ_y + κ_z, κ_z, 0). For a unit
    direction n (link frame)

        n·δ(p) ≤ Σ_i |n_i|·translation_i + Σ_a √(1 − n_a²)·κ_a·λ_a(p),

    and the right side, convex in p (norms of linear maps), is largest over the solid at a
    vertex of its hull (``points``, the link frame [m]): a plate tilting about its centre is
    charged at its corners' levers about each axis, not at the ball's radius about every axis.
    Without ``points`` (a curved solid) λ_a = r, the ball (ρ_a ≤ |p| ≤ r, and the composition
    moves no point off its sphere); where both are known the smaller bound is taken. A part
    with a yaw error and no height error never moves vertically; the ball bound of
    :meth:`bound` says it moves |t| + Σ_a κ_a·max_p λ_a(p) in every direction.
    """

    rotation: NDArray[np.float64]
    translation: NDArray[np.float64]
    angles: NDArray[np.float64]
    radius: float
    points: NDArray[np.float64] | None = None

    @cached_property
    def _levers(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """κ_a (3,) and the levers λ_a(p) (N, 3) [m] of the hull's vertices (class formula)."""
        kappa = 2.0 * np.sin(self.angles / 2.0)
        p = np.asarray(self.points, dtype=float)
        norms = np.linalg.norm(p, axis=1)
        rho = np.sqrt(np.clip(norms[:, None] ** 2 - p * p, 0.0, None))
        later = np.array([kappa[1] + kappa[2], kappa[2], 0.0])
        return kappa, rho + later[None, :] * norms[:, None]

    def support(self, direction: NDArray[np.float64]) -> float:
        """Largest displacement [m] of a point of the solid along the world unit ``direction``."""
        n = self.rotation.T @ direction
        along = float(np.abs(n) @ self.translation)
        across = np.sqrt(np.clip(1.0 - n * n, 0.0, 1.0))
        kappa = 2.0 * np.sin(self.angles / 2.0)
        ball = float(across @ kappa) * self.radius
        if self.points is None or not np.any(kappa):
            return along + ball
        _, levers = self._levers
        return along + min(ball, float(np.max(levers @ (across * kappa))))

    def bound(self) -> float:
        """Largest displacement [m] in any direction: |t|_max + Σ_a κ_a·max_p λ_a(p).

        |t| + Σ_i θ_i·r without the hull's vertices (κ_a ≤ θ_a, λ_a ≤ r).
        """
        shift = float(np.linalg.norm(self.translation))
        ball = float(np.sum(self.angles)) * self.radius
        if self.points is None or not np.any(self.angles):
            return shift + ball
        kappa, levers = self._levers
        return shift + min(ball, float(np.max(levers @ kappa)))


@dataclass(frozen=True)
class Displacement:
    """A solid's displacement bound: the sum over the uncertain links above it.

    Each link's error moves the subtree rigidly, so displacements add.
    """

    links: tuple[LinkDisplacement, ...]

    def support(self, direction: NDArray[np.float64]) -> float:
        """Largest displacement [m] along the world unit ``direction``."""
        return sum((link.support(direction) for link in self.links), 0.0)

    def bound(self) -> float:
        """Largest displacement [m] in any direction."""
        return sum((link.bound() for link in self.links), 0.0)


@dataclass(frozen=True)
class SweepOptions:
    """Options of the swept checks."""

    clearance: float = 1e-3
    """[m] a pair closer than this counts as a collision (and bounds the number of steps)."""
    max_checks: int = 100_000
    """Safety stop on distance evaluations; reaching it reports the path as not free."""
    margins: Mapping[str, float] = field(default_factory=dict)
    """[m] extra clearance per body name: a pair (a, b) must stay ``clearance + margins[a] +
    margins[b]`` apart. The planner puts here how far a body may be from where it is believed
    (an object's pose error, the hand's positioning error), so a path clear of the believed
    world is clear of every world the task allows."""
    displacements: Mapping[str, Displacement] = field(default_factory=dict)
    """Per body name, a directional displacement bound (a solid under uncertain links): a pair
    (a, b) whose closest points lie along n must keep ``clearance + margins[a] + margins[b] +
    D_a(n) + D_b(n)`` apart. Convex bodies separated by a slab of width d along n stay apart
    if they move by less than d along n, so the bound need only hold along n; where n is
    unknown the ball bound :meth:`Displacement.bound` is used."""
    rigid: frozenset[str] = frozenset()
    """Bodies that move together (the arm's links, the hand and the held pin under one hand
    error): a pair of them keeps the clearance only."""
    lazy: bool = False
    """Measure only the pairs that can decide a step (:func:`_advance_lazy`): the same steps,
    stops and pairs as measuring every pair, with far fewer distance queries. Used without
    :attr:`displacements` only."""

    def pair_margins(self, pairs: Sequence[tuple[str, str]]) -> NDArray[np.float64]:
        """The margins [m] of each pair in any direction (displacements at their ball bound).

        0 for bodies without one, and for a pair of :attr:`rigid` bodies.
        """
        m, d, rigid = self.margins, self.displacements, self.rigid
        out = []
        for a, b in pairs:
            if a in rigid and b in rigid:
                out.append(0.0)
                continue
            total = m.get(a, 0.0) + m.get(b, 0.0)
            total += sum((d[x].bound() for x in (a, b) if x in d), 0.0)
            out.append(total)
        return np.array(out, dtype=float)

    def directional(self, pairs: Sequence[tuple[str, str]]) -> NDArray[np.int64]:
        """Indices of the pairs with a directional displacement (not both rigid)."""
        d, rigid = self.displacements, self.rigid
        return np.array(
            [
                k
                for k, (a, b) in enumerate(pairs)
                if (a in d or b in d) and not (a in rigid and b in rigid)
            ],
            dtype=np.int64,
        )

    def pair_margin_along(self, pair: tuple[str, str], direction: NDArray[np.float64]) -> float:
        """The margin [m] of ``pair`` whose closest points lie along the unit ``direction``."""
        a, b = pair
        if a in self.rigid and b in self.rigid:
            return 0.0
        if not np.any(direction):
            return float(self.pair_margins([pair])[0])
        total = self.margins.get(a, 0.0) + self.margins.get(b, 0.0)
        for x in (a, b):
            if x in self.displacements:
                total += self.displacements[x].support(direction)
        return total

    def required(self, pairs: Sequence[tuple[str, str]]) -> NDArray[np.float64]:
        """The distance [m] each pair must keep in any direction: clearance plus margins."""
        return self.clearance + self.pair_margins(pairs)


@dataclass(frozen=True)
class SweepResult:
    """Outcome of a swept check.

    ``free``: no checked pair came closer than the clearance. ``s``: path parameter in [0, 1]
    (or time [s] for trajectories) where the check stopped (1 / duration when free); ``q`` the
    configuration there; ``pair`` and ``distance`` [m] the closest pair at that point; ``checks``
    the number of distance evaluations.
    """

    free: bool
    s: float
    q: NDArray[np.float64]
    pair: tuple[str, str] | None
    distance: float
    checks: int
    required: float = 0.0
    """[m] the distance ``pair`` had to keep there (clearance and margins along its
    direction)."""


def _advance(
    scene: CollisionScene,
    position: Callable[[float], NDArray[np.float64]],
    end: float,
    rates: NDArray[np.float64],
    options: SweepOptions,
) -> SweepResult:
    """Conservative advancement over s ∈ [0, end]: q = position(s), |dq_j/ds| ≤ rates_j."""
    directional = options.directional(scene.pairs)
    if options.lazy and not directional.size and scene.pairs:
        return _advance_lazy(scene, position, end, rates, options)
    bounds = scene.pair_bounds @ rates  # M per pair [m per unit s]
    margins = options.pair_margins(scene.pairs)
    s, checks = 0.0, 0
    while True:
        q = position(s)
        if not scene.pairs:
            return SweepResult(True, end, q, None, float("inf"), checks)
        d = scene.distance_bounds(q, exact_below=options.clearance + margins)
        checks += 1
        # The margins play the bodies' own surfaces: a step of gap/M cannot bring a pair inside
        # its margins, and a gap ≤ clearance stops the check (so every step is ≥ clearance/M).
        # A pair with a directional displacement keeps its margin along its closest points'
        # direction (SweepOptions.displacements), never more than the ball bound.
        gap = d - margins
        if directional.size:
            near = directional[gap[directional] <= options.clearance + margins[directional]]
            for j in near.tolist():
                along = options.pair_margin_along(scene.pairs[j], scene.normal(j))
                gap[j] = d[j] - min(along, float(margins[j]))
        k = int(np.argmin(gap))
        need = float(d[k] - gap[k]) + options.clearance
        if gap[k] <= options.clearance:
            return SweepResult(False, s, q, scene.pairs[k], float(d[k]), checks, need)
        if s >= end:
            return SweepResult(True, end, q, scene.pairs[k], float(d[k]), checks, need)
        if checks >= options.max_checks:
            return SweepResult(False, s, q, scene.pairs[k], float(d[k]), checks, need)
        moving = bounds > 0
        step = float(np.min(gap[moving] / bounds[moving])) if np.any(moving) else end - s
        s = min(end, s + step)


LAZY_SLACK = 1e-4
"""[m] a pair whose lower bound is within this of deciding a step is measured: far above
Coal's GJK tolerance (≈ 1 µm), so rounding in the measured distances cannot hide a pair."""


def _advance_lazy(
    scene: CollisionScene,
    position: Callable[[float], NDArray[np.float64]],
    end: float,
    rates: NDArray[np.float64],
    options: SweepOptions,
) -> SweepResult:
    """:func:`_advance` measuring only the pairs that decide each step.

    At each s the eager check measures every pair's gap g_k = d_k − margin_k, stops at the
    first argmin if its gap is ≤ the clearance, and otherwise steps by min_k g_k/M_k over the
    moving pairs. Here every pair has a lower bound ℓ_k ≤ d_k
    (:meth:`CollisionScene.lower_bounds`); a pair is measured when ℓ_k − margin_k − slack could
    be ≤ the clearance, ≤ the smallest measured gap, or (moving) ≤ M_k times the smallest
    measured ratio, until no unmeasured pair can be. Unmeasured pairs then have gaps strictly
    above every value the eager check takes its minimum, argmin and step from, so both checks
    take the same steps and stop at the same s with the same pair and distance.
    """
    bounds = scene.tight_pair_bounds @ rates  # M per pair [m per unit s]
    margins = options.pair_margins(scene.pairs)
    clearance = options.clearance
    exact_below = clearance + margins
    moving = bounds > 0
    any_moving = bool(np.any(moving))
    per_rate = np.where(moving, bounds, 1.0)
    n = len(scene.pairs)
    s, checks = 0.0, 0
    while True:
        q = position(s)
        lower = scene.lower_bounds(q, exact_below) - margins - LAZY_SLACK  # on the gaps [m]
        lower_ratio = np.where(moving, lower / per_rate, np.inf)  # on the steps [unit s]
        d = np.full(n, np.inf)
        fresh = np.zeros(n, dtype=bool)
        checks += 1

        def measure(
            indices: Sequence[int],
            d: NDArray[np.float64] = d,
            fresh: NDArray[np.bool_] = fresh,
        ) -> None:
            for j in indices:
                if not fresh[j]:
                    d[j] = scene.measure(j, float(exact_below[j]))
                    fresh[j] = True

        measure(np.flatnonzero(lower <= clearance).tolist())
        measure([int(np.argmin(lower))] + ([int(np.argmin(lower_ratio))] if any_moving else []))
        while True:
            gap = d - margins
            g_min = float(np.min(gap))
            r_min = float(np.min(gap[moving] / bounds[moving])) if any_moving else np.inf
            wanted = ~fresh & ((lower <= g_min) | (lower_ratio <= r_min))
            if not wanted.any():
                break
            measure(np.flatnonzero(wanted).tolist())
        k = int(np.argmin(gap))
        need = float(d[k] - gap[k]) + clearance
        if gap[k] <= clearance:
            return SweepResult(False, s, q, scene.pairs[k], float(d[k]), checks, need)
        if s >= end:
            return SweepResult(True, end, q, scene.pairs[k], float(d[k]), checks, need)
        if checks >= options.max_checks:
            return SweepResult(False, s, q, scene.pairs[k], float(d[k]), checks, need)
        step = r_min if any_moving else end - s
        s = min(end, s + step)


def swept_segment(
    scene: CollisionScene, q0: ArrayLike, q1: ArrayLike, options: SweepOptions | None = None
) -> SweepResult:
    """Check the straight joint-space segment q(s) = q0 + s·(q1 − q0), s ∈ [0, 1]."""
    a = np.asarray(q0, dtype=float)
    delta = np.asarray(q1, dtype=float) - a
    return _advance(scene, lambda s: a + s * delta, 1.0, np.abs(delta), options or SweepOptions())


def swept_path(
    scene: CollisionScene, waypoints: Sequence[ArrayLike], options: SweepOptions | None = None
) -> SweepResult:
    """Check a joint-space polyline segment by segment; ``s`` of a hit is segment index + s."""
    opts = options or SweepOptions()
    points = [np.asarray(w, dtype=float) for w in waypoints]
    total = 0
    last: SweepResult | None = None
    for i in range(len(points) - 1):
        result = swept_segment(scene, points[i], points[i + 1], opts)
        total += result.checks
        if not result.free:
            return SweepResult(
                False, i + result.s, result.q, result.pair, result.distance, total, result.required
            )
        last = result
    if last is None:
        c = scene.clearance(points[0])
        free = c.distance > opts.clearance
        return SweepResult(free, 0.0, points[0], c.pair, c.distance, 1)
    return SweepResult(True, float(len(points) - 1), last.q, last.pair, last.distance, total)


def swept_trajectory(
    scene: CollisionScene,
    position: Callable[[float], NDArray[np.float64]],
    duration: float,
    speed_bound: ArrayLike,
    options: SweepOptions | None = None,
) -> SweepResult:
    """Check a timed trajectory q(t), t ∈ [0, duration] [s], with |q̇_j| ≤ ``speed_bound``_j.

    The same distance argument in time: a pair at distance d cannot touch within d/M [s],
    M = m·v_max. Use the joint velocity limits the trajectory was planned under.
    """
    return _advance(
        scene,
        position,
        float(duration),
        np.abs(np.asarray(speed_bound, dtype=float)),
        options or SweepOptions(),
    )
