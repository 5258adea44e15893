"""The machine an AL program drives: a small protocol, monitor data, and an ideal machine.

The interpreter (:mod:`synth.al.interpreter`) owns the program's *beliefs* (its variables and
affixments). Everything it learns about the *true* world comes through a :class:`Machine`:
where the hand really is, the forces it senses, the finger opening, the clock. The replay
(``synth/replay``) implements the protocol with inverse kinematics, Coal collisions and
contact; :class:`IdealMachine` implements it with a world that is exactly the program's beliefs.

**Units.** SI throughout: poses are ``pin.SE3`` with translations in [m], forces [N], torques
[N·m], openings [m], times [s]. Directions are unit vectors in world coordinates.

**Motions and monitors.** A motion statement (``MOVE``, ``OPEN``, ``CLOSE``, ``CENTER``) is
one call. Its ``ON`` conditions arrive as data (:data:`MonitorSpec`), evaluated by the
interpreter *before* the motion starts (thresholds and directions are fixed at that moment, like
the destinations, S:1341). The machine decides from its own geometry *when* a condition becomes
true. Then it pauses and returns a :class:`MotionResult` with ``fired`` set to that monitor's
index; the interpreter runs the handler (the statement after ``DO``) at that instant, and calls
either :meth:`Machine.stop` (the handler executed ``STOP``, or aborted) or
:meth:`Machine.resume` (it did not; the motion goes on). A monitor fires at most once per
motion (seed-al-subset.md §7 decision): the machine never reports the same index twice in one
motion. When nothing fires, the call returns with ``fired=None`` once the motion is over:
``arrived`` says whether the hand reached its last target, or stopped early on its own (a
contact that no monitor was watching, a stall). ``ON ARRIVAL`` is the interpreter's business
(it runs when ``arrived`` and no handler stopped the motion) and is never sent to the machine.

Constraints (``WITH FORCE(XHAT)=0``, ``WITH DURATION > 2*SEC``) arrive as
:data:`MotionConstraint` data; ``segment`` says which target's segment a constraint qualifies
(a ``WITH`` list written right after a ``VIA`` list, S:1202–1215) or None for the whole
motion. A machine may ignore constraints it cannot model, but must not ignore monitors.

**Force convention** (al-language.md §8.5): ``force(d)`` is the component along the world
direction ``d`` of the force the environment exerts on the hand and what it holds. Pressing a
pin down onto a surface gives a positive ``force(ZHAT)``. ``torque(a)`` is the component along
the world axis ``a`` of the environment's torque about the hand frame's origin.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal, Protocol, TypeAlias, runtime_checkable

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "DurationConstraint",
    "DurationMonitor",
    "EventMonitor",
    "ForceConstraint",
    "ForceMonitor",
    "IdealMachine",
    "Machine",
    "MachineCommand",
    "MonitorSpec",
    "MotionConstraint",
    "MotionGate",
    "MotionResult",
    "OpeningMonitor",
    "Relation",
    "TorqueConstraint",
    "TorqueMonitor",
    "interpolate",
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
# The protocol


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


@runtime_checkable
class Machine(Protocol):
    """An arm with a two-finger hand, as an AL program sees it (see the module docstring).

    ``line`` is the AL line of the statement, for the machine's own reports (violations).
    """

    def hand_pose(self) -> pin.SE3:
        """The sensed pose of the hand frame in the world [m]."""
        ...

    def opening(self) -> float:
        """The finger separation [m]."""
        ...

    def force(self, direction: NDArray[np.float64]) -> float:
        """The sensed force along a world unit direction [N]."""
        ...

    def torque(self, axis: NDArray[np.float64]) -> float:
        """The sensed torque about a world unit axis through the hand origin [N·m]."""
        ...

    def time(self) -> float:
        """The clock [s]: simulated time since the program started."""
        ...

    def move(
        self,
        targets: Sequence[pin.SE3],
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Move the hand through ``targets`` (vias in order, then the destination)."""
        ...

    def open_hand(
        self,
        width: float,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Open (or close) the fingers to ``width`` [m]."""
        ...

    def close_hand(
        self,
        width: float | None,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Close the fingers to ``width`` [m], or until they stop on something (None)."""
        ...

    def center(
        self,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Close until one finger touches, then move the arm until both touch (S:1306)."""
        ...

    def resume(self) -> MotionResult:
        """Continue the paused motion (its handler did not stop it)."""
        ...

    def stop(self) -> None:
        """End the paused motion where it is (``STOP``, or an ``ABORT`` in its handler)."""
        ...


# --------------------------------------------------------------------------------------------
# The ideal machine


def interpolate(start: pin.SE3, end: pin.SE3, s: float) -> pin.SE3:
    """The pose a fraction ``s`` ∈ [0, 1] along the straight path from ``start`` to ``end``.

    Translation is linear in world coordinates; the rotation turns about one fixed axis,
    ``R(s) = R_0 · exp(s · log(R_0ᵀ R_1))``.
    """
    rotation = start.rotation @ pin.exp3(s * pin.log3(start.rotation.T @ end.rotation))
    translation = (1.0 - s) * start.translation + s * end.translation
    return pin.SE3(rotation, translation)


@dataclass(frozen=True, eq=False)
class MachineCommand:
    """One call made to an :class:`IdealMachine`, recorded for tests and reports."""

    kind: Literal["move", "open", "close", "center"]
    targets: tuple[pin.SE3, ...]
    monitors: tuple[MonitorSpec, ...]
    constraints: tuple[MotionConstraint, ...]
    width: float | None
    line: int


@dataclass
class _Motion:
    """A motion in progress: path knots with their times, and what happens at its end."""

    command: MachineCommand
    path: list[pin.SE3]
    knots: list[float]
    end: float
    arrives: bool
    end_force: NDArray[np.float64]
    opening_start: float
    opening_end: float
    start_time: float
    elapsed: float = 0.0
    fired: set[int] = field(default_factory=set)


_ZERO3 = np.zeros(3)


class MotionGate:
    """What every machine checks before it starts a motion (AL's one-motion-at-a-time rule).

    A motion paused by a monitor (``_motion`` not None) must be stopped or resumed before the
    next command; a ``MOVE`` needs at least one target. Shared by :class:`IdealMachine` and
    :class:`synth.replay.machine.ReplayMachine`.
    """

    _motion: object | None = None

    def _check_idle(self) -> None:
        if self._motion is not None:
            raise RuntimeError("a motion is paused; call stop() or resume() first")

    def _check_move(self, targets: Sequence[pin.SE3]) -> None:
        self._check_idle()
        if not targets:
            raise ValueError("a motion needs at least one target")


class IdealMachine(MotionGate):
    """A machine whose world is exactly the program's beliefs.

    Nothing is ever touched: sensed forces and torques are zero, every motion reaches its last
    target, and the hand is where it was commanded. ``CLOSE`` and ``CENTER`` end with the fingers
    at ``grasp_width`` [m] — the width of whatever the fingers close on (0 for nothing); the hand
    does not move while centring (the believed part is already centred). Each motion segment
    takes ``segment_time`` [s] (stretched or squeezed by ``WITH DURATION`` constraints), each hand
    operation ``hand_time`` [s].

    Monitors are checked at the instants where something can change: the moment of the call or
    resume, each duration threshold, and the end of the motion (where sensors take their final
    values). Subclasses model contact by overriding :meth:`contact`.

    Every call is appended to :attr:`commands`.
    """

    def __init__(
        self,
        hand_pose: pin.SE3 | None = None,
        *,
        opening: float = 0.0,
        grasp_width: float = 0.0,
        segment_time: float = 1.0,
        hand_time: float = 0.5,
    ) -> None:
        self._hand = pin.SE3.Identity() if hand_pose is None else pin.SE3(hand_pose)
        self._opening = float(opening)
        self.grasp_width = float(grasp_width)
        self.segment_time = float(segment_time)
        self.hand_time = float(hand_time)
        self._time = 0.0
        self._force: NDArray[np.float64] = _ZERO3.copy()
        self._motion: _Motion | None = None
        self.commands: list[MachineCommand] = []

    # ---- sensors

    def hand_pose(self) -> pin.SE3:
        """The hand pose [m] (a copy)."""
        return pin.SE3(self._hand)

    def opening(self) -> float:
        """The finger opening [m]."""
        return self._opening

    def force(self, direction: NDArray[np.float64]) -> float:
        """Sensed force along ``direction`` [N]: zero unless a contact ended the last motion."""
        return float(self._force @ np.asarray(direction, dtype=float))

    def torque(self, axis: NDArray[np.float64]) -> float:
        """Sensed torque [N·m]: always zero here."""
        return 0.0

    def time(self) -> float:
        """The clock [s]."""
        return self._time

    # ---- override point

    def contact(
        self, command: MachineCommand, path: Sequence[pin.SE3], knots: Sequence[float]
    ) -> tuple[float, NDArray[np.float64]] | None:
        """Where a ``move`` is stopped by contact: (elapsed time [s], world force [N]) or None.

        ``path`` is the start pose followed by the targets, ``knots`` the elapsed time at each.
        The ideal machine touches nothing.
        """
        return None

    # ---- motions

    def _segment_times(self, command: MachineCommand) -> list[float]:
        n = len(command.targets)
        times = [self.segment_time] * n
        whole: list[DurationConstraint] = []
        for c in command.constraints:
            if not isinstance(c, DurationConstraint):
                continue
            if c.segment is None:
                whole.append(c)
            elif 0 <= c.segment < n:
                times[c.segment] = _apply_duration(times[c.segment], c)
        total = sum(times)
        for c in whole:
            wanted = _apply_duration(total, c)
            if total > 0 and wanted != total:
                times = [t * wanted / total for t in times]
                total = wanted
        return times

    def move(
        self,
        targets: Sequence[pin.SE3],
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Move through ``targets``; see the class docstring."""
        self._check_move(targets)
        command = MachineCommand(
            "move",
            tuple(pin.SE3(t) for t in targets),
            tuple(monitors),
            tuple(constraints),
            None,
            line,
        )
        self.commands.append(command)
        path = [self.hand_pose(), *command.targets]
        knots = [0.0]
        for t in self._segment_times(command):
            knots.append(knots[-1] + t)
        stop = self.contact(command, path, knots)
        end, arrives, force = knots[-1], True, _ZERO3
        if stop is not None:
            end = min(max(float(stop[0]), 0.0), knots[-1])
            arrives, force = False, np.asarray(stop[1], dtype=float)
        self._force = _ZERO3.copy()
        self._motion = _Motion(
            command, path, knots, end, arrives, force, self._opening, self._opening, self._time
        )
        return self._advance()

    def _hand_operation(
        self,
        kind: Literal["open", "close", "center"],
        width: float | None,
        final_opening: float,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        self._check_idle()
        command = MachineCommand(kind, (), tuple(monitors), tuple(constraints), width, line)
        self.commands.append(command)
        here = self.hand_pose()
        self._force = _ZERO3.copy()
        self._motion = _Motion(
            command,
            [here, here],
            [0.0, self.hand_time],
            self.hand_time,
            True,
            _ZERO3,
            self._opening,
            final_opening,
            self._time,
        )
        return self._advance()

    def open_hand(
        self,
        width: float,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Set the opening to ``width`` [m]."""
        return self._hand_operation("open", width, width, monitors, constraints, line)

    def close_hand(
        self,
        width: float | None,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Close to ``width`` [m], or onto ``grasp_width`` if that is wider (or width is None)."""
        final = self.grasp_width if width is None else max(width, self.grasp_width)
        return self._hand_operation("close", width, final, monitors, constraints, line)

    def center(
        self,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Close onto ``grasp_width``; the hand does not move."""
        return self._hand_operation("center", None, self.grasp_width, monitors, constraints, line)

    def resume(self) -> MotionResult:
        """Continue the paused motion."""
        if self._motion is None:
            raise RuntimeError("no motion is paused")
        return self._advance()

    def stop(self) -> None:
        """End the paused motion where it is."""
        motion = self._motion
        if motion is None:
            raise RuntimeError("no motion is paused")
        self._settle(motion, motion.elapsed, arrived=False)

    # ---- the event loop of one motion

    def _pose_at(self, motion: _Motion, elapsed: float) -> pin.SE3:
        knots = motion.knots
        if elapsed >= knots[-1]:
            return pin.SE3(motion.path[-1])
        for i in range(1, len(knots)):
            if elapsed <= knots[i]:
                span = knots[i] - knots[i - 1]
                s = 1.0 if span <= 0 else (elapsed - knots[i - 1]) / span
                return interpolate(motion.path[i - 1], motion.path[i], s)
        return pin.SE3(motion.path[-1])

    def _holds(self, motion: _Motion, monitor: MonitorSpec, elapsed: float) -> bool:
        at_end = elapsed >= motion.end
        if isinstance(monitor, ForceMonitor):
            return monitor.holds(motion.end_force if at_end else _ZERO3)
        if isinstance(monitor, TorqueMonitor):
            return monitor.holds(_ZERO3)
        if isinstance(monitor, OpeningMonitor):
            return monitor.holds(motion.opening_end if at_end else motion.opening_start)
        if isinstance(monitor, DurationMonitor):
            return monitor.holds(elapsed)
        return False  # no external events in an ideal world

    def _advance(self) -> MotionResult:
        motion = self._motion
        assert motion is not None
        instants = {motion.elapsed, motion.end}
        for m in motion.command.monitors:
            if isinstance(m, DurationMonitor) and motion.elapsed <= m.threshold <= motion.end:
                instants.add(m.threshold)
                if m.relation == ">":
                    instants.add(math.nextafter(m.threshold, math.inf))
        for t in sorted(x for x in instants if x <= motion.end):
            for i, m in enumerate(motion.command.monitors):
                if i not in motion.fired and self._holds(motion, m, t):
                    motion.fired.add(i)
                    motion.elapsed = t
                    self._hand = self._pose_at(motion, t)
                    self._time = motion.start_time + t
                    if t >= motion.end:
                        self._opening = motion.opening_end
                        self._force = motion.end_force.copy()
                    return MotionResult(i, False, self._hand, self._time)
        return self._settle(motion, motion.end, arrived=motion.arrives)

    def _settle(self, motion: _Motion, elapsed: float, *, arrived: bool) -> MotionResult:
        self._hand = self._pose_at(motion, elapsed)
        self._time = motion.start_time + elapsed
        done = elapsed >= motion.end
        if motion.command.kind == "move":
            self._force = motion.end_force.copy() if done else _ZERO3.copy()
        else:
            fraction = 1.0 if motion.end <= 0 else min(elapsed / motion.end, 1.0)
            self._opening = motion.opening_start + fraction * (
                motion.opening_end - motion.opening_start
            )
        self._motion = None
        return MotionResult(None, arrived and done, self._hand, self._time)


def _apply_duration(time: float, c: DurationConstraint) -> float:
    if c.relation in (">", "≥"):
        return max(time, c.seconds)
    if c.relation in ("<", "≤"):
        return min(time, c.seconds)
    if c.relation == "=":
        return c.seconds
    return time
