"""The planner's facts: what each hypothetical world assumes (seed §3.5, L1747–1767).

Each candidate strategy plans in a child world of the task's (:class:`synth.models.world.World`,
seed L1800): the grasp affixes the pin to the hand, the approach fixes its standoff and φ, the
refinement records the accuracy it estimated and the tap it chose. The error chains read
their terms back from these facts (:mod:`synth.strategies.relations`), so a strategy's
estimate follows what its own world holds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from synth.models.world import Fact
from synth.strategies.records import Grasp

__all__ = [
    "Accuracy",
    "Affixed",
    "ApproachPhi",
    "ApproachStandoff",
    "At",
    "Bounds",
    "GraspDetermination",
    "HandError",
    "Holding",
    "InHole",
    "TapAt",
    "Tapped",
    "Task",
    "Uncertain",
]

Bounds = tuple[tuple[str, float, float], ...]
"""``(param, lo, hi)`` bounds [m, rad] of an error block."""


@dataclass(frozen=True)
class Task(Fact):
    """The task the root world plans."""

    name: str


@dataclass(frozen=True)
class InHole(Fact):
    """``pin`` starts ``depth`` [m] deep in ``hole`` (its rack)."""

    KEY: ClassVar[tuple[str, ...]] = ("pin",)
    pin: str
    hole: str
    depth: float


@dataclass(frozen=True)
class At(Fact):
    """Where ``pin`` is: a frame's AL name or a program point (``departure``)."""

    KEY: ClassVar[tuple[str, ...]] = ("pin",)
    pin: str
    place: str


@dataclass(frozen=True)
class Holding(Fact):
    """What ``hand`` holds (``nothing`` when empty)."""

    KEY: ClassVar[tuple[str, ...]] = ("hand",)
    hand: str
    what: str


@dataclass(frozen=True)
class HandError(Fact):
    """Where ``hand``'s positioning error comes from: a task field, or ``exact``."""

    KEY: ClassVar[tuple[str, ...]] = ("hand",)
    hand: str
    source: str


@dataclass(frozen=True)
class Uncertain(Fact):
    """``frame``'s location is known only to the block stated in the task field ``source``."""

    KEY: ClassVar[tuple[str, ...]] = ("frame",)
    frame: str
    source: str


@dataclass(frozen=True)
class Affixed(Fact):
    """``pin`` is held in ``hand`` by ``grasp`` (AL ``AFFIX … NONRIGIDLY``, seed L2630)."""

    KEY: ClassVar[tuple[str, ...]] = ("pin", "hand")
    pin: str
    hand: str
    grasp: Grasp


@dataclass(frozen=True)
class GraspDetermination(Fact):
    """How well the grasp fixes ``pin`` in the hand: the residual error block after ``center``.

    Empty ``residual``: the seed's NILTRANS (L2630), the pin exactly held.
    """

    KEY: ClassVar[tuple[str, ...]] = ("pin",)
    pin: str
    residual: Bounds = ()


@dataclass(frozen=True)
class ApproachStandoff(Fact):
    """The approach point's height [m] over ``hole`` (seed §4.5, L2203)."""

    KEY: ClassVar[tuple[str, ...]] = ("pin", "hole")
    pin: str
    hole: str
    standoff: float


@dataclass(frozen=True)
class ApproachPhi(Fact):
    """The approach direction φ [rad] about the hole axis (seed L2203)."""

    KEY: ClassVar[tuple[str, ...]] = ("pin", "hole")
    pin: str
    hole: str
    phi: float


@dataclass(frozen=True)
class Accuracy(Fact):
    """The footprint at the approach point: Δx, Δy, Δz [m], ζ, Δθ [rad] (seed L2220)."""

    KEY: ClassVar[tuple[str, ...]] = ("pin", "hole")
    pin: str
    hole: str
    dx: float
    dy: float
    dz: float
    zeta: float
    dtheta: float


@dataclass(frozen=True)
class TapAt(Fact):
    """A tapping place ``offset`` [m] from the hole on ``surface`` (seed §4.6, L2244)."""

    KEY: ClassVar[tuple[str, ...]] = ("pin", "surface")
    pin: str
    surface: str
    offset: tuple[float, float, float]


@dataclass(frozen=True)
class Tapped(Fact):
    """The refinement taps ``surface`` at ``offset`` [m] before the insertion."""

    KEY: ClassVar[tuple[str, ...]] = ("surface",)
    surface: str
    offset: tuple[float, float, float]
