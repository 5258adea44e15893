"""Assembly sequences with and without information reuse: expected and replayed times.

Usage: python benchmarks/sequence.py [--trials N] [--tasks a,b]
For each sequence fixture, the pipeline twice: with reuse (each step planned from what the
earlier seats taught, the program correcting the part after each seat) and without (each step
planned with the task's own blocks, no corrections). Prints the planner's expected time, the
replay's mean simulated time over the proof's trials, the proof's rate, and the ratios
without/with. A sequence refused without reuse prints the first line of its refusal.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from synth.exceptions import NoStrategyError
from synth.pipeline import SequenceSynthesis, SynthesisOptions, synthesize
from synth.replay.proof import ProofOptions

ROOT = Path(__file__).resolve().parent.parent
TASKS = ("seed_box_two_pins", "seed_box_four_pins", "plate_two_pins_shim")


def run(task: str, reuse: bool, trials: int) -> tuple[float, float, str, float] | str:
    """(expected [s], replayed mean [s], proof rate, wall [s]) or the refusal's first line."""
    options = SynthesisOptions(proof=ProofOptions(trials=trials, workers=1), reuse=reuse)
    start = time.perf_counter()
    try:
        made = synthesize(ROOT / "fixtures" / "tasks" / f"{task}.yaml", options)
    except NoStrategyError as exc:
        return str(exc).splitlines()[0]
    wall = time.perf_counter() - start
    assert isinstance(made, SequenceSynthesis)
    proof = made.proof
    report = proof.monte_carlo
    replayed = report.time_mean if report.time_mean is not None else proof.nominal.time
    rate = f"{proof.successes}/{proof.trials}" if proof.trials else "nominal"
    return made.sequence.expected_time, replayed, rate, wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30)
    parser.add_argument("--tasks", default=",".join(TASKS))
    args = parser.parse_args()
    header = (
        f"{'task':22}{'reuse':>6}{'expected [s]':>14}{'replayed [s]':>14}{'proof':>9}"
        f"{'wall [s]':>10}{'exp ×':>8}{'rep ×':>8}"
    )
    print(header)
    print("-" * len(header))
    for task in [t for t in args.tasks.split(",") if t]:
        with_reuse = run(task, True, args.trials)
        without = run(task, False, args.trials)
        for label, result in (("yes", with_reuse), ("no", without)):
            if isinstance(result, str):
                print(f"{task:22}{label:>6}  refused: {result[:110]}")
                continue
            expected, replayed, rate, wall = result
            ratios = ""
            if label == "no" and not isinstance(with_reuse, str):
                ratios = f"{expected / with_reuse[0]:8.2f}{replayed / with_reuse[1]:8.2f}"
            print(
                f"{task:22}{label:>6}{expected:14.2f}{replayed:14.2f}{rate:>9}{wall:10.1f}{ratios}",
                flush=True,
            )


if __name__ == "__main__":
    main()
