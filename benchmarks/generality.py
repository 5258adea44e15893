"""Generality suite: synthesize and prove a program for every task of the manifest.

Usage: python benchmarks/generality.py [--trials N] [--workers W] [--fast] [--only NAME] [--why]
                                      [--check] [--no-seed-fixtures]
Reads ``fixtures/tasks/generality/expected.yaml`` (and adds the seed's own plannable fixtures,
which must be proven too); per task, prints the expectation (``plan`` or
``refuse`` with the cause the refusal's first line must name), the decision (the chosen
strategy and its refinement, or the refusal's first line), the planning time, the proof's trials
and successes, and PASS or FAIL against the expectation; then a tally.

A plannable task passes when its program's nominal replay succeeds and at least ``MIN_SUCCESS``
of its ``--trials`` Monte Carlo trials do (``--trials 0``: the nominal run alone). An impossible
task passes when it is refused and the refusal's first line contains its ``cause``
(case-insensitive); a refusal naming another cause is a FAIL. ``--why`` adds, under each task,
the failing trials grouped by outcome, AL line and message; ``--check`` exits 1 unless every
task passes.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from synth.exceptions import SynthError
from synth.pipeline import SynthesisOptions, synthesize
from synth.replay.proof import ProofOptions
from synth.strategies import PinInHoleStrategy

ROOT = Path(__file__).resolve().parent.parent
SUITE = ROOT / "fixtures" / "tasks" / "generality"
MANIFEST = SUITE / "expected.yaml"
MIN_SUCCESS = 0.99
"""Monte Carlo success rate a plannable task's program must reach."""


@dataclass(frozen=True)
class Expectation:
    """One manifest entry: ``plan`` or ``refuse`` (with the cause its first line names)."""

    task: str
    expect: str
    cause: str | None
    why: str
    fast: bool
    path: Path | None = None
    """The task file (default: the suite's ``<task>.yaml``)."""

    @property
    def file(self) -> Path:
        """The task file."""
        return self.path if self.path is not None else SUITE / f"{self.task}.yaml"


@dataclass
class Synthesis:
    """A task taken to a program and its proof.

    ``decision`` summarises the chosen strategy; ``planning_time`` [s] is the planner's own;
    ``nominal`` the nominal replay's outcome (``success``, ``abort``, ...); ``trials`` and
    ``successes`` the Monte Carlo proof; ``failures`` counts the failing runs (nominal included)
    by (outcome, AL line, message).
    """

    program: str
    decision: str
    planning_time: float
    nominal: str
    trials: int
    successes: int
    failures: Counter[tuple[str, int | None, str]] = field(default_factory=Counter)


def _decision(strategy: PinInHoleStrategy) -> str:
    """``ω=135° γ=135° d=3.54 cm φ=45° + search (7 pts)``: the strategy and its refinements."""
    steps = []
    if strategy.tap is not None:
        steps.append("tap")
    if strategy.search is not None:
        steps.append(f"search ({strategy.search.expected_points} pts)")
    return f"{strategy.name} + {' + '.join(steps) if steps else 'direct'}"


def _synthesize(path: Path, trials: int, workers: int) -> Synthesis:
    """Task file → proven program by :func:`synth.pipeline.synthesize` (the one pipeline).

    Raises :class:`~synth.exceptions.SynthError` when the task is refused, which includes a
    task none of whose candidates' programs passed the proof. ``failures`` lists the first
    failing trial of every candidate the proof rejected before the chosen one.
    """
    options = SynthesisOptions(
        proof=ProofOptions(trials=trials, min_success=MIN_SUCCESS, seed=0, workers=workers)
    )
    made = synthesize(path, options)
    failures: Counter[tuple[str, int | None, str]] = Counter()
    for attempt in made.attempts:
        failed = attempt.proof.first_failure
        if failed is not None:
            failures[(failed.outcome, failed.line, f"{attempt.candidate}: {failed.message}")] += 1
    proof = made.proof
    return Synthesis(
        program=made.program,
        decision=_decision(made.strategy)
        + (f" (after {len(made.attempts) - 1} rejected)" if len(made.attempts) > 1 else ""),
        planning_time=made.plan.planning_time,
        nominal=proof.nominal.outcome,
        trials=proof.trials,
        successes=proof.successes,
        failures=failures,
    )


def load_manifest(path: Path = MANIFEST) -> list[Expectation]:
    """The manifest's entries, in file order."""
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    out = []
    for name, entry in data["tasks"].items():
        expect = entry["expect"]
        if expect not in ("plan", "refuse"):
            raise ValueError(f"{name}: expect must be 'plan' or 'refuse', not {expect!r}")
        cause = entry.get("cause")
        if expect == "refuse" and not cause:
            raise ValueError(f"{name}: a refusal needs the 'cause' its first line names")
        out.append(Expectation(name, expect, cause, entry.get("why", ""), bool(entry.get("fast"))))
    return out


SEED_FIXTURES = ("seed_4_8", "seed_4_8_tap", "seed_4_8_fixture")
"""The seed's plannable fixtures (fixtures/tasks/): every one must be proven too."""


def seed_entries() -> list[Expectation]:
    """The seed's fixtures as plannable entries (``--seed-fixtures``)."""
    return [
        Expectation(
            name,
            "plan",
            None,
            "the seed's own task",
            False,
            ROOT / "fixtures/tasks" / f"{name}.yaml",
        )
        for name in SEED_FIXTURES
    ]


@dataclass(frozen=True)
class Row:
    """One line of the table."""

    task: str
    expectation: str
    decision: str
    plan_time: float | None
    proof: str
    wall: float
    passed: bool
    note: str = ""
    why: tuple[str, ...] = ()


def judge(entry: Expectation, trials: int, workers: int) -> Row:
    """Synthesize ``entry``'s task and compare the outcome with its expectation."""
    expectation = "plan" if entry.expect == "plan" else f"refuse: {entry.cause}"
    start = time.perf_counter()
    try:
        made = _synthesize(entry.file, trials, workers)
    except SynthError as exc:
        wall = time.perf_counter() - start
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        if entry.expect == "plan":
            return Row(entry.task, expectation, first, None, "-", wall, False, "refused")
        assert entry.cause is not None
        # The task's own name ("hole_out_of_reach") must not count as naming the cause.
        named = entry.cause.lower() in first.lower().replace(entry.task.lower(), "")
        note = "" if named else f"first line does not name {entry.cause!r}"
        return Row(entry.task, expectation, first, None, "-", wall, named, note)
    wall = time.perf_counter() - start
    proof = f"{made.successes}/{made.trials}" if made.trials else "nominal"
    why = tuple(
        f"{count:4d} × {outcome} at AL line {line}: {message}"
        for (outcome, line, message), count in made.failures.most_common()
    )
    if entry.expect == "refuse":
        note = f"planned (nominal {made.nominal}); expected a refusal naming {entry.cause!r}"
        return Row(
            entry.task,
            expectation,
            made.decision,
            made.planning_time,
            proof,
            wall,
            False,
            note,
            why,
        )
    rate_ok = made.trials == 0 or made.successes >= MIN_SUCCESS * made.trials
    passed = made.nominal == "success" and rate_ok
    note = "" if passed else f"nominal {made.nominal}" if made.nominal != "success" else "rate"
    return Row(
        entry.task, expectation, made.decision, made.planning_time, proof, wall, passed, note, why
    )


def _clip(text: str, width: int) -> str:
    return text if len(text) <= width else text[: width - 1] + "…"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=500, help="Monte Carlo proof trials")
    parser.add_argument("--workers", type=int, default=2, help="replay worker processes")
    parser.add_argument("--fast", action="store_true", help="only the tasks marked fast")
    parser.add_argument("--only", action="append", metavar="NAME", help="only this task")
    parser.add_argument("--why", action="store_true", help="list failing trials per task")
    parser.add_argument("--check", action="store_true", help="exit 1 unless every task passes")
    parser.add_argument(
        "--no-seed-fixtures",
        action="store_true",
        help="leave out the seed's own fixtures (fixtures/tasks/seed_4_8*.yaml)",
    )
    args = parser.parse_args(argv)

    entries = load_manifest() + ([] if args.no_seed_fixtures else seed_entries())
    if args.fast:
        entries = [e for e in entries if e.fast]
    if args.only:
        unknown = set(args.only) - {e.task for e in entries}
        if unknown:
            parser.error(f"not in the manifest: {', '.join(sorted(unknown))}")
        entries = [e for e in entries if e.task in args.only]

    header = (
        f"{'task':34}{'expect':20}{'decision':58}{'plan [s]':>9}{'proof':>10}{'wall [s]':>9}"
        f"  outcome"
    )
    print(header)
    print("-" * len(header))
    tally: Counter[str] = Counter()
    for entry in entries:
        row = judge(entry, args.trials, args.workers)
        tally[f"{entry.expect} {'PASS' if row.passed else 'FAIL'}"] += 1
        plan_time = "-" if row.plan_time is None else f"{row.plan_time:.2f}"
        verdict = "PASS" if row.passed else f"FAIL ({row.note})" if row.note else "FAIL"
        print(
            f"{row.task:34}{_clip(row.expectation, 19):20}{_clip(row.decision, 57):58}"
            f"{plan_time:>9}{row.proof:>10}{row.wall:9.1f}  {verdict}",
            flush=True,
        )
        if args.why:
            for line in row.why[:5]:
                print(f"{'':34}{_clip(line, 150)}")
    passed = sum(n for k, n in tally.items() if k.endswith("PASS"))
    total = sum(tally.values())
    print("-" * len(header))
    parts = [
        f"plannable {tally['plan PASS']}/{tally['plan PASS'] + tally['plan FAIL']} proven",
        f"impossible {tally['refuse PASS']}/{tally['refuse PASS'] + tally['refuse FAIL']} "
        "refused with their cause",
    ]
    print(f"tally: {passed}/{total} PASS — {'; '.join(parts)}")
    return 1 if args.check and passed != total else 0


if __name__ == "__main__":
    sys.exit(main())
