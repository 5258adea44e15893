"""The trace of one replay run: the arm, the hand and the pins through time, and the events.

A :class:`TraceRecorder` is the machine's :class:`~synth.replay.motion.MotionObserver`: each
time a motion has been played up to a pause or its end, it samples the motion's own timeline
(``Motion.state_at``, the instants and states the replay itself uses) every ``dt`` seconds and at
the instant reached. No second simulation: the samples are the replay's states. Between motions
the AL statements take no time, so the samples cover the run; where one motion ends and the
next starts, the instant's one sample is the next motion's (times strictly increase).

:func:`record_run` runs the nominal world (``trial`` None) or Monte Carlo trial ``trial`` (the
same draw as :func:`synth.replay.run.run_trial`) with a recorder and returns the
:class:`Trace`. Its JSON is documented in ``docs/trace.md`` (schema ``synth.trace/1``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from synth.replay.machine import ReplayMachine, configuration_of
from synth.replay.motion import Motion
from synth.replay.report import RunReport
from synth.replay.run import (
    ReplayContext,
    machine_for,
    run_machine,
    trial_world,
)
from synth.replay.truth import HandErrors, nominal_world

__all__ = [
    "DEFAULT_DT",
    "SCHEMA",
    "Trace",
    "TraceEvent",
    "TraceRecorder",
    "TraceSample",
    "pose_json",
    "record_run",
]

SCHEMA = "synth.trace/1"
DEFAULT_DT = 0.02
"""[s] sampling period of a trace."""


def pose_json(pose: pin.SE3) -> dict[str, list[float]]:
    """``{"translation": [x, y, z] [m], "quaternion": [x, y, z, w]}`` (world frame)."""
    q = pin.Quaternion(pose.rotation)
    return {
        "translation": [float(v) for v in pose.translation],
        "quaternion": [float(q.x), float(q.y), float(q.z), float(q.w)],
    }


@dataclass(frozen=True, eq=False)
class TraceSample:
    """The state at time ``t`` [s]: joints ``q`` [rad, m], the true hand and pin poses [m].

    ``line`` is the AL line of the motion being played, ``motion`` its kind; ``opening`` [m]
    the fingers' opening; ``pins`` every pin's true pose by AL name.
    """

    t: float
    line: int
    motion: str
    q: tuple[float, ...]
    opening: float
    hand: pin.SE3
    pins: dict[str, pin.SE3]

    def to_json(self) -> dict[str, Any]:
        """One element of the trace's ``samples``."""
        return {
            "t": self.t,
            "line": self.line,
            "motion": self.motion,
            "q": list(self.q),
            "opening": self.opening,
            "hand": pose_json(self.hand),
            "pins": {name: pose_json(pose) for name, pose in self.pins.items()},
        }


@dataclass(frozen=True)
class TraceEvent:
    """Something that happened at ``t`` [s] on AL line ``line``.

    ``kind``: ``start`` (a motion begins), ``monitor`` (a condition monitor fired and the motion
    paused), ``end`` (the motion ended), ``violation`` (the machine stopped the program), or
    ``outcome`` (the run's verdict, last). ``motion`` names the motion's kind (``move``,
    ``open``, ``close``, ``center``); ``detail`` says more.
    """

    t: float
    kind: str
    line: int | None
    motion: str = ""
    detail: str = ""

    def to_json(self) -> dict[str, Any]:
        """One element of the trace's ``events``."""
        return {
            "t": self.t,
            "kind": self.kind,
            "line": self.line,
            "motion": self.motion,
            "detail": self.detail,
        }


@dataclass(frozen=True, eq=False)
class Trace:
    """A recorded run: its samples in time order, its events, its report (docs/trace.md)."""

    task: str
    program: str
    trial: int | None
    seed: int
    dt: float
    joints: tuple[str, ...]
    samples: tuple[TraceSample, ...]
    events: tuple[TraceEvent, ...]
    report: RunReport

    def to_json(self) -> dict[str, Any]:
        """The ``synth replay --trace`` document (schema ``synth.trace/1``, SI units)."""
        return {
            "schema": SCHEMA,
            "task": self.task,
            "program": self.program,
            "trial": self.trial,
            "seed": self.seed,
            "dt": self.dt,
            "joints": list(self.joints),
            "outcome": self.report.to_json(),
            "samples": [s.to_json() for s in self.samples],
            "events": [e.to_json() for e in self.events],
        }


@dataclass(eq=False)
class TraceRecorder:
    """Samples every motion of ``machine`` every ``dt`` [s] (see the module docstring)."""

    machine: ReplayMachine
    pin_names: dict[str, str]
    dt: float = DEFAULT_DT
    samples: list[TraceSample] = field(default_factory=list)
    events: list[TraceEvent] = field(default_factory=list)
    _played: dict[int, float] = field(default_factory=dict)
    _motions: list[Motion] = field(default_factory=list)
    """Every motion seen, held so that ``id`` keys stay unique for the whole run."""

    def __post_init__(self) -> None:
        if self.dt <= 0:
            raise ValueError(f"dt must be > 0 s, got {self.dt}")

    def played(self, motion: Motion, elapsed: float, paused: bool) -> None:
        """Sample ``motion`` from where it was last sampled up to ``elapsed`` [s]."""
        key = id(motion)
        first = key not in self._played
        since = self._played.get(key, 0.0)
        if first:
            # Keep the motion alive: a freed motion's id may be reused by the next one, which
            # would then look already played and leave a gap in the samples.
            self._motions.append(motion)
            self.events.append(TraceEvent(motion.start_time, "start", motion.line, motion.kind))
        instants = list(np.arange(since if first else since + self.dt, elapsed, self.dt))
        more = first or elapsed > since + 1e-12  # a stop right after a pause adds no instant
        if more and (not instants or elapsed - instants[-1] > 1e-9):
            instants.append(elapsed)
        for at in instants:
            sample = self._sample(motion, min(float(at), elapsed))
            if self.samples and sample.t <= self.samples[-1].t + 1e-12:
                self.samples[-1] = sample  # one motion ends where the next starts: keep the next
            else:
                self.samples.append(sample)
        self._played[key] = elapsed
        time = motion.start_time + elapsed
        if paused:
            self.events.append(TraceEvent(time, "monitor", motion.line, motion.kind))
        else:
            self.events.append(TraceEvent(time, "end", motion.line, motion.kind))

    def _sample(self, motion: Motion, elapsed: float) -> TraceSample:
        state = motion.state_at(elapsed)
        q = configuration_of(self.machine.arm, state)
        held = self.machine.held_pin()
        pins = {}
        for frame, pin_state in self.machine.pins.items():
            pose = pin_state.pose
            if pin_state is held and state.pin_pose is not None:
                pose = state.pin_pose
            pins[self.pin_names.get(frame, frame)] = pin.SE3(pose)
        return TraceSample(
            t=motion.start_time + elapsed,
            line=motion.line,
            motion=motion.kind,
            q=tuple(float(v) for v in q),
            opening=float(state.opening),
            hand=state.sensed * state.error,
            pins=pins,
        )


def record_run(
    context: ReplayContext,
    *,
    trial: int | None = None,
    seed: int = 0,
    dt: float = DEFAULT_DT,
    program: str = "<al>",
) -> Trace:
    """Run the nominal world (``trial`` None) or trial ``trial`` of ``seed`` with a recorder."""
    if trial is None:
        world, hand = nominal_world(context.graph), HandErrors.none()
    else:
        if trial < 0:
            raise ValueError(f"trial must be ≥ 0, got {trial}")
        world, hand = trial_world(context, seed, trial)
    machine = machine_for(context, world, hand)
    recorder = TraceRecorder(machine, dict(context.graph.al_names), dt)
    machine.observer = recorder
    report, _ = run_machine(context, machine)
    events = list(recorder.events)
    for v in machine.violations:
        events.append(TraceEvent(v.time, "violation", v.line, "", f"{v.kind}: {v.detail}"))
    events.append(TraceEvent(report.time, "outcome", report.line, "", report.outcome))
    events.sort(key=lambda e: e.t)  # stable: same-time events keep their order
    model = context.arm.model
    joints = tuple(str(model.names[j]) for j in range(1, model.njoints))
    return Trace(
        task=context.spec.name,
        program=program,
        trial=trial,
        seed=seed,
        dt=dt,
        joints=joints,
        samples=tuple(recorder.samples),
        events=tuple(events),
        report=report,
    )
