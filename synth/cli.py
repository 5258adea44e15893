"""Command line: ``synth plan``, ``synth replay``, ``synth errors``, … — parsing, I/O, printing.

Nothing heavy is imported at import time, so ``synth --help`` stays fast.

Exit codes (listed in ``synth --help``): 0 success; 1 a replay whose nominal run fails
(``synth replay``); 2 unusable input or a refusal — every :class:`~synth.exceptions.SynthError`
(one line on stderr, e.g. no strategy proven) and argparse's usage errors; 70 an internal error
(one line too, unless ``SYNTH_DEBUG=1`` asks for the traceback); 130 interrupted.

``-o -`` (``synth plan``) writes the program to standard output; the summary then goes to
standard error, so standard output carries the program alone.

``synth replay``::

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
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Literal, TextIO

from synth.cores import available_cores
from synth.exceptions import SynthError
from synth.progress import BAR_MIN_TRIALS, ProgressBar

EXIT_OK = 0
EXIT_REPLAY_FAILED = 1
EXIT_USAGE = 2
EXIT_INTERNAL = 70
EXIT_INTERRUPTED = 130
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, as a shell reports a process the signal ended

EXIT_CODES_HELP = f"""exit codes:
  {EXIT_OK}   success
  {EXIT_REPLAY_FAILED}   synth replay: the program's nominal run failed (abort, violation, pin
      not seated)
  {EXIT_USAGE}   unusable input or a refusal: bad arguments, an invalid task or program, no
      strategy proven (synth plan), an AL runtime error (synth replay)
  {EXIT_INTERNAL}  internal error (SYNTH_DEBUG=1 prints the traceback)
  {EXIT_INTERRUPTED} interrupted
  {EXIT_BROKEN_PIPE} the reader of standard output closed it (e.g. `| head`)"""
DEFAULT_PROOF_TRIALS = 100
"""Proof trials of ``synth plan`` (kept equal to :data:`synth.replay.proof.DEFAULT_PROOF_TRIALS`
by a test; the CLI does not import the replay to print its help)."""
DEFAULT_MIN_SUCCESS = 0.99
"""Required proof success rate (as :data:`synth.replay.proof.DEFAULT_MIN_SUCCESS`)."""

DEFAULT_TRIALS = 100
"""Monte Carlo trials of ``synth replay`` when ``--trials`` is not given."""

Command = Callable[[argparse.Namespace], int]


def add_workers_argument(parser: Any, what: str) -> None:
    """``--workers K``: the processes running ``what`` (``synth plan`` and ``synth replay``)."""
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        help=f"processes running {what} (default and most: one per CPU core)",
    )


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
    from synth.replay.run import replay_context
    from synth.replay.trace import record_run

    context = replay_context(text, args.task, filename=args.program, distribution=args.distribution)
    trace = record_run(context, trial=args.trial, seed=args.seed, program=args.program)
    write_output(args.trace, (json.dumps(trace.to_json()) + "\n").encode("utf-8"))


def _display_name(path: str) -> str:
    """How a program's source is named in messages: ``<stdin>`` for ``-``."""
    return "<stdin>" if path == "-" else path


def _cmd_replay(args: argparse.Namespace) -> int:
    """``synth replay`` (its exit codes: the module docstring)."""
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

    from synth.report import replay_summary

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
    rate = report.monte_carlo.success_rate
    below = args.min_success is not None and rate is not None and rate < args.min_success
    if args.json:
        document = report.to_json()
        if args.min_success is not None:
            document["min_success"] = {"required": args.min_success, "rate": rate, "met": not below}
        records.finish(document)
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
    if args.min_success is not None and (args.trial is not None or args.trials == 0):
        # a rate needs trials: with none (or one re-run alone) the bound would never be checked
        alone = "--trial I re-runs one trial" if args.trial is not None else "--trials is 0"
        raise SynthError(f"--min-success compares a Monte Carlo rate, but {alone}")


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
        print(f"replay {args.program}: trial {args.trial} of seed {args.seed} alone")
        print(trial_text(record))
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
            print(trial_text(record))


def _add_replay_parser(sub: Any) -> None:
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
        type=int,
        default=DEFAULT_TRIALS,
        help=f"Monte Carlo trials in sampled true worlds (default: {DEFAULT_TRIALS}; 0: none)",
    )
    p.add_argument("--seed", type=_seed, default=0, help="random seed of the trials (default: 0)")
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
    p.set_defaults(func=_cmd_replay)


def _cmd_errors(args: argparse.Namespace) -> int:
    from synth.errors.chain import chain_between
    from synth.errors.estimate import estimate_errors
    from synth.models.graph import AttributeGraph
    from synth.models.loader import load_task
    from synth.report import errors_table

    graph = AttributeGraph(load_task(args.task))
    start, end = graph.resolve(args.from_), graph.resolve(args.to)
    report = estimate_errors(chain_between(graph, start, end), start, end)
    if args.json:
        print(json.dumps(report.to_json(), indent=2))
    else:
        print(errors_table(report, graph))
    return 0


def _cmd_locate(args: argparse.Namespace) -> int:
    from synth.errors.locate import SEED_OPTIONS, locate_objects
    from synth.models.graph import AttributeGraph
    from synth.models.loader import load_task
    from synth.report import locate_report

    spec = load_task(args.task)
    results = locate_objects(spec, options=SEED_OPTIONS if args.seed_method else None)
    if args.json:
        print(json.dumps({"task": spec.name, "objects": [r.to_json() for r in results]}, indent=2))
    else:
        print(locate_report(results, AttributeGraph(spec), constraints=args.constraints))
    return 0


def _integer_from_zero(noun: str, most: int | None = None) -> Callable[[str], int]:
    """An argparse type: an integer from 0 to ``most`` (no bound when None), named ``noun``."""
    allowed = "0 or more" if most is None else f"0 to {most}"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if value < 0 or (most is not None and value > most):
            raise argparse.ArgumentTypeError(f"a {noun} is {allowed}, got {value}")
        return value

    return parse


_seed = _integer_from_zero("seed")
"""``--seed``: numpy's generators take non-negative seeds, and the service refuses others."""
_port = _integer_from_zero("port", 65535)
"""``--port``: a TCP port, 0 (any free one) to 65535."""


def _cmd_serve(args: argparse.Namespace) -> int:
    from server.serve import serve

    return serve(args.host, args.port, args.db, args.token, args.model_dir or ())


def _cmd_plan(args: argparse.Namespace) -> int:
    from pathlib import Path

    from synth.models.loader import load_task
    from synth.pipeline import SequenceSynthesis, SynthesisOptions, synthesize
    from synth.replay.proof import ProofOptions
    from synth.report import plan_summary, sequence_summary
    from synth.strategies import PlanOptions

    spec = load_task(args.task)
    if args.svg is not None:
        picture_format(args.svg)
    if args.proof_trials is not None and args.proof_trials < 0:
        raise SynthError(f"--proof-trials must be 0 or more, got {args.proof_trials}")
    if args.min_success is not None and not 0.0 <= args.min_success <= 1.0:
        raise SynthError(f"--min-success must lie between 0 and 1, got {args.min_success}")
    workers = resolve_workers(args.workers)
    options = SynthesisOptions(
        plan=PlanOptions(try_harder=args.try_harder, exhaustive=args.exhaustive),
        proof=ProofOptions.for_task(
            spec,
            trials=args.proof_trials,
            min_success=args.min_success,
            seed=args.seed,
            workers=workers,
        ),
        preamble=args.preamble,
    )
    to_stdout = args.output == "-"
    show = options.proof is not None and options.proof.trials >= BAR_MIN_TRIALS
    show = show and (args.progress or sys.stderr.isatty())
    bar = ProgressBar(sys.stderr, label="proof") if show else None
    try:
        result = synthesize(
            spec,
            options,
            base_dir=Path(args.task).resolve().parent,
            progress=None if bar is None else (lambda _name, done, total: bar(done, total)),
        )
    finally:
        if bar is not None:
            bar.close()
    summary = sys.stderr if to_stdout else sys.stdout
    if to_stdout:
        sys.stdout.write(result.program)
        sys.stdout.flush()
    elif args.output is not None:
        write_output(args.output, result.program.encode("utf-8"))
    if args.svg is not None:
        from synth.pictures.plan import draw_plan, plan_picture
        from synth.pictures.render import figure_bytes

        figure = draw_plan(plan_picture(*result.pictured))
        write_output(args.svg, figure_bytes(figure, picture_format(args.svg)))
    if args.json:
        print(json.dumps(result.to_json(), indent=2), file=summary)
    else:
        if isinstance(result, SequenceSynthesis):
            text = sequence_summary(result.sequence, result.proof, verbose=args.verbose)
        else:
            text = plan_summary(
                result.plan, result.proof, records=args.records, verbose=args.verbose
            )
        print(text, file=summary)
        if args.output is not None and not to_stdout:
            print(f"AL program written to {args.output}", file=summary)
        if args.svg is not None:
            print(f"plan picture written to {args.svg}", file=summary)
    return 0


def _cmd_view(args: argparse.Namespace) -> int:
    from pathlib import Path

    from synth.models.loader import load_task
    from synth.pictures.view import view_html, view_scene
    from synth.replay.run import replay_context
    from synth.replay.trace import record_run

    if args.proof_trials < 0:
        raise SynthError(f"--proof-trials must be 0 or more, got {args.proof_trials}")
    base_dir = Path(args.task).resolve().parent
    spec = load_task(args.task)
    if args.program is not None:
        text, name = read_program(args.program), args.program
    else:
        from synth.pipeline import SynthesisOptions, synthesize
        from synth.replay.proof import ProofOptions

        proof = ProofOptions.for_task(
            spec, trials=args.proof_trials, workers=resolve_workers(args.workers)
        )
        text = synthesize(spec, SynthesisOptions(proof=proof), base_dir=base_dir).program
        name = f"{spec.name}.al"
    context = replay_context(text, spec, filename=name, base_dir=base_dir)
    trace = record_run(context, program=name)
    write_output(args.output, view_html(view_scene(context, trace, text)).encode("utf-8"))
    report = trace.report
    print(
        f"view of {name} on {spec.name} written to {args.output} "
        f"(nominal run: {report.outcome}, {report.time:.2f} s, {len(trace.samples)} frames)"
    )
    return 0


def _version() -> str:
    """The installed package's version (the source tree's when synth is not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("synth")
    except PackageNotFoundError:  # pragma: no cover - run from a source tree
        from synth import __version__

        return __version__


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``synth`` command."""
    parser = argparse.ArgumentParser(
        prog="synth",
        description="Task-level synthesis of AL pin-in-hole programs (after Taylor, 1976).",
        epilog=EXIT_CODES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("errors", help="bound the run-time error of one frame relative to another")
    p.add_argument("task", help="task specification (YAML)")
    p.add_argument(
        "--from",
        dest="from_",
        required=True,
        metavar="A",
        help="reference frame: a frame name or its AL name (e.g. BH1)",
    )
    p.add_argument("--to", required=True, metavar="B", help="frame whose error is bounded")
    p.add_argument("--json", action="store_true", help="print JSON (SI units)")
    p.set_defaults(func=_cmd_errors)

    p = sub.add_parser(
        "plan",
        help="choose a pin-in-hole strategy (seed ch. IV §4.1–4.6) and write it only once its "
        "replay proves it",
        description="Plan best-first, emit the chosen strategy's AL program and prove it by "
        "replay (nominal run and Monte Carlo). A candidate that fails its proof is rejected "
        "and the next is tried; exit 2 when none is proven, with the root cause first.",
    )
    p.add_argument("task", help="task specification (YAML) with insertion and manipulator")
    p.add_argument("--json", action="store_true", help="print JSON (SI units)")
    p.add_argument(
        "--try-harder",
        action="store_true",
        help="keep every grasp orientation ω with an arm solution, not the best three",
    )
    p.add_argument(
        "--exhaustive",
        action="store_true",
        help="refine every candidate instead of stopping at the best-first cutoff",
    )
    p.add_argument(
        "-o",
        "--output",
        metavar="PROGRAM.al",
        help="write the AL program of the chosen strategy to this file (the summary still "
        "prints); '-': to standard output, the summary then going to standard error",
    )
    p.add_argument(
        "--records",
        action="store_true",
        help="also print the chosen strategy's record in the seed's PHL SPEC layout",
    )
    p.add_argument(
        "--verbose",
        action="store_true",
        help="keep the seed's line references (seed Lnnnn) in the summary",
    )
    p.add_argument(
        "--progress",
        action="store_true",
        help="draw the proof's progress bar on stderr even when it is not a terminal",
    )
    p.add_argument(
        "--svg",
        metavar="PICTURE",
        help="draw the plan (top view in the hole's frame, side view of the heights) to this "
        "file: SVG, or PNG when it ends in .png",
    )
    p.add_argument(
        "--preamble",
        action="store_true",
        help="start the program with the task's frame declarations and affixments (stand-alone)",
    )
    p.add_argument(
        "--proof-trials",
        type=int,
        default=None,
        metavar="N",
        help="Monte Carlo trials of the replay proof (default: the task's proof.trials, else "
        f"{DEFAULT_PROOF_TRIALS}; 0: the nominal replay only)",
    )
    p.add_argument(
        "--min-success",
        type=float,
        default=None,
        metavar="RATE",
        help="success rate the proof must reach (default: the task's proof.min_success, else "
        f"{DEFAULT_MIN_SUCCESS:g})",
    )
    p.add_argument("--seed", type=_seed, default=0, help="random seed of the proof (default: 0)")
    add_workers_argument(p, "the proof's trials")
    p.set_defaults(func=_cmd_plan)

    p = sub.add_parser("locate", help="derive object locations from their contacts (seed A.1)")
    p.add_argument("task", help="task specification (YAML) with a contacts section")
    p.add_argument("--json", action="store_true", help="print JSON (SI units)")
    p.add_argument(
        "--constraints",
        action="store_true",
        help="also list the constraint rows, laid out as in the seed",
    )
    p.add_argument(
        "--seed-method",
        action="store_true",
        help="bound each estimate with one relaxation, as the seed's printed figures",
    )
    p.set_defaults(func=_cmd_locate)

    p = sub.add_parser("serve", help="run the HTTP service (docs/api.md)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default: 127.0.0.1)")
    p.add_argument("--port", type=_port, default=8000, help="port (default: 8000; 0: any free)")
    p.add_argument("--db", metavar="PATH|URL", help="SQLite file or SQLAlchemy URL ($SYNTH_DB)")
    p.add_argument("--token", help="bearer token required for writes ($SYNTH_TOKEN)")
    p.add_argument(
        "--model-dir",
        action="append",
        metavar="DIR",
        help="directory task URDFs may come from; repeatable ($SYNTH_MODEL_DIRS)",
    )
    p.set_defaults(func=_cmd_serve)

    _add_replay_parser(sub)

    p = sub.add_parser(
        "view",
        help="write one offline HTML page: the workcell, the arm and the program's nominal run "
        "in 3-D, the AL line being executed highlighted",
    )
    p.add_argument("task", help="task specification (YAML) with a manipulator")
    p.add_argument(
        "program",
        nargs="?",
        metavar="PROGRAM.al",
        help="the AL program to show (default: plan the task and show its program)",
    )
    p.add_argument(
        "-o", "--output", default="view.html", metavar="VIEW.html", help="default: view.html"
    )
    p.add_argument(
        "--proof-trials",
        type=int,
        default=0,
        metavar="N",
        help="Monte Carlo trials of the plan's proof when no program is given (default: 0, "
        "the nominal replay only)",
    )
    add_workers_argument(p, "the proof's trials")
    p.set_defaults(func=_cmd_view)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``synth`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    func: Command = args.func
    try:
        return func(args)
    except SynthError as exc:
        print(f"synth {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("synth: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        # The reader of standard output went away (`synth replay … --json | head`): stop
        # quietly, as a process killed by SIGPIPE would, and keep the interpreter's last flush
        # from raising again at exit (the recipe of Python's signal module documentation).
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_BROKEN_PIPE
    except Exception as exc:
        if os.environ.get("SYNTH_DEBUG"):
            raise
        print(
            f"synth {args.command}: internal error: {type(exc).__name__}: {exc} "
            "(set SYNTH_DEBUG=1 for a traceback)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
