"""Time the referee: AL parsing, the nominal replay, Monte Carlo trials, fast against reference.

Usage: python benchmarks/replay.py [--trials N] [--repeat N] [--fast-trials N]
                                   [--reference-trials N] [--only-ratio] [--baseline DIR]
Prints a table: parse time per kB of AL (the seed's search listing), the nominal replay of the
search and first-cut programs on seed_4_8 (median of ``--repeat`` runs), and Monte Carlo trials
per second on 1 and 2 worker processes (``--trials`` trials each), net of the set-up a run with
as many trials as workers takes (parsing, the arm and meshes, the nominal run, starting workers).

**Fast against reference.** For the seed's search listing and synth's own program
(fixtures/golden/seed_4_8.al), trials 0, 1, … of seed 0 run in this process on the fast path
(``--fast-trials``) and on the reference path, ``ReplayOptions(reference=True)``: every pair and
target measured at every step of a global-Lipschitz advancement, scenes rebuilt
(``--reference-trials``, the first of the same trials; the reference path is today's main's,
unchanged). Printed per path: trials/s (wall and CPU: the machine may be shared), µs per motion
(per MOVE), µs per contact query and the queries per trial (Coal's distance queries, each pair
of a scene-wide query counted: :class:`Counts`, in a separate, untimed pass), and the ratio of
the two rates; the outcomes of the shared trials are checked to agree.

**Against a checkout.** ``--baseline DIR`` (a checkout of today's main, say ``git worktree add
/tmp/main main``) times the same trials of its default path in a subprocess with
``PYTHONPATH=DIR``, alternating with this tree's, and prints both rates and their ratio.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import coal
import pinocchio as pin
from _timing import per_call_us

import synth.replay.machine as machine
from synth.al.parser import parse_program
from synth.replay import ReplayOptions, replay_context, replay_program, run_nominal, run_trial

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "al"
SEED = ROOT / "fixtures" / "tasks" / "seed_4_8.yaml"
PROGRAMS = {
    "seed_4_8_search.al": DATA / "seed_4_8_search.al",
    "golden/seed_4_8.al": ROOT / "fixtures" / "golden" / "seed_4_8.al",
}


class Counts:
    """Motions and Coal distance queries, counted by wrapping the functions that make them.

    ``pinocchio.computeDistance`` counts one, ``pinocchio.computeDistances`` one per pair of
    the geometry model, ``coal.distance`` one: every distance query of either path goes
    through one of them.
    """

    def __init__(self) -> None:
        self.motions = 0
        self.queries = 0
        self._saved: list[tuple[object, str, object]] = []

    def _wrap(self, owner: object, name: str, cost: Callable[..., int]) -> None:
        original = getattr(owner, name)
        self._saved.append((owner, name, original))

        def counted(*args: object, **kwargs: object) -> object:
            self.queries += cost(*args, **kwargs)
            return original(*args, **kwargs)

        setattr(owner, name, counted)

    def __enter__(self) -> Counts:
        self._wrap(pin, "computeDistance", lambda *a, **k: 1)
        self._wrap(
            pin,
            "computeDistances",
            lambda *a, **k: len(a[2].collisionPairs) if len(a) > 2 else 1,
        )
        self._wrap(coal, "distance", lambda *a, **k: 1)
        original_move = machine.ReplayMachine.move
        self._saved.append((machine.ReplayMachine, "move", original_move))

        def move(*args: object, **kwargs: object) -> object:
            self.motions += 1
            return original_move(*args, **kwargs)  # type: ignore[arg-type]

        machine.ReplayMachine.move = move  # type: ignore[method-assign]
        return self

    def __exit__(self, *exc: object) -> None:
        for owner, name, original in reversed(self._saved):
            setattr(owner, name, original)


def timed_trials(text: str, reference: bool, n: int) -> tuple[float, float, list[tuple]]:
    """Wall and CPU seconds of trials 0 … n−1 of seed 0, and their outcomes."""
    context = replay_context(text, SEED, options=ReplayOptions(reference=reference))
    run_trial(context, 0, 0)  # warm: meshes, hulls, caches
    wall, cpu = time.perf_counter(), time.process_time()
    runs = [run_trial(context, 0, i) for i in range(n)]
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    return wall, cpu, [(r.outcome, r.line, r.message) for r in runs]


def compare_paths(
    name: str, text: str, fast_n: int, reference_n: int
) -> list[tuple[str, str, str]]:
    """Rows of fast against reference on ``text``: trials/s, µs per motion and per query."""
    rows = []
    rates = {}
    outcomes = {}
    for label, reference, n in (("fast", False, fast_n), ("reference", True, reference_n)):
        context = replay_context(text, SEED, options=ReplayOptions(reference=reference))
        run_trial(context, 0, 0)
        with Counts() as counts:
            for i in range(min(n, 3)):
                run_trial(context, 0, i)
        per_trial = (counts.motions / min(n, 3), counts.queries / min(n, 3))
        wall, cpu, outcomes[label] = timed_trials(text, reference, n)
        rates[label] = (n / wall, n / cpu)
        trial_us = 1e6 * wall / n
        rows.append(
            (
                f"{label} path ({name}, 1 process)",
                f"{rates[label][0]:,.2f} trials/s",
                f"{n} trials ({rates[label][1]:,.2f}/s of CPU); {trial_us / per_trial[0]:,.0f} µs "
                f"per motion, {trial_us / per_trial[1]:,.1f} µs per contact query, "
                f"{per_trial[1]:,.0f} queries per trial",
            )
        )
    shared = min(fast_n, reference_n)
    agree = [a[0] for a in outcomes["fast"][:shared]] == [
        b[0] for b in outcomes["reference"][:shared]
    ]
    rows.append(
        (
            f"fast / reference ({name})",
            f"{rates['fast'][0] / rates['reference'][0]:,.2f}×",
            f"CPU {rates['fast'][1] / rates['reference'][1]:,.2f}×; outcomes of the {shared} "
            f"shared trials {'agree' if agree else 'DIFFER'}",
        )
    )
    return rows


_CHILD = """
import sys, time
from pathlib import Path
import synth
assert Path(synth.__file__).resolve().parent.parent == Path.cwd().resolve(), synth.__file__
import synth.replay as replay
from synth.replay import run_trial
# today's main calls it build_context; this tree, replay_context
make = getattr(replay, "replay_context", None) or getattr(replay, "build_context")
text = Path(sys.argv[1]).read_text(encoding="utf-8")
context = make(text, sys.argv[2])
run_trial(context, 0, 0)
n = int(sys.argv[3])
wall, cpu = time.perf_counter(), time.process_time()
for i in range(n):
    run_trial(context, 0, i)
print(time.perf_counter() - wall, time.process_time() - cpu)
"""


def _child_rate(path: Path, n: int, tree: Path) -> tuple[float, float]:
    """Trials/s (wall, CPU) of ``tree``'s default path in a subprocess."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, str(path), str(SEED), str(n)],
        env=env,
        cwd=tree,  # `python -c` puts the working directory first on sys.path
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    return n / float(out[0]), n / float(out[1])


def against_baseline(baseline: Path, n: int, rounds: int = 2) -> list[tuple[str, str, str]]:
    """Rows of this tree's default path against ``baseline``'s, alternating subprocesses."""
    rows = []
    for name, path in PROGRAMS.items():
        ours, theirs = [], []
        for _ in range(rounds):
            theirs.append(_child_rate(path, n, baseline))
            ours.append(_child_rate(path, n, ROOT))
        mine = (sum(r[0] for r in ours) / rounds, sum(r[1] for r in ours) / rounds)
        base = (sum(r[0] for r in theirs) / rounds, sum(r[1] for r in theirs) / rounds)
        rows.append(
            (
                f"this tree / {baseline.name} ({name})",
                f"{mine[0] / base[0]:,.2f}×",
                f"{mine[0]:,.2f} against {base[0]:,.2f} trials/s wall, {mine[1]:,.2f} against "
                f"{base[1]:,.2f} of CPU ({mine[1] / base[1]:,.2f}×); {n} trials, {rounds} rounds "
                f"alternated",
            )
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=200, help="Monte Carlo trials per figure")
    parser.add_argument("--repeat", type=int, default=5, help="repetitions of the timed calls")
    parser.add_argument("--fast-trials", type=int, default=40, help="trials on the fast path")
    parser.add_argument(
        "--reference-trials", type=int, default=10, help="trials on the reference path"
    )
    parser.add_argument(
        "--only-ratio", action="store_true", help="print the fast/reference rows only"
    )
    parser.add_argument(
        "--baseline", type=Path, default=None, help="a checkout to time this tree against"
    )
    args = parser.parse_args()

    rows: list[tuple[str, str, str]] = []
    for name, path in PROGRAMS.items():
        text = path.read_text(encoding="utf-8")
        rows += compare_paths(name, text, args.fast_trials, args.reference_trials)
    if args.baseline is not None:
        rows += against_baseline(args.baseline.resolve(), args.fast_trials)
    if args.only_ratio:
        print_rows(rows)
        return
    search = (DATA / "seed_4_8_search.al").read_text(encoding="utf-8")
    kb = len(search.encode("utf-8")) / 1024
    parse_us = per_call_us(lambda: parse_program(search), args.repeat * 20)
    rows.append(("parse (seed_4_8_search.al)", f"{parse_us / kb:,.0f} µs/kB", f"{kb:.2f} kB"))

    for name in ("seed_4_8_search.al", "seed_4_8_first_cut.al"):
        text = (DATA / name).read_text(encoding="utf-8")
        context = replay_context(text, SEED, filename=name)
        outcome = run_nominal(context)
        us = per_call_us(lambda context=context: run_nominal(context), args.repeat)
        rows.append(
            (
                f"nominal replay ({name})",
                f"{us / 1000:,.0f} ms",
                f"{outcome.outcome}, {outcome.time:.2f} s simulated",
            )
        )

    for name in ("seed_4_8_search.al", "seed_4_8_first_cut.al"):
        text = (DATA / name).read_text(encoding="utf-8")
        for workers in (1, 2):
            start = time.perf_counter()
            replay_program(text, SEED, trials=workers, seed=0, workers=workers)
            overhead = time.perf_counter() - start  # parse, build, nominal run, start workers
            start = time.perf_counter()
            report = replay_program(text, SEED, trials=args.trials, seed=0, workers=workers)
            wall = time.perf_counter() - start
            steady = (args.trials - workers) / max(wall - overhead, 1e-9)
            rate = report.monte_carlo.success_rate or 0.0
            rows.append(
                (
                    f"Monte Carlo ({name}, {workers} worker{'s' if workers > 1 else ''})",
                    f"{steady:,.1f} trials/s",
                    f"{args.trials} trials in {wall:.1f} s incl. {overhead:.1f} s set-up, "
                    f"success {100 * rate:.1f}%",
                )
            )

    print_rows(rows)


def print_rows(rows: list[tuple[str, str, str]]) -> None:
    """The table: operation, figure, note."""
    width = max(len(r[0]) for r in rows)
    value = max(len(r[1]) for r in rows)
    print(f"{'operation':<{width}}  {'time':>{value}}  note")
    for label, figure, note in rows:
        print(f"{label:<{width}}  {figure:>{value}}  {note}")


if __name__ == "__main__":
    main()
