"""Error estimates of a relation: first-order (the seed's figures) and certified bounds.

For ``T = from⁻¹ ∘ to`` with nominal ``(R₀, p₀)`` the errors are expressed in the ``from``
frame:

* displacement ``Δp = p(v) − p₀``; ``Δx, Δy, Δz`` are its components (seed §4.5.2–4.5.3);
* rotation ``ΔR = R(v) R₀ᵀ ≈ I + [Δθ]×`` (seed Eqn 3.5.1, L2205); ``Δθ_x, Δθ_y, Δθ_z`` are the
  components of its rotation vector;
* tilt: the angle between the true and nominal axis ``a₀ = R₀ẑ`` of ``to``. The seed's figure
  (§4.5.1, L2250) is ``max_i max |d_i · ΔR a₀|`` over six directions ``d_i`` ⟂ a₀,
  ``ζ_i = 0°, 30°, …, 150°``.

First-order bounds are LPs over the linear part of the Taylor model. Certified bounds add the
rigorous remainder (see :mod:`synth.errors.taylor`) and convert exactly where the seed
linearised:

* ``ℓ·Δp ∈ LP(ℓ·Σ v_i p_i) ± r_p``;
* the rotation vector ``ω`` of ΔR has ``s = sin|ω| ω̂ = vee(skew ΔR)``, so ``s ∈ LP ± r_R``, and
  ``ω = (|ω|/sin|ω|) s`` with ``|ω| ≤ asin |s|_max`` once ``cos|ω| = (tr ΔR − 1)/2 ≥ 1 − 1.5 r_R``
  shows ``|ω| < 90°``;
* tilt: ``sin(tilt) = |a₀ × R(v)ẑ| ≤ max_i h_i / cos(15°)`` for the support values ``h_i`` of the
  in-plane part in the six directions (a circumscribed 12-gon), each certified with ``± r_R``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from synth.errors.bounds import Interval, bound_linear
from synth.errors.chain import ErrorChain, Perturbation
from synth.errors.parameters import ParameterSpace
from synth.errors.taylor import PoseModel, TaylorModel, vee
from synth.exceptions import EstimationError

TILT_DIRECTIONS = 6
"""Directions ζ_i = i·180°/6 of the seed's Δθ table (L2250) and footprint (L2420)."""

AXIS_NAMES = ("dx", "dy", "dz", "dtheta_x", "dtheta_y", "dtheta_z")


@dataclass(frozen=True)
class ErrorBounds:
    """Bounds of the six error components [m, rad] and the axis tilt [rad]."""

    dx: Interval
    dy: Interval
    dz: Interval
    dtheta_x: Interval
    dtheta_y: Interval
    dtheta_z: Interval
    tilt: float

    def to_json(self) -> dict[str, object]:
        """JSON shape of ``synth errors --json`` (SI units)."""
        out: dict[str, object] = {k: getattr(self, k).as_list() for k in AXIS_NAMES}
        out["tilt"] = self.tilt
        return out


@dataclass(frozen=True)
class ErrorReport:
    """First-order and certified errors of ``start⁻¹ ∘ end`` in the ``start`` frame."""

    start: str
    end: str
    first_order: ErrorBounds
    certified: ErrorBounds
    position_remainder: tuple[float, float, float]
    rotation_remainder: tuple[float, float, float]
    parameters: tuple[str, ...]

    def to_json(self) -> dict[str, object]:
        """JSON shape of ``synth errors --json``."""
        return {
            "from": self.start,
            "to": self.end,
            "first_order": self.first_order.to_json(),
            "certified": self.certified.to_json(),
            "remainder": {
                "position": list(self.position_remainder),
                "rotation": list(self.rotation_remainder),
            },
            "parameters": list(self.parameters),
        }


@dataclass(frozen=True, eq=False)
class RelationModel:
    """A chain's Taylor model re-expressed as errors in the ``from`` frame."""

    space: ParameterSpace
    displacement: TaylorModel  # Δp = p(v) − p₀, value 0
    rotation_error: TaylorModel  # ΔR = R(v) R₀ᵀ, value I
    axis: TaylorModel  # R(v) ẑ, value a₀
    nominal_axis: np.ndarray

    @classmethod
    def of(cls, chain: ErrorChain) -> RelationModel:
        """Build from a chain (one pass of Taylor-model arithmetic)."""
        model: PoseModel = chain.pose_model()
        m = chain.space.magnitude
        r0 = model.rotation.value
        p0 = model.translation.value
        disp = model.translation + TaylorModel.constant(-p0, m)
        rot_err = model.rotation @ TaylorModel.constant(r0.T, m)
        axis = model.rotation @ TaylorModel.constant(np.array([0.0, 0.0, 1.0]), m)
        return cls(chain.space, disp, rot_err, axis, r0[:, 2].copy())

    def displacement_along(self, direction: np.ndarray) -> tuple[Interval, Interval]:
        """First-order and certified bounds of ``direction · Δp``."""
        d = np.asarray(direction, dtype=float)
        first = bound_linear(self.displacement.linear @ d, self.space)
        return first, first.widened(float(np.abs(d) @ self.displacement.remainder))

    def sine_vector(self, direction: np.ndarray) -> tuple[Interval, Interval]:
        """First-order bound of ``direction · Δθ`` and certified bound of ``direction · s``."""
        d = np.asarray(direction, dtype=float)
        first = bound_linear(vee(self.rotation_error.linear) @ d, self.space)
        return first, first.widened(float(np.abs(d) @ vee_remainder(self.rotation_error.remainder)))

    def tilt_directions(self, count: int = TILT_DIRECTIONS) -> np.ndarray:
        """Unit vectors ``cos ζ e₁ + sin ζ e₂`` ⟂ a₀, ζ = i·180°/count.

        ``e₁, e₂ = x̂, ŷ`` of the ``from`` frame when a₀ ∥ ẑ (the seed's case).
        """
        a0 = self.nominal_axis
        if abs(a0[2]) > 1.0 - 1e-9:
            e1, e2 = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
        else:
            e1 = np.cross([0.0, 0.0, 1.0], a0)
            e1 /= np.linalg.norm(e1)
            e2 = np.cross(a0, e1)
        zeta = np.arange(count) * math.pi / count
        return np.cos(zeta)[:, None] * e1 + np.sin(zeta)[:, None] * e2

    def tilt_table(self, count: int = TILT_DIRECTIONS) -> tuple[np.ndarray, np.ndarray]:
        """Seed §4.5.1's Δθ_i = max |d_i · ΔR a₀|: first-order and certified, per direction."""
        first, cert = [], []
        for d in self.tilt_directions(count):
            f = bound_linear(self.axis.linear @ d, self.space)
            first.append(f.magnitude)
            cert.append(f.magnitude + float(np.abs(d) @ self.axis.remainder))
        return np.array(first), np.array(cert)

    def footprint_table(self, count: int = TILT_DIRECTIONS) -> tuple[np.ndarray, np.ndarray]:
        """Seed §4.5.3's ξ_k = max |(cos ζ_k, sin ζ_k, 0) · Δp|, ζ_k = k·180°/count."""
        zeta = np.arange(count) * math.pi / count
        first, cert = [], []
        for z in zeta:
            f, c = self.displacement_along(np.array([math.cos(z), math.sin(z), 0.0]))
            first.append(f.magnitude)
            cert.append(c.magnitude)
        return np.array(first), np.array(cert)


def certified_tilt(table: np.ndarray) -> float:
    """Certified tilt [rad] from the certified Δθ_i of equally spaced directions.

    ``asin(max_i Δθ_i / cos(π / 2n))``: n directions π/n apart (six, 30°), so the support of
    the tilt vector in any direction is at most ``max_i h_i / cos 15°`` (a 12-gon
    circumscribes the support set; module docstring).
    """
    half_spacing = math.pi / (2 * len(table))
    return math.asin(min(1.0, float(np.max(table)) / math.cos(half_spacing)))


def _bounds(p: list[Interval], t: list[Interval], tilt: float) -> ErrorBounds:
    return ErrorBounds(
        dx=p[0], dy=p[1], dz=p[2], dtheta_x=t[0], dtheta_y=t[1], dtheta_z=t[2], tilt=tilt
    )


def _triple(x: np.ndarray) -> tuple[float, float, float]:
    return (float(x[0]), float(x[1]), float(x[2]))


def vee_remainder(b: np.ndarray) -> np.ndarray:
    """Entrywise bound of ``vee(skew Q)`` given ``|Q| ≤ b``: ``(b₂₁ + b₁₂)/2, …``."""
    return 0.5 * np.array([b[2, 1] + b[1, 2], b[0, 2] + b[2, 0], b[1, 0] + b[0, 1]])


def _rotation_tolerances(chain: ErrorChain) -> str:
    """``owner rz ±80°, …``: the rotation tolerances along a chain, largest first."""
    used = {t.block for t in chain.terms if isinstance(t, Perturbation)}
    found = []
    for index in sorted(used):
        block = chain.space.blocks[index]
        for k, name in enumerate(block.names):
            if name in ("rx", "ry", "rz"):
                width = max(-float(block.lo[k]), float(block.hi[k]))
                found.append((width, f"{block.owner} {name} ±{math.degrees(width):.3g}°"))
    found.sort(key=lambda item: -item[0])
    return ", ".join(text for _, text in found) or "no rotation tolerance"


def estimate_errors(chain: ErrorChain, start: str = "from", end: str = "to") -> ErrorReport:
    """First-order and certified error bounds of a relation chain (module docstring)."""
    rel = RelationModel.of(chain)
    # cos|ω| = (tr ΔR − 1)/2 ≥ 1 − Σ B_ii / 2 (the linear part is skew, trace 0); the
    # axis stays within 90° when a₀·R(v)ẑ ≥ 1 − |a₀|·B_axis > 0.
    trace_slack = float(np.trace(rel.rotation_error.remainder))
    axis_slack = float(np.abs(rel.nominal_axis) @ rel.axis.remainder)
    if trace_slack >= 2.0 or axis_slack >= 1.0:
        raise EstimationError(
            f"rotation errors of {start}→{end} are too large for a certified small-angle bound "
            f"({_rotation_tolerances(chain)}); together they must stay well below 90°"
        )
    first_p, cert_p, first_t, cert_s = [], [], [], []
    for d in np.eye(3):
        f, c = rel.displacement_along(d)
        first_p.append(f)
        cert_p.append(c)
        f, c = rel.sine_vector(d)
        first_t.append(f)
        cert_s.append(c)
    # |ω| ≤ asin |s|_max, and ω = (|ω| / sin|ω|) s with that factor in [1, g].
    s_max = math.sqrt(sum(c.magnitude**2 for c in cert_s))
    theta_max = math.asin(min(1.0, s_max))
    g = theta_max / math.sin(theta_max) if theta_max > 0 else 1.0
    cert_t = [Interval(min(c.lo, g * c.lo), max(c.hi, g * c.hi)) for c in cert_s]

    tilt_first, tilt_cert = rel.tilt_table()
    first = _bounds(first_p, first_t, float(tilt_first.max()))
    certified = _bounds(cert_p, cert_t, certified_tilt(tilt_cert))
    return ErrorReport(
        start,
        end,
        first,
        certified,
        _triple(rel.displacement.remainder),
        _triple(vee_remainder(rel.rotation_error.remainder)),
        chain.space.labels,
    )
