"""``synth replay``: a program's nominal run and Monte Carlo trials on the simulated arm.

Its usage and exit codes are in :mod:`synth.cli`'s docstring and ``synth replay --help``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from typing import Any, TextIO

from synth.cli.arguments import (
    COUNT,
    DEFAULT_TRIALS,
    INDEX,
    SEED,
    add_workers_argument,
    picture_format,
    rate,
    resolve_workers,
)
from synth.cli.files import display_name, read_program, write_output
from synth.exceptions import SynthError
from synth.progress import BAR_MIN_TRIALS, ProgressBar


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
    from synth.replay.run import replay_context
    from synth.replay.trace import record_run

    context = replay_context(text, args.task, filename=args.program, distribution=args.distribution)
    trace = record_run(context, trial=args.trial, seed=args.seed, program=args.program)
    write_output(args.trace, (json.dumps(trace.to_json()) + "\n").encode("utf-8"))


def _cmd_replay(args: argparse.Namespace) -> int:
    """``synth replay`` (its exit codes: the module docstring)."""
    from synth.models.loader import load_task

    if args.preamble:
        if args.json:
            raise SynthError("--preamble prints AL declarations; --json does not apply")
        from synth.codegen.binding import preamble
        from synth.models.believed import believed_graph

        print(preamble(believed_graph(load_task(args.task))), end="")
        return 0
    if args.program is None:
        raise SynthError("give the PROGRAM.al to replay (or --preamble to print the binding)")
    _check_diagnostics(args)
    workers = resolve_workers(args.workers)
    if args.svg is not None:
        picture_format(args.svg)
        if args.trials == 0:
            raise SynthError("--svg draws the Monte Carlo trials: give --trials 1 or more")
    if args.trial is not None and args.svg is not None:
        raise SynthError("--svg draws many trials; --trial I re-runs one")
    if args.trial is not None and args.export_trajectory is not None:
        # the export is the commanded motion for a real arm: the nominal run, not a trial's
        raise SynthError(
            "--export-trajectory writes the nominal run's motion; --trial I re-runs a trial "
            "(--trace records the trial)"
        )
    if args.export_trajectory == "-":
        raise SynthError(
            "--export-trajectory -: the format comes from the file's name (.yaml or .csv); give "
            "a file name, not standard output"
        )
    if args.trace == "-" and args.json:
        raise SynthError("--json and --trace - both write to standard output: give --trace a file")
    export = args.export_trajectory
    if export is not None and not export.lower().endswith((".yaml", ".yml", ".csv")):
        raise SynthError(f"--export-trajectory {export}: the file must end in .yaml or .csv")
    text = read_program(args.program)
    if args.trial is not None:
        if args.trace is not None:
            _write_trace(args, text)
        status = _run_one(args, text)
        if args.trace is not None and args.trace != "-":
            print(
                f"trace of trial {args.trial} written to {args.trace}",
                file=sys.stderr if args.json else sys.stdout,
            )
        return status

    from synth.report import replay_summary

    show = args.trials >= BAR_MIN_TRIALS and (args.progress or sys.stderr.isatty())
    bar = ProgressBar(sys.stderr) if show else None
    report_to = _report_stream(args)
    records = _TrialOutput(report_to, args.failures, stream_json=args.json)
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
    rate = report.monte_carlo.success_rate
    below = args.min_success is not None and rate is not None and rate < args.min_success
    if args.json:
        document = report.to_json()
        if args.min_success is not None:
            document["min_success"] = {"required": args.min_success, "rate": rate, "met": not below}
        records.finish(document)
    else:
        print(replay_summary(report), file=report_to)
        if args.distribution is not None and args.trials:
            print(
                f"  errors: every block sampled {args.distribution} (--distribution)",
                file=report_to,
            )
        records.print_failures()
        if args.svg is not None:
            print(f"Monte Carlo picture written to {args.svg}", file=report_to)
        if args.trace is not None and args.trace != "-":
            print(f"trace of the nominal run written to {args.trace}", file=report_to)
    if args.export_trajectory is not None:
        _export(args, text, report)
    if report.interrupted:
        return 130
    if not report.ok:
        return 2 if report.nominal.outcome == "error" else 1
    if below:
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
    from synth.replay.run import replay_program

    try:
        report = replay_program(
            text,
            args.task,
            trials=args.trials,
            seed=args.seed,
            workers=min(workers, max(args.trials, 1)),
            filename=display_name(args.program),
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
    if args.min_success is not None and (args.trial is not None or args.trials == 0):
        # a rate needs trials: with none (or one re-run alone) the bound would never be checked
        alone = "--trial I re-runs one trial" if args.trial is not None else "--trials is 0"
        raise SynthError(f"--min-success compares a Monte Carlo rate, but {alone}")
    if args.trial is not None and args.trials is not None:
        raise SynthError("--trial I re-runs one trial of --seed alone; --trials does not apply")
    if args.trials is None:
        args.trials = DEFAULT_TRIALS


def _report_stream(args: argparse.Namespace) -> TextIO:
    """Where the text report goes: standard error when ``--trace -`` takes standard output.

    As ``plan -o -`` sends its summary there.
    """
    return sys.stderr if args.trace == "-" else sys.stdout


def _run_one(args: argparse.Namespace, text: str) -> int:
    """``--trial I``: trial I alone; exit 0 if it succeeds, 2 for an AL error, else 1."""
    from synth.replay.run import replay_one
    from synth.report import trial_text

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
        report_to = _report_stream(args)
        print(
            f"replay {args.program}: trial {args.trial} of seed {args.seed} alone", file=report_to
        )
        print(trial_text(record), file=report_to)
    if record.run.success:
        return 0
    return 2 if record.run.outcome == "error" else 1


def _export(args: argparse.Namespace, text: str, report: Any) -> None:
    """``--export-trajectory``: the nominal run's joint trajectory (YAML or CSV)."""
    if report.nominal.outcome != "success":
        print("synth replay: no trajectory exported: the nominal run failed", file=sys.stderr)
        return
    from synth.replay.trajectory import export_trajectory, write_trajectory

    trajectory = export_trajectory(text, args.task, filename=display_name(args.program))
    write_trajectory(trajectory, args.export_trajectory)
    print(
        f"trajectory of {len(trajectory.points)} points written to {args.export_trajectory}",
        file=sys.stderr if args.json else sys.stdout,
    )


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
        from synth.report import trial_text

        for record in self.failures:
            print(trial_text(record, every_hand_error=False))


def add_replay_parser(sub: Any) -> None:
    """Add the ``replay`` subcommand to ``synth``'s subparsers."""
    p = sub.add_parser(
        "replay",
        help="run an AL program on the simulated arm: a nominal run and Monte Carlo trials",
        epilog="exit codes: 0 the nominal run succeeds; 1 it fails (abort, violation, pin not "
        "seated) or the Monte Carlo rate is below --min-success; 2 unusable input (syntax "
        "error, missing file, AL runtime error); 70 internal error; 130 interrupted; 141 the "
        "reader of standard output closed it",
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
        type=COUNT,
        default=None,  # DEFAULT_TRIALS when not given: --trial refuses it given
        help=f"Monte Carlo trials in sampled true worlds (default: {DEFAULT_TRIALS}; 0: none)",
    )
    p.add_argument("--seed", type=SEED, default=0, help="random seed of the trials (default: 0)")
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
        type=COUNT,
        default=0,
        metavar="K",
        help="print the first K failing trials with the errors each sampled",
    )
    p.add_argument(
        "--trial",
        type=INDEX,
        default=None,
        metavar="I",
        help="re-run Monte Carlo trial I of --seed alone (its sampled world, outcome, line); "
        "with --trace, record that trial instead of the nominal run",
    )
    p.add_argument(
        "--min-success",
        type=rate,
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
    p.set_defaults(func=_cmd_replay)
