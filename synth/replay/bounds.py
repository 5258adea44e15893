"""Proven bounds on how far the points of a moving body travel along a joint-space segment.

The replay's conservative advancement (:mod:`synth.replay.contact`, :mod:`synth.replay.sweep`)
steps from s to s + h only when nothing can touch meanwhile, so it needs, for a body carried by
joint k along q(s) = q₀ + s·Δ, a bound on |p(s + h) − p(s)| over all its points p. The global
bound Σ_j ρ_j·|Δ_j| (levers ρ_j over the whole segment, :mod:`synth.models.arm.sweep`) counts
every joint's sweep with its longest lever at full length; a shoulder pitch compensated by the
wrist (the pin lowered straight down) moves the pin at a third of it. Here the first-order term
is exact at s and only the second-order remainder is bounded globally (Taylor with integral
remainder, p(s+h) − p(s) − h·p'(s) = ∫₀ʰ (h − u)·p''(s+u) du):

    |p(s + h) − p(s)| ≤ h·|p'(s)| + ½·h²·A,      A ≥ sup |p''| over the segment.

**First order.** With (v, ω) the world velocity of joint k's frame at s per unit s (Pinocchio's
forward kinematics with velocity Δ), a point p = o_k + r moves at p' = v + ω × r, so every point
within R of o_k moves at |p'| ≤ |v| + |ω|·R; along a unit direction n, n·p' ≥ n·v − |n × ω|·R
(n·(ω × r) = r·(n × ω)).

**Second order.** For a serial chain, p' = Σ_j Δ_j·c_j with c_j = ω_j × (p − o_j) for a
revolute joint (unit axis ω_j through o_j) and c_j = a_j (unit axis) for a prismatic one. A
joint i before j turns axis j and everything after it about axis i, so dω_j/ds = Σ_{i<j, rev}
Δ_i·ω_i × ω_j, |dω_j/ds| ≤ W_j := Σ_{i<j, rev} |Δ_i|, and

    d/ds (p − o_j) = Σ_{i<j, rev} Δ_i·ω_i × (p − o_j) + Σ_{i≥j} Δ_i·c_i(p)

(a prismatic joint before j moves p and o_j alike). With L_j ≥ |p − o_j| over the segment and
ℓ_i = L_i (revolute) or 1 (prismatic), U_j := Σ_{i≥j} |Δ_i|·ℓ_i:

    |dc_j/ds| ≤ 2·W_j·L_j + U_j (revolute j),    |dc_j/ds| ≤ W_j (prismatic j),
    A = Σ_j |Δ_j|·|dc_j/ds|.

L_j is the lever bound of :func:`synth.models.arm.sweep.body_motion_bounds` (chain lengths,
the prismatic extensions over the segment's joint box, the body's ball): :func:`levers`.

**A body moved by the hand error too** (the held pin: p = F(q(s))·w(s), w(s) = X·E(s)·z with
E(s) = (R₀·exp(s·[Ω]), t₀ + s·Δt) blending the two targets' errors and z = G·x the point in
the hand): w' = X_R·(R_e·[Ω]·z + Δt), |w'| ≤ b := |Δt| + |Ω|·|z|, |w''| ≤ |Ω|²·|z|, and
p'' = (the chain's term at fixed w) + 2·ω × F_R·w' + F_R·w'', so A gains 2·Ω_max·b +
|Ω|²·|z| (Ω_max = Σ_rev |Δ_j| bounds |ω|), and the first-order term gains b. The points stay
within |X·G·x| + |t_e| + θ_e·|z| of o_k: |t_e(s)| ≤ max(|t₀|, |t₁|) on the straight blend, and
the rotation angle of R_e(s) is at most max(θ₀, θ₁) because geodesic balls of radius < π/2 in
SO(3) are convex.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.arm import Arm
from synth.replay.motion import Segment
from synth.vec3 import cross3, norm3

__all__ = ["ArmChain", "PinExtent", "PinFlight", "curvatures", "safe_step"]


def safe_step(gap: float, rate: float, curvature: float) -> float:
    """Largest h ≥ 0 with gap − rate·τ − ½·curvature·τ² > 0 for every τ ∈ [0, h).

    ``gap`` [m] a lower bound now, ``rate`` [m per unit s] a bound on how fast it can shrink
    (negative: it grows), ``curvature`` [m per unit s²] the second-order bound A. The positive
    root of the quadratic, in the cancellation-free form 2g / (r + √(r² + 2Ag)); inf where the
    bound never reaches 0 (A = 0, r ≤ 0), 0 for g ≤ 0.
    """
    if gap <= 0.0:
        return 0.0
    root = math.sqrt(max(rate * rate + 2.0 * curvature * gap, 0.0))
    denominator = rate + root
    if denominator <= 0.0:
        return math.inf
    return 2.0 * gap / denominator


@dataclass(frozen=True, eq=False)
class ArmChain:
    """An arm's kinematic chain, prepared for the bounds of the module docstring.

    ``revolute`` per velocity index; ``lengths`` |t_i| of each joint's placement in its parent
    [m]; ``supports[k]`` the velocity indices of the joints carrying joint k, base first.
    """

    arm: Arm
    revolute: NDArray[np.bool_]
    lengths: NDArray[np.float64]
    prismatic_index: NDArray[np.int64]
    supports: tuple[tuple[int, ...], ...]
    data: pin.Data

    @staticmethod
    def of(arm: Arm) -> ArmChain:
        """The chain of ``arm`` (one ``pin.Data`` of its own; made once per arm)."""
        cached = _CHAINS.get(id(arm))
        if cached is not None and cached.arm is arm:
            return cached
        chain = ArmChain._make(arm)
        _CHAINS[id(arm)] = chain
        return chain

    @staticmethod
    def _make(arm: Arm) -> ArmChain:
        model = arm.model
        kinds = arm.limits.kinds
        revolute = np.array([k == "revolute" for k in kinds], dtype=bool)
        lengths = np.zeros(model.nv)
        supports = []
        for j in range(model.njoints):
            chain = tuple(model.joints[i].idx_v for i in model.supports[j] if i != 0)
            supports.append(chain)
            if j != 0:
                lengths[model.joints[j].idx_v] = float(
                    np.linalg.norm(model.jointPlacements[j].translation)
                )
        prismatic = np.flatnonzero(~revolute)
        return ArmChain(arm, revolute, lengths, prismatic, tuple(supports), model.createData())

    def mask(self, joint: int) -> NDArray[np.bool_]:
        """The velocity indices of the joints carrying ``joint``, as a mask."""
        out = np.zeros(self.lengths.shape[0], dtype=bool)
        out[list(self.supports[joint])] = True
        return out

    def levers(
        self,
        supports: NDArray[np.bool_],
        radii: NDArray[np.float64],
        q0: NDArray[np.float64],
        q1: NDArray[np.float64],
    ) -> NDArray[np.float64]:
        """L[p, j] ≥ |x − o_j| [m] for the points x within ``radii[p]`` of body p's joint.

        Body p's supporting joints are ``supports[p]`` (velocity indices). Over the segment's
        joint box [min(q₀, q₁), max(q₀, q₁)]: L_j = R_p + Σ_{i after j in the chain}
        (|t_i| + e_i), e_i = max |q_i| over the box for a prismatic joint i (0 for a
        revolute one); 0 for joints not carrying the body. Pinocchio numbers a chain's joints
        parents first, so "after j" is a reverse cumulative sum over the support.
        """
        reach = np.zeros_like(self.lengths)
        index = self.prismatic_index
        reach[index] = np.maximum(np.abs(q0[index]), np.abs(q1[index]))
        steps = supports * (self.lengths + reach)[None, :]
        after = np.cumsum(steps[:, ::-1], axis=1)[:, ::-1] - steps  # Σ over i > j
        return np.where(supports, radii[:, None] + after, 0.0)

    def curvature(
        self, joint: int, levers: NDArray[np.float64], delta: NDArray[np.float64]
    ) -> float:
        """A ≥ sup |p''| [m per unit s²] for points of a body on ``joint`` (module docstring)."""
        rates = np.where(self.mask(joint), np.abs(delta), 0.0)[None, :]
        return float(curvatures(self.revolute, levers[None, :], rates)[0])


def curvatures(
    revolute: NDArray[np.bool_], levers: NDArray[np.float64], rates: NDArray[np.float64]
) -> NDArray[np.float64]:
    """A per row of |Δ'| (zero off the body's support), levers L alike (module docstring).

    W_j = Σ_{i<j, rev} |Δ'_i|, U_j = Σ_{i≥j} |Δ'_i|·ℓ_i (ℓ = L for revolute, 1 for
    prismatic), A = Σ_j |Δ'_j|·(rev: 2·W_j·L_j + U_j; prismatic: W_j). Pinocchio numbers a
    chain's joints parents first, so the sums run over the velocity indices in order.
    """
    turned = np.cumsum(rates * revolute, axis=1) - rates * revolute  # exclusive: i < j
    arm = np.where(revolute, levers, 1.0)
    tail = np.cumsum((rates * arm)[:, ::-1], axis=1)[:, ::-1]  # inclusive: i ≥ j
    term = np.where(revolute, 2.0 * turned * levers + tail, turned)
    return np.sum(rates * term, axis=1)


_CHAINS: dict[int, ArmChain] = {}


@dataclass(frozen=True)
class PinExtent:
    """How far a held pin's points reach [m], for the grip ``grip``.

    From the hand, ``reach`` = max |G·x|; from the hand joint's origin, ``radius`` =
    max |X·G·x| (X the hand frame in that joint).
    """

    grip: pin.SE3
    reach: float
    radius: float

    @staticmethod
    def of(chain: ArmChain, grip: pin.SE3, points: NDArray[np.float64]) -> PinExtent:
        """The extent of ``points`` (pin frame, columns) held with ``grip``."""
        frame = chain.arm.model.frames[chain.arm.hand_frame]
        x_r, x_t = np.array(frame.placement.rotation), np.array(frame.placement.translation)
        in_hand = np.asarray(grip.rotation) @ points + np.asarray(grip.translation)[:, None]
        in_joint = x_r @ in_hand + x_t[:, None]
        return PinExtent(
            grip,
            float(np.sqrt(np.max(np.einsum("ij,ij->j", in_hand, in_hand)))),
            float(np.sqrt(np.max(np.einsum("ij,ij->j", in_joint, in_joint)))),
        )


class PinFlight:
    """The held pin along one segment: its pose and the speed bounds of the module docstring.

    The pin's pose is P(s) = M_k(q(s))·X·E(s)·G with M_k the hand joint's placement, X the
    hand frame in that joint, E(s) the blended hand error (:meth:`Segment.error_rt`) and G the
    grip (hand from pin). :meth:`at` evaluates everything one step needs at s; ``radius`` [m]
    holds the pin about the joint's origin, ``blend`` [m per unit s] bounds the error's own
    motion of its points, ``curvature`` [m per unit s²] is A.
    """

    def __init__(self, chain: ArmChain, seg: Segment, extent: PinExtent) -> None:
        arm = chain.arm
        self.chain = chain
        self.model = arm.model
        self.data = chain.data
        frame = arm.model.frames[arm.hand_frame]
        self.joint = int(frame.parentJoint)
        self.segment = seg
        self.q0 = np.asarray(seg.q0, dtype=float)
        self.delta = np.asarray(seg.q1, dtype=float) - self.q0
        grip = extent.grip
        x_r, x_t = np.array(frame.placement.rotation), np.array(frame.placement.translation)
        g_r, g_t = np.array(grip.rotation), np.array(grip.translation)
        self._x_r, self._x_t, self._g_r, self._g_t = x_r, x_t, g_r, g_t
        reach = extent.reach
        t_e = max(norm3(seg.e0.translation), norm3(seg.e1.translation))
        theta_e = max(
            norm3(pin.log3(seg.e0.rotation)),
            norm3(pin.log3(seg.e1.rotation)),
        )
        self.radius = extent.radius + t_e + theta_e * reach
        turn = norm3(pin.log3(seg.e0.rotation.T @ seg.e1.rotation))
        shift = norm3(seg.e1.translation - seg.e0.translation)
        self.blend = shift + turn * reach
        levers = chain.levers(
            chain.mask(self.joint)[None, :], np.array([self.radius]), self.q0, self.q0 + self.delta
        )[0]
        omega_max = float(np.abs(self.delta[chain.revolute]).sum())
        self.curvature = (
            chain.curvature(self.joint, levers, self.delta)
            + 2.0 * omega_max * self.blend
            + turn * turn * reach
        )
        # filled by at()
        self.rotation = np.eye(3)
        self.translation = np.zeros(3)
        self.origin = np.zeros(3)
        self.velocity = np.zeros(3)
        self.omega = np.zeros(3)
        self.speed = 0.0

    def at(self, s: float) -> None:
        """Evaluate at ``s``: the pin's pose, the joint's origin and velocity, the speed bound."""
        q = self.q0 + s * self.delta
        pin.forwardKinematics(self.model, self.data, q, self.delta)
        placement = self.data.oMi[self.joint]
        m_r = placement.rotation
        m_t = placement.translation
        twist = self.data.v[self.joint]
        self.velocity = m_r @ twist.linear
        self.omega = m_r @ twist.angular
        self.origin = np.array(m_t)
        r_e, t_e = self.segment.error_rt(s)
        inner_r = self._x_r @ r_e
        self.rotation = m_r @ (inner_r @ self._g_r)
        self.translation = m_r @ (inner_r @ self._g_t + self._x_r @ t_e + self._x_t) + m_t
        self.speed = norm3(self.velocity) + norm3(self.omega) * self.radius + self.blend

    def tip(self, s: float) -> NDArray[np.float64]:
        """The pin frame's origin (its tip centre) at ``s`` [m]; leaves :meth:`at`'s values."""
        q = self.q0 + s * self.delta
        pin.forwardKinematics(self.model, self.data, q)
        placement = self.data.oMi[self.joint]
        r_e, t_e = self.segment.error_rt(s)
        local = self._x_r @ (r_e @ self._g_t + t_e) + self._x_t
        return np.asarray(placement.rotation @ local + placement.translation)

    def pose(self, s: float) -> pin.SE3:
        """The pin's world pose at ``s`` [m]."""
        self.at(s)
        return pin.SE3(self.rotation, self.translation)

    def approach(self, normals: NDArray[np.float64]) -> NDArray[np.float64]:
        """Per unit normal n (rows): a bound on how fast any pin point moves along −n now.

        −n·v + |n × ω|·R + b [m per unit s], from the last :meth:`at`; |n × ω|² = |ω|² −
        (n·ω)² for a unit n.
        """
        along = normals @ self.omega
        across = np.sqrt(np.maximum(float(self.omega @ self.omega) - along * along, 0.0))
        return -(normals @ self.velocity) + across * self.radius + self.blend

    def point_rate(self, point: NDArray[np.float64], direction: NDArray[np.float64]) -> float:
        """d/ds of direction·(a pin point now at world ``point``), without the error's part."""
        return float(direction @ (self.velocity + cross3(self.omega, point - self.origin)))
