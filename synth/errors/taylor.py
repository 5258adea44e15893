"""First-order Taylor models with rigorous remainders: the certified half of error estimation.

The seed linearises every error (Eqn 3.5.1, L2205): ``Δp ≈ Σ v_k p_k``, ``ΔR ≈ I + Σ v_k M_k``.
That first-order value is not an upper bound of the true error — rotations bend lever arms
(appendix A.2: the exact |Δz| reaches ≈ 0.15 cm where the linear bound says 0.127 cm).

A Taylor model here is a triple ``(X₀, {X_i}, B)`` standing for every matrix (or vector)
``X(v) = X₀ + Σ v_i X_i + Q(v)`` with ``|Q(v)| ≤ B`` *entrywise* for all ``v`` in the parameter
box ``|v_i| ≤ m_i``. Leaves are exact:

* translation parameter ``t`` along axis e: ``X₀ = 0``, ``X_t = e``, ``B = 0``;
* elementary rotation ``rot(e_k, θ)``, ``|θ| ≤ a ≤ π``: ``X₀ = I``, ``X_θ = [e_k]×``; the rest
  ``R − I − θ[e_k]×`` has ``cos θ − 1`` on the two diagonal entries ⟂ e_k and ``±(sin θ − θ)``
  off the diagonal, so ``B`` holds ``1 − cos a`` and ``a − sin a`` there (both ≤ a²/2).

Products propagate the bound. Write ``|L|`` for the entrywise absolute value and
``L̄ = Σ m_i |X_i|`` (so ``|Σ v_i X_i| ≤ L̄`` entrywise on the box). For ``C = A·B``::

    C₀ = A₀B₀,   C_i = A₀B_i + A_iB₀,
    B_C = L̄_A L̄_B + (|A₀| + L̄_A) B_B + B_A (|B₀| + L̄_B) + B_A B_B

(all products of non-negative matrices, each term an entrywise upper bound of the matching term
of the exact product). So ``B`` bounds the nonlinear remainder of the whole chain: a linear
functional ``ℓ·X`` lies within ``[min ℓ·ΣvX_i, max ℓ·ΣvX_i] ± |ℓ|·B`` over the feasible set.
Interval arithmetic overestimates when large quantities cancel (a 1 m lever arm out and back);
:mod:`synth.errors.chain` therefore conjugates every perturbation to the end of the chain so that
only local lever arms enter the products.

**Rounding.** Everything is computed in float64, so the stored ``C₀`` and ``C_i`` differ from
the exact products of the stored factors. Each product and sum pads ``B`` with the standard
bound of that rounding (Higham, *Accuracy and Stability of Numerical Algorithms*, §3.1: an inner
product of length k computed in floating point is within γ_k·|a|·|b| of the exact one, γ_k =
k·u/(1 − k·u), u = 2⁻⁵³): γ_k·|A₀||B₀| for the value and γ_{k+1}·Σ m_i(|A₀||B_i| + |A_i||B₀|)
for the linear part over the box, and then scales the padded ``B`` by (1 + γ_{k+n+8}) for the
rounding of the (non-negative) bound arithmetic itself. The leaves' remainders are computed
without cancellation (``1 − cos a = 2 sin²(a/2)``) and padded likewise. So the remainder bounds
the true chain minus the first-order model *as stored*, not only in exact arithmetic.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

UNIT_ROUNDOFF = float(np.finfo(np.float64).eps) / 2.0
"""u = 2⁻⁵³, the unit roundoff of float64."""


def gamma(k: int) -> float:
    """γ_k = k·u/(1 − k·u): the relative error bound of k float64 operations (Higham §3.1)."""
    return k * UNIT_ROUNDOFF / (1.0 - k * UNIT_ROUNDOFF)


def rotation_remainder(axis: int, a: float) -> np.ndarray:
    """Entrywise bound of ``rot(e_axis, θ) − I − θ[e_axis]×`` for ``|θ| ≤ a`` (a ≤ π).

    ``1 − cos a`` on the two diagonal entries ⟂ e_axis, as 2 sin²(a/2) (no cancellation);
    ``a − sin a`` off the diagonal, plus 4u·a for its cancellation; both scaled by 1 + γ_4 so
    that the computed value is not below the exact one.
    """
    a = abs(a)
    if a > np.pi:
        raise ValueError("rotation tolerance above 180° has no first-order model")
    b = np.zeros((3, 3))
    i, j = (axis + 1) % 3, (axis + 2) % 3
    pad = 1.0 + gamma(4)
    b[i, i] = b[j, j] = 2.0 * np.sin(a / 2.0) ** 2 * pad
    b[i, j] = b[j, i] = (max(a - np.sin(a), 0.0) + 4.0 * UNIT_ROUNDOFF * a) * pad
    return b


@dataclass(frozen=True, eq=False)
class TaylorModel:
    """``X(v) = value + Σ v_i linear[i] + Q``; ``|Q| ≤ remainder`` entrywise for ``|v| ≤ m``."""

    value: np.ndarray
    linear: np.ndarray
    remainder: np.ndarray
    magnitude: np.ndarray

    @classmethod
    def constant(cls, value: np.ndarray, magnitude: np.ndarray) -> TaylorModel:
        """An exactly known matrix or vector."""
        value = np.array(value, dtype=float)
        return cls(
            value, np.zeros((len(magnitude), *value.shape)), np.zeros(value.shape), magnitude
        )

    @classmethod
    def translation(cls, axis: int, index: int, magnitude: np.ndarray) -> TaylorModel:
        """The vector ``v_index · e_axis`` (exact, zero remainder)."""
        lin = np.zeros((len(magnitude), 3))
        lin[index, axis] = 1.0
        return cls(np.zeros(3), lin, np.zeros(3), magnitude)

    @classmethod
    def rotation(cls, axis: int, index: int, magnitude: np.ndarray) -> TaylorModel:
        """``rot(e_axis, v_index)`` with the remainder of :func:`rotation_remainder`."""
        lin = np.zeros((len(magnitude), 3, 3))
        lin[index] = skew(np.eye(3)[axis])
        return cls(np.eye(3), lin, rotation_remainder(axis, float(magnitude[index])), magnitude)

    def spread(self) -> np.ndarray:
        """``L̄ = Σ m_i |X_i|``: an entrywise bound of the linear part on the box."""
        return np.tensordot(self.magnitude, np.abs(self.linear), axes=1)

    def __matmul__(self, other: TaylorModel) -> TaylorModel:
        a0, b0 = self.value, other.value
        if b0.ndim == 1:
            lin = np.einsum("ij,nj->ni", a0, other.linear) + np.einsum("nij,j->ni", self.linear, b0)
        else:
            lin = np.einsum("ij,njk->nik", a0, other.linear) + np.einsum(
                "nij,jk->nik", self.linear, b0
            )
        la, lb = self.spread(), other.spread()
        ra, rb = self.remainder, other.remainder
        abs_a0, abs_b0 = np.abs(a0), np.abs(b0)
        k = a0.shape[-1]
        rounding = gamma(k) * (abs_a0 @ abs_b0) + gamma(k + 1) * (abs_a0 @ lb + la @ abs_b0)
        rem = la @ lb + (abs_a0 + la) @ rb + ra @ (abs_b0 + lb) + ra @ rb + rounding
        rem = rem * (1.0 + gamma(k + len(self.magnitude) + 8))
        return TaylorModel(a0 @ b0, lin, rem, self.magnitude)

    def __add__(self, other: TaylorModel) -> TaylorModel:
        exact = TaylorModel(
            self.value + other.value,
            self.linear + other.linear,
            self.remainder + other.remainder,
            self.magnitude,
        )
        # each stored sum is within u of the exact one: |C₀| u, and Σ m_i |C_i| u over the box
        rounding = UNIT_ROUNDOFF * (np.abs(exact.value) + exact.spread())
        rem = (exact.remainder + rounding) * (1.0 + gamma(len(self.magnitude) + 4))
        return TaylorModel(exact.value, exact.linear, rem, self.magnitude)

    def __neg__(self) -> TaylorModel:
        return TaylorModel(-self.value, -self.linear, self.remainder, self.magnitude)

    @property
    def T(self) -> TaylorModel:
        """Transpose."""
        return TaylorModel(
            self.value.T, np.swapaxes(self.linear, 1, 2), self.remainder.T, self.magnitude
        )


def skew(w: np.ndarray) -> np.ndarray:
    """``[w]×``, so that ``[w]× u = w × u`` (the seed's M_x, M_y, M_z for unit axes, L2262)."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def vee(m: np.ndarray) -> np.ndarray:
    """Inverse of :func:`skew` on the skew part of ``m`` (last two axes)."""
    s = 0.5 * (m - np.swapaxes(m, -1, -2))
    return np.stack([s[..., 2, 1], s[..., 0, 2], s[..., 1, 0]], axis=-1)


@dataclass(frozen=True, eq=False)
class PoseModel:
    """A rigid transform ``(R, p)`` whose rotation and translation are Taylor models."""

    rotation: TaylorModel
    translation: TaylorModel

    def __mul__(self, other: PoseModel) -> PoseModel:
        """``(R₁, p₁)(R₂, p₂) = (R₁R₂, R₁p₂ + p₁)``."""
        return PoseModel(
            self.rotation @ other.rotation, self.rotation @ other.translation + self.translation
        )

    def inverse(self) -> PoseModel:
        """``(R, p)⁻¹ = (Rᵀ, −Rᵀp)``."""
        rt = self.rotation.T
        return PoseModel(rt, -(rt @ self.translation))
