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
true; every machine plays its motions on the same timeline (:mod:`synth.al.timeline`:
checkpoints, monitor firing, resume and stop, ``WITH DURATION``). Then it pauses and returns
a :class:`MotionResult` with ``fired`` set to that monitor's index; the interpreter runs the
handler (the statement after ``DO``) at that instant, and calls either :meth:`Machine.stop`
(the handler executed ``STOP``, or aborted) or :meth:`Machine.resume` (it did not; the motion
goes on). A monitor fires at most once per
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

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, Protocol, runtime_checkable

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.al.motions import (
    Direction,
    DurationConstraint,
    DurationMonitor,
    EventMonitor,
    ForceConstraint,
    ForceMonitor,
    MonitorSpec,
    MotionConstraint,
    MotionResult,
    OpeningMonitor,
    Relation,
    TorqueConstraint,
    TorqueMonitor,
    relation_holds,
)
from synth.al.timeline import (
    Checkpoint,
    MotionGate,
    Timeline,
    TimelineMachine,
    contact_checkpoints,
    monitor_checkpoints,
    segment_times,
)

__all__ = [
    "Direction",
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


@dataclass(eq=False)
class _Motion(Timeline):
    """A motion of the ideal machine: its timeline, the path's knots and their times [s]."""

    path: tuple[pin.SE3, ...] = ()
    knots: tuple[float, ...] = ()

    def pose_at(self, elapsed: float) -> pin.SE3:
        """The hand pose ``elapsed`` [s] into the motion (straight between knots)."""
        knots = self.knots
        if elapsed >= knots[-1]:
            return pin.SE3(self.path[-1])
        for i in range(1, len(knots)):
            if elapsed <= knots[i]:
                span = knots[i] - knots[i - 1]
                s = 1.0 if span <= 0 else (elapsed - knots[i - 1]) / span
                return interpolate(self.path[i - 1], self.path[i], s)
        return pin.SE3(self.path[-1])


class IdealMachine(TimelineMachine["_Motion"]):
    """A machine whose world is exactly the program's beliefs.

    Nothing is ever touched: sensed forces and torques are zero, every motion reaches its last
    target, and the hand is where it was commanded. ``CLOSE`` and ``CENTER`` end with the fingers
    at ``grasp_width`` [m] — the width of whatever the fingers close on (0 for nothing); the hand
    does not move while centring (the believed part is already centred). Each motion segment
    takes ``segment_time`` [s], each hand operation ``hand_time`` [s], both stretched or
    squeezed by ``WITH DURATION`` constraints; the fingers move linearly in time.

    Monitors are played on the shared timeline (:mod:`synth.al.timeline`). Subclasses model
    contact by overriding :meth:`contact`: the motion stops there, the force rising to the
    returned force.

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
        self._force: NDArray[np.float64] = np.zeros(3)
        self._torque: NDArray[np.float64] = np.zeros(3)
        self._motion: _Motion | None = None
        self.commands: list[MachineCommand] = []

    # ---- sensors

    def hand_pose(self) -> pin.SE3:
        """The hand pose [m] (a copy)."""
        return pin.SE3(self._hand)

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
        path = (self.hand_pose(), *command.targets)
        knots = [0.0]
        for t in segment_times([self.segment_time] * len(targets), command.constraints):
            knots.append(knots[-1] + t)
        stop = self.contact(command, path, knots)
        end = knots[-1] if stop is None else min(max(float(stop[0]), 0.0), knots[-1])
        motion = _Motion(
            "move",
            line,
            command.monitors,
            self._time,
            end,
            monitor_checkpoints(command.monitors, end),
            stop is None,
            self._opening,
            self._opening,
            path=path,
            knots=tuple(knots),
        )
        if stop is not None:
            force = np.asarray(stop[1], dtype=float)
            peak = float(np.linalg.norm(force))
            normal = force / peak if peak > 0.0 else np.zeros(3)
            contact_checkpoints(motion, normal, np.zeros(3), peak)
        return self._start(motion)

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
        duration = segment_times([self.hand_time], command.constraints)[0]
        opening = (self._opening, float(final_opening))
        motion = _Motion(
            kind,
            line,
            command.monitors,
            self._time,
            duration,
            monitor_checkpoints(command.monitors, duration, opening=opening),
            True,
            *opening,
            path=(here, here),
            knots=(0.0, duration),
        )
        return self._start(motion)

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

    # ---- the timeline's hooks

    def _show(self, motion: _Motion, checkpoint: Checkpoint) -> None:
        self._settle(motion, checkpoint.elapsed)

    def _settle(self, motion: _Motion, elapsed: float) -> None:
        self._hand = motion.pose_at(elapsed)
        self._time = motion.start_time + elapsed
        self._opening = motion.opening_at(elapsed)
