"""An arm: a Pinocchio model in world coordinates, its hand frame, limits and collision bodies.

The base placement T_world_base is folded into the model (the first joints' placements and the
fixed base frames), so forward kinematics gives the hand frame directly in the world frame, the
frame the task and AL programs use. Inverse kinematics dispatches to the arm's closed form when
it has one (the Stanford arm, seed eqs. 14–32; UR arms, :mod:`.ur`) and to the
damped-least-squares solver otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from synth.models.arm.bodies import Body
from synth.models.arm.limits import JointLimits
from synth.models.manipulator import HandSpec


class ClosedFormInverse(Protocol):
    """T_world_hand ↦ every attainable configuration (empty when none).

    ``hint`` is the configuration the arm comes from: an inverse whose joints turn through more
    than 2π returns each solution at the whole-turn alias nearest it (:mod:`.ur`).
    """

    def __call__(
        self, world_from_hand: pin.SE3, hint: ArrayLike | None = None
    ) -> list[NDArray[np.float64]]:
        """Every attainable solution."""
        ...


@dataclass(frozen=True, eq=False, repr=False)
class Arm:
    """A manipulator ready for kinematics and collision checking.

    ``model`` has all joints revolute or prismatic (configuration and velocity spaces coincide);
    ``hand_frame`` is the id of AL's hand frame (origin between the finger pads, z = approach,
    fingers closing along x). ``bodies`` are the arm links' and the hand's collision shapes
    (fingers at full opening). ``disabled_pairs`` holds link-name pairs never checked against
    each other (from an SRDF). ``grasp_joint`` is the joint the seed's rating examines (θ5 of
    the Stanford arm, L2086), if the arm has such a joint.

    The cached ``pin.Data`` makes calls cheap but not thread-safe; use :meth:`new_data` for
    concurrent work.
    """

    name: str
    model: pin.Model
    hand_frame: int
    limits: JointLimits
    hand: HandSpec
    bodies: tuple[Body, ...]
    world_from_base: pin.SE3
    disabled_pairs: frozenset[frozenset[str]] = frozenset()
    closed_form: ClosedFormInverse | None = None
    grasp_joint: int | None = None
    _data: pin.Data = field(init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_data", self.model.createData())

    def __repr__(self) -> str:
        kind = "closed form" if self.closed_form is not None else "DLS"
        return f"Arm({self.name!r}, {self.nq} joints, {len(self.bodies)} bodies, inverse: {kind})"

    @property
    def nq(self) -> int:
        """Number of joints (configuration size)."""
        return int(self.model.nq)

    def new_data(self) -> pin.Data:
        """Return a fresh Pinocchio data object for this model."""
        return self.model.createData()

    def forward(self, q: ArrayLike) -> pin.SE3:
        """T_world_hand(q): the hand frame in world coordinates (a copy)."""
        qa = np.asarray(q, dtype=float)
        pin.forwardKinematics(self.model, self._data, qa)
        return pin.updateFramePlacement(self.model, self._data, self.hand_frame).copy()

    def jacobian(self, q: ArrayLike) -> NDArray[np.float64]:
        """Hand-frame Jacobian in the hand frame (``pin.LOCAL``): 6 × n, [m/rad | 1] and [1]."""
        qa = np.asarray(q, dtype=float)
        return pin.computeFrameJacobian(self.model, self._data, qa, self.hand_frame, pin.LOCAL)

    def inverse(
        self,
        world_from_hand: pin.SE3,
        *,
        hint: ArrayLike | None = None,
        rng: np.random.Generator | None = None,
    ) -> list[NDArray[np.float64]]:
        """Return configurations reaching ``world_from_hand`` (empty when none is found).

        With a closed form every attainable solution is returned (in the closed form's order);
        otherwise the multi-start DLS solver's distinct solutions, sorted by distance to
        ``hint`` when given. ``rng`` seeds the DLS starts (a fixed seed when omitted, so results
        are reproducible).
        """
        if self.closed_form is not None:
            return self.closed_form(world_from_hand, hint=hint)
        from synth.models.arm.ik import build_ik, solve_ik_all

        problem = build_ik(self, world_from_hand, hint=hint)
        return solve_ik_all(problem, rng if rng is not None else np.random.default_rng(0))
