"""The arm's swept check on the fast path: both ends measured, then only what can still touch.

:func:`fast_sweep` answers what :func:`synth.models.arm.swept_segment` answers on a
:class:`~synth.models.arm.CollisionScene`: a step point of the straight joint-space segment
q(s) = q₀ + s·Δ, s ∈ [0, 1], where a checked pair is within the clearance c (the first one), or
that there is none.

**How far a pair's gap can close.** A pair's distance depends only on the joints that move one
of its bodies relative to the other, less those that turn a solid of revolution about its own
axis (the mask of :attr:`~synth.models.arm.CollisionScene.tight_pair_bounds`). Along the segment
with only those joints moving (Δ' = Δ on the mask, 0 elsewhere) the pair's relative pose, hence
its distance, is the true one at every s, so from s₀

    d(s₀ + τ) ≥ d(s₀) − τ·a(s₀) − ½·A·τ²,   a = |v_a| + |ω_a|·R_a + |v_b| + |ω_b|·R_b,

with v, ω the velocity of each body's joint frame under Δ' at s₀ (exact, from the joint
Jacobians), R the ball about the joint's origin holding the body and A the sum of both bodies'
second-order bounds under Δ' (:mod:`synth.replay.bounds`). The same holds backwards from the
end: d(1 − τ) ≥ d(1) − τ·a(1) − ½·A·τ².

**Both ends first.** Every pair is measured at q₀ and at q₁ (one Coal query of all hulls each,
in C++; a mesh within the clearance on its mesh). Over the whole segment a pair is at least

    m = min over s of max(f₀(s), f₁(s)),  f₀(s) = d₀ − a₀s − ½As²,  f₁(s) = d₁ − a₁(1−s) − ½A(1−s)²,

and since f₀ falls and f₁ rises and f₀ − f₁ = (d₀ − d₁ + a₁ + ½A) − (a₀ + a₁ + A)·s is linear,
m is f₀ at the root s* of that line (clipped to [0, 1]). A pair with m > c cannot come within
c anywhere on the segment: it is done. Typically none or a few pairs remain.

**Then the few, interval by interval.** Between two measured points the same floor bounds each
remaining pair. From the start, an interval where every floor stays beyond c/2 is clear, and
its right end is tested: a pair within c there is the stop, with Coal's pair and distance.
Otherwise the interval's midpoint is measured and the interval split; the A-term shrinks with
the square of the interval, so a handful of splits prove a long motion clear. A stop's
interval is clear, so the stop lies between c/2 and c from the pair's surfaces (the floor at
its right end is at most its distance there), and no dip below c/2 is stepped over (the
reference sweep steps up to contact and stops anywhere in (0, c]).

Coal's distance d may exceed the true one by its GJK tolerance (up to 10⁻³·d was observed,
:data:`~synth.replay.contact.GJK_MARGIN`): the bounds start from d·(1 − 2·10⁻³) and keep
:data:`_SLACK` in hand. The end's measurement is kept on the scene and is the next segment's
start when it begins there (a via point, the next motion).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.arm import CollisionScene, SweepOptions, SweepResult
from synth.models.arm.bodies import bounding_radius
from synth.models.arm.collision import min_distances
from synth.replay.bounds import ArmChain, curvatures
from synth.replay.contact import GJK_MARGIN

__all__ = ["Ends", "PairMotion", "below_gap", "closing_rates", "fast_sweep", "two_ended_floor"]

_SLACK = 1e-5
"""[m] kept in hand below every bound on a measured gap: ten times Coal's GJK tolerance."""


@dataclass(frozen=True, eq=False)
class PairMotion:
    """A scene's pairs prepared for the bounds: per pair and side, the joints that count.

    ``joints[p]`` the joint carrying body p (0: the world); ``radii[p]`` the ball about it
    holding the body [m]; ``supports[p]`` its supporting joints (velocity indices);
    ``sides[k, i]`` the body index of side i of pair k; ``masks[k, i]`` the joints (velocity
    indices) that move side i relative to the other and can change the distance.
    """

    bodies: tuple[object, ...]
    pairs: tuple[tuple[str, str], ...]
    joints: NDArray[np.int64]
    radii: NDArray[np.float64]
    supports: NDArray[np.bool_]
    sides: NDArray[np.int64]
    masks: NDArray[np.bool_]
    exact: NDArray[np.bool_]
    _margins: dict[int, tuple[SweepOptions, NDArray[np.float64]]] = field(default_factory=dict)

    def margins(self, options: SweepOptions) -> NDArray[np.float64]:
        """``options.pair_margins`` of the scene's pairs (kept per options object)."""
        cached = self._margins.get(id(options))
        if cached is None or cached[0] is not options:
            cached = (options, options.pair_margins(self.pairs))
            self._margins[id(options)] = cached
        return cached[1]

    @staticmethod
    def of(scene: CollisionScene) -> PairMotion:
        """The pairs of ``scene``, kept on the scene; after a reposition only the radii anew.

        A reposition keeps the bodies, solids and pairs and moves the environment and the
        held object; of what is kept here only the held object's ball can change.
        """
        cached = getattr(scene, "_pair_motion", None)
        if isinstance(cached, PairMotion):
            if cached.bodies is scene.bodies:
                return cached
            motion = cached._moved(scene)
        else:
            motion = PairMotion._made(scene)
        scene._pair_motion = motion  # type: ignore[attr-defined]
        return motion

    @staticmethod
    def _made(scene: CollisionScene) -> PairMotion:
        model = scene.model
        names = [b.name for b in scene.bodies]
        index = {n: i for i, n in enumerate(names)}
        joints = np.array([b.joint for b in scene.bodies], dtype=np.int64)
        supports = np.zeros((len(names), model.nv), dtype=bool)
        for p, body in enumerate(scene.bodies):
            for j in model.supports[body.joint]:
                if j != 0:
                    supports[p, model.joints[j].idx_v] = True
        sides = np.array([[index[a], index[b]] for a, b in scene.pairs], dtype=np.int64)
        sides = sides.reshape(-1, 2)
        tight = scene.tight_pair_bounds > 0.0
        masks = np.stack([tight & supports[sides[:, 0]], tight & supports[sides[:, 1]]], axis=1)
        empty = np.zeros(0)
        exact = np.asarray(scene.bound_is_exact, dtype=bool)
        base = PairMotion((), scene.pairs, joints, empty, supports, sides, masks, exact)
        return base._moved(scene)

    def steps(
        self,
        chain: ArmChain,
        q0: NDArray[np.float64],
        q1: NDArray[np.float64],
        checked: NDArray[np.int64] | None = None,
    ) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
        """The straight joint move q₀ → q₁ seen by the ``checked`` pairs (all by default).

        ``signed[k, i]`` the joint step Δ = q₁ − q₀ restricted to the joints moving side i of
        pair k; ``sides[k]`` its bodies; ``curvature[k]`` the bound on the second derivative of
        pair k's gap along s: :func:`~synth.replay.bounds.curvatures` of each side's levers
        (over the box q₀ … q₁) and |Δ|, summed over both sides.
        """
        delta = np.asarray(q1, dtype=float) - np.asarray(q0, dtype=float)
        masks = self.masks if checked is None else self.masks[checked]
        sides = self.sides if checked is None else self.sides[checked]
        signed = delta[None, None, :] * masks
        levers = chain.levers(self.supports, self.radii, q0, q1)
        curvature = curvatures(chain.revolute, levers[sides[:, 0]], np.abs(signed[:, 0]))
        curvature += curvatures(chain.revolute, levers[sides[:, 1]], np.abs(signed[:, 1]))
        return signed, sides, curvature

    def _moved(self, scene: CollisionScene) -> PairMotion:
        """The same structure with the scene's current placements."""
        radii = np.array(
            [
                bounding_radius(b.geometry, b.placement) if b.joint != 0 else 0.0
                for b in scene.bodies
            ]
        )
        return PairMotion(
            scene.bodies,
            self.pairs,
            self.joints,
            radii,
            self.supports,
            self.sides,
            self.masks,
            self.exact,
            self._margins,
        )


@dataclass(eq=False)
class Ends:
    """Every pair measured at one configuration, with the joint Jacobian there.

    ``d`` [m]: each pair's value of :meth:`CollisionScene.distance_bounds` (its hulls', its
    meshes' where within ``exact_below``); ``jacobian`` the world-frame joint Jacobian (columns:
    each joint's screw at the world origin); ``origins`` the joints' origins [m].
    """

    q: NDArray[np.float64]
    d: NDArray[np.float64]
    jacobian: NDArray[np.float64]
    origins: NDArray[np.float64]
    key: tuple[object, ...]

    @staticmethod
    def measure(
        scene: CollisionScene, q: NDArray[np.float64], exact_below: NDArray[np.float64]
    ) -> Ends:
        """All pairs at ``q``: one Coal query of every hull pair, the meshes where needed."""
        key = (scene.bodies, scene.bound_data, scene.geometry_data, exact_below.tobytes())
        cached = getattr(scene, "_fast_ends", None)
        if isinstance(cached, Ends) and cached.key == key and np.array_equal(cached.q, q):
            return cached
        data = scene.data
        pin.computeJointJacobians(scene.model, data, q)
        pin.computeDistances(scene.model, data, scene.bound_model, scene.bound_data, q)
        d = min_distances(scene.bound_data.distanceResults)
        motion = PairMotion.of(scene)
        recheck = np.flatnonzero((d <= exact_below) & ~motion.exact)
        if recheck.size:
            pin.updateGeometryPlacements(
                scene.model, data, scene.geometry_model, scene.geometry_data
            )
            for k in recheck.tolist():
                pin.computeDistance(scene.geometry_model, scene.geometry_data, k)
                d[k] = scene.geometry_data.distanceResults[k].min_distance
        ends = Ends(
            np.array(q),
            d,
            np.array(data.J),
            np.array([m.translation for m in data.oMi]),
            key,
        )
        scene._fast_ends = ends  # type: ignore[attr-defined]
        return ends


def _measure_pairs(
    scene: CollisionScene,
    q: NDArray[np.float64],
    exact_below: NDArray[np.float64],
    pairs: NDArray[np.int64],
) -> Ends:
    """Only ``pairs`` at ``q``, one query each (fewer than a whole scene's).

    ``d`` in their order; the Jacobian and origins as :meth:`Ends.measure`.
    """
    data = scene.data
    pin.computeJointJacobians(scene.model, data, q)
    pin.updateGeometryPlacements(scene.model, data, scene.bound_model, scene.bound_data)
    exact = PairMotion.of(scene).exact
    results = scene.bound_data.distanceResults
    meshes = False
    d = np.empty(pairs.size)
    for i, k in enumerate(pairs.tolist()):
        pin.computeDistance(scene.bound_model, scene.bound_data, k)
        value = results[k].min_distance
        if value <= exact_below[k] and not exact[k]:
            if not meshes:
                pin.updateGeometryPlacements(
                    scene.model, data, scene.geometry_model, scene.geometry_data
                )
                meshes = True
            pin.computeDistance(scene.geometry_model, scene.geometry_data, k)
            value = scene.geometry_data.distanceResults[k].min_distance
        d[i] = value
    origins = np.array([m.translation for m in data.oMi])
    return Ends(np.array(q), d, np.array(data.J), origins, ())


_FEW = 12
"""Pairs measured one by one below this many; above, every pair in one query."""


def two_ended_floor(
    d0: NDArray[np.float64],
    a0: NDArray[np.float64],
    d1: NDArray[np.float64],
    a1: NDArray[np.float64],
    curvature: NDArray[np.float64],
    length: float = 1.0,
) -> NDArray[np.float64]:
    """The least over τ ∈ [0, L] of max(f₀(τ), f₁(τ)) per pair [m] (module docstring).

    f₀(τ) = d₀ − a₀τ − ½Aτ² from the start of an interval of length L, f₁(τ) = d₁ −
    a₁(L − τ) − ½A(L − τ)² from its end. f₀ − f₁ = (d₀ − d₁ + a₁L + ½AL²) − (a₀ + a₁ + AL)·τ
    is linear with a slope ≤ 0, so the max is the falling f₀ before the root τ* and the
    rising f₁ after: its least value is at τ* (f₀ = f₁), or at an end when τ* falls outside.
    """
    slope = a0 + a1 + curvature * length
    with np.errstate(divide="ignore", invalid="ignore"):
        root = np.where(
            slope > 0.0,
            (d0 - d1 + a1 * length + 0.5 * curvature * length * length) / slope,
            0.5 * length,
        )
    tau = np.clip(root, 0.0, length)
    f0 = d0 - a0 * tau - 0.5 * curvature * tau * tau
    f1 = d1 - a1 * (length - tau) - 0.5 * curvature * (length - tau) ** 2
    return np.maximum(f0, f1)


def fast_sweep(
    scene: CollisionScene,
    chain: ArmChain,
    q0: NDArray[np.float64],
    q1: NDArray[np.float64],
    options: SweepOptions,
    *,
    relax: bool = True,
    only: NDArray[np.int64] | None = None,
) -> SweepResult:
    """Check q(s) = q₀ + s·(q₁ − q₀), s ∈ [0, 1], as :func:`swept_segment` (module docstring).

    ``relax``: a motion that starts closer than the clearance c to something (a finger resting
    where the last motion stopped it) is checked with c halved below that start distance, as
    :func:`synth.replay.sweeps.sweep_options` does for the reference path. Without directional
    displacements only (the replay's sweeps): ``options.margins`` are distances every pair adds
    to the clearance. ``only``: the pairs to check (indices into the scene's pairs; the others
    proven beyond c already, :mod:`synth.replay.tubes`), measured one by one.
    """
    q0 = np.asarray(q0, dtype=float)
    q1 = np.asarray(q1, dtype=float)
    delta = q1 - q0
    if not scene.pairs or (only is not None and not len(only)):
        return SweepResult(True, 1.0, q1, None, float("inf"), 0)
    motion = PairMotion.of(scene)
    clearance = options.clearance
    exact_below = clearance + motion.margins(options)
    checked = np.arange(len(scene.pairs)) if only is None else np.asarray(only, dtype=np.int64)
    margins = exact_below[checked] - clearance

    def measured(q: NDArray[np.float64], pairs: NDArray[np.int64]) -> tuple[Ends, NDArray]:
        """The checked ``pairs`` (indices into ``checked``) at q: their Ends and distances."""
        if only is None and (pairs is everything or pairs.size >= _FEW):
            ends = Ends.measure(scene, q, exact_below)
            return ends, ends.d[checked[pairs]]
        ends = _measure_pairs(scene, q, exact_below, checked[pairs])
        return ends, ends.d

    everything = np.arange(checked.size)
    start, start_d = measured(q0, everything)
    if relax and float(np.min(start_d)) < clearance:
        clearance = max(0.5 * float(np.min(start_d)), 0.0)
    slack = min(_SLACK, 0.1 * clearance)
    signed, sides, curvature = motion.steps(chain, q0, q1, checked)  # signed: (pairs, 2, nv)
    gap0 = below_gap(start_d, margins)
    rate0 = closing_rates(start, motion, sides, signed)
    if float(np.min(start_d - margins)) <= clearance:
        k = int(np.argmin(start_d - margins))
        pair = scene.pairs[int(checked[k])]
        return SweepResult(
            False, 0.0, q0, pair, float(start_d[k]), 1, float(margins[k]) + clearance
        )
    end, end_d = measured(q1, everything)
    gap1 = below_gap(end_d, margins)
    rate1 = closing_rates(end, motion, sides, signed)
    floor = two_ended_floor(gap0, rate0, gap1, rate1, curvature)
    active = np.flatnonzero(floor - slack <= clearance)
    if not active.size:
        return SweepResult(True, 1.0, q1, None, float("inf"), 2)
    # the pairs that may come within c: split the segment until every interval is clear
    sides, signed, curvature = sides[active], signed[active], curvature[active]
    half = 0.5 * clearance + slack
    margin = margins[active]
    points = [
        _Point(0.0, q0, start_d[active], gap0[active], rate0[active]),
        _Point(1.0, q1, end_d[active], gap1[active], rate1[active]),
    ]
    checks, i = 2, 0
    while True:
        left, right = points[i], points[i + 1]
        floor = two_ended_floor(
            left.gap, left.rate, right.gap, right.rate, curvature, right.s - left.s
        )
        if np.all(floor > half) or right.s - left.s <= _FINEST:
            # no pair dips below c/2 in [left, right]: the stop test moves on to `right`
            gaps = right.d - margin
            k = int(np.argmin(gaps))
            if gaps[k] <= clearance:
                need = float(margin[k]) + clearance
                pair = scene.pairs[int(checked[active[k]])]
                return SweepResult(False, right.s, right.q, pair, float(right.d[k]), checks, need)
            if right.s >= 1.0:
                return SweepResult(True, 1.0, q1, None, float("inf"), checks)
            i += 1
            continue
        if checks >= options.max_checks:
            return SweepResult(False, left.s, left.q, None, float("inf"), checks)
        s = 0.5 * (left.s + right.s)
        q = q0 + s * delta
        here, d = measured(q, active)
        points.insert(
            i + 1, _Point(s, q, d, below_gap(d, margin), closing_rates(here, motion, sides, signed))
        )
        checks += 1


@dataclass(frozen=True, eq=False)
class _Point:
    """A measured point of the segment: s, q, Coal's distances, gap bounds, closing rates."""

    s: float
    q: NDArray[np.float64]
    d: NDArray[np.float64]
    gap: NDArray[np.float64]
    rate: NDArray[np.float64]


_FINEST = 1e-12
"""An interval this short is taken as clear: its floor is its ends' values within rounding."""


def closing_rates(
    ends: Ends, motion: PairMotion, sides: NDArray[np.int64], signed: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Per pair how fast its gap can close at ``ends``' configuration [m per unit s].

    With the world-frame joint Jacobian J (columns: each joint's screw (v₀_j, ω_j) at the
    world origin), side i of a pair turns at ω = Σ_j Δ'_j·ω_j and its joint's origin o moves
    at v = Σ_j Δ'_j·v₀_j + ω × o; its points within R of o move at most |v| + |ω|·R, and the
    gap closes at most at the sum over both sides.
    """
    linear, angular = ends.jacobian[:3], ends.jacobian[3:]
    count = sides.shape[0]
    weights = np.concatenate([signed[:, 0], signed[:, 1]])
    bodies = np.concatenate([sides[:, 0], sides[:, 1]])
    omega = weights @ angular.T
    o = ends.origins[motion.joints[bodies]]
    velocity = weights @ linear.T
    velocity[:, 0] += omega[:, 1] * o[:, 2] - omega[:, 2] * o[:, 1]
    velocity[:, 1] += omega[:, 2] * o[:, 0] - omega[:, 0] * o[:, 2]
    velocity[:, 2] += omega[:, 0] * o[:, 1] - omega[:, 1] * o[:, 0]
    speed = np.sqrt(np.einsum("ij,ij->i", velocity, velocity))
    spin = np.sqrt(np.einsum("ij,ij->i", omega, omega))
    rate = speed + spin * motion.radii[bodies]
    return rate[:count] + rate[count:]


def below_gap(d: NDArray[np.float64], margins: NDArray[np.float64]) -> NDArray[np.float64]:
    """Lower bounds on the true gaps from Coal's distances ``d`` (:data:`GJK_MARGIN`)."""
    return d * (1.0 - GJK_MARGIN) - margins


def _safe_steps(
    gaps: NDArray[np.float64], rates: NDArray[np.float64], curvature: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Per pair the largest h with gap − rate·τ − ½·A·τ² > 0 on [0, h) (0 for gap ≤ 0)."""
    positive = np.maximum(gaps, 0.0)
    root = np.sqrt(rates * rates + 2.0 * curvature * positive)
    denominator = rates + root
    with np.errstate(divide="ignore", invalid="ignore"):
        steps = np.where(denominator > 0.0, 2.0 * positive / denominator, np.inf)
    return np.where(gaps > 0.0, steps, 0.0)
