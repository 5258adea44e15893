"""Time `synth plan` per fixture: best-first against exhaustive selection (seed §4.6).

Usage: python benchmarks/plan.py [--repeat N] [--tasks seed_4_8,seed_4_8_ur5,seed_4_8_panda]
For every task fixture the planner accepts (and each with --try-harder), prints the median
planning time of both modes, their ratio, whether they chose the same strategy, how many
candidates each refined, and the IK, motion-time, bound and LP calls of each. ``×seed``: the
best-first time over seed_4_8's (the Stanford arm, measured first in the same process), so
the URDF arms' fixtures (seed_4_8_ur5, seed_4_8_panda: the same task) read as a cost ratio.
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path

from synth.exceptions import SynthError
from synth.models.loader import load_task
from synth.pipeline import SynthesisOptions, synthesize
from synth.replay.proof import ProofOptions
from synth.strategies import PlanOptions, PlanResult

ROOT = Path(__file__).resolve().parent.parent


def timed(spec, repeat: int, **kwargs) -> tuple[float, PlanResult]:
    """Median planning time [s] over ``repeat`` runs of the pipeline, and the last plan.

    The pipeline runs with the nominal proof only; the planner's own ``planning_time``
    excludes the proof, so the figure is the planner's.
    """
    options = SynthesisOptions(plan=PlanOptions(**kwargs), proof=ProofOptions(trials=0))
    samples = []
    result = synthesize(spec, options).plan  # warm caches (arm model, solver import)
    for _ in range(repeat):
        result = synthesize(spec, options).plan
        samples.append(result.planning_time)
    return statistics.median(samples), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--tasks", default="", help="fixture names, comma-separated (default: all)")
    args = parser.parse_args()
    chosen = {t for t in args.tasks.split(",") if t}

    baseline, _ = timed(load_task(ROOT / "fixtures/tasks/seed_4_8.yaml"), args.repeat)
    header = (
        f"{'fixture':28}{'cand':>5}{'bf [s]':>8}{'×seed':>7}{'ex [s]':>8}{'ex/bf':>7}{'same':>6}"
        f"{'refined':>9}{'IK bf/ex':>11}{'motion bf/ex':>14}{'bounds bf/ex':>14}{'LP bf/ex':>10}"
        f"{'sweeps bf/ex':>14}"
    )
    print(header)
    print("-" * len(header))
    for path in sorted((ROOT / "fixtures/tasks").glob("*.yaml")):
        if chosen and path.stem not in chosen:
            continue
        spec = load_task(path)
        if spec.insertions is not None:
            print(f"{path.stem:28}an assembly sequence: benchmarks/sequence.py times it")
            continue
        for harder in (False, True):
            label = path.stem + (" --try-harder" if harder else "")
            try:
                bf_time, bf = timed(spec, args.repeat, try_harder=harder)
            except SynthError as exc:  # no insertion, or objects its contacts do not locate
                if not harder:
                    print(f"{path.stem:28}not plannable: {exc}")
                break
            ex_time, ex = timed(spec, args.repeat, try_harder=harder, exhaustive=True)
            same = bf.strategy.name == ex.strategy.name
            pairs = [
                f"{bf.counters[k]}/{ex.counters[k]}"
                for k in ("ik", "motion_time", "bounds", "lp", "sweeps")
            ]
            print(
                f"{label:28}{len(ex.candidates):5d}{bf_time:8.3f}{bf_time / baseline:7.2f}"
                f"{ex_time:8.3f}"
                f"{ex_time / bf_time:7.2f}{'yes' if same else 'NO':>6}"
                f"{f'{bf.refined}/{ex.refined}':>9}"
                f"{pairs[0]:>11}{pairs[1]:>14}{pairs[2]:>14}{pairs[3]:>10}{pairs[4]:>14}"
            )
            assert same, f"{label}: best-first {bf.strategy.name} ≠ exhaustive {ex.strategy.name}"


if __name__ == "__main__":
    main()
