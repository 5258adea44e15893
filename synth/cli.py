"""Command line: ``synth errors``, ``synth locate``, … — parsing, I/O and printing only.

Exit codes (listed in ``synth --help``): 0 success; 1 a replay whose nominal run fails
(``synth replay``); 2 unusable input or a refusal — every :class:`~synth.exceptions.SynthError`
(one line on stderr, e.g. no strategy proven) and argparse's usage errors; 70 an internal error
(one line too, unless ``SYNTH_DEBUG=1`` asks for the traceback); 130 interrupted.

``-o -`` (``synth plan``) writes the program to standard output; the summary then goes to
standard error, so standard output carries the program alone.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable, Sequence

from synth.exceptions import SynthError
from synth.replay.cli_command import (  # light: heavy imports run later
    BAR_MIN_TRIALS,
    ProgressBar,
    add_replay_parser,
    add_workers_argument,
    picture_format,
    resolve_workers,
    write_output,
)

EXIT_OK = 0
EXIT_REPLAY_FAILED = 1
EXIT_USAGE = 2
EXIT_INTERNAL = 70
EXIT_INTERRUPTED = 130

EXIT_CODES_HELP = f"""exit codes:
  {EXIT_OK}   success
  {EXIT_REPLAY_FAILED}   synth replay: the program's nominal run failed (abort, violation, pin
      not seated)
  {EXIT_USAGE}   unusable input or a refusal: bad arguments, an invalid task or program, no
      strategy proven (synth plan), an AL runtime error (synth replay)
  {EXIT_INTERNAL}  internal error (SYNTH_DEBUG=1 prints the traceback)
  {EXIT_INTERRUPTED} interrupted"""
DEFAULT_PROOF_TRIALS = 100
"""Proof trials of ``synth plan`` (kept equal to :data:`synth.replay.proof.DEFAULT_PROOF_TRIALS`
by a test; the CLI does not import the replay to print its help)."""
DEFAULT_MIN_SUCCESS = 0.99
"""Required proof success rate (as :data:`synth.replay.proof.DEFAULT_MIN_SUCCESS`)."""

Command = Callable[[argparse.Namespace], int]


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
    from synth.replay.run import build_context
    from synth.replay.trace import record_run

    if args.proof_trials < 0:
        raise SynthError(f"--proof-trials must be 0 or more, got {args.proof_trials}")
    base_dir = Path(args.task).resolve().parent
    spec = load_task(args.task)
    if args.program is not None:
        from synth.replay.cli_command import read_program

        text, name = read_program(args.program), args.program
    else:
        from synth.pipeline import SynthesisOptions, synthesize
        from synth.replay.proof import ProofOptions

        proof = ProofOptions.for_task(
            spec, trials=args.proof_trials, workers=resolve_workers(args.workers)
        )
        text = synthesize(spec, SynthesisOptions(proof=proof), base_dir=base_dir).program
        name = f"{spec.name}.al"
    context = build_context(text, spec, filename=name, base_dir=base_dir)
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
    p.add_argument("--seed", type=int, default=0, help="random seed of the proof (default: 0)")
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
    p.add_argument("--port", type=int, default=8000, help="port (default: 8000; 0: any free)")
    p.add_argument("--db", metavar="PATH|URL", help="SQLite file or SQLAlchemy URL ($SYNTH_DB)")
    p.add_argument("--token", help="bearer token required for writes ($SYNTH_TOKEN)")
    p.add_argument(
        "--model-dir",
        action="append",
        metavar="DIR",
        help="directory task URDFs may come from; repeatable ($SYNTH_MODEL_DIRS)",
    )
    p.set_defaults(func=_cmd_serve)

    add_replay_parser(sub)

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
