"""One motion's timeline, played the same way by every machine: checkpoints, monitors, stops.

A machine (:class:`synth.al.machine.IdealMachine`, :class:`synth.replay.machine.ReplayMachine`)
turns a motion statement into a :class:`Timeline`: the motion's length ``end`` [s], its
:class:`Checkpoint` s — the instants where a monitor can change its value — and how the sensors
read at each. :class:`TimelineMachine` plays it: it visits the checkpoints in order and pauses
at the first unfired monitor that holds (the interpreter then runs its handler and calls
:meth:`~TimelineMachine.resume` or :meth:`~TimelineMachine.stop`); when none does, the motion
runs to its end. What a machine does at an instant (where its hand is, what it holds) it says
through three hooks: ``_show`` (a monitor fired), ``_settle`` (the motion ends there) and
``_ended`` (it ran to its end). Units: [s], [N], [N·m], [m].

**Durations** (:func:`segment_times`). Each segment of a motion has its machine's own time; a
``WITH DURATION rel t`` written after a via list sets that segment's time (``>``/``≥``: at
least t, ``<``/``≤``: at most t, ``=``: exactly t), one for the whole motion scales every
segment by wanted/total. A motion whose segments take no time at all (the arm is already
there) and must take t takes it on its last segment: a program that waits with
``MOVE BARM TO BARM WITH DURATION = 2*SEC`` waits 2 s.

**Checkpoints.** Sensor values are piecewise constant or linear in time, so a monitor can only
switch at a few instants:

* the start (and the instant of every resume: the cursor stays on the checkpoint where a
  monitor fired, so the next monitor that holds there fires at the same instant);
* a ``DURATION rel t`` monitor at t and at the next float after t (where ``>`` and ``≠`` start
  to hold), :func:`duration_checkpoints`;
* an ``OPENING rel w`` monitor, while the fingers move linearly from w₀ to w₁ over the motion's
  length T, at t = T·(w − w₀)/(w₁ − w₀) and just after, :func:`opening_checkpoints`;
* a contact at the end of a motion: the force rises from 0 to its peak F there along the unit
  ``normal``, with torque ``lever × force`` about the hand; a ``FORCE(d) rel f`` monitor
  switches at the level L where L·(d·n) rel f starts to hold (:func:`crossing_level`), so the
  checkpoints are those levels, in increasing order, at the contact's instant
  (:func:`ramp_levels`);
* the end.

A monitor fires at most once per motion; ``EVENT`` monitors never fire (no machine here has
external sensors).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Generic, Literal, TypeVar

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.al.motions import (
    DurationConstraint,
    DurationMonitor,
    EventMonitor,
    ForceMonitor,
    MonitorSpec,
    MotionConstraint,
    MotionResult,
    OpeningMonitor,
    TorqueMonitor,
    relation_holds,
)
from synth.vec3 import cross3

__all__ = [
    "Checkpoint",
    "MotionGate",
    "Timeline",
    "TimelineMachine",
    "apply_duration",
    "crossing_level",
    "duration_checkpoints",
    "duration_conflict",
    "monitor_holds",
    "opening_checkpoints",
    "ramp_levels",
    "segment_times",
]

_ZERO3 = np.zeros(3)
_ZERO3.flags.writeable = False


def apply_duration(time: float, constraint: DurationConstraint) -> float:
    """The time [s] ``time`` becomes under ``constraint`` (``≠`` leaves it)."""
    if constraint.relation in (">", "≥"):
        return max(time, constraint.seconds)
    if constraint.relation in ("<", "≤"):
        return min(time, constraint.seconds)
    if constraint.relation == "=":
        return constraint.seconds
    return time


def duration_conflict(
    constraints: Sequence[MotionConstraint],
) -> tuple[DurationConstraint, DurationConstraint] | None:
    """Two ``WITH DURATION`` constraints of one segment (or of the whole motion) no time meets.

    Each constraint bounds the time from below (``>``, ``≥``, ``=``) or above (``<``, ``≤``,
    ``=``), as :func:`apply_duration` applies it; the bounds of one scope conflict when the
    greatest lower one exceeds the least upper one. Returns the binding earlier constraint and
    the later one that contradicts it, or None. Applied in turn they would silently leave the
    last one's time (``= 2`` then ``= 3`` takes 3 s).
    """
    lower: dict[int | None, DurationConstraint] = {}
    upper: dict[int | None, DurationConstraint] = {}
    for c in constraints:
        if not isinstance(c, DurationConstraint) or c.relation in ("≠",):
            continue
        scope = c.segment
        if c.relation in (">", "≥", "="):
            bound = upper.get(scope)
            if bound is not None and c.seconds > bound.seconds:
                return bound, c
            if scope not in lower or c.seconds > lower[scope].seconds:
                lower[scope] = c
        if c.relation in ("<", "≤", "="):
            bound = lower.get(scope)
            if bound is not None and c.seconds < bound.seconds:
                return bound, c
            if scope not in upper or c.seconds < upper[scope].seconds:
                upper[scope] = c
    return None


def segment_times(
    durations: Sequence[float], constraints: Sequence[MotionConstraint]
) -> list[float]:
    """Segment times [s] stretched or squeezed by the ``WITH DURATION`` constraints.

    Per-segment constraints first, then each whole-motion one scales all segments by
    wanted/total; a motion of total 0 that must take t > 0 takes it on its last segment.
    """
    times = list(durations)
    whole = []
    for c in constraints:
        if not isinstance(c, DurationConstraint):
            continue
        if c.segment is None:
            whole.append(c)
        elif 0 <= c.segment < len(times):
            times[c.segment] = apply_duration(times[c.segment], c)
    total = sum(times)
    for c in whole:
        wanted = apply_duration(total, c)
        if total > 0 and wanted != total:
            times = [t * wanted / total for t in times]
            total = wanted
        elif total == 0 and wanted > 0 and times:
            times[-1] = wanted
            total = wanted
    return times


def crossing_level(
    value_per_newton: float, relation: str, threshold: float, peak: float
) -> float | None:
    """Smallest force level L ∈ (0, peak] [N] at which ``L·c rel threshold`` holds, or None.

    ``c`` = ``value_per_newton``: the monitored component per newton of contact force. The
    candidates are the first level above 0, the exact crossing threshold/c nudged past it, and
    the peak; the least that satisfies the relation is returned.
    """
    candidates = [1e-9, peak]
    if value_per_newton != 0.0:
        exact = threshold / value_per_newton
        candidates.append(exact + max(abs(exact) * 1e-12, 1e-12))
    for level in sorted(c for c in candidates if 0.0 < c <= peak):
        if relation_holds(level * value_per_newton, relation, threshold):  # type: ignore[arg-type]
            return level
    return None


def ramp_levels(
    monitors: Sequence[MonitorSpec],
    normal: NDArray[np.float64],
    lever: NDArray[np.float64],
    peak: float,
) -> list[float]:
    """Force levels [N] of a contact ramp 0 → ``peak`` along ``normal`` where a monitor switches.

    A force monitor watches ``direction · (L·n)``; a torque monitor ``axis · (lever × L·n)``.
    """
    levels = set()
    moment = cross3(lever, normal)
    for m in monitors:
        if isinstance(m, ForceMonitor):
            per_newton = float(np.dot(m.direction, normal))
        elif isinstance(m, TorqueMonitor):
            per_newton = float(np.dot(m.axis, moment))
        else:
            continue
        level = crossing_level(per_newton, m.relation, m.threshold, peak)
        if level is not None:
            levels.add(level)
    return sorted(levels)


@dataclass(frozen=True)
class Checkpoint:
    """An instant ``elapsed`` [s] after the motion started where monitors are checked.

    ``level`` [N]: the contact force there (None: no contact); ``violation``: the machine's
    record of a violation that ends the motion there (raised by the machine's ``_violated``).
    """

    elapsed: float
    level: float | None = None
    violation: Any = None


def duration_checkpoints(monitors: Sequence[MonitorSpec], end: float) -> list[Checkpoint]:
    """A duration monitor's threshold t and the next float after it, within [0, end]."""
    out = []
    for m in monitors:
        if isinstance(m, DurationMonitor) and 0.0 <= m.threshold <= end:
            out.append(Checkpoint(m.threshold))
            out.append(Checkpoint(min(math.nextafter(m.threshold, math.inf), end)))
    return out


def opening_checkpoints(
    monitors: Sequence[MonitorSpec], start: float, final: float, end: float
) -> list[Checkpoint]:
    """Where an opening monitor's threshold is crossed while the fingers go start → final."""
    out: list[Checkpoint] = []
    if final == start:
        return out
    for m in monitors:
        if isinstance(m, OpeningMonitor):
            fraction = (m.threshold - start) / (final - start)
            if 0.0 <= fraction <= 1.0:
                t = fraction * end
                out.append(Checkpoint(t))
                out.append(Checkpoint(min(math.nextafter(t, math.inf), end)))
    return out


def monitor_holds(
    monitor: MonitorSpec,
    force: NDArray[np.float64],
    torque: NDArray[np.float64],
    opening: float,
    elapsed: float,
) -> bool:
    """Whether ``monitor`` holds with these sensor readings ``elapsed`` [s] into the motion."""
    if isinstance(monitor, ForceMonitor):
        return monitor.holds(force)
    if isinstance(monitor, TorqueMonitor):
        return monitor.holds(torque)
    if isinstance(monitor, OpeningMonitor):
        return monitor.holds(opening)
    if isinstance(monitor, DurationMonitor):
        return monitor.holds(elapsed)
    assert isinstance(monitor, EventMonitor)
    return False  # no external sensors


@dataclass(eq=False)
class Timeline:
    """A motion being played back (see the module docstring).

    ``end`` [s] its length (where it stops early, if it does); ``arrives``: it reaches its
    last target; the fingers go ``opening_start`` → ``opening_end`` [m] linearly over
    ``end``; a motion that ends on a contact has ``contact`` set, the contact force rising to
    ``peak`` [N] along the unit ``normal`` with torque ``lever × force`` (``lever`` [m] from the
    hand). ``cursor`` is the next checkpoint, ``fired`` the monitors that fired, ``detected``
    whether one fired on the contact force.
    """

    kind: Literal["move", "open", "close", "center"]
    line: int
    monitors: tuple[MonitorSpec, ...]
    start_time: float
    end: float
    checkpoints: list[Checkpoint]
    arrives: bool
    opening_start: float = 0.0
    opening_end: float = 0.0
    contact: bool = False
    peak: float = 0.0
    normal: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    lever: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    cursor: int = 0
    fired: set[int] = field(default_factory=set)
    detected: bool = False

    def opening_at(self, elapsed: float) -> float:
        """The finger opening [m] ``elapsed`` [s] into the motion (linear over ``end``)."""
        fraction = 1.0 if self.end <= 0 else min(max(elapsed / self.end, 0.0), 1.0)
        return self.opening_start + fraction * (self.opening_end - self.opening_start)

    def readings(
        self, checkpoint: Checkpoint
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
        """Force [N], torque [N·m] and opening [m] at ``checkpoint``."""
        opening = self.opening_at(checkpoint.elapsed)
        if checkpoint.level is None:
            return _ZERO3, _ZERO3, opening
        force = checkpoint.level * self.normal
        return force, cross3(self.lever, force), opening

    def seal(self) -> None:
        """Order the checkpoints: by instant, plain ones before the contact levels, rising."""
        self.checkpoints.sort(key=lambda c: (c.elapsed, -1.0 if c.level is None else c.level))


def monitor_checkpoints(
    monitors: Sequence[MonitorSpec],
    end: float,
    *,
    opening: tuple[float, float] | None = None,
) -> list[Checkpoint]:
    """The start, the duration (and, for a hand motion, opening) checkpoints, and the end."""
    out = [Checkpoint(0.0), *duration_checkpoints(monitors, end)]
    if opening is not None:
        out += opening_checkpoints(monitors, opening[0], opening[1], end)
    out.append(Checkpoint(end))
    return out


class MotionGate:
    """What every machine checks before it starts a motion (AL's one-motion-at-a-time rule).

    A motion paused by a monitor (``_motion`` not None) must be stopped or resumed before the
    next command; a ``MOVE`` needs at least one target.
    """

    _motion: object | None = None

    def _check_idle(self) -> None:
        if self._motion is not None:
            raise RuntimeError("a motion is paused; call stop() or resume() first")

    def _check_move(self, targets: Sequence[pin.SE3]) -> None:
        self._check_idle()
        if not targets:
            raise ValueError("a motion needs at least one target")


M = TypeVar("M", bound=Timeline)


class TimelineMachine(MotionGate, Generic[M]):
    """Plays :class:`Timeline` s of type ``M``: the event loop, resume and stop.

    See the module docstring. Subclasses keep ``_time`` [s], ``_opening`` [m], ``_force`` [N]
    and ``_torque`` [N·m], which the sensors read, and implement :meth:`hand_pose` and the hooks
    ``_show``, ``_settle``; ``_violated``, ``_stopped`` and ``_ended`` default to raising,
    nothing and nothing.
    """

    _motion: M | None = None  # type: ignore[assignment]
    _time: float
    _opening: float
    _force: NDArray[np.float64]
    _torque: NDArray[np.float64]

    # ---- sensors

    def hand_pose(self) -> pin.SE3:  # pragma: no cover - every machine has its own
        """The sensed hand pose [m]."""
        raise NotImplementedError

    def opening(self) -> float:
        """The finger opening [m]."""
        return self._opening

    def force(self, direction: NDArray[np.float64]) -> float:
        """Sensed force along world ``direction`` [N].

        The contact's reaction on the hand (and the pin it holds) where a contact ended or
        paused the last motion; zero otherwise.
        """
        return float(self._force @ np.asarray(direction, dtype=float))

    def torque(self, axis: NDArray[np.float64]) -> float:
        """Sensed torque about world ``axis`` through the hand origin [N·m]."""
        return float(self._torque @ np.asarray(axis, dtype=float))

    def time(self) -> float:
        """The clock [s]: the simulated time the program has run."""
        return self._time

    # ---- hooks

    def _show(self, motion: M, checkpoint: Checkpoint) -> None:
        """Present the instant where a monitor fired (clock, hand, opening; force is set)."""
        raise NotImplementedError

    def _settle(self, motion: M, elapsed: float) -> None:
        """End ``motion`` ``elapsed`` [s] after it started: the machine stays there."""
        raise NotImplementedError

    def _violated(self, motion: M, checkpoint: Checkpoint) -> None:
        """A violation checkpoint was reached (the motion has settled there): raise it."""
        raise RuntimeError(f"violation at {checkpoint.elapsed} s: {checkpoint.violation}")

    def _stopped(self, motion: M, at_contact: bool) -> None:
        """The program stopped ``motion`` (``at_contact``: while the contact force rose)."""

    def _ended(self, motion: M) -> None:
        """``motion`` ran to its end (sensors read the contact force already, if any)."""

    # ---- playing

    def _start(self, motion: M) -> MotionResult:
        motion.seal()
        self._force = _ZERO3.copy()
        self._torque = _ZERO3.copy()
        self._motion = motion
        return self._advance()

    def _sense(self, motion: M, level: float | None) -> None:
        if level is None:
            self._force, self._torque = _ZERO3.copy(), _ZERO3.copy()
        else:
            self._force = level * motion.normal
            self._torque = cross3(motion.lever, self._force)

    def resume(self) -> MotionResult:
        """Continue the paused motion."""
        if self._motion is None:
            raise RuntimeError("no motion is paused")
        return self._advance()

    def stop(self) -> None:
        """End the paused motion where it is (the force where the contact had risen to)."""
        motion = self._motion
        if motion is None:
            raise RuntimeError("no motion is paused")
        checkpoint = motion.checkpoints[min(motion.cursor, len(motion.checkpoints) - 1)]
        self._motion = None
        self._settle(motion, checkpoint.elapsed)
        self._sense(motion, checkpoint.level)
        self._stopped(motion, checkpoint.level is not None)

    def _advance(self) -> MotionResult:
        motion = self._motion
        assert motion is not None
        checkpoints = motion.checkpoints
        while motion.cursor < len(checkpoints):
            checkpoint = checkpoints[motion.cursor]
            if checkpoint.violation is not None:
                self._motion = None
                self._settle(motion, checkpoint.elapsed)
                self._violated(motion, checkpoint)
                raise RuntimeError("_violated must raise")  # pragma: no cover
            force, torque, opening = motion.readings(checkpoint)
            for i, monitor in enumerate(motion.monitors):
                if i in motion.fired:
                    continue
                if not monitor_holds(monitor, force, torque, opening, checkpoint.elapsed):
                    continue
                motion.fired.add(i)
                if checkpoint.level is not None:
                    motion.detected = True
                self._show(motion, checkpoint)
                self._sense(motion, checkpoint.level)
                return MotionResult(i, False, self.hand_pose(), self._time)
            motion.cursor += 1
        self._motion = None
        self._settle(motion, motion.end)
        if motion.contact:
            self._sense(motion, motion.peak)
        self._ended(motion)
        return MotionResult(None, motion.arrives, self.hand_pose(), self._time)


def contact_checkpoints(
    motion: Timeline, normal: NDArray[np.float64], lever: NDArray[np.float64], peak: float
) -> None:
    """End ``motion`` on a contact: the force rises to ``peak`` [N] along ``normal`` at its end."""
    motion.contact = True
    motion.peak = peak
    motion.normal = np.asarray(normal, dtype=float)
    motion.lever = np.asarray(lever, dtype=float)
    for level in ramp_levels(motion.monitors, motion.normal, motion.lever, peak):
        motion.checkpoints.append(Checkpoint(motion.end, level=level))
