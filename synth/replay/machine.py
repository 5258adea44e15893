"""The simulated workcell as an AL machine: the arm model in a true world, with contact.

:class:`ReplayMachine` implements :class:`synth.al.machine.Machine`. The interpreter keeps the
program's beliefs; this machine keeps the truth (:mod:`synth.replay.truth`) and never reads
the planner's estimates. Units are SI: [m], [rad], [N], [N·m], [s]. This module is the
protocol's glue; the machine's parts are:

=============================  ===========================================================
:mod:`synth.al.timeline`       the timeline every machine plays: checkpoints, monitors,
                               resume and stop, ``WITH DURATION`` (shared with
                               :class:`~synth.al.machine.IdealMachine`)
:mod:`synth.replay.motion`     a motion's segments and states along them
:mod:`synth.replay.walk`       the held pin's walk: free flight, capture, guidance, sliding
:mod:`synth.replay.sweeps`     the arm's sweep: collisions, the hand's contacts and slides
:mod:`synth.replay.hand`       opening and closing, grasp and release
:mod:`synth.replay.goal`       the goal verdict
:mod:`synth.replay.cell`       settings, the pins' true state, the violation stop
=============================  ===========================================================

**Motions** (AL's joint-interpolated motions, seed L1219: "the required coordination is
achieved by solving the joint angle equations for each position"). Every hand target of a
``MOVE`` (via points in order, then the destination) goes through inverse kinematics
(:mod:`synth.replay.reach`): a target without an attainable solution is a violation
(``unreachable`` or ``joint_limit``) at the motion's AL line, and the arm does not move. The arm
then moves along the straight joint-space segments between the solutions, each in the time
:func:`synth.models.arm.motion_time` gives (the planner's function; its quintic rule, the
shortest quintic that keeps every joint within its speed, acceleration and jerk limits),
stretched by ``WITH DURATION`` constraints, with that quintic time law along each segment
(seed L3846, AL's 5th-order polynomials), at rest at each via. The arm's reading of its hand
(BMANIP) is the forward kinematics of that path; the true hand is that pose times the hand
positioning error, which is drawn afresh for every target and blends linearly (SE(3)
interpolation) between targets.

**Collisions and contact.** Each segment is swept for the arm links, the palm and the fingers
(at their true opening) against the table, the objects and the free pins, and against each
other (:mod:`synth.replay.sweeps`). An arm link closer than ``sweep.clearance`` to anything is a
``collision`` violation at that instant. The palm and fingers are on the wrist's force sensor:
their touching the workcell is a contact (below). The held pin is swept on its own
(:mod:`synth.replay.walk`, :mod:`synth.replay.contact`: conservative advancement with Coal on
the true geometry, and each hole's mouth plane watched). The first contact ends the motion,
except in two cases:

* *capture*: the pin's tip circle arrives inside a hole's mouth with an admissible tilt
  (:mod:`synth.replay.capture`). The pin slides along the hole's axis, the arm complying, until
  it bottoms at its seated depth (a contact); if the commanded path stops short, the motion
  arrives with the pin partly inserted. A pin standing in a hole when a motion starts is
  withdrawn along the hole's axis; a path that drags it more than ``compliance`` sideways while
  it is in the hole jams it (``collision``). A pin that arrives tilted beyond the angle at which
  its two-point contact sticks (:mod:`synth.replay.wedging`, the task's friction) wedges there:
  a ``wedged`` violation;
* *sliding*: a push meeting a surface at less than ``slide_angle`` (a pin lifted or lowered
  beside a box) slides along it, the arm yielding along the normal by the least shift that
  keeps the pin out of the obstacle (on a face, the plane it touched; past an edge, less) until
  the path clears the obstacle; needing more than ``compliance`` jams it (a contact), and the
  sliding pin meeting another solid (the table under a box's wall) stops there (a contact).

**Force.** At a contact the force rises from 0 to the arm's stall force ``stall_force``,
modelled as happening at that instant, in the direction opposite to the touching point's motion
(a blocked position-controlled arm pushes along its path; the hole's axis when the pin bottoms).
A monitor ``FORCE(v) > f`` therefore fires at contact as soon as its threshold is exceeded,
monitors in the order of the force each needs; there is no force noise. If no monitor stops the
motion it stalls there (``arrived`` false). A contact no force or torque monitor detected is a
``collision`` violation (the program pushed into something without noticing), except a pin
bottoming in a hole (the allowed pin–hole contact).

**Hand** (:mod:`synth.replay.hand`). ``OPEN``/``CLOSE``/``CENTER`` take ``hand_time``; ``CENTER``
(and ``CLOSE``) grasps a free pin between the open pads and registers the hand on it; opening
the fingers wider than a held pin lets it go.

**Goal** (:meth:`ReplayMachine.goal`, :mod:`synth.replay.goal`): the insertion's pin is let go,
stands in the target hole at its seated depth (within ``seat_tolerance``), and no palm or
finger is within ``clear_distance`` of it.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import Literal, NoReturn

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.al.machine import MonitorSpec, MotionConstraint, MotionResult
from synth.al.timeline import (
    Checkpoint,
    TimelineMachine,
    contact_checkpoints,
    monitor_checkpoints,
    segment_times,
)
from synth.models.arm import (
    FINGERS,
    Arm,
    CollisionScene,
    HeldObject,
    Obstacle,
    motion_time,
)
from synth.models.arm.collision import SceneCache
from synth.models.workcell import Workcell
from synth.replay.bounds import ArmChain
from synth.replay.capture import seat_depth, seated_pose, tip_placement
from synth.replay.cell import (
    PinState,
    ReplayOptions,
    ViolationStop,
    complied,
    configuration_of,
    free_obstacles,
    pin_states,
)
from synth.replay.goal import goal_verdict
from synth.replay.hand import finger_collision, grasp, grasp_candidate, hand_motion, release
from synth.replay.motion import Motion, MotionObserver, MotionState, Phase, Segment, Slide, Stop
from synth.replay.reach import ReachProblem, describe_pose, leaving_branch, solve_near
from synth.replay.report import Violation, ViolationKind
from synth.replay.sweeps import SweepContext, sweep_segment
from synth.replay.truth import HandErrors
from synth.replay.walk import WalkContext, walk_segment

__all__ = ["PinState", "ReplayMachine", "ReplayOptions", "ViolationStop", "configuration_of"]

_COMPLIANCE_POINTS = 9
"""Points of a guided or sliding phase where the arm's compliance is checked for its branch."""

_STOP_MARGIN = 0.1
"""[rad] (5.7°) A segment whose revolute joints all stay this far from their stops is not
checked for a compliance that leaves the arm's branch (:meth:`ReplayMachine._far_from_stops`)."""


class ReplayMachine(TimelineMachine[Motion]):
    """The Machine protocol on ``arm`` in a true ``workcell`` (see the module docstring).

    ``hand_errors`` is the stream of hand positioning errors (:class:`HandErrors.none` for the
    nominal run); ``q_start`` the arm's initial configuration (the hand at the task's park
    frame); ``scenes`` a cache of collision scenes shared by the runs of one process (none: a
    scene is built for every grasp and opening). Every violation is kept in
    :attr:`violations` before :class:`ViolationStop` is raised. ``observer`` (None: nobody)
    is told how far each motion has been played, on the machine's own timeline
    (:class:`~synth.replay.motion.MotionObserver`).
    """

    def __init__(
        self,
        arm: Arm,
        workcell: Workcell,
        pins: dict[str, pin.SE3],
        q_start: NDArray[np.float64],
        hand_errors: HandErrors,
        options: ReplayOptions | None = None,
        scenes: SceneCache | None = None,
    ) -> None:
        self.arm = arm
        self.scenes = scenes
        self.workcell = workcell
        self.options = options or ReplayOptions()
        self.hand_errors = hand_errors
        self.violations: list[Violation] = []
        self.pins: dict[str, PinState] = pin_states(workcell, pins)
        self._time = 0.0
        self._opening = 0.0
        self._error = pin.SE3.Identity()
        self._q = np.array(q_start, dtype=float)
        self._sensed = arm.forward(self._q)
        self._force = np.zeros(3)
        self._torque = np.zeros(3)
        self._motion: Motion | None = None
        self._scene: CollisionScene | None = None
        self.observer: MotionObserver | None = None
        self._chain = ArmChain.of(arm)

    # ---- sensors

    def hand_pose(self) -> pin.SE3:
        """The arm's reading of its hand pose [m] (forward kinematics, not the truth)."""
        return pin.SE3(self._sensed)

    def true_hand(self) -> pin.SE3:
        """The hand's true pose [m]: the reading times the current positioning error."""
        return self._sensed * self._error

    @property
    def configuration(self) -> NDArray[np.float64]:
        """The arm's joint configuration now (a copy): where a later program starts."""
        return self._q.copy()

    def held_pin(self) -> PinState | None:
        """The pin the hand holds, if any."""
        for state in self.pins.values():
            if state.held:
                return state
        return None

    # ---- the true world's solids

    def _violation(self, kind: ViolationKind, line: int, detail: str, time: float) -> Violation:
        return Violation(kind, line, detail, time)

    def _raise(self, violation: Violation) -> NoReturn:
        self.violations.append(violation)
        self._time = max(self._time, violation.time)
        raise ViolationStop(violation)

    def _obstacles(self) -> list[Obstacle]:
        """The static solids and every pin the hand does not hold, at their true poses."""
        return free_obstacles(self.workcell, self.pins)

    def scene(self) -> CollisionScene:
        """The collision scene of the current opening, grasp and free pins (cached)."""
        if self._scene is None or self._scene.opening != self._opening:
            held = self.held_pin()
            obstacles = self._obstacles()
            holder = None
            allowed: list[tuple[str, str]] = []
            if held is not None:
                assert held.grip is not None
                holder = HeldObject(held.model.name, held.model.geometry, held.grip)
                allowed += [(finger, held.model.name) for finger in FINGERS]
                allowed += [(held.model.name, o.name) for o in obstacles]  # swept on its own
            if self.scenes is not None and not self.options.reference:
                self._scene = self.scenes.scene(
                    self.arm, obstacles, held=holder, allowed=allowed, opening=self._opening
                )
            else:
                self._scene = CollisionScene(
                    self.arm, obstacles, held=holder, allowed=allowed, opening=self._opening
                )
        return self._scene

    def _invalidate(self) -> None:
        self._scene = None

    # ---- the state along a move

    def _state(self, segment: Segment, s: float, held: PinState | None) -> MotionState:
        q = segment.q(s)
        reading = self.arm.forward(q)
        error = segment.error(s)
        if held is None:
            return MotionState(q, q, reading, error, None, None, 0.0, self._opening)
        assert held.grip is not None
        commanded = reading * error * held.grip
        phase = segment.phase_at(s)
        if phase.slide is not None:
            pose = phase.slide.yielded(commanded)
            sensed = pose * held.grip.inverse() * error.inverse()
            return MotionState(None, q, sensed, error, pose, None, 0.0, self._opening)
        hole = phase.hole
        if hole is None:
            return MotionState(q, q, reading, error, commanded, None, 0.0, self._opening)
        seat = seat_depth(hole, held.model)
        depth = min(max(-tip_placement(hole, commanded).axial, 0.0), seat)
        pose = seated_pose(hole, depth, commanded)
        sensed = pose * held.grip.inverse() * error.inverse()
        return MotionState(None, q, sensed, error, pose, hole, depth, self._opening)

    def _apply(self, state: MotionState) -> None:
        self._q = configuration_of(self.arm, state)
        self._sensed = pin.SE3(state.sensed)
        self._error = pin.SE3(state.error)
        held = self.held_pin()
        if held is not None and state.pin_pose is not None:
            held.pose = pin.SE3(state.pin_pose)
            held.hole, held.depth = state.hole, state.depth
            held.rests_on = None

    # ---- motions

    def move(
        self,
        targets: Sequence[pin.SE3],
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Move the hand through ``targets`` (see the module docstring)."""
        self._check_move(targets)
        configurations, durations, problem = _joint_path(self.arm, self._q, targets)
        if problem is not None:
            k = len(configurations) - 1
            which = "destination" if k == len(targets) - 1 else f"via point {k + 1}"
            self._raise(
                self._violation(problem.kind, line, f"{which}: {problem.detail}", self._time)
            )
        times = segment_times(list(durations), constraints)
        for k, (wanted, fastest) in enumerate(zip(times, durations, strict=True)):
            if wanted < fastest * (1.0 - 1e-9):  # WITH DURATION squeezed it
                which = "the motion" if len(times) == 1 else f"segment {k + 1} of the motion"
                detail = (
                    f"WITH DURATION asks {which} to take {wanted:.4g} s; at its joint limits "
                    f"the arm needs {fastest:.4g} s"
                )
                self._raise(self._violation("too_fast", line, detail, self._time))
        errors = [self._error] + [self.hand_errors.next(line, k + 1) for k in range(len(targets))]
        segments = []
        t = 0.0
        for k in range(len(targets)):
            segments.append(
                Segment(
                    configurations[k],
                    configurations[k + 1],
                    errors[k],
                    errors[k + 1],
                    t,
                    times[k],
                )
            )
            t += times[k]
        return self._start(self._plan(segments, self.held_pin(), tuple(monitors), line))

    def _plan(
        self,
        segments: list[Segment],
        held: PinState | None,
        monitors: tuple[MonitorSpec, ...],
        line: int,
    ) -> Motion:
        """Walk the segments: pin contacts, guidance and arm sweeps; the motion's timeline."""
        scene = self.scene()
        obstacles = self._obstacles()
        walking = WalkContext(
            self.arm, self.workcell, self.options, obstacles, line, self._time, self._chain
        )
        sweeping = SweepContext(
            self.arm, self.options, {o.name for o in obstacles}, line, self._time, self._chain
        )
        hole = held.hole if held is not None else None
        slide: Slide | None = None
        stop: Stop | None = None
        end_segment = len(segments) - 1
        for index, seg in enumerate(segments):
            pin_stop: Stop | None = None
            if held is not None:
                walk = walk_segment(walking, held, seg, hole, slide)
                pin_stop, hole, slide = walk.stop, walk.hole, walk.slide
                pin_stop = self._complying(seg, held, pin_stop, line) or pin_stop
            else:
                seg.phases = [Phase(0.0)]
            limit = 1.0 if pin_stop is None else pin_stop.s
            stop = sweep_segment(sweeping, scene, seg, limit) or pin_stop
            if stop is not None:
                end_segment = index
                break
        end_s = 1.0 if stop is None else stop.s
        last = segments[end_segment]
        end_time = last.time(end_s)

        def locate(elapsed: float) -> tuple[Segment, float]:
            for k, seg in enumerate(segments[: end_segment + 1]):
                if elapsed <= seg.t0 + seg.duration or k == end_segment:
                    s = seg.s_at(elapsed)
                    return seg, (min(s, end_s) if k == end_segment else s)
            return last, end_s

        def state_at(elapsed: float) -> MotionState:
            seg, s = locate(elapsed)
            return self._state(seg, s, held)

        motion = Motion(
            "move",
            line,
            monitors,
            self._time,
            end_time,
            monitor_checkpoints(monitors, end_time),
            stop is None,
            self._opening,
            self._opening,
            state_at=state_at,
        )
        if stop is not None and stop.violation is not None:
            motion.checkpoints.append(Checkpoint(end_time, violation=stop.violation))
        elif stop is not None:
            final = state_at(end_time)
            hand = final.sensed * final.error
            motion.stop = stop
            lever = np.asarray(stop.point - hand.translation, dtype=float)
            contact_checkpoints(motion, stop.reaction, lever, self.options.stall_force)
        return motion

    def _complying(
        self, seg: Segment, held: PinState, pin_stop: Stop | None, line: int
    ) -> Stop | None:
        """A stop where the arm, complying with a hole or a slide, would leave its branch.

        Guided by a hole the hand follows the pin, not the path: its pose is the path's
        displaced by the guidance, and the joints are its inverse nearest the path's
        (:func:`~synth.replay.cell.configuration_of`). Next to a joint's stop the branch may
        not reach that pose; the nearest solution is then another branch, the wrist turned by
        180°, which no compliance makes: a ``joint_limit`` violation. Checked at
        :data:`_COMPLIANCE_POINTS` evenly spaced points of each guided or sliding phase: a
        sampled check, not a proven one (the guidance changes slowly along a phase).
        """
        limit = 1.0 if pin_stop is None else pin_stop.s
        if self._far_from_stops(seg):
            return None
        for k, phase in enumerate(seg.phases):
            if phase.start > limit:
                break
            if phase.hole is None and phase.slide is None:
                continue
            end = min(seg.phases[k + 1].start if k + 1 < len(seg.phases) else 1.0, limit)
            for s in np.linspace(phase.start, end, _COMPLIANCE_POINTS):
                state = self._state(seg, s, held)
                turned = None if state.q is not None else complied(self.arm, state)[1]
                if turned is None:
                    continue
                guide = phase.hole.name if phase.hole is not None else "a face it slides on"
                problem = leaving_branch(f"complying with {guide}", turned)
                time = self._time + seg.time(float(s))
                violation = self._violation(problem.kind, line, problem.detail, time)
                return Stop(float(s), "violation", held.model.name, guide, violation=violation)
        return None

    def _far_from_stops(self, seg: Segment) -> bool:
        """Every revolute joint stays :data:`_STOP_MARGIN` from its stops along ``seg``.

        Along the straight q0 → q1 a joint's distance to a stop is linear, so its least is at an
        end. A compliance of millimetres and a degree or two turns no joint that far on the
        branch the arm stands on, so it cannot need another branch (a wrist turned 180°).
        """
        limits = self.arm.limits
        revolute = np.array([kind == "revolute" for kind in limits.kinds])
        ends = np.stack([seg.q0, seg.q1])[:, revolute]
        lower, upper = limits.lower[revolute], limits.upper[revolute]
        return bool(np.min(np.minimum(ends - lower, upper - ends)) > _STOP_MARGIN)

    # ---- the hand

    def _hand_operation(
        self,
        kind: Literal["open", "close", "center"],
        final: float,
        finish: Callable[[], None] | None,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        self._check_idle()
        duration = segment_times([self.options.hand_time], constraints)[0]
        motion = hand_motion(
            kind,
            line,
            monitors,
            self._time,
            duration,
            (self._opening, final),
            self._q,
            self.hand_pose(),
            self._error,
            finish,
        )
        return self._start(motion)

    def open_hand(
        self,
        width: float,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Open (or close) the fingers to ``width`` [m]; wider than a held pin lets it go."""
        final = self._opening_within_travel("OPEN", width, line)
        held = self.held_pin()
        if held is not None and final < self._opening:
            final = self._opening  # the pin stops the fingers
        finish = None
        if held is not None and final > self._opening:
            finish = lambda: self._release(held, line)  # noqa: E731
        elif final > self._opening:
            finish = lambda: self._check_fingers(line)  # noqa: E731
        return self._hand_operation("open", final, finish, monitors, constraints, line)

    def close_hand(
        self,
        width: float | None,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Close the fingers to ``width`` [m] or onto a pin between them (grasped as CENTER)."""
        if self.held_pin() is not None:
            return self._hand_operation("close", self._opening, None, monitors, constraints, line)
        candidate = self._grasp_candidate()
        floor = (
            0.0
            if width is None
            else min(self._opening_within_travel("CLOSE", width, line), self._opening)
        )
        if candidate is not None and candidate[1] >= floor:
            state, diameter, offset = candidate
            finish = lambda: self._grasp(state, offset, line)  # noqa: E731
            return self._hand_operation("close", diameter, finish, monitors, constraints, line)
        return self._hand_operation("close", floor, None, monitors, constraints, line)

    def center(
        self,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Close until one finger touches, then move the arm until both touch (S:1306)."""
        if self.held_pin() is not None:
            return self._hand_operation("center", self._opening, None, monitors, constraints, line)
        candidate = self._grasp_candidate()
        if candidate is None:
            return self._hand_operation("center", 0.0, None, monitors, constraints, line)
        state, diameter, offset = candidate
        finish = lambda: self._grasp(state, offset, line)  # noqa: E731
        return self._hand_operation("center", diameter, finish, monitors, constraints, line)

    def _opening_within_travel(self, statement: str, width: float, line: int) -> float:
        """``width`` [m], or a ``joint_limit`` violation when the fingers cannot reach it.

        The fingers open from 0 to the hand's ``max_opening``; ``OPEN BHAND TO 100*CM`` (or
        to −1 cm) was clamped to that travel without a word.
        """
        most = self.arm.hand.max_opening
        if 0.0 <= width <= most + 1e-12:
            return min(float(width), most)
        detail = (
            f"{statement} to {100 * width:.4g} cm: the fingers open from 0 to {100 * most:.4g} cm"
        )
        self._raise(self._violation("joint_limit", line, detail, self._time))

    def _grasp_candidate(self) -> tuple[PinState, float, float] | None:
        return grasp_candidate(
            self.arm, self.pins.values(), self.true_hand(), self._opening, self.options.pad_tilt
        )

    def _grasp(self, state: PinState, offset: float, line: int) -> None:
        try:
            self._sensed, self._q = grasp(self.arm, state, self.true_hand(), offset, self._q)
        except ReachProblem as problem:
            self._raise(self._violation(problem.kind, line, problem.detail, self._time))
        self._error = pin.SE3.Identity()
        self._invalidate()

    def _release(self, state: PinState, line: int) -> None:
        release(state)
        self._invalidate()
        self._check_fingers(line)

    def _check_fingers(self, line: int) -> None:
        hit = finger_collision(self.scene(), self._q)
        if hit is not None:
            a, b = hit
            self._raise(
                self._violation("collision", line, f"opening the fingers: {a} hit {b}", self._time)
            )

    # ---- the timeline's hooks

    def _show(self, motion: Motion, checkpoint: Checkpoint) -> None:
        """Present the paused instant: clock, hand reading and opening."""
        if self.observer is not None:
            self.observer.played(motion, checkpoint.elapsed, True)
        state = motion.state_at(checkpoint.elapsed)
        self._time = motion.start_time + checkpoint.elapsed
        self._sensed = pin.SE3(state.sensed)
        self._opening = state.opening

    def _settle(self, motion: Motion, elapsed: float) -> None:
        """End the motion ``elapsed`` [s] after it started: the arm, hand and pin stay there."""
        if self.observer is not None:
            self.observer.played(motion, elapsed, False)
        state = motion.state_at(elapsed)
        self._time = motion.start_time + elapsed
        self._apply(state)
        self._opening = state.opening
        self._force = np.zeros(3)
        self._torque = np.zeros(3)

    def _violated(self, motion: Motion, checkpoint: Checkpoint) -> NoReturn:
        self._raise(checkpoint.violation)

    def _stopped(self, motion: Motion, at_contact: bool) -> None:
        self._note_rest(motion, at_contact)

    def _ended(self, motion: Motion) -> None:
        stop = motion.stop
        if stop is not None and stop.kind == "surface" and not motion.detected:
            self._raise(
                self._violation(
                    "collision",
                    motion.line,
                    f"{stop.body} hit {stop.obstacle}{f' ({stop.note})' if stop.note else ''} "
                    f"and no force monitor of the motion noticed (hand at "
                    f"{describe_pose(self.true_hand())})",
                    self._time,
                )
            )
        self._note_rest(motion, stop is not None)
        if motion.finish is not None:
            motion.finish()

    def _note_rest(self, motion: Motion, at_contact: bool) -> None:
        held, stop = self.held_pin(), motion.stop
        if (
            held is not None
            and at_contact
            and stop is not None
            and stop.kind == "surface"
            and stop.body == held.model.name
        ):
            held.rests_on = stop.obstacle

    # ---- the goal

    def goal(self, pin_frame: str, hole_frame: str) -> tuple[bool, str]:
        """Whether ``pin_frame`` is seated in ``hole_frame``, let go, the hand clear; and why."""
        state = self.pins[pin_frame]
        target = self.workcell.hole(hole_frame)
        return goal_verdict(state, target, self.scene, self._q, self.options)


_PATHS: dict[bytes, tuple[Arm, list[NDArray[np.float64]], tuple[float, ...]]] = {}
_PATHS_KEPT = 32


def _joint_path(
    arm: Arm, q: NDArray[np.float64], targets: Sequence[pin.SE3]
) -> tuple[list[NDArray[np.float64]], tuple[float, ...], ReachProblem | None]:
    """The configurations reaching ``targets`` in turn from ``q``, the segments' times.

    Each target's solution nearest the one before (:func:`solve_near`), timed by
    :func:`motion_time` (zeros when the arm does not move). At the first target without an
    attainable solution the list stops and its problem is returned (no times). A pure function
    of the arm, ``q`` and the targets, kept for the last few reached: a program's first motion
    commands the same targets from the same park in every trial.
    """
    key = b"".join([q.tobytes(), *(t.homogeneous.tobytes() for t in targets)])
    kept = _PATHS.get(key)
    if kept is not None and kept[0] is arm:
        return [c.copy() for c in kept[1]], kept[2], None
    configurations = [np.array(q, dtype=float)]
    for target in targets:
        try:
            configurations.append(solve_near(arm, pin.SE3(target), configurations[-1]))
        except ReachProblem as problem:
            return configurations, (), problem
    durations = (0.0,) * len(targets)
    if any(np.any(b != a) for a, b in itertools.pairwise(configurations)):
        durations = tuple(motion_time(arm.limits, configurations).segments)
    while len(_PATHS) >= _PATHS_KEPT:
        _PATHS.pop(next(iter(_PATHS)))
    _PATHS[key] = (arm, [c.copy() for c in configurations], durations)
    return configurations, durations, None
