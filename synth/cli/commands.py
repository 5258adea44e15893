"""The other ``synth`` commands: ``errors``, ``locate``, ``serve`` and ``view``."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from synth.cli.arguments import COUNT, PORT, add_workers_argument, resolve_workers
from synth.cli.files import read_program, write_output
from synth.exceptions import SynthError


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
    unplaced = [r.problem.obj for r in results if not r.estimates]
    if unplaced:  # contacts that contradict each other or the sizes: the task is bad input
        names = ", ".join(unplaced)
        print(f"synth locate: error: no pose satisfies the contacts of {names}", file=sys.stderr)
        return 2
    return 0


def _cmd_serve(args: argparse.Namespace) -> int:
    from server.serve import serve

    return serve(args.host, args.port, args.db, args.token, args.model_dir or ())


def _cmd_view(args: argparse.Namespace) -> int:
    from pathlib import Path

    from synth.models.loader import load_task
    from synth.pictures.view import view_html, view_scene
    from synth.replay.run import replay_context
    from synth.replay.trace import record_run

    if args.output != "-" and Path(args.output).suffix.lower() not in (".html", ".htm"):
        # the page is HTML whatever the name says: `-o v.png` wrote HTML into v.png
        raise SynthError(f"-o {args.output}: the view is an HTML page; name it .html (or '-')")
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
    where = "standard output" if args.output == "-" else args.output
    # a program planned here is written to no file: its name is not one to look for
    shown = name if args.program is not None else "the program planned for it"
    print(
        f"view of {shown} on {spec.name} written to {where} "
        f"(nominal run: {report.outcome}, {report.time:.2f} s, {len(trace.samples)} frames)",
        file=sys.stderr if args.output == "-" else sys.stdout,
    )
    return 0


def add_errors_parser(sub: Any) -> None:
    """Add the ``errors`` subcommand (the error bound of one frame from another)."""
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


def add_locate_parser(sub: Any) -> None:
    """Add the ``locate`` subcommand (object locations from contacts) to ``synth``'s subparsers."""
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


def add_serve_parser(sub: Any) -> None:
    """Add the ``serve`` subcommand (the HTTP service) to ``synth``'s subparsers."""
    p = sub.add_parser("serve", help="run the HTTP service (docs/api.md)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default: 127.0.0.1)")
    p.add_argument("--port", type=PORT, default=8000, help="port (default: 8000; 0: any free)")
    p.add_argument("--db", metavar="PATH|URL", help="SQLite file or SQLAlchemy URL ($SYNTH_DB)")
    p.add_argument("--token", help="bearer token required for writes ($SYNTH_TOKEN)")
    p.add_argument(
        "--model-dir",
        action="append",
        metavar="DIR",
        help="directory task URDFs may come from; repeatable ($SYNTH_MODEL_DIRS)",
    )
    p.set_defaults(func=_cmd_serve)


def add_view_parser(sub: Any) -> None:
    """Add the ``view`` subcommand (the 3-D page of a nominal run) to ``synth``'s subparsers."""
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
        "-o",
        "--output",
        default="view.html",
        metavar="VIEW.html",
        help="default: view.html; '-': to standard output (the summary to standard error)",
    )
    p.add_argument(
        "--proof-trials",
        type=COUNT,
        default=0,
        metavar="N",
        help="Monte Carlo trials of the plan's proof when no program is given (default: 0, "
        "the nominal replay only)",
    )
    add_workers_argument(p, "the proof's trials")
    p.set_defaults(func=_cmd_view)
