"""Joint limits of an arm: position range, velocity, acceleration and (optionally) jerk.

Every array is in configuration order and SI units: a revolute joint's entries are in [rad],
[rad/s], [rad/s²], [rad/s³]; a prismatic joint's in [m], [m/s], [m/s²], [m/s³]. The arm layer
handles only arms whose joints are all revolute or prismatic, so a configuration ``q`` and a
joint velocity have the same length ``n`` and ``q`` can be differenced directly.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from synth.exceptions import ArmModelError

JointKind = Literal["revolute", "prismatic"]

QUINTIC_PEAK_TO_AVERAGE: float = 15.0 / 8.0
"""Peak over average speed of a rest-to-rest fifth-order polynomial (minimum-jerk) move.

AL plans each joint as a 5th-order polynomial in time (seed L5095–5105, eq. 1-1). For
q(τ) = Δ·(10τ³ − 15τ⁴ + 6τ⁵), τ = t/T, the speed peaks at τ = ½ with q̇ = (15/8)·Δ/T, so a move
whose peak speed respects v_max has average speed at most (8/15)·v_max.
"""


def _frozen(values: ArrayLike, n: int, what: str) -> NDArray[np.float64]:
    array = np.array(values, dtype=float).reshape(-1)
    if array.shape != (n,):
        raise ArmModelError(f"{what} has {array.shape[0]} entries, expected {n}")
    if not np.all(np.isfinite(array)):
        raise ArmModelError(f"{what} must be finite")
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class JointLimits:
    """Per-joint limits; arrays are read-only copies, SI units (see the module docstring)."""

    names: tuple[str, ...]
    kinds: tuple[JointKind, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    velocity: NDArray[np.float64]
    acceleration: NDArray[np.float64]
    jerk: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        n = len(self.names)
        if len(self.kinds) != n:
            raise ArmModelError(f"{len(self.kinds)} joint kinds for {n} joints")
        for field in ("lower", "upper", "velocity", "acceleration"):
            object.__setattr__(self, field, _frozen(getattr(self, field), n, f"{field} limits"))
        if self.jerk is not None:
            object.__setattr__(self, "jerk", _frozen(self.jerk, n, "jerk limits"))
        if np.any(self.lower > self.upper):
            bad = [self.names[i] for i in np.flatnonzero(self.lower > self.upper)]
            raise ArmModelError(f"lower limit above upper limit for joint(s) {', '.join(bad)}")
        for field in ("velocity", "acceleration", "jerk"):
            values = getattr(self, field)
            if values is not None and np.any(values <= 0):
                raise ArmModelError(f"{field} limits must be positive")

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.names)

    def contains(self, q: ArrayLike, tolerance: float = 0.0) -> bool:
        """Whether ``lower − tolerance ≤ q ≤ upper + tolerance`` holds for every joint."""
        qa = np.asarray(q, dtype=float)
        return bool(np.all(qa >= self.lower - tolerance) and np.all(qa <= self.upper + tolerance))

    def clip(self, q: ArrayLike) -> NDArray[np.float64]:
        """``q`` clipped into the position limits (a new array)."""
        return np.clip(np.asarray(q, dtype=float), self.lower, self.upper)

    def seed_average_speed(self) -> NDArray[np.float64]:
        """Highest average joint speed of an AL quintic move: v̄ = (8/15)·v_max [rad/s | m/s]."""
        return self.velocity / QUINTIC_PEAK_TO_AVERAGE

    def replace(
        self,
        *,
        velocity: ArrayLike | None = None,
        acceleration: ArrayLike | None = None,
        jerk: ArrayLike | None = None,
    ) -> JointLimits:
        """Return a copy with some rate limits overridden (e.g. by the task's arm section)."""
        return JointLimits(
            names=self.names,
            kinds=self.kinds,
            lower=self.lower,
            upper=self.upper,
            velocity=self.velocity if velocity is None else np.asarray(velocity, dtype=float),
            acceleration=(
                self.acceleration if acceleration is None else np.asarray(acceleration, dtype=float)
            ),
            jerk=self.jerk if jerk is None else np.asarray(jerk, dtype=float),
        )
