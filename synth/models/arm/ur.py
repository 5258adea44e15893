"""Closed-form inverse kinematics of Universal Robots arms, from ``ur_analytic_ik``.

``ur_analytic_ik`` (Victor-Louis De Gusseme, airo-mono; C++ with nanobind bindings, on PyPI)
solves the UR's three-parallel-axes wrist in closed form: up to 8 solutions (shoulder left or
right × elbow up or down × wrist flipped or not), each joint in [−π, π], for the flange
``tool0`` in the DH base frame. example-robot-data's URDFs put ``base_link`` turned π about z
from that DH base and ``tool0`` where the library puts it; :func:`ur_inverse` does not assume
this but measures the fixed transform T_urdf_dh = T_urdf_tool0(q)·T_dh_tool0(q)⁻¹ at one
configuration and checks it at others (a mismatch means a URDF whose joints the library's DH
table does not describe, and the arm keeps the DLS solver).

UR joints turn through ±2π, so every solution θ has aliases θ + 2πk inside the limits. The
nearest-solution rule (:func:`synth.models.arm.rating.nearest_solution`) compares max-norm joint
changes, which per joint are smallest at the alias nearest the hint; given a hint the inverse
returns, for each branch, that alias of every joint, so the rule sees every branch at its
nearest. Without a hint each joint keeps the library's value in [−π, π] (inside any UR limits).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import ModuleType

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from synth.models.arm.limits import JointLimits

_CHECK_CONFIGURATIONS = 5
_CHECK_TOLERANCE = 1e-7  # [m] and [1]: the library's DH constants are printed to 1e-5 mm


def ur_module(name: str) -> ModuleType | None:
    """The ``ur_analytic_ik`` submodule for an arm (``ur5``), or None when not installed."""
    try:
        import ur_analytic_ik
    except ImportError:
        return None
    return getattr(ur_analytic_ik, name, None)


@dataclass(frozen=True, eq=False)
class URInverse:
    """T_world_hand ↦ every attainable configuration, by the UR closed form.

    T_dh_tool0 = T_world_dh⁻¹ · T_world_hand · T_tool0_hand⁻¹, solved by ``ur_analytic_ik``,
    then each joint moved by whole turns to the alias nearest the hint (or kept) and the
    solutions outside the joint limits dropped.
    """

    solver: ModuleType
    world_from_dh: pin.SE3
    tool0_from_hand: pin.SE3
    limits: JointLimits
    _inverse: tuple[pin.SE3, pin.SE3] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        inverse = (self.world_from_dh.inverse(), self.tool0_from_hand.inverse())
        object.__setattr__(self, "_inverse", inverse)

    def __call__(
        self, world_from_hand: pin.SE3, hint: ArrayLike | None = None
    ) -> list[NDArray[np.float64]]:
        """Every attainable solution, each joint at its alias nearest ``hint`` when given."""
        dh_inv, hand_inv = self._inverse
        target = (dh_inv * world_from_hand * hand_inv).homogeneous
        raw = self.solver.inverse_kinematics(np.ascontiguousarray(target))
        if not raw:
            return []
        q = np.array(raw, dtype=float)  # (k, 6), one branch a row
        lower, upper = self.limits.lower, self.limits.upper
        if hint is not None:
            near = np.asarray(hint, dtype=float)
            q += 2 * math.pi * np.round((near - q) / (2 * math.pi))
            # the nearest alias may lie past a stop; step back one turn towards the range
            q = np.where(q > upper, q - 2 * math.pi, q)
            q = np.where(q < lower, q + 2 * math.pi, q)
        q = q[np.all((q >= lower - 1e-12) & (q <= upper + 1e-12), axis=1)]
        # a branch repeated (at a singularity two coincide) is kept once, in the library's order
        gaps = np.max(np.abs(q[:, None, :] - q[None, :, :]), axis=2)
        repeated = np.any(np.tril(gaps <= 1e-9, k=-1), axis=1)
        return list(q[~repeated])


def ur_inverse(
    name: str,
    model: pin.Model,
    tool0_frame: int,
    hand_frame: int,
    limits: JointLimits,
    rng: np.random.Generator | None = None,
) -> URInverse | None:
    """The closed form for a UR ``model`` (world-placed), or None when it does not apply.

    None when ``ur_analytic_ik`` is not installed or its forward kinematics, mapped through
    the measured base transform, misses the model's ``tool0`` anywhere among a few random
    configurations by more than 1e-7.
    """
    solver = ur_module(name)
    if solver is None or model.nq != 6:
        return None
    data = model.createData()

    def tool0(q: NDArray[np.float64]) -> pin.SE3:
        pin.framesForwardKinematics(model, data, q)
        return data.oMf[tool0_frame].copy()

    def library(q: NDArray[np.float64]) -> pin.SE3:
        return pin.SE3(np.asarray(solver.forward_kinematics(*q), dtype=float))

    zero = np.zeros(6)
    world_dh = tool0(zero) * library(zero).inverse()
    generator = rng if rng is not None else np.random.default_rng(0)
    for q in generator.uniform(-math.pi, math.pi, size=(_CHECK_CONFIGURATIONS, 6)):
        if not np.allclose(
            (world_dh * library(q)).homogeneous, tool0(q).homogeneous, atol=_CHECK_TOLERANCE
        ):
            return None
    pin.framesForwardKinematics(model, data, zero)
    tool0_hand = data.oMf[tool0_frame].actInv(data.oMf[hand_frame])
    return URInverse(solver, world_dh, tool0_hand, limits)
