"""``synth replay``: run an AL program on the simulated arm — parsing, I/O and printing only.

    synth replay PROGRAM.al --task TASK.yaml [--trials N] [--seed S] [--workers K] [--json]
                 [--progress] [--failures K] [--min-success P]
    synth replay PROGRAM.al --task TASK.yaml --trials N --dask ADDRESS|local
    synth replay PROGRAM.al --task TASK.yaml --trial I [--seed S] [--json]
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
from typing import Any, TextIO

from synth.exceptions import SynthError

__all__ = [
    "DEFAULT_TRIALS",
    "ProgressBar",
    "add_replay_parser",
    "add_workers_argument",
    "available_cores",
    "resolve_workers",
    "run_replay",
]

DEFAULT_TRIALS = 100
"""Monte Carlo trials when ``--trials`` is not given."""
_BAR_MIN_TRIALS = 20
"""Fewer trials than this finish too fast to need a bar."""


class ProgressBar:
    """A one-line progress bar on a text stream: ``replay [#####.....] 120/300 trials 0:42``."""

    def __init__(self, stream: TextIO, width: int = 30) -> None:
        self.stream = stream
        self.width = width
        self.start = time.monotonic()
        self.drawn = False

    def __call__(self, done: int, total: int) -> None:
        """Redraw for ``done`` of ``total`` trials."""
        filled = self.width * done // max(total, 1)
        elapsed = int(time.monotonic() - self.start)
        bar = "#" * filled + "." * (self.width - filled)
        self.stream.write(
            f"\rreplay [{bar}] {done}/{total} trials {elapsed // 60}:{elapsed % 60:02d}"
        )
        self.stream.flush()
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


def add_replay_parser(sub: Any) -> None:
    """Add the ``replay`` subcommand to ``synth``'s subparsers."""
    p = sub.add_parser(
        "replay",
        help="run an AL program on the simulated arm: a nominal run and Monte Carlo trials",
    )
    p.add_argument("program", nargs="?", metavar="PROGRAM.al", help="the AL program to replay")
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
        "--progress",
        action="store_true",
        help="draw the progress bar on stderr even when it is not a terminal",
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
        help="re-run Monte Carlo trial I of --seed alone (its sampled world, outcome, line)",
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


def _read_program(path: str) -> str:
    """The program file's text; a byte that is not UTF-8 is reported at its line:column."""
    try:
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
            filename=path,
        ) from None


def run_replay(args: argparse.Namespace) -> int:
    """Run ``synth replay`` with parsed ``args``; the exit code (see the module docstring)."""
    from synth.models.loader import load_task

    if args.preamble:
        from synth.al.binding import preamble
        from synth.errors.locate import believed_graph

        print(preamble(believed_graph(load_task(args.task))), end="")
        return 0
    if args.program is None:
        raise SynthError("give the PROGRAM.al to replay (or --preamble to print the binding)")
    if args.trials < 0:
        raise SynthError(f"--trials must be 0 or more, got {args.trials}")
    _check_diagnostics(args)
    workers = resolve_workers(args.workers)
    text = _read_program(args.program)
    if args.trial is not None:
        return _run_one(args, text)

    from synth.replay.report import replay_summary

    show = args.trials >= _BAR_MIN_TRIALS and (args.progress or sys.stderr.isatty())
    bar = ProgressBar(sys.stderr) if show else None
    records = _TrialOutput(sys.stdout, args.failures, stream_json=args.json)
    with contextlib.ExitStack() as stack:
        client = None
        if args.dask is not None and args.trials:
            from synth.replay.cluster import dask_client

            client = stack.enter_context(dask_client(args.dask, workers))
        report = _replay_with(args, text, workers, bar, records, client)
    if args.json:
        records.finish(report.to_json())
    else:
        print(replay_summary(report))
        if args.distribution is not None and args.trials:
            print(f"  errors: every block sampled {args.distribution} (--distribution)")
        records.print_failures()
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
            filename=args.program,
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
