"""Arm sweeps proven once and reused: a clearance tube about a swept joint-space segment.

A replay sweeps nearly the same motions in every trial: the same statements, with targets that
differ by the sampled errors. A free sweep of q(s) = q₀ + s·Δ, s ∈ [0, 1], proves a floor c_k
under each pair's gap at every s (:func:`certify`: the two-ended floors of
:mod:`synth.replay.advance` over a subdivision of [0, 1], from Coal's distances less GJK's
margin and the pair's margin). A later sweep q'(s) = q₀' + s·Δ' of the same scene (the same
bodies and pairs, repositioned to another trial's poses, :class:`~synth.models.arm.SceneCache`)
moves each point of body p, at each s, by at most

    δ_p = Σ_j w_pj·ε_j + |Δt_p| + ‖ΔR_p‖₂·ρ_p,

* ε_j = max(|q₀' − q₀|_j, |q₁' − q₁|_j) ≥ |q'(s) − q(s)|_j, both paths straight in s;
* w_pj the lever L_pj of body p about revolute joint j (:meth:`ArmChain.levers` over the box
  holding all four ends), 1 for a prismatic joint: going from q(s) to q'(s) one joint at a
  time, every intermediate configuration lies in that box, a turn ε about a revolute axis moves
  a point at r from it along an arc of length ε·r, and a prismatic joint translates by ε;
* (Δt_p, ΔR_p) the change of the body's placement in its joint's frame (an object's true pose,
  the grip), ρ_p the ball about the body's own origin holding it: |R'x + t' − Rx − t| ≤ |Δt| +
  ‖R' − R‖₂·|x|, and ‖R' − R‖₂ = ‖I − RᵀR'‖₂ = 2·sin(θ/2) = √(3 − tr RᵀR') for the angle θ of
  RᵀR' (its eigenvalues are 1, e^{±iθ}). The joint part uses the levers of the old placement:
  the point F(q)·P·x goes to F(q')·P·x (the levers), then to F(q')·P'·x (the placement,
  rigidly).

A pair's gap is 1-Lipschitz in the points of each of its solids, and only the joints of the
pair's mask (:attr:`PairMotion.masks`: those that move one side relative to the other and can
change the distance) count, so the new gap is at least c_k − δ_a − δ_b at every s. A pair
where that exceeds the clearance (and :data:`~synth.replay.advance._SLACK`) cannot come within
it anywhere on the new path: :func:`~synth.replay.advance.fast_sweep` would measure it farther
than the clearance at every point, never stop on it, and sweeping the other pairs alone
(``only``) gives the same verdict. Typically every pair of a gross motion is proven and a few
(the fingers above the box) are left to sweep, one Coal query each.

A scene keeps a few tubes (:class:`Tubes`), built after free sweeps that no tube helped, at
most :data:`BUILDS` per AL line: a line whose paths differ in every trial (a search pattern's
points) stops paying for tubes after that.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.arm import CollisionScene, SweepOptions
from synth.models.arm.bodies import bounding_radius
from synth.replay.advance import (
    _SLACK,
    Ends,
    PairMotion,
    below_gap,
    closing_rates,
    two_ended_floor,
)
from synth.replay.bounds import ArmChain

__all__ = ["BUILDS", "Placements", "Tube", "Tubes", "certify"]

BUILDS = 12
"""Tubes built per AL line and scene before the line stops building them."""

_KEPT = 32
"""Tubes kept per scene (the oldest goes)."""

_TRIED = 3
"""Tubes tried per sweep, nearest ends first."""

_FINEST = 1.0 / 64.0
"""A certificate's intervals are split no finer than this (at most 65 measured points)."""


@dataclass(frozen=True, eq=False)
class Placements:
    """The scene's bodies' placements in their joints' frames, stacked, and their own balls.

    ``rotations`` (B, 3, 3), ``translations`` (B, 3) [m], ``own_radii`` ρ_p (B,) [m]: the ball
    about the body's own origin that holds it.
    """

    bodies: tuple[object, ...]
    rotations: NDArray[np.float64]
    translations: NDArray[np.float64]
    own_radii: NDArray[np.float64]

    @staticmethod
    def of(scene: CollisionScene) -> Placements:
        """The placements of ``scene``'s bodies now (kept while its bodies stay the same)."""
        cached = getattr(scene, "_placements", None)
        if isinstance(cached, Placements) and cached.bodies is scene.bodies:
            return cached
        own = getattr(scene, "_own_radii", None)
        if own is None or own.shape[0] != len(scene.bodies):
            identity = pin.SE3.Identity()
            own = np.array([bounding_radius(b.geometry, identity) for b in scene.bodies])
            scene._own_radii = own  # type: ignore[attr-defined]
        placements = Placements(
            scene.bodies,
            np.array([b.placement.rotation for b in scene.bodies]).reshape(-1, 3, 3),
            np.array([b.placement.translation for b in scene.bodies]).reshape(-1, 3),
            own,
        )
        scene._placements = placements  # type: ignore[attr-defined]
        return placements

    def moved(self, other: Placements) -> NDArray[np.float64]:
        """Per body, how far any of its points moves from this placement to ``other``'s [m]."""
        shift = np.linalg.norm(other.translations - self.translations, axis=1)
        # tr RᵀR' = Σ R∘R'; its rounding (≈ 10⁻¹⁶) moves √(3 − tr) by ≈ 10⁻⁸: within _SLACK
        trace = np.einsum("bij,bij->b", self.rotations, other.rotations)
        turn = np.sqrt(np.maximum(3.0 - trace, 0.0))
        return shift + turn * self.own_radii


@dataclass(frozen=True, eq=False)
class Tube:
    """A free sweep's certificate (module docstring).

    ``q0``, ``q1`` the swept segment's ends; ``floors`` per pair a lower bound [m] on its gap
    (less its margin) at every s; ``radii`` the bodies' balls about their joints' origins and
    ``placements`` their placements when it was built.
    """

    q0: NDArray[np.float64]
    q1: NDArray[np.float64]
    floors: NDArray[np.float64]
    radii: NDArray[np.float64]
    placements: Placements

    def unproven(
        self,
        scene: CollisionScene,
        chain: ArmChain,
        q0: NDArray[np.float64],
        q1: NDArray[np.float64],
        clearance: float,
    ) -> NDArray[np.int64]:
        """The pairs this tube cannot keep beyond ``clearance`` along q₀ → q₁ (docstring)."""
        motion = PairMotion.of(scene)
        eps = np.maximum(np.abs(q0 - self.q0), np.abs(q1 - self.q1))
        reach = np.maximum(np.maximum(np.abs(q0), np.abs(q1)), np.abs(self.q0))
        reach = np.maximum(reach, np.abs(self.q1))
        levers = chain.levers(motion.supports, self.radii, reach, reach)
        weights = np.where(chain.revolute[None, :], levers, motion.supports.astype(float))
        sides = motion.sides
        # Σ_j w_pj·ε_j per pair and side, over the pair's mask only
        joint = np.einsum("kij,kij,j->ki", motion.masks, weights[sides], eps)
        placed = self.placements.moved(Placements.of(scene))[sides]
        moved = np.sum(joint + placed, axis=1)
        slack = min(_SLACK, 0.1 * clearance)
        return np.flatnonzero(self.floors - moved - slack <= clearance)


def certify(
    scene: CollisionScene,
    chain: ArmChain,
    q0: NDArray[np.float64],
    q1: NDArray[np.float64],
    options: SweepOptions,
) -> Tube:
    """The floors of q₀ → q₁ on ``scene``: each pair's gap less its margin, at every s [m].

    Both ends are measured (every pair, :class:`~synth.replay.advance.Ends`), and an interval
    is split at its midpoint while some pair's two-ended floor there is below half its gap at
    either end, down to :data:`_FINEST`: the floors then keep about half of each pair's gap,
    which is what a nearby sweep can spend on its displacement.
    """
    motion = PairMotion.of(scene)
    margins = motion.margins(options)
    exact_below = options.clearance + margins
    delta = q1 - q0
    signed, sides, curvature = motion.steps(chain, q0, q1)

    def point(s: float) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
        ends = Ends.measure(scene, q0 + s * delta, exact_below)
        return s, below_gap(ends.d, margins), closing_rates(ends, motion, sides, signed)

    floors = np.full(len(scene.pairs), np.inf)
    stack = [(point(0.0), point(1.0))]
    while stack:
        (s_a, gap_a, rate_a), (s_b, gap_b, rate_b) = stack.pop()
        length = s_b - s_a
        floor = two_ended_floor(gap_a, rate_a, gap_b, rate_b, curvature, length)
        if length > _FINEST and np.any(floor < 0.5 * np.minimum(gap_a, gap_b)):
            middle = point(0.5 * (s_a + s_b))
            stack += [((s_a, gap_a, rate_a), middle), (middle, (s_b, gap_b, rate_b))]
            continue
        floors = np.minimum(floors, floor)
    return Tube(np.array(q0), np.array(q1), floors, motion.radii.copy(), Placements.of(scene))


@dataclass(eq=False)
class Tubes:
    """The tubes of one scene, and how many each AL line has built."""

    tubes: list[Tube] = field(default_factory=list)
    built: dict[int, int] = field(default_factory=dict)

    @staticmethod
    def of(scene: CollisionScene) -> Tubes:
        """The tubes kept on ``scene`` (they outlive its repositioning)."""
        tubes = getattr(scene, "_tubes", None)
        if not isinstance(tubes, Tubes):
            tubes = Tubes()
            scene._tubes = tubes  # type: ignore[attr-defined]
        return tubes

    def unproven(
        self,
        scene: CollisionScene,
        chain: ArmChain,
        q0: NDArray[np.float64],
        q1: NDArray[np.float64],
        clearance: float,
    ) -> NDArray[np.int64] | None:
        """The pairs left to sweep on q₀ → q₁ after the nearest kept tube that proves most.

        The nearest tube is tried first, the next ones only while none has proven more than
        half the pairs: on the seed's programs a farther tube never left fewer pairs than a
        nearest one that proved most (0 of 260 sweeps), and each test costs a lever bound.
        None when no tube is kept or none proves more than half the pairs (the whole scene is
        swept then); empty when one proves them all.
        """
        if not self.tubes or chain.arm.model.nq != chain.arm.model.nv:
            return None
        starts = np.array([t.q0 for t in self.tubes])
        ends = np.array([t.q1 for t in self.tubes])
        far = np.max(np.abs(starts - q0), axis=1) + np.max(np.abs(ends - q1), axis=1)
        best: NDArray[np.int64] | None = None
        for k in np.argsort(far)[:_TRIED].tolist():
            left = self.tubes[k].unproven(scene, chain, q0, q1, clearance)
            if best is None or left.size < best.size:
                best = left
            if 2 * best.size <= len(scene.pairs):
                break
        if best is None or 2 * best.size > len(scene.pairs):
            return None
        return best

    def build(
        self,
        line: int,
        scene: CollisionScene,
        chain: ArmChain,
        q0: NDArray[np.float64],
        q1: NDArray[np.float64],
        options: SweepOptions,
    ) -> None:
        """Certify a free sweep of ``line`` (unless the line has built :data:`BUILDS`)."""
        if self.built.get(line, 0) >= BUILDS or chain.arm.model.nq != chain.arm.model.nv:
            return
        self.built[line] = self.built.get(line, 0) + 1
        if len(self.tubes) >= _KEPT:
            self.tubes.pop(0)
        self.tubes.append(certify(scene, chain, q0, q1, options))
