"""What an AL motion statement hands its machine, and what it gets back.

The data of :mod:`synth.al.machine`'s protocol: monitors (``ON <condition> DO``), constraints
(``WITH <condition>``), the relation a condition uses, and :class:`MotionResult`. See
:mod:`synth.al.machine` for what they mean to a machine and :mod:`synth.al.timeline` for how
a machine plays a motion's monitors. Units: SI (forces [N], torques [N·m], openings [m],
times [s]); directions are unit vectors in world coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, TypeAlias

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "Direction",
    "DurationConstraint",
    "DurationMonitor",
    "EventMonitor",
    "ForceConstraint",
    "ForceMonitor",
    "MonitorSpec",
    "MotionConstraint",
    "MotionResult",
    "OpeningMonitor",
    "Relation",
    "TorqueConstraint",
    "TorqueMonitor",
    "relation_holds",
]

Relation = Literal["<", ">", "=", "≤", "≥", "≠"]
"""The relation of a condition, with the sensed quantity on the left."""

Direction: TypeAlias = tuple[float, float, float]
"""A unit vector in world coordinates, as an immutable tuple."""


def relation_holds(value: float, relation: Relation, threshold: float) -> bool:
    """``value relation threshold``; ``=`` and ``≠`` are exact comparisons."""
    if relation == "<":
        return value < threshold
    if relation == ">":
        return value > threshold
    if relation == "≤":
        return value <= threshold
    if relation == "≥":
        return value >= threshold
    if relation == "=":
        return value == threshold
    return value != threshold


def _axis(direction: Direction) -> NDArray[np.float64]:
    return np.array(direction, dtype=float)


# --------------------------------------------------------------------------------------------
# Monitors: ON <condition> DO ...


@dataclass(frozen=True)
class ForceMonitor:
    """``ON FORCE(d) rel f``: the sensed force along world direction ``d`` [N] (S:1376)."""

    direction: Direction
    relation: Relation
    threshold: float
    line: int = 0

    def holds(self, force: ArrayLike) -> bool:
        """Whether the condition holds for the sensed world force vector ``force`` [N]."""
        value = float(_axis(self.direction) @ np.asarray(force))
        return relation_holds(value, self.relation, self.threshold)


@dataclass(frozen=True)
class TorqueMonitor:
    """``ON TORQUE(a) rel t``: sensed torque about world axis ``a`` [N·m] (S:1391)."""

    axis: Direction
    relation: Relation
    threshold: float
    line: int = 0

    def holds(self, torque: ArrayLike) -> bool:
        """Whether the condition holds for the sensed world torque vector ``torque`` [N·m]."""
        value = float(_axis(self.axis) @ np.asarray(torque))
        return relation_holds(value, self.relation, self.threshold)


@dataclass(frozen=True)
class OpeningMonitor:
    """``ON OPENING rel w``: the finger separation [m] (S:1579, S:2725)."""

    relation: Relation
    threshold: float
    line: int = 0

    def holds(self, opening: float) -> bool:
        """Whether the condition holds for the finger opening ``opening`` [m]."""
        return relation_holds(opening, self.relation, self.threshold)


@dataclass(frozen=True)
class DurationMonitor:
    """``ON DURATION rel t``: time since this motion started [s]."""

    relation: Relation
    threshold: float
    line: int = 0

    def holds(self, elapsed: float) -> bool:
        """Whether the condition holds ``elapsed`` [s] after the motion started."""
        return relation_holds(elapsed, self.relation, self.threshold)


@dataclass(frozen=True)
class EventMonitor:
    """``ON e DO``: an external event (a sensor such as an electric eye, S:1210).

    Only the machine can raise it during a motion. Signals from other AL processes are not seen
    by a motion in progress, because the interpreter interleaves processes between statements
    (see :mod:`synth.al.interpreter`).
    """

    event: str
    line: int = 0


MonitorSpec: TypeAlias = (
    ForceMonitor | TorqueMonitor | OpeningMonitor | DurationMonitor | EventMonitor
)


# --------------------------------------------------------------------------------------------
# Constraints: WITH <condition>


@dataclass(frozen=True)
class ForceConstraint:
    """``WITH FORCE(d) = f``: exert ``f`` [N] along ``d``; ``f = 0`` means comply along d."""

    direction: Direction
    value: float
    segment: int | None = None
    line: int = 0


@dataclass(frozen=True)
class TorqueConstraint:
    """``WITH TORQUE(a) = t``: exert ``t`` [N·m] about ``a``; 0 means comply about a."""

    axis: Direction
    value: float
    segment: int | None = None
    line: int = 0


@dataclass(frozen=True)
class DurationConstraint:
    """``WITH DURATION rel t`` [s]: ``>``/``≥`` a minimum, ``=`` exact, ``<``/``≤`` a maximum."""

    relation: Relation
    seconds: float
    segment: int | None = None
    line: int = 0


MotionConstraint: TypeAlias = ForceConstraint | TorqueConstraint | DurationConstraint


# --------------------------------------------------------------------------------------------
# What a motion call reports


@dataclass(frozen=True, eq=False)
class MotionResult:
    """What a motion call (or :meth:`Machine.resume`) reports.

    ``fired``: index into the call's monitors of the monitor that just became true — the motion
    is paused at that instant until :meth:`Machine.stop` or :meth:`Machine.resume` — or None
    when the motion is over. ``arrived``: the motion is over and the hand reached the last
    target (always False while paused). ``hand_pose``: the sensed hand pose now [m].
    ``time``: the machine clock now [s].
    """

    fired: int | None
    arrived: bool
    hand_pose: pin.SE3
    time: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "hand_pose", pin.SE3(self.hand_pose))
        if self.fired is not None and self.arrived:
            raise ValueError("a paused motion has not arrived")
