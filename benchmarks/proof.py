"""Time ``synth plan``'s proof: the pipeline on the seed's tasks with proofs of several sizes.

Usage: python benchmarks/proof.py [--trials 0,30,100,200] [--workers 1,2] [--tasks a,b]
Prints, per task and proof size, the wall time of :func:`synth.pipeline.synthesize` (plan,
emit, nominal replay and the Monte Carlo proof), the trials the sequential test consumed, its
decision, and the ratio to the nominal-only pipeline run in the same process. The default proof
(``synth.replay.proof.DEFAULT_PROOF_TRIALS``) was chosen from this table so that ``synth plan``
on seed_4_8 stays interactive on 2 cores.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from synth.pipeline import SynthesisOptions, synthesize
from synth.replay.proof import DEFAULT_PROOF_TRIALS, ProofOptions

ROOT = Path(__file__).resolve().parent.parent
TASKS = ("seed_4_8", "seed_4_8_tap")


def _ints(text: str) -> list[int]:
    return [int(x) for x in text.split(",") if x]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=_ints, default=[0, 30, DEFAULT_PROOF_TRIALS, 200])
    parser.add_argument("--workers", type=_ints, default=[1, 2])
    parser.add_argument(
        "--tasks",
        type=lambda text: [t for t in text.split(",") if t],
        default=list(TASKS),
        help="fixture names, e.g. seed_4_8_ur5,seed_4_8_panda (default: the seed's two)",
    )
    args = parser.parse_args()

    header = (
        f"{'task':16}{'trials':>7}{'workers':>8}{'wall [s]':>10}{'used':>6}{'ok':>5}"
        f"{'decided by':>14}{'× nominal':>11}"
    )
    print(header)
    print("-" * len(header))
    for task in args.tasks:
        path = ROOT / "fixtures" / "tasks" / f"{task}.yaml"
        synthesize(path, SynthesisOptions(proof=ProofOptions(trials=0)))  # warm caches
        baseline: float | None = None
        for trials in args.trials:
            for workers in args.workers if trials else [1]:
                options = SynthesisOptions(proof=ProofOptions(trials=trials, workers=workers))
                start = time.perf_counter()
                made = synthesize(path, options)
                wall = time.perf_counter() - start
                baseline = wall if baseline is None else baseline
                proof = made.proof
                print(
                    f"{task:16}{trials:7d}{workers:8d}{wall:10.2f}{proof.trials:6d}"
                    f"{proof.successes:5d}{proof.decided_by:>14}{wall / baseline:11.1f}",
                    flush=True,
                )


if __name__ == "__main__":
    main()
