"""Time the referee: AL parsing, the nominal replay, and Monte Carlo trials on 1 and 2 workers.

Usage: python benchmarks/replay.py [--trials N] [--repeat N]
Prints a table: parse time per kB of AL (the seed's search listing), the nominal replay of the
search and first-cut programs on seed_4_8 (median of ``--repeat`` runs), and Monte Carlo trials
per second on 1 and 2 worker processes (``--trials`` trials each), net of the set-up a run with
as many trials as workers takes (parsing, the arm and meshes, the nominal run, starting workers).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from _timing import per_call_us

from synth.al.parser import parse_program
from synth.replay import build_context, replay, run_nominal

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "al"
SEED = ROOT / "fixtures" / "tasks" / "seed_4_8.yaml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=200, help="Monte Carlo trials per figure")
    parser.add_argument("--repeat", type=int, default=5, help="repetitions of the timed calls")
    args = parser.parse_args()

    rows: list[tuple[str, str, str]] = []
    search = (DATA / "seed_4_8_search.al").read_text(encoding="utf-8")
    kb = len(search.encode("utf-8")) / 1024
    parse_us = per_call_us(lambda: parse_program(search), args.repeat * 20)
    rows.append(("parse (seed_4_8_search.al)", f"{parse_us / kb:,.0f} µs/kB", f"{kb:.2f} kB"))

    for name in ("seed_4_8_search.al", "seed_4_8_first_cut.al"):
        text = (DATA / name).read_text(encoding="utf-8")
        context = build_context(text, SEED, filename=name)
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
            replay(text, SEED, trials=workers, seed=0, workers=workers)
            overhead = time.perf_counter() - start  # parse, build, nominal run, start workers
            start = time.perf_counter()
            report = replay(text, SEED, trials=args.trials, seed=0, workers=workers)
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

    width = max(len(r[0]) for r in rows)
    value = max(len(r[1]) for r in rows)
    print(f"{'operation':<{width}}  {'time':>{value}}  note")
    for label, figure, note in rows:
        print(f"{label:<{width}}  {figure:>{value}}  {note}")


if __name__ == "__main__":
    main()
