"""The proven motion for other tools: the nominal run's joint trajectory as ROS YAML or CSV.

:func:`record_nominal` replays a program in the nominal world on a :class:`RecordingMachine`,
which keeps every motion the machine played (its AL line, its kind, its monitors, when it
started and where it ended). The trajectory is sampled from the machine's own timeline: each
motion's ``state_at`` (straight joint-space segments, the quintic time law, the durations of
:func:`synth.models.arm.motion_time`), every ``dt`` [s] and at each motion's end, where the
point is the configuration the machine settled in. Nothing is re-planned or re-timed here.

A fixed trajectory cannot replace the program's sensing: each point names the AL line of its
motion and its ``segment`` kind — ``free`` (a move without force or torque monitors),
``guarded`` (a move that stops on a force or torque: on a real arm it must run as a guarded
move, not as these positions), ``open``/``close`` (the fingers, the arm still) or ``center``
(the fingers close and the arm centres on the pin: sensing). Times are the nominal run's; a
real run stops a guarded move where the force rises.

Formats (:func:`trajectory_yaml`, :func:`trajectory_csv`): a ROS
``trajectory_msgs/JointTrajectory`` (``joint_names``; ``points`` with ``positions`` [rad | m]
and ``time_from_start`` {``sec``, ``nanosec``}; the segment marks in a comment per point and in
a parallel ``synth_segments`` list a ROS reader ignores), and CSV with the columns
``time_from_start`` [s], one per joint, ``al_line``, ``segment``, ``guarded``.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from synth.al.machine import ForceMonitor, TorqueMonitor
from synth.exceptions import SynthError
from synth.replay.machine import ReplayMachine
from synth.replay.motion import Motion
from synth.replay.report import RunReport
from synth.replay.run import ReplayContext, replay_context, run_machine
from synth.replay.truth import HandErrors, nominal_world

__all__ = [
    "DEFAULT_DT",
    "RecordingMachine",
    "Trajectory",
    "TrajectoryPoint",
    "export_trajectory",
    "record_nominal",
    "trajectory_csv",
    "trajectory_yaml",
    "write_trajectory",
]

DEFAULT_DT = 0.02
"""Sampling period [s] of the exported trajectory (50 Hz), besides each motion's end."""


@dataclass(frozen=True)
class PlayedMotion:
    """One motion as the machine played it: from ``start`` [s] for ``elapsed`` [s].

    ``samples`` are (elapsed [s], configuration) pairs read from the motion's timeline while
    it was current (the held pin's grip it depends on changes later); ``q_end`` is the
    configuration the machine settled in.
    """

    motion: Motion
    start: float
    elapsed: float
    samples: tuple[tuple[float, tuple[float, ...]], ...]
    q_end: tuple[float, ...]


class RecordingMachine(ReplayMachine):
    """A :class:`ReplayMachine` that keeps each motion it played (:attr:`played`).

    ``dt`` [s] is the sampling period of the motions' timelines.
    """

    played: list[PlayedMotion]
    dt: float = DEFAULT_DT

    def _settle(self, motion: Motion, elapsed: float) -> None:
        samples = []
        for e in _samples(elapsed, self.dt):
            state = motion.state_at(e)
            q: NDArray[np.float64] = state.q if state.q is not None else state.hint
            samples.append((e, tuple(float(x) for x in q)))
        super()._settle(motion, elapsed)
        if not hasattr(self, "played"):
            self.played = []
        self.played.append(
            PlayedMotion(
                motion, motion.start_time, elapsed, tuple(samples), tuple(float(x) for x in self._q)
            )
        )


@dataclass(frozen=True)
class TrajectoryPoint:
    """A sample: ``time`` [s] from the start, ``positions`` [rad | m], its motion's marks."""

    time: float
    positions: tuple[float, ...]
    line: int
    segment: str

    @property
    def guarded(self) -> bool:
        """Whether the point lies on a guarded move (one that stops on a force or torque)."""
        return self.segment == "guarded"


@dataclass(frozen=True)
class Trajectory:
    """The nominal run's joint trajectory and the run's report."""

    joint_names: tuple[str, ...]
    points: tuple[TrajectoryPoint, ...]
    report: RunReport


def _segment(motion: Motion) -> str:
    if motion.kind != "move":
        return motion.kind
    guarded = any(isinstance(m, ForceMonitor | TorqueMonitor) for m in motion.monitors)
    return "guarded" if guarded else "free"


def _samples(elapsed: float, dt: float) -> list[float]:
    """Instants [s] from 0 every ``dt`` up to ``elapsed`` (the end itself excluded)."""
    count = math.ceil(elapsed / dt - 1e-9) if elapsed > 0 else 0
    return [k * dt for k in range(count) if k * dt < elapsed - 1e-9]


def _points(played: list[PlayedMotion]) -> list[TrajectoryPoint]:
    points: list[TrajectoryPoint] = []
    for p in played:
        kind, line = _segment(p.motion), p.motion.line
        for e, q in p.samples:
            points.append(TrajectoryPoint(p.start + e, q, line, kind))
        points.append(TrajectoryPoint(p.start + p.elapsed, p.q_end, line, kind))
    # a motion of no duration repeats the instant of the one before: keep the later point
    kept: list[TrajectoryPoint] = []
    for point in points:
        if kept and point.time <= kept[-1].time + 1e-12:
            kept[-1] = point
        else:
            kept.append(point)
    return kept


def record_nominal(context: ReplayContext, *, dt: float = DEFAULT_DT) -> Trajectory:
    """Run ``context``'s program in the nominal world and sample its joint trajectory."""
    if not dt > 0:
        raise SynthError(f"the trajectory's sampling period must be positive, got {dt}")
    world = nominal_world(context.graph)
    workcell = context.workcell.place(world)
    pins = {frame: world.pose(frame) for frame in workcell.pins}
    machine = RecordingMachine(
        context.arm, workcell, pins, context.q_park, HandErrors.none(), context.options
    )
    machine.played = []
    machine.dt = dt
    report, _ = run_machine(context, machine)
    start = TrajectoryPoint(0.0, tuple(float(x) for x in context.q_park), 0, "start")
    points = [start, *_points(machine.played)]
    if len(points) > 1 and points[1].time <= 0.0:
        points = points[1:]
    return Trajectory(tuple(context.arm.limits.names), tuple(points), report)


def export_trajectory(
    program_text: str,
    task: Any,
    *,
    dt: float = DEFAULT_DT,
    filename: str = "<al>",
    base_dir: str | Path | None = None,
) -> Trajectory:
    """The nominal run's joint trajectory of ``program_text`` on ``task`` (a spec or a file).

    Raises :class:`~synth.exceptions.SynthError` when the nominal run does not succeed: only
    a proven motion is exported.
    """
    if isinstance(task, str | Path) and base_dir is None:
        base_dir = Path(task).resolve().parent
    context = replay_context(program_text, task, filename=filename, base_dir=base_dir)
    trajectory = record_nominal(context, dt=dt)
    if trajectory.report.outcome != "success":
        r = trajectory.report
        where = f" at AL line {r.line}" if r.line else ""
        raise SynthError(f"no trajectory exported: the nominal run ended in {r.outcome}{where}")
    return trajectory


def _stamp(t: float) -> dict[str, int]:
    """ROS ``builtin_interfaces/Duration``: whole seconds and nanoseconds."""
    nanos = round(t * 1e9)
    return {"sec": nanos // 1_000_000_000, "nanosec": nanos % 1_000_000_000}


def trajectory_yaml(trajectory: Trajectory) -> str:
    """A ROS ``trajectory_msgs/JointTrajectory`` as YAML, a comment naming each point's motion."""
    out = io.StringIO()
    out.write("# trajectory_msgs/JointTrajectory: synth's nominal replay (positions in rad | m)\n")
    out.write("# guarded segments stop on a force on a real arm: run them as guarded moves\n")
    out.write("joint_names: [" + ", ".join(trajectory.joint_names) + "]\n")
    out.write("points:\n")
    for p in trajectory.points:
        stamp = _stamp(p.time)
        positions = ", ".join(repr(x) for x in p.positions)
        out.write(f"  # AL line {p.line}: {p.segment}\n")
        out.write(f"  - positions: [{positions}]\n")
        out.write(f"    time_from_start: {{sec: {stamp['sec']}, nanosec: {stamp['nanosec']}}}\n")
    out.write("synth_segments:\n")
    for p in trajectory.points:
        out.write(
            f"  - {{al_line: {p.line}, segment: {p.segment}, guarded: {str(p.guarded).lower()}}}\n"
        )
    return out.getvalue()


def trajectory_csv(trajectory: Trajectory) -> str:
    """The trajectory as CSV: time [s], one column per joint, the AL line, segment, guarded."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["time_from_start", *trajectory.joint_names, "al_line", "segment", "guarded"])
    for p in trajectory.points:
        writer.writerow(
            [repr(p.time), *(repr(x) for x in p.positions), p.line, p.segment, int(p.guarded)]
        )
    return out.getvalue()


def write_trajectory(trajectory: Trajectory, path: str | Path) -> None:
    """Write ``trajectory`` to ``path``, its directory made as needed.

    ``.yaml``/``.yml`` as ROS YAML, ``.csv`` as CSV.
    """
    target = Path(path)
    suffix = target.suffix.lower()
    if suffix in (".yaml", ".yml"):
        text = trajectory_yaml(trajectory)
    elif suffix == ".csv":
        text = trajectory_csv(trajectory)
    else:
        raise SynthError(f"{target}: the trajectory's file must end in .yaml, .yml or .csv")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)  # as every other output's is
        target.write_text(text, encoding="utf-8", newline="\n")
    except OSError as exc:
        raise SynthError(f"cannot write {target}: {exc.strerror or exc}") from None
