"""The error footprint of a pin-hole relation (seed §4.5.1–4.5.3, Figure 4.1).

From the relation ``hole⁻¹ ∘ end`` (:mod:`synth.strategies.relations`):

* tilt (L2225–2235): ``Δθ_i = max |(cos ζ_i, sin ζ_i, 0) · ΔR ẑ|`` for six ζ_i, and
  ``Δθ = max_i Δθ_i``; certified: ``sin Δθ ≤ max_i h_i / cos 15°`` over the support values
  ``h_i`` with remainders (the circumscribed 12-gon of :mod:`synth.errors.estimate`);
* along the axis (L2283): ``Δz = max |ẑ · Δp|``;
* in the plane (L2420–2434): ``ξ_k = max |(cos ζ_k, sin ζ_k, 0) · Δp|``, ζ_k = 30°·k,
  ``Δx = max_k ξ_k``, ``Δy = ξ_(k+3) mod 6``, ``ζ = ζ_k``: a rectangle ±Δx × ±Δy turned by ζ.

The approach's path bow (:mod:`synth.strategies.bow`, the joint-interpolated move's largest
distance from the axis above the seat) is a lateral offset of at most ``b`` in some direction,
so it adds at most ``b`` to every ξ_k: ``ξ_k + b``.

Decisions use the certified values (first order plus the Taylor remainder); the first-order
ones, which are the seed's figures, are kept in ``first_order`` for display. ζ here is measured
in the hole frame; the seed measured it in the hole frame turned by φ (tests/test_errors_seed.py),
so ``ζ_seed = ζ − φ`` modulo 180°.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from synth.errors.chain import ErrorChain
from synth.errors.estimate import TILT_DIRECTIONS, RelationModel, certified_tilt
from synth.strategies.context import PlanContext
from synth.strategies.records import ErrorFootprint

DIRECTIONS = np.arange(TILT_DIRECTIONS) * math.pi / TILT_DIRECTIONS
"""ζ_k = k·30° [rad], k = 0…5 (L2420)."""


def footprint_box(xi: NDArray[np.float64]) -> tuple[float, float, float]:
    """``(Δx, Δy, ζ)`` from the six ξ_k (L2430–2434): the largest, the one 90° away, its ζ."""
    k = int(np.argmax(xi))
    half = len(xi) // 2
    return float(xi[k]), float(xi[(k + half) % len(xi)]), float(DIRECTIONS[k])


def footprint_tables(
    ctx: PlanContext, model: RelationModel
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """First-order and certified ξ_k [m] (counted as six bound evaluations)."""
    ctx.counters.count_bounds(model.space, len(DIRECTIONS))
    return model.footprint_table(len(DIRECTIONS))


def estimate_footprint(
    ctx: PlanContext, chain: ErrorChain, bow: float = 0.0
) -> tuple[ErrorFootprint, RelationModel]:
    """The footprint of a relation: certified fields, first-order figures in ``first_order``.

    ``bow`` [m] is added to every ξ_k, certified and first order (module docstring).
    """
    model = RelationModel.of(chain)
    xi_first, xi_cert = footprint_tables(ctx, model)
    xi_first, xi_cert = xi_first + bow, xi_cert + bow
    ctx.counters.count_bounds(model.space, TILT_DIRECTIONS)
    tilt_first, tilt_cert = model.tilt_table(TILT_DIRECTIONS)
    ctx.counters.count_bounds(model.space)
    dz_first, dz_cert = model.displacement_along(np.array([0.0, 0.0, 1.0]))
    dx, dy, zeta = footprint_box(xi_cert)
    fx, fy, fzeta = footprint_box(xi_first)
    first = {
        "dx": fx,
        "dy": fy,
        "zeta": fzeta,
        "dz": dz_first.magnitude,
        "dtheta": float(np.max(tilt_first)),
    }
    return (
        ErrorFootprint(
            dx=dx,
            dy=dy,
            dz=dz_cert.magnitude,
            zeta=zeta,
            dtheta=certified_tilt(tilt_cert),
            first_order=first,
        ),
        model,
    )
