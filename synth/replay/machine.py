"""The simulated workcell as an AL machine: the arm model in a true world, with contact.

:class:`ReplayMachine` implements :class:`synth.al.machine.Machine`. The interpreter keeps the
program's beliefs; this machine keeps the truth (:mod:`synth.replay.truth`) and never reads
the planner's estimates. Units are SI: [m], [rad], [N], [N·m], [s].

**Motions** (AL's joint-interpolated motions, seed L1219: "the required coordination is
achieved by solving the joint angle equations for each position"). Every hand target of a
``MOVE`` (via points in order, then the destination) goes through inverse kinematics
(:mod:`synth.replay.reach`): a target without an attainable solution is a violation
(``unreachable`` or ``joint_limit``) at the motion's AL line, and the arm does not move. The arm
then moves along the straight joint-space segments between the solutions, each in the time
:func:`synth.models.arm.motion_time` gives (the planner's function; ruckig rule, vias blended),
stretched by ``WITH DURATION`` constraints, with a quintic time law along each segment
(seed L3846, AL's 5th-order polynomials). The arm's reading of its hand (BMANIP) is the forward
kinematics of that path; the true hand is that pose times the hand positioning error, which is
drawn afresh for every target and blends linearly (SE(3) interpolation) between targets.

**Collisions and contact.** Each segment is swept (:func:`synth.models.arm.swept_segment`,
conservative advancement on Coal distances) for the arm links, the palm and the fingers (at their
true opening) against the table, the objects and the free pins, and against each other. An arm
link closer than ``sweep.clearance`` to anything is a ``collision`` violation at that instant.
The palm and fingers are on the wrist's force sensor: their touching the workcell is a contact
(below). The held pin is swept on its own (:mod:`synth.replay.contact`: conservative advancement
with Coal on the true geometry, and each hole's mouth plane watched). The first contact ends the
motion, except in two cases:

* *capture*: the pin's tip circle arrives inside a hole's mouth with an admissible tilt
  (:mod:`synth.replay.capture`). The pin slides along the hole's axis, the arm complying, until
  it bottoms at its seated depth (a contact); if the commanded path stops short, the motion
  arrives with the pin partly inserted. A pin standing in a hole when a motion starts is
  withdrawn along the hole's axis; a path that drags it more than ``compliance`` sideways while
  it is in the hole jams it (``collision``). A pin that arrives tilted beyond the angle at which
  its two-point contact sticks (:mod:`synth.replay.wedging`, the task's friction) wedges there:
  a ``wedged`` violation;
* *sliding*: a push meeting a surface at less than ``slide_angle`` (a pin lifted or lowered
  beside a box) slides along it, the arm yielding along the normal until the path clears the
  obstacle; needing more than ``compliance`` jams it (a contact).

**Force.** At a contact the force rises from 0 to the arm's stall force ``stall_force``,
modelled as happening at that instant, in the direction opposite to the touching point's motion
(a blocked position-controlled arm pushes along its path; the hole's axis when the pin bottoms).
A monitor ``FORCE(v) > f`` therefore fires at contact as soon as its threshold is exceeded,
monitors in the order of the force each needs; there is no force noise. If no monitor stops the
motion it stalls there (``arrived`` false). A contact no force or torque monitor detected is a
``collision`` violation (the program pushed into something without noticing), except a pin
bottoming in a hole (the allowed pin–hole contact).

**Hand.** ``OPEN``/``CLOSE``/``CENTER`` take ``hand_time`` (50 jiffies, seed App. 2, L3854–3857).
``CENTER`` (and ``CLOSE``, whose fingers comply the same way) grasps a free pin whose axis runs
between the open pads (within ``pad_tilt`` of their plane, within a pad radius of their centres):
the arm moves along the hand's x until both pads touch, the opening becomes the pin's diameter
at the pads, and the hand is registered on the pin: its reading becomes its true pose (the
seed's hand "holds the pin with essentially no error", L2244), so the pin's pose in the hand is
known as well as the pin's location was. A grasp that misses closes the fingers to 0. Opening
the fingers wider than the pin lets it go: a pin standing in a hole whose axis points up drops to
its seated depth; anything else stays where it is. Opening the fingers into something is a
``collision``.

**Goal** (:meth:`ReplayMachine.goal`): the insertion's pin is let go, stands in the target hole
at its seated depth (within ``seat_tolerance``), and no palm or finger is within
``clear_distance`` of it.
"""

from __future__ import annotations

import contextlib
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Literal, NoReturn

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.al.interpreter import MAX_STATEMENTS, MAX_TIME, MAX_WALL_TIME
from synth.al.machine import (
    DurationMonitor,
    EventMonitor,
    ForceMonitor,
    MonitorSpec,
    MotionConstraint,
    MotionGate,
    MotionResult,
    OpeningMonitor,
    TorqueMonitor,
)
from synth.models.arm import (
    FINGERS,
    HAND_BODIES,
    JIFFY,
    Arm,
    CollisionScene,
    HeldObject,
    JointLimits,
    Obstacle,
    SweepOptions,
    SweepResult,
    motion_time,
    swept_segment,
)
from synth.models.arm.bodies import Body
from synth.models.arm.collision import SceneCache
from synth.models.arm.sweep import LAZY_SLACK, body_motion_bounds
from synth.models.workcell import HoleSite, PinModel, Workcell
from synth.replay.capture import inserted_depth, seat_depth, seated_pose, tip_placement
from synth.replay.contact import first_contact, guided_motion, scrape
from synth.replay.motion import (
    Checkpoint,
    Motion,
    MotionObserver,
    MotionState,
    Phase,
    Segment,
    Slide,
    Stop,
    crossing_level,
    point_on,
    push_reaction,
    segment_times,
)
from synth.replay.reach import ReachProblem, describe_pose, solve_near
from synth.replay.report import Violation, ViolationKind
from synth.replay.truth import HandErrors
from synth.replay.wedging import wedging_onset

__all__ = ["PinState", "ReplayMachine", "ReplayOptions", "ViolationStop", "configuration_of"]


@dataclass(frozen=True)
class ReplayOptions:
    """Physical and numerical settings of the simulated workcell (SI units)."""

    stall_force: float = 20.0
    """[N] the force the arm pushes with when a motion is blocked [est]: 2 kg-force, far above
    the seed's 8 oz (2.2 N) thresholds."""
    contact_clearance: float = 2e-5
    """[m] pin–surface distance that counts as touching (a pin stops between half of it and
    it from the surface)."""
    sweep: SweepOptions = field(default_factory=lambda: SweepOptions(clearance=1e-3))
    """Swept checks of the arm, palm and fingers: a pair closer than 1 mm is a collision."""
    compliance: float = 0.01
    """[m] how far the arm yields sideways, to a hole guiding the pin or to a surface the pin or
    a finger slides along [est]: wider than any mouth of the seed's parts (0.57 cm), so no
    captured pin jams on its own offset."""
    exit_margin: float = 1e-3
    """[m] a withdrawn pin is clear of its hole when its tip is this far above the mouth."""
    hand_time: float = 50 * JIFFY
    """[s] OPEN, CLOSE and CENTER (seed App. 2, L3854–3857: 50 jiffies)."""
    slide_angle: float = math.radians(20.0)
    """[rad] a push that meets a surface at less than this angle slides along it, the arm
    yielding up to ``compliance`` [est: friction and the servo's give]; steeper pushes stop."""
    pad_tilt: float = math.radians(10.0)
    """[rad] largest angle between a pin's axis and the pads' plane for a grasp."""
    seat_tolerance: float = 1e-4
    """[m] a pin within this of its seated depth is seated."""
    clear_distance: float = 1e-3
    """[m] the hand is clear of the pin when palm and fingers are at least this far from it."""
    max_statements: int = MAX_STATEMENTS
    """Statements one run may execute (the interpreter's budgets: :mod:`synth.al.interpreter`)."""
    max_time: float = MAX_TIME
    """[s] simulated time one run may take; past it the run is an AL runtime error."""
    max_wall_time: float = MAX_WALL_TIME
    """[s] real time one run may take (a loop of motions that take no simulated time)."""
    reference: bool = False
    """Take the reference path: every distance measured at every step of every sweep and
    contact search, the collision scene rebuilt for every grasp and opening. The fast path
    (the default) measures only what can decide a step and reuses scenes; both give the same
    runs (``benchmarks/replay.py`` times one against the other)."""


class ViolationStop(Exception):
    """Raised by the machine to end the run at a violation (caught by the replay)."""

    def __init__(self, violation: Violation) -> None:
        super().__init__(f"{violation.kind} at line {violation.line}: {violation.detail}")
        self.violation = violation


@dataclass
class PinState:
    """A pin in the true world.

    ``pose``: its world pose [m]; ``grip``: hand-from-pin while held; ``hole`` and ``depth``:
    the hole whose bore it stands in and the tip's depth there [m]; ``rests_on``: the obstacle
    it was last stopped on.
    """

    model: PinModel
    pose: pin.SE3
    grip: pin.SE3 | None = None
    hole: HoleSite | None = None
    depth: float = 0.0
    rests_on: str | None = None

    @property
    def held(self) -> bool:
        """True while the hand holds the pin."""
        return self.grip is not None


# --------------------------------------------------------------------------------------------
# The machine


def configuration_of(arm: Arm, state: MotionState) -> NDArray[np.float64]:
    """The arm's joints [rad, m] in ``state``.

    The path's, or where the arm complied (the pin guided by a hole or sliding) the inverse of
    the sensed hand nearest the path's.
    """
    if state.q is not None:
        return state.q.copy()
    try:
        return solve_near(arm, state.sensed, state.hint)
    except ReachProblem:
        return state.hint.copy()  # complied a hair beyond the model: keep the path


class ReplayMachine(MotionGate):
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
        self.pins: dict[str, PinState] = {}
        for frame, pose in pins.items():
            model = workcell.pins[frame]
            state = PinState(model, pin.SE3(pose))
            for hole in workcell.holes:
                depth = inserted_depth(hole, model, pose)
                if depth is not None:
                    state.hole, state.depth = hole, depth
                    break
            self.pins[frame] = state
        self._time = 0.0
        self._opening = 0.0
        self._error = pin.SE3.Identity()
        self._q = np.array(q_start, dtype=float)
        self._sensed = arm.forward(self._q)
        self._force = np.zeros(3)
        self._torque = np.zeros(3)
        self._motion: Motion | None = None
        self._scene: CollisionScene | None = None
        hand_frame = arm.model.frames[arm.hand_frame]
        self._hand_joint = int(hand_frame.parentJoint)
        self._joint_from_hand = hand_frame.placement
        self.observer: MotionObserver | None = None

    # ---- sensors

    def hand_pose(self) -> pin.SE3:
        """The arm's reading of its hand pose [m] (forward kinematics, not the truth)."""
        return pin.SE3(self._sensed)

    def true_hand(self) -> pin.SE3:
        """The hand's true pose [m]: the reading times the current positioning error."""
        return self._sensed * self._error

    def opening(self) -> float:
        """The finger opening [m]."""
        return self._opening

    def force(self, direction: NDArray[np.float64]) -> float:
        """Sensed force along world ``direction`` [N] (the reaction on the hand and pin)."""
        return float(self._force @ np.asarray(direction, dtype=float))

    def torque(self, axis: NDArray[np.float64]) -> float:
        """Sensed torque about world ``axis`` through the hand origin [N·m]."""
        return float(self._torque @ np.asarray(axis, dtype=float))

    @property
    def configuration(self) -> NDArray[np.float64]:
        """The arm's joint configuration now (a copy): where a later program starts."""
        return self._q.copy()

    def time(self) -> float:
        """The simulated clock [s]."""
        return self._time

    def held_pin(self) -> PinState | None:
        """The pin the hand holds, if any."""
        for state in self.pins.values():
            if state.held:
                return state
        return None

    # ---- geometry helpers

    def _violation(self, kind: ViolationKind, line: int, detail: str, time: float) -> Violation:
        return Violation(kind, line, detail, time)

    def _raise(self, violation: Violation) -> NoReturn:
        self.violations.append(violation)
        self._time = max(self._time, violation.time)
        raise ViolationStop(violation)

    def _obstacles(self) -> list[Obstacle]:
        """The static solids and every pin the hand does not hold, at their true poses."""
        out = list(self.workcell.obstacles)
        for state in self.pins.values():
            if not state.held:
                out.append(Obstacle(state.model.name, state.model.geometry, state.pose))
        return out

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

    def _pin_speed(self, state: PinState, segment: Segment) -> float:
        """Bound [m per unit s] on the speed of every point of the held pin along ``segment``."""
        assert state.grip is not None
        body = Body(
            state.model.name,
            self._hand_joint,
            state.model.name,
            self._joint_from_hand * state.grip,
            state.model.geometry,
            "held",
        )
        # the levers of the bound only need the prismatic extensions this segment passes through
        limits = self.arm.limits
        low, high = np.minimum(segment.q0, segment.q1), np.maximum(segment.q0, segment.q1)
        swept = JointLimits(
            limits.names, limits.kinds, low, high, limits.velocity, limits.acceleration
        )
        rho = body_motion_bounds(self.arm.model, swept, [body])[0]
        reach = state.model.reach(state.grip)
        t_e = float(
            max(np.linalg.norm(segment.e0.translation), np.linalg.norm(segment.e1.translation))
        )
        r_e = float(
            max(
                np.linalg.norm(pin.log3(segment.e0.rotation)),
                np.linalg.norm(pin.log3(segment.e1.rotation)),
            )
        )
        margin = np.where(rho > 0, 2.0 * (t_e + r_e * reach), 0.0)
        margin = np.where(np.array(self.arm.limits.kinds) == "prismatic", 0.0, margin)
        dq = np.abs(segment.q1 - segment.q0)
        d_error = segment.e0.inverse() * segment.e1
        blend = float(np.linalg.norm(segment.e1.translation - segment.e0.translation))
        blend += float(np.linalg.norm(pin.log3(d_error.rotation))) * (reach + t_e)
        return float((rho + margin) @ dq) + blend

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
            shift = phase.slide.deflection(commanded) * phase.slide.normal
            pose = pin.SE3(commanded.rotation, commanded.translation + shift)
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
        configurations = [self._q]
        for k, target in enumerate(targets):
            try:
                configurations.append(solve_near(self.arm, pin.SE3(target), configurations[-1]))
            except ReachProblem as problem:
                which = "destination" if k == len(targets) - 1 else f"via point {k + 1}"
                self._raise(
                    self._violation(problem.kind, line, f"{which}: {problem.detail}", self._time)
                )
        durations = [0.0] * len(targets)
        if any(np.any(b != a) for a, b in itertools.pairwise(configurations)):
            durations = list(motion_time(self.arm.limits, configurations).segments)
        durations = segment_times(durations, constraints)
        errors = [self._error] + [self.hand_errors.next() for _ in targets]
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
                    durations[k],
                )
            )
            t += durations[k]
        held = self.held_pin()
        self._force = np.zeros(3)
        self._torque = np.zeros(3)
        motion = self._plan(segments, held, tuple(monitors), line)
        self._motion = motion
        return self._advance()

    def _plan(
        self,
        segments: list[Segment],
        held: PinState | None,
        monitors: tuple[MonitorSpec, ...],
        line: int,
    ) -> Motion:
        """Walk the segments: pin contacts, guidance and arm sweeps; the motion's timeline."""
        options = self.options
        scene = self.scene()
        hole = held.hole if held is not None else None
        slide: Slide | None = None
        obstacles = self._obstacles()
        stop: Stop | None = None
        end_segment = len(segments) - 1
        for index, seg in enumerate(segments):
            seg.phases = [Phase(0.0, hole, slide)]
            pin_stop: Stop | None = None
            s = 0.0
            while held is not None and s < 1.0 and pin_stop is None:
                grip = held.grip
                assert grip is not None

                r_g, t_g = np.array(grip.rotation), np.array(grip.translation)

                def commanded(
                    x: float,
                    seg: Segment = seg,
                    r_g: NDArray[np.float64] = r_g,
                    t_g: NDArray[np.float64] = t_g,
                ) -> pin.SE3:
                    # reading ∘ error ∘ grip, composed as matrices
                    reading = self.arm.forward(seg.q(x))
                    r_r, t_r = reading.rotation, reading.translation
                    r_e, t_e = seg.error_rt(x)
                    rotation = r_r @ r_e @ r_g
                    return pin.SE3(rotation, r_r @ (r_e @ t_g + t_e) + t_r)

                speed = self._pin_speed(held, seg)
                if hole is not None:
                    end = guided_motion(
                        hole,
                        commanded,
                        seat=seat_depth(hole, held.model),
                        start=s,
                        compliance=options.compliance,
                        exit_margin=options.exit_margin,
                    )
                    if end.kind == "exit":
                        hole, s = None, end.s
                        seg.phases.append(Phase(s))
                    elif end.kind == "bottom":
                        tip = seated_pose(hole, end.depth, commanded(end.s)).translation
                        pin_stop = Stop(end.s, "seat", held.model.name, hole.name, tip, hole.axis)
                    elif end.kind == "jam":
                        detail = (
                            f"{held.model.name} jammed in {hole.name}: the motion drags it "
                            f"{100 * end.lateral:.2f} cm sideways while it is in the hole"
                        )
                        violation = self._violation(
                            "collision", line, detail, self._time + seg.time(end.s)
                        )
                        pin_stop = Stop(
                            end.s, "violation", held.model.name, hole.name, violation=violation
                        )
                    else:
                        s = 1.0
                    continue
                if slide is not None:
                    current = slide
                    slid = scrape(
                        held.model,
                        commanded,
                        speed,
                        current.obstacle,
                        current.normal,
                        current.pin_point,
                        current.origin,
                        start=s,
                        compliance=options.compliance,
                        clearance=options.contact_clearance,
                    )
                    if slid.kind == "free":
                        slide, s = None, slid.s
                        seg.phases.append(Phase(s))
                    elif slid.kind == "jam":
                        pin_point = current.pin_point
                        pin_stop = Stop(
                            slid.s,
                            "surface",
                            held.model.name,
                            current.obstacle.name,
                            commanded(slid.s).act(pin_point),
                            push_reaction(partial(point_on, commanded, pin_point), slid.s),
                            note=f"slid along it and jammed, {100 * slid.deflection:.2f} cm in",
                        )
                    else:
                        s = 1.0
                    continue
                found = first_contact(
                    held.model,
                    commanded,
                    speed,
                    obstacles,
                    self.workcell.holes,
                    start=s,
                    clearance=options.contact_clearance,
                    friction=self.workcell.friction,
                    reference=options.reference,
                )
                if found is None:
                    s = 1.0
                elif found.kind == "wedge":
                    assert found.hole is not None
                    entry = commanded(found.s)
                    pin_stop = self._wedged(held, found.hole, entry, seg, found.s, line)
                elif found.kind == "capture":
                    assert found.hole is not None
                    hole, s = found.hole, found.s
                    seg.phases.append(Phase(s, hole))
                else:
                    local = found.pin_point
                    reaction = push_reaction(partial(point_on, commanded, local), found.s)
                    into = float(reaction @ found.normal)  # the push's component into the surface
                    if into < math.sin(options.slide_angle):
                        # a grazing push: the pin slides along the surface, the arm yields
                        touched = next(o for o in obstacles if o.name == found.obstacle)
                        origin = commanded(found.s).act(local)
                        slide = Slide(touched, found.normal, local, origin)
                        s = found.s
                        seg.phases.append(Phase(s, slide=slide))
                    else:
                        pin_stop = Stop(
                            found.s,
                            "surface",
                            held.model.name,
                            found.obstacle,
                            found.point,
                            reaction,
                        )
            limit = 1.0 if pin_stop is None else pin_stop.s
            stop = self._sweep(scene, seg, limit, line) or pin_stop
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

        checkpoints = [Checkpoint(0.0), *self._duration_checkpoints(monitors, end_time)]
        motion = Motion(
            "move", line, monitors, self._time, end_time, checkpoints, state_at, stop is None
        )
        if stop is not None and stop.violation is not None:
            motion.checkpoints.append(Checkpoint(end_time, violation=stop.violation))
        elif stop is not None:
            final = state_at(end_time)
            hand = final.sensed * final.error
            motion.stop = stop
            motion.normal = np.asarray(stop.reaction, dtype=float)
            motion.lever = np.asarray(stop.point - hand.translation, dtype=float)
            for level in self._ramp_levels(monitors, motion.normal, motion.lever):
                motion.checkpoints.append(Checkpoint(end_time, level=level))
        motion.checkpoints.sort(key=lambda c: (c.elapsed, -1.0 if c.level is None else c.level))
        return motion

    def _wedged(
        self, held: PinState, hole: HoleSite, pose: pin.SE3, seg: Segment, s: float, line: int
    ) -> Stop:
        """The stop of a pin that enters ``hole`` at a wedging tilt (a ``wedged`` violation)."""
        tilt = tip_placement(hole, pose).tilt
        onset = wedging_onset(2.0 * hole.radius, 2.0 * held.model.radius, self.workcell.friction)
        detail = (
            f"{held.model.name} wedged in {hole.name}: it entered tilted "
            f"{math.degrees(tilt):.2f}°, "
            f"beyond the {math.degrees(onset):.2f}° at which its two-point contact sticks "
            f"(μ = {self.workcell.friction:g})"
        )
        violation = self._violation("wedged", line, detail, self._time + seg.time(s))
        return Stop(s, "violation", held.model.name, hole.name, violation=violation)

    def _sweep_options(self, scene: CollisionScene, q: NDArray[np.float64]) -> SweepOptions:
        """The sweep's options, with the clearance halved below a contact the motion starts in.

        A motion that starts where a previous one stopped on contact (a finger on the box top)
        begins closer than the clearance; it is a collision only if it comes closer still.
        """
        options = self.options.sweep
        if not scene.pairs:
            return options
        if self.options.reference:
            start = float(np.min(scene.distance_bounds(q, exact_below=options.clearance)))
        else:
            # only pairs whose lower bound reaches the clearance can be below it
            options = replace(options, lazy=True)
            below = np.full(len(scene.pairs), options.clearance)
            lower = scene.lower_bounds(q, below) - LAZY_SLACK
            close = np.flatnonzero(lower <= below).tolist()
            near = [scene.measure(k, options.clearance) for k in close]
            start = min(near, default=np.inf)
        if start >= options.clearance:
            return options
        return SweepOptions(
            clearance=max(0.5 * start, 0.0), max_checks=options.max_checks, lazy=options.lazy
        )

    def _sweep(self, scene: CollisionScene, seg: Segment, limit: float, line: int) -> Stop | None:
        """Sweep the arm and hand over s ∈ [0, limit] of ``seg``: the first stop, if any.

        A palm or finger pushed along a surface at a grazing angle slides: its pair is left out
        until the path clears the surface (the rest is still swept), then the sweep goes on.
        """
        start = 0.0
        while start < limit:
            options = self._sweep_options(scene, seg.q(start))
            sweep = swept_segment(scene, seg.q(start), seg.q(limit), options)
            if sweep.free:
                return None
            s_hit = start + sweep.s * (limit - start)
            found = self._sweep_stop(scene, seg, start, s_hit, limit, sweep, line)
            if isinstance(found, Stop):
                return found
            s_free, pair = found
            relaxed = CollisionScene(
                self.arm,
                scene.environment,
                held=scene.held,
                allowed=[*scene.allowed, pair],
                opening=scene.opening,
            )
            inner = swept_segment(
                relaxed, seg.q(s_hit), seg.q(s_free), self._sweep_options(relaxed, seg.q(s_hit))
            )
            if not inner.free:
                s_in = s_hit + inner.s * (s_free - s_hit)
                found = self._sweep_stop(relaxed, seg, s_hit, s_in, s_free, inner, line, False)
                assert isinstance(found, Stop)
                return found
            start = s_free
        return None

    def _sweep_stop(
        self,
        scene: CollisionScene,
        seg: Segment,
        start: float,
        s_hit: float,
        limit: float,
        sweep: SweepResult,
        line: int,
        slide: bool = True,
    ) -> Stop | tuple[float, tuple[str, str]]:
        """What the sweep's first close pair means.

        A violation (an arm link), a sensed contact of the palm or a finger, or their slide,
        returned as (where the path clears the surface, the pair).
        """
        a, b = sweep.pair if sweep.pair is not None else ("?", "?")
        obstacles = {o.name for o in self._obstacles()}
        if b in HAND_BODIES and a in obstacles:
            a, b = b, a
        if a not in HAND_BODIES or b not in obstacles:
            detail = (
                f"{a} hit {b} ({100 * sweep.distance:.2f} cm apart) at "
                f"{describe_pose(self.arm.forward(sweep.q))}"
            )
            violation = self._violation("collision", line, detail, self._time + seg.time(s_hit))
            return Stop(s_hit, "violation", a, b, violation=violation)
        # the palm or a finger touches the workcell: the wrist sensor feels it
        k = scene.pairs.index((a, b)) if (a, b) in scene.pairs else scene.pairs.index((b, a))
        point, on_body, normal = self._pair_contact(scene, seg.q(s_hit), a, b)
        local = scene.body_pose(seg.q(s_hit), a).actInv(on_body)

        def body_point(x: float) -> NDArray[np.float64]:
            return np.asarray(scene.body_pose(seg.q(x), a).act(local), dtype=float)

        reaction = push_reaction(body_point, s_hit)
        options = self.options
        note = ""
        if slide and float(reaction @ normal) < math.sin(options.slide_angle):
            origin = body_point(s_hit)
            moved = float(np.linalg.norm(body_point(min(limit, s_hit + 1e-3)) - origin))
            ds = 1e-3 * 2e-4 / moved if moved > 0.0 else limit - s_hit
            s = s_hit
            while s < limit:
                s = min(limit, s + ds)
                deflection = -float(normal @ (body_point(s) - origin))
                if deflection > options.compliance:
                    note = f"slid along it and jammed, {100 * deflection:.2f} cm in"
                    break
                if self._pair_distance(scene, seg.q(s), k) > options.sweep.clearance:
                    return s, (a, b)
            else:
                return limit, (a, b)
        s_stop = self._back_off(scene, seg, start, s_hit, k)
        return Stop(s_stop, "surface", a, b, point, reaction, note=note)

    @staticmethod
    def _pair_distance(scene: CollisionScene, q: NDArray[np.float64], k: int) -> float:
        """Exact distance [m] of the scene's pair ``k`` at ``q``."""
        pin.updateGeometryPlacements(
            scene.model, scene.data, scene.geometry_model, scene.geometry_data, q
        )
        pin.computeDistance(scene.geometry_model, scene.geometry_data, k)
        return float(scene.geometry_data.distanceResults[k].min_distance)

    def _back_off(
        self, scene: CollisionScene, seg: Segment, start: float, s_hit: float, k: int
    ) -> float:
        """A stop in [start, s_hit] where pair ``k`` is at least a quarter clearance apart."""
        quarter = 0.25 * self.options.sweep.clearance
        if self._pair_distance(scene, seg.q(s_hit), k) >= quarter:
            return s_hit
        lo, hi = start, s_hit
        for _ in range(16):
            mid = 0.5 * (lo + hi)
            if self._pair_distance(scene, seg.q(mid), k) >= 2 * quarter:
                lo = mid
            else:
                hi = mid
        return lo

    def _pair_contact(
        self, scene: CollisionScene, q: NDArray[np.float64], a: str, b: str
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Nearest points on ``b`` and on ``a`` at ``q`` [m], and b's surface normal towards a."""
        geometry = {body.name: body.geometry for body in scene.bodies}
        pa, pb = scene.body_pose(q, a), scene.body_pose(q, b)
        request, result = coal.DistanceRequest(), coal.DistanceResult()
        coal.distance(
            geometry[a],
            coal.Transform3s(pa.rotation, pa.translation),
            geometry[b],
            coal.Transform3s(pb.rotation, pb.translation),
            request,
            result,
        )
        normal = -np.asarray(result.normal, dtype=float)  # Coal's points from a to b
        norm = float(np.linalg.norm(normal)) if np.all(np.isfinite(normal)) else 0.0
        normal = normal / norm if norm > 1e-12 else np.zeros(3)
        on_b = np.asarray(result.getNearestPoint2(), dtype=float)
        on_a = np.asarray(result.getNearestPoint1(), dtype=float)
        return on_b, on_a, normal

    def _duration_checkpoints(
        self, monitors: Sequence[MonitorSpec], end: float
    ) -> list[Checkpoint]:
        out = []
        for m in monitors:
            if isinstance(m, DurationMonitor) and 0.0 <= m.threshold <= end:
                out.append(Checkpoint(m.threshold))
                out.append(Checkpoint(min(math.nextafter(m.threshold, math.inf), end)))
        out.append(Checkpoint(end))
        return out

    def _ramp_levels(
        self,
        monitors: Sequence[MonitorSpec],
        normal: NDArray[np.float64],
        lever: NDArray[np.float64],
    ) -> list[float]:
        """Force levels [N] of the contact ramp where a force or torque monitor switches."""
        stall = self.options.stall_force
        levels = set()
        moment = np.cross(lever, normal)
        for m in monitors:
            if isinstance(m, ForceMonitor):
                level = crossing_level(
                    float(np.dot(m.direction, normal)), m.relation, m.threshold, stall
                )
            elif isinstance(m, TorqueMonitor):
                level = crossing_level(
                    float(np.dot(m.axis, moment)), m.relation, m.threshold, stall
                )
            else:
                continue
            if level is not None:
                levels.add(level)
        return sorted(levels)

    # ---- the hand

    def _grasp_candidate(self) -> tuple[PinState, float, float] | None:
        """A free pin between the open pads: (pin, opening on it [m], centring offset δ [m])."""
        hand = self.arm.hand
        true_hand = self.true_hand()
        for state in self.pins.values():
            if state.held:
                continue
            local = true_hand.actInv(state.pose)
            o, a = local.translation, local.rotation[:, 2]
            if abs(a[0]) > math.sin(self.options.pad_tilt):
                continue
            lam = (a[0] * o[0] - float(a @ o)) / (1.0 - a[0] * a[0])
            p = o + lam * a
            radius = state.model.radius_at(lam)
            if (
                radius > 0.0
                and math.hypot(p[1], p[2]) <= hand.finger_pad_radius
                and abs(p[0]) + radius <= self._opening / 2
            ):
                return state, 2.0 * radius, float(p[0])
        return None

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
        start, here = self._opening, self.hand_pose()
        error = self._error
        self._force = np.zeros(3)
        self._torque = np.zeros(3)

        def state_at(elapsed: float) -> MotionState:
            fraction = 1.0 if duration <= 0 else min(elapsed / duration, 1.0)
            q = self._q
            return MotionState(
                q, q, here, error, None, None, 0.0, start + fraction * (final - start)
            )

        checkpoints = [Checkpoint(0.0), *self._duration_checkpoints(monitors, duration)]
        for m in monitors:
            if isinstance(m, OpeningMonitor) and final != start:
                fraction = (m.threshold - start) / (final - start)
                if 0.0 <= fraction <= 1.0:
                    t = fraction * duration
                    checkpoints.append(Checkpoint(t))
                    checkpoints.append(Checkpoint(min(math.nextafter(t, math.inf), duration)))
        checkpoints.sort(key=lambda c: c.elapsed)
        self._motion = Motion(
            kind, line, tuple(monitors), self._time, duration, checkpoints, state_at, True
        )
        self._motion.finish = finish
        return self._advance()

    def open_hand(
        self,
        width: float,
        monitors: Sequence[MonitorSpec],
        constraints: Sequence[MotionConstraint],
        line: int,
    ) -> MotionResult:
        """Open (or close) the fingers to ``width`` [m]; wider than a held pin lets it go."""
        final = min(max(float(width), 0.0), self.arm.hand.max_opening)
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
        floor = 0.0 if width is None else min(max(float(width), 0.0), self._opening)
        if candidate is not None and candidate[1] >= floor:
            state, diameter, offset = candidate
            finish = lambda: self._grasp(state, offset)  # noqa: E731
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
        finish = lambda: self._grasp(state, offset)  # noqa: E731
        return self._hand_operation("center", diameter, finish, monitors, constraints, line)

    def _grasp(self, state: PinState, offset: float) -> None:
        """The pads close on ``state``'s pin; the arm centres by ``offset`` [m] along hand x."""
        true_hand = self.true_hand() * pin.SE3(np.eye(3), np.array([offset, 0.0, 0.0]))
        self._sensed = true_hand
        self._error = pin.SE3.Identity()
        # a centring move of a few mm at the edge of the workspace keeps the joints
        with contextlib.suppress(ReachProblem):
            self._q = solve_near(self.arm, true_hand, self._q)
        state.grip = true_hand.actInv(state.pose)
        state.rests_on = None
        self._invalidate()

    def _release(self, state: PinState, line: int) -> None:
        state.grip = None
        hole = state.hole
        if hole is not None and float(hole.axis[2]) > 0.5:
            state.depth = seat_depth(hole, state.model)
            state.pose = seated_pose(hole, state.depth, state.pose)
        self._invalidate()
        self._check_fingers(line)

    def _check_fingers(self, line: int) -> None:
        scene = self.scene()
        hits = [
            (a, b) for a, b in scene.collisions(self._q) if a in HAND_BODIES or b in HAND_BODIES
        ]
        if hits:
            a, b = hits[0]
            self._raise(
                self._violation("collision", line, f"opening the fingers: {a} hit {b}", self._time)
            )

    # ---- the event loop of one motion

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
        checkpoint = motion.checkpoints[min(motion.cursor, len(motion.checkpoints) - 1)]
        self._motion = None
        self._settle(motion, checkpoint.elapsed)
        if motion.kind == "move" and checkpoint.level is not None:
            self._force = checkpoint.level * motion.normal
            self._torque = np.cross(motion.lever, self._force)
        self._note_rest(motion, checkpoint.level is not None)

    def _sensor_values(
        self, motion: Motion, checkpoint: Checkpoint, state: MotionState
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
        if checkpoint.level is None:
            return np.zeros(3), np.zeros(3), state.opening
        force = checkpoint.level * motion.normal
        return force, np.cross(motion.lever, force), state.opening

    def _holds(
        self,
        monitor: MonitorSpec,
        values: tuple[NDArray[np.float64], NDArray[np.float64], float],
        elapsed: float,
    ) -> bool:
        force, torque, opening = values
        if isinstance(monitor, ForceMonitor):
            return monitor.holds(force)
        if isinstance(monitor, TorqueMonitor):
            return monitor.holds(torque)
        if isinstance(monitor, OpeningMonitor):
            return monitor.holds(opening)
        if isinstance(monitor, DurationMonitor):
            return monitor.holds(elapsed)
        assert isinstance(monitor, EventMonitor)
        return False  # no external sensors in this workcell

    def _advance(self) -> MotionResult:
        motion = self._motion
        assert motion is not None
        while motion.cursor < len(motion.checkpoints):
            checkpoint = motion.checkpoints[motion.cursor]
            if checkpoint.violation is not None:
                self._motion = None
                self._settle(motion, checkpoint.elapsed)
                self._raise(checkpoint.violation)
            state = motion.state_at(checkpoint.elapsed)
            values = self._sensor_values(motion, checkpoint, state)
            for i, monitor in enumerate(motion.monitors):
                if i in motion.fired or not self._holds(monitor, values, checkpoint.elapsed):
                    continue
                motion.fired.add(i)
                if checkpoint.level is not None:
                    motion.detected = True
                self._show(motion, checkpoint, state)
                return MotionResult(i, False, self.hand_pose(), self._time)
            motion.cursor += 1
        self._motion = None
        self._settle(motion, motion.end)
        stop = motion.stop
        if stop is not None:
            self._force = self.options.stall_force * motion.normal
            self._torque = np.cross(motion.lever, self._force)
            if stop.kind == "surface" and not motion.detected:
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
        return MotionResult(None, motion.arrives, self.hand_pose(), self._time)

    def _show(self, motion: Motion, checkpoint: Checkpoint, state: MotionState) -> None:
        """Present the paused instant: clock, hand reading, opening and sensed force."""
        if self.observer is not None:
            self.observer.played(motion, checkpoint.elapsed, True)
        self._time = motion.start_time + checkpoint.elapsed
        self._sensed = pin.SE3(state.sensed)
        self._opening = state.opening
        force, torque, _ = self._sensor_values(motion, checkpoint, state)
        self._force, self._torque = force, torque

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
        name = state.model.name
        target = self.workcell.hole(hole_frame)
        if state.held:
            return False, f"the hand still holds {name}"
        if state.hole is None or state.hole.frame != hole_frame:
            if state.hole is not None:
                return False, f"{name} is in {state.hole.name}, not in {target.name}"
            where = f"it rests on {state.rests_on}" if state.rests_on else "it is not in a hole"
            return False, f"{name} is not in {target.name}: {where}"
        seat = seat_depth(target, state.model)
        if state.depth < seat - self.options.seat_tolerance:
            return False, (
                f"{name} is only {100 * state.depth:.2f} cm into {target.name} "
                f"(seated: {100 * seat:.2f} cm)"
            )
        scene = self.scene()
        distances = scene.distances(self._q)
        near = [
            d
            for (a, b), d in zip(scene.pairs, distances, strict=True)
            if name in (a, b) and (a in HAND_BODIES or b in HAND_BODIES)
        ]
        if near and min(near) < self.options.clear_distance:
            return False, f"the hand is not clear of {name} ({100 * min(near):.2f} cm)"
        return True, f"{name} seated in {target.name}"
