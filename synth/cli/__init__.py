"""Command line: ``synth plan``, ``synth replay``, ``synth errors``, … — parsing, I/O, printing.

One module per command (:mod:`~synth.cli.plan`, :mod:`~synth.cli.replay`, the others in
:mod:`~synth.cli.commands`), their argument types, defaults and exit codes in
:mod:`~synth.cli.arguments` and their files in :mod:`~synth.cli.files`; this module builds
the parser and runs a command.

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
import os
import sys
from collections.abc import Sequence

from synth.cli.arguments import (
    DEFAULT_MIN_SUCCESS,
    DEFAULT_PROOF_TRIALS,
    DEFAULT_TRIALS,
    EXIT_BROKEN_PIPE,
    EXIT_CODES_HELP,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_REPLAY_FAILED,
    EXIT_USAGE,
    Command,
)
from synth.cli.commands import (
    add_errors_parser,
    add_locate_parser,
    add_serve_parser,
    add_view_parser,
)
from synth.cli.files import check_outputs
from synth.cli.plan import add_plan_parser
from synth.cli.replay import add_replay_parser
from synth.exceptions import SynthError

__all__ = [
    "DEFAULT_MIN_SUCCESS",
    "DEFAULT_PROOF_TRIALS",
    "DEFAULT_TRIALS",
    "EXIT_BROKEN_PIPE",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_REPLAY_FAILED",
    "EXIT_USAGE",
    "build_parser",
    "main",
]


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

    add_errors_parser(sub)
    add_plan_parser(sub)
    add_locate_parser(sub)
    add_serve_parser(sub)
    add_replay_parser(sub)
    add_view_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``synth`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    func: Command = args.func
    try:
        check_outputs(args)
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
