"""``synth replay``: run an AL program on the simulated arm — parsing, I/O and printing only.

    synth replay PROGRAM.al|- --task TASK.yaml [--trials N] [--seed S] [--workers K] [--json]
                 [--progress] [--failures K] [--min-success P]
                 [--export-trajectory OUT.yaml|OUT.csv] [--svg MC.svg] [--trace T.json]
    synth replay PROGRAM.al --task TASK.yaml --trials N --dask ADDRESS|local
    synth replay PROGRAM.al --task TASK.yaml --trial I [--seed S] [--json] [--trace T.json]
    synth replay --preamble --task TASK.yaml

Exit codes: 0 when the program is valid and its nominal run succeeds (and, with
``--min-success P``, the observed Monte Carlo success rate k/n is at least P — the rate, as
the proof compares it, not its Wilson bound); 1 when the nominal run fails (abort, violation,
pin not seated) or the rate is below P; 2 for unusable input — a syntax error, a missing or
invalid file, or an AL runtime error such as an unknown frame name (the report is still printed
for the last); 130 when Ctrl-C stopped the trials (the report of the trials done is printed).
``--preamble`` prints the task's world binding as AL declarations and exits 0.

``--json`` streams one record per trial (index, seed, the error parameters each perturbed
frame sampled, outcome, AL line, message, time) into a ``"trials"`` array ahead of the report's
own keys, written as the trials finish: nothing is kept per trial. ``--failures K`` keeps the
first K failing trials (at most K records) and prints them after the summary. ``--trial I``
re-runs trial I of ``--seed`` alone (no nominal run): the same world and hand errors it had in
the full run.

This module imports nothing heavy at import time, so ``synth --help`` stays fast.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, Literal, TextIO

from synth.exceptions import SynthError

__all__ = [
    "BAR_MIN_TRIALS",
    "DEFAULT_TRIALS",
    "ProgressBar",
    "add_replay_parser",
    "add_workers_argument",
    "available_cores",
    "picture_format",
    "read_program",
    "resolve_workers",
    "run_replay",
    "write_output",
]

DEFAULT_TRIALS = 100
"""Monte Carlo trials when ``--trials`` is not given."""
BAR_MIN_TRIALS = 20
"""Fewer trials than this finish too fast to need a bar."""


def _clock(seconds: float) -> str:
    """``m:ss`` of a duration [s] (``h:mm:ss`` from an hour on)."""
    whole = round(seconds)
    hours, rest = divmod(whole, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


class ProgressBar:
    """A one-line progress bar on a text stream, with the rate and the time left.

    ``replay [#####.....] 120/300 trials 0:42, 2.9 trials/s, ETA 1:02``. The rate is the
    trials done over the time since the bar started; the ETA the trials left at that rate
    (a sequential proof may stop before its budget, so the ETA is an upper bound there).
    ``clock`` is the time source [s] (tests pass a fake one).
    """

    def __init__(
        self,
        stream: TextIO,
        width: int = 30,
        *,
        label: str = "replay",
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.stream = stream
        self.width = width
        self.label = label
        self.clock = clock
        self.start = clock()
        self.drawn = False
        self._width_drawn = 0

    def line(self, done: int, total: int) -> str:
        """The bar's text for ``done`` of ``total`` trials (without the carriage return)."""
        filled = self.width * min(done, total) // max(total, 1)
        elapsed = max(self.clock() - self.start, 0.0)
        bar = "#" * filled + "." * (self.width - filled)
        text = f"{self.label} [{bar}] {done}/{total} trials {_clock(elapsed)}"
        if done > 0 and elapsed > 0.0:
            rate = done / elapsed  # [trials/s]
            text += f", {rate:.3g} trials/s, ETA {_clock(max(total - done, 0) / rate)}"
        return text

    def __call__(self, done: int, total: int) -> None:
        """Redraw for ``done`` of ``total`` trials."""
        text = self.line(done, total)
        pad = max(self._width_drawn - len(text), 0)  # blank what a longer line left behind
        self.stream.write("\r" + text + " " * pad)
        self.stream.flush()
        self._width_drawn = len(text)
        self.drawn = True

    def close(self) -> None:
        """End the bar's line."""
        if self.drawn:
            self.stream.write("\n")
            self.stream.flush()


def add_workers_argument(parser: Any, what: str) -> None:
    """``--workers K``: the processes running ``what`` (``synth plan`` and ``synth replay``)."""
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        help=f"processes running {what} (default and most: one per CPU core)",
    )


def available_cores() -> int:
    """CPU cores this process may run on (its affinity mask where the OS has one)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # not on Linux
        return max(1, os.cpu_count() or 1)


def resolve_workers(value: int | None, *, stream: TextIO | None = None) -> int:
    """``--workers`` as a count: one per CPU core when not given, and never more than the cores.

    Below 1 is a usage error. A larger count is capped at :func:`available_cores` with a
    one-line note on ``stream`` (standard error by default): more processes than cores only
    add start-up time and memory, and the trials' results do not depend on the count.
    """
    cores = available_cores()
    workers = value if value is not None else cores
    if workers < 1:
        raise SynthError(f"--workers must be 1 or more, got {workers}")
    if workers > cores:
        print(
            f"synth: --workers {workers} capped at the {cores} CPU cores available",
            file=stream if stream is not None else sys.stderr,
        )
        workers = cores
    return workers


def picture_format(path: str) -> Literal["svg", "png"]:
    """The format a picture's file name asks for; a usage error unless ``.svg`` or ``.png``."""
    lower = path.lower()
    if lower.endswith(".svg"):
        return "svg"
    if lower.endswith(".png"):
        return "png"
    raise SynthError(f"{path}: a picture must end in .svg or .png")


def write_output(path: str, data: bytes) -> None:
    """Write an output file (its directory made as needed); a usage error when it cannot."""
    out = Path(path)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_bytes(data)
    except OSError as exc:
        raise SynthError(f"cannot write {out}: {exc.strerror or exc}") from None


def add_replay_parser(sub: Any) -> None:
    """Add the ``replay`` subcommand to ``synth``'s subparsers."""
    p = sub.add_parser(
        "replay",
        help="run an AL program on the simulated arm: a nominal run and Monte Carlo trials",
        epilog="exit codes: 0 the nominal run succeeds; 1 it fails (abort, violation, pin not "
        "seated); 2 unusable input (syntax error, missing file, AL runtime error); 70 internal "
        "error",
    )
    p.add_argument(
        "program",
        nargs="?",
        metavar="PROGRAM.al",
        help="the AL program to replay ('-': read it from standard input)",
    )
    p.add_argument("--task", required=True, metavar="TASK.yaml", help="task specification")
    p.add_argument(
        "--trials",
        type=int,
        default=DEFAULT_TRIALS,
        help=f"Monte Carlo trials in sampled true worlds (default: {DEFAULT_TRIALS}; 0: none)",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed of the trials (default: 0)")
    add_workers_argument(p, "the trials")
    p.add_argument(
        "--distribution",
        choices=("uniform", "normal"),
        default=None,
        help="sample every error block from this distribution instead of the task's own "
        "(normal: σ = tolerance/3, truncated; seed ch. IX)",
    )
    p.add_argument("--json", action="store_true", help="print the report as JSON (SI units)")
    p.add_argument(
        "--preamble",
        action="store_true",
        help="print the task's world binding as AL declarations and exit",
    )
    p.add_argument(
        "--svg",
        metavar="PICTURE",
        help="draw the trials' sampled errors, coloured by outcome, failing trials labelled by "
        "AL line and kind, to this file (SVG, or PNG when it ends in .png)",
    )
    p.add_argument(
        "--trace",
        metavar="TRACE.json",
        help="record the nominal run (or --trial I) to this JSON file: time, joints, hand and "
        "pin poses, events with their AL lines (docs/trace.md)",
    )
    p.add_argument(
        "--progress",
        action="store_true",
        help="draw the progress bar on stderr even when it is not a terminal",
    )
    p.add_argument(
        "--export-trajectory",
        metavar="OUT.yaml|OUT.csv",
        help="write the nominal run's joint trajectory: a ROS trajectory_msgs/JointTrajectory "
        "(.yaml) or CSV, each point marked with its AL line and whether it is guarded",
    )
    p.add_argument(
        "--failures",
        type=int,
        default=0,
        metavar="K",
        help="print the first K failing trials with the errors each sampled",
    )
    p.add_argument(
        "--trial",
        type=int,
        default=None,
        metavar="I",
        help="re-run Monte Carlo trial I of --seed alone (its sampled world, outcome, line); "
        "with --trace, record that trial instead of the nominal run",
    )
    p.add_argument(
        "--min-success",
        type=float,
        default=None,
        metavar="P",
        help="exit 1 when the observed Monte Carlo success rate is below P (0–1; the rate "
        "itself is compared, as the proof does, not its Wilson bound)",
    )
    p.add_argument(
        "--dask",
        default=None,
        metavar="ADDRESS",
        help="run the trials on the Dask cluster whose scheduler is at ADDRESS, or on a new "
        "local cluster of --workers processes with 'local' (needs the dask extra)",
    )
    p.set_defaults(func=run_replay)


def read_program(path: str) -> str:
    """The program file's text (``-``: standard input); a usage error when it cannot be read.

    A byte that is not UTF-8 is reported at its line:column.
    """
    try:
        if path == "-":
            stdin = sys.stdin
            binary = getattr(stdin, "buffer", None)
            raw = binary.read() if binary is not None else stdin.read().encode("utf-8")
        else:
            with open(path, "rb") as f:
                raw = f.read()
    except FileNotFoundError:
        raise SynthError(f"{path}: no such program file") from None
    except OSError as exc:
        raise SynthError(f"{path}: cannot read the program: {exc.strerror or exc}") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        from synth.exceptions import ALSyntaxError

        before = raw[: exc.start].decode("utf-8", "replace")
        line = before.count("\n") + 1
        column = len(before) - (before.rfind("\n") + 1) + 1  # in characters, 1-based
        raise ALSyntaxError(
            line,
            column,
            f"byte 0x{raw[exc.start]:02x} is not UTF-8 text (AL programs are UTF-8)",
            filename=_display_name(path),
        ) from None


def _write_montecarlo(args: argparse.Namespace, report: Any) -> None:
    from synth.models.loader import load_task
    from synth.pictures.montecarlo import draw_montecarlo, montecarlo_picture
    from synth.pictures.render import figure_bytes
    from synth.replay.run import replay_graph, world_errors

    graph = replay_graph(load_task(args.task), args.distribution)
    errors = [world_errors(graph, args.seed, i) for i in range(len(report.trials))]
    figure = draw_montecarlo(montecarlo_picture(report, errors, graph))
    write_output(args.svg, figure_bytes(figure, picture_format(args.svg)))


def _write_trace(args: argparse.Namespace, text: str) -> None:
    from synth.replay.run import build_context
    from synth.replay.trace import record_run

    context = build_context(text, args.task, filename=args.program, distribution=args.distribution)
    trace = record_run(context, trial=args.trial, seed=args.seed, program=args.program)
    write_output(args.trace, (json.dumps(trace.to_json()) + "\n").encode("utf-8"))


def _display_name(path: str) -> str:
    """How a program's source is named in messages: ``<stdin>`` for ``-``."""
    return "<stdin>" if path == "-" else path


def run_replay(args: argparse.Namespace) -> int:
    """Run ``synth replay`` with parsed ``args``; the exit code (see the module docstring)."""
    from synth.models.loader import load_task

    if args.preamble:
        from synth.codegen.binding import preamble
        from synth.models.believed import believed_graph

        print(preamble(believed_graph(load_task(args.task))), end="")
        return 0
    if args.program is None:
        raise SynthError("give the PROGRAM.al to replay (or --preamble to print the binding)")
    if args.trials < 0:
        raise SynthError(f"--trials must be 0 or more, got {args.trials}")
    _check_diagnostics(args)
    workers = resolve_workers(args.workers)
    if args.svg is not None:
        picture_format(args.svg)
        if args.trials == 0:
            raise SynthError("--svg draws the Monte Carlo trials: give --trials 1 or more")
    if args.trial is not None and args.svg is not None:
        raise SynthError("--svg draws many trials; --trial I re-runs one")
    export = args.export_trajectory
    if export is not None and not export.lower().endswith((".yaml", ".yml", ".csv")):
        raise SynthError(f"--export-trajectory {export}: the file must end in .yaml or .csv")
    text = read_program(args.program)
    if args.trial is not None:
        if args.trace is not None:
            _write_trace(args, text)
        return _run_one(args, text)

    from synth.replay.report import replay_summary

    show = args.trials >= BAR_MIN_TRIALS and (args.progress or sys.stderr.isatty())
    bar = ProgressBar(sys.stderr) if show else None
    records = _TrialOutput(sys.stdout, args.failures, stream_json=args.json)
    with contextlib.ExitStack() as stack:
        client = None
        if args.dask is not None and args.trials:
            from synth.replay.cluster import dask_client

            client = stack.enter_context(dask_client(args.dask, workers))
        report = _replay_with(args, text, workers, bar, records, client)
    if args.svg is not None:
        _write_montecarlo(args, report)
    if args.trace is not None:
        _write_trace(args, text)
    if args.json:
        records.finish(report.to_json())
    else:
        print(replay_summary(report))
        if args.distribution is not None and args.trials:
            print(f"  errors: every block sampled {args.distribution} (--distribution)")
        records.print_failures()
        if args.svg is not None:
            print(f"Monte Carlo picture written to {args.svg}")
        if args.trace is not None:
            print(f"trace of the nominal run written to {args.trace}")
    if args.export_trajectory is not None:
        _export(args, text, report)
    if report.interrupted:
        return 130
    if not report.ok:
        return 2 if report.nominal.outcome == "error" else 1
    rate = report.monte_carlo.success_rate
    if args.min_success is not None and rate is not None and rate < args.min_success:
        if not args.json:
            print(
                f"  below --min-success {args.min_success:g}: observed rate {rate:.4f}",
                file=sys.stderr,
            )
        return 1
    return 0


def _replay_with(
    args: argparse.Namespace,
    text: str,
    workers: int,
    bar: ProgressBar | None,
    records: _TrialOutput,
    client: Any,
) -> Any:
    """The replay of ``args`` (on ``client``'s Dask cluster when given); the bar closed."""
    from synth.replay.run import replay

    try:
        report = replay(
            text,
            args.task,
            trials=args.trials,
            seed=args.seed,
            workers=min(workers, max(args.trials, 1)),
            filename=_display_name(args.program),
            progress=bar,
            distribution=args.distribution,
            on_trial=records if records.wanted else None,
            failures_only=not args.json,
            client=client,
        )
    finally:
        if bar is not None:
            bar.close()
    return report


def _check_diagnostics(args: argparse.Namespace) -> None:
    """Usage errors of ``--failures``, ``--trial`` and ``--min-success``."""
    if args.failures < 0:
        raise SynthError(f"--failures must be 0 or more, got {args.failures}")
    if args.trial is not None and args.trial < 0:
        raise SynthError(f"--trial must be 0 or more, got {args.trial}")
    if args.min_success is not None and not 0.0 <= args.min_success <= 1.0:
        raise SynthError(f"--min-success must be between 0 and 1, got {args.min_success:g}")


def _run_one(args: argparse.Namespace, text: str) -> int:
    """``--trial I``: trial I alone; exit 0 if it succeeds, 2 for an AL error, else 1."""
    from synth.replay.run import replay_one

    record = replay_one(
        text,
        args.task,
        args.trial,
        seed=args.seed,
        filename=args.program,
        distribution=args.distribution,
    )
    if args.json:
        print(json.dumps(record.to_json(), indent=2))
    else:
        print(f"replay {args.program}: trial {args.trial} of seed {args.seed} alone")
        print(_describe_trial(record))
    if record.run.success:
        return 0
    return 2 if record.run.outcome == "error" else 1


def _export(args: argparse.Namespace, text: str, report: Any) -> None:
    """``--export-trajectory``: the nominal run's joint trajectory (YAML or CSV)."""
    if report.nominal.outcome != "success":
        print("synth replay: no trajectory exported: the nominal run failed", file=sys.stderr)
        return
    from synth.replay.trajectory import export_trajectory, write_trajectory

    trajectory = export_trajectory(text, args.task, filename=_display_name(args.program))
    write_trajectory(trajectory, args.export_trajectory)
    print(
        f"trajectory of {len(trajectory.points)} points written to {args.export_trajectory}",
        file=sys.stderr if args.json else sys.stdout,
    )


def _describe_trial(record: Any) -> str:
    """A trial as text: outcome, AL line, message, time, and the errors it sampled."""
    run = record.run
    where = f" at line {run.line}" if run.line is not None else ""
    lines = [f"trial {record.index}: {run.outcome}{where}: {run.message}; {run.time:.2f} s"]
    for v in run.violations:
        lines.append(f"  violation: {v.kind} at line {v.line}: {v.detail}")
    for frame, values in record.errors.items():
        parts = ", ".join(
            f"{name} {value * 100:+.4f} cm"
            if name in ("x", "y", "z")
            else f"{name} {value * 57.29577951308232:+.4f}°"
            for name, value in values.items()
        )
        lines.append(f"  {frame}: {parts}")
    return "\n".join(lines)


class _TrialOutput:
    """Where trial records go: into the ``--json`` object, or the first ``K`` failures.

    Memory stays bounded: JSON records are written as they arrive, and at most ``K`` failures
    are kept for the text report.
    """

    def __init__(self, stream: TextIO, failures: int, *, stream_json: bool) -> None:
        self.stream = stream
        self.limit = failures
        self.stream_json = stream_json
        self.failures: list[Any] = []
        self.count = 0

    @property
    def wanted(self) -> bool:
        """Whether the replay should pass trial records at all."""
        return self.stream_json or self.limit > 0

    def __call__(self, record: Any) -> None:
        if self.stream_json:
            head = '{\n  "trials": [\n    ' if self.count == 0 else ",\n    "
            self.stream.write(head + json.dumps(record.to_json()))
            self.stream.flush()
        elif len(self.failures) < self.limit:
            self.failures.append(record)
        self.count += 1

    def finish(self, report: dict[str, Any]) -> None:
        """Close the JSON object: the trials array, then the report's own keys."""
        rest = json.dumps(report, indent=2)
        if self.count == 0:
            self.stream.write('{\n  "trials": [],\n' + rest[2:] + "\n")
        else:
            self.stream.write("\n  ],\n" + rest[2:] + "\n")
        self.stream.flush()

    def print_failures(self) -> None:
        """The kept failures, each with its sampled world."""
        if not self.limit:
            return
        if not self.failures:
            print("failures: none")
            return
        print(f"first {len(self.failures)} failing trial(s):")
        for record in self.failures:
            print(_describe_trial(record))
