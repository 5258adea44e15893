"""``synth plan``: choose a strategy, write its AL program once its replay proves it."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from synth.cli.arguments import (
    COUNT,
    DEFAULT_MIN_SUCCESS,
    DEFAULT_PROOF_TRIALS,
    SEED,
    add_workers_argument,
    picture_format,
    rate,
    resolve_workers,
)
from synth.cli.files import write_output
from synth.progress import BAR_MIN_TRIALS, ProgressBar


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
        if result.fallback is not None:
            print(f"\nWarning: {result.fallback}", file=summary)
        if args.output is not None and not to_stdout:
            print(f"AL program written to {args.output}", file=summary)
        if args.svg is not None:
            print(f"plan picture written to {args.svg}", file=summary)
    return 0


def add_plan_parser(sub: Any) -> None:
    """Add the ``plan`` subcommand (plan, prove and write a program) to ``synth``'s subparsers."""
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
        type=COUNT,
        default=None,
        metavar="N",
        help="Monte Carlo trials of the replay proof (default: the task's proof.trials, else "
        f"{DEFAULT_PROOF_TRIALS}; 0: the nominal replay only)",
    )
    p.add_argument(
        "--min-success",
        type=rate,
        default=None,
        metavar="RATE",
        help="success rate the proof must reach (default: the task's proof.min_success, else "
        f"{DEFAULT_MIN_SUCCESS:g})",
    )
    p.add_argument("--seed", type=SEED, default=0, help="random seed of the proof (default: 0)")
    add_workers_argument(p, "the proof's trials")
    p.set_defaults(func=_cmd_plan)
