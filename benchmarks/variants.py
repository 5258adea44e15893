"""Plan and prove random variants of the seed's cell, and replay each proven program afresh.

Usage: python benchmarks/variants.py [--seed S] [--count N] [--proof-trials N]
                                     [--replay-trials N] [--out DIR]
Each variant takes the seed's task on one of its three arms (``fixtures/tasks/seed_4_8.yaml``,
``_ur5``, ``_panda``) and draws, from ``random.Random(seed)``: BH1's diameter (0.4–1.2 cm), the
fit (0.05–1.5 mm of diametral clearance), the chamfer, the depth (d_f = the hole's depth,
0.8–2.0 cm), the pin's length, taper and tip, BH1's place on the box's face, the box's yaw, and
scales of ×0.5–2 on the box's and the hand's error blocks (Δr_ok is set a little wider than the
parts' lead, as a measured one would be). The other corner holes stay, unless within 2 cm of
BH1. The task files are written to ``--out`` (default: a temporary directory), so any row can be
planned again with ``synth plan DIR/NAME.yaml``.

Per variant: the pipeline plans and proves it (``--proof-trials`` at seed 0, one process),
then the proven program is replayed at seed 1 (``--replay-trials``), trials the proof never
saw. Printed: the decision (the chosen strategy, or the refusal's root cause), the planning
and proof time, the proof's successes, the fresh replay's successes and its first failing
trial (index, outcome, message); then a tally. Every program synth writes should pass its
fresh replay at about the proof's rate; a refusal should name a cause a robotics engineer
recognises.
"""

from __future__ import annotations

import argparse
import random
import tempfile
import time
from collections import Counter
from pathlib import Path

import yaml

from synth.exceptions import NoStrategyError, SynthError
from synth.pipeline import SynthesisOptions, synthesize
from synth.replay import replay_program
from synth.replay.proof import ProofOptions
from synth.replay.run import TrialRecord

ROOT = Path(__file__).resolve().parent.parent
FIXTURES = ROOT / "fixtures" / "tasks"
ARMS = {"stanford": "seed_4_8.yaml", "ur5": "seed_4_8_ur5.yaml", "panda": "seed_4_8_panda.yaml"}


def variant(rng: random.Random, index: int) -> tuple[str, dict]:
    """One random variant of the seed's cell: its name and task document."""
    arm = rng.choice(sorted(ARMS))
    spec = yaml.safe_load((FIXTURES / ARMS[arm]).read_text(encoding="utf-8"))
    hole = round(rng.uniform(0.4, 1.2), 3)  # [cm]
    fit = rng.choice([0.005, 0.01, 0.02, 0.05, 0.08, 0.15])
    chamfer = rng.choice([0.0, 0.05, 0.1, 0.25, 0.3])
    depth = round(rng.uniform(0.8, 2.0), 2)
    diameter = round(hole - fit, 3)
    taper = round(min(rng.uniform(0.1, 0.4), 0.4 * diameter), 2)
    tip = round(max(0.05, diameter / 2 - taper * rng.uniform(0.3, 0.9)), 3)
    x, y = round(rng.uniform(-3.2, 3.8), 2), round(rng.uniform(-2.8, 3.2), 2)
    box_scale, hand_scale = rng.choice([0.5, 1.0, 1.5, 2.0]), rng.choice([0.5, 1.0, 2.0])
    yaw = round(rng.uniform(-20, 20), 1)
    frames = {f["name"]: f for f in spec["frames"]}
    frames["box"]["pose"]["rotation"] = [{"z": f"{yaw} deg"}]
    block = frames["box"]["uncertainty"]
    block.update(
        x=f"{0.3 * box_scale:.3f} in", y=f"{0.2 * box_scale:.3f} in", rz=f"{5 * box_scale} deg"
    )
    for name in ("bh1", "rh1"):
        shape = frames[name]["shape"]
        shape.update(diameter=f"{hole} cm", chamfer_width=f"{chamfer} cm", depth=f"{depth} cm")
    frames["bh1"]["pose"]["translation"] = [f"{x} cm", f"{y} cm", "4.90 cm"]
    for name in ("bh2", "bh3", "bh4"):
        hx, hy = (float(v.split()[0]) for v in frames[name]["pose"]["translation"][:2])
        if abs(hx - x) < 2 and abs(hy - y) < 2:
            spec["frames"] = [f for f in spec["frames"] if f["name"] != name]
    frames["pin1"]["pose"]["translation"] = ["0 cm", "0 cm", f"-{depth} cm"]
    frames["pin1"]["shape"] = {
        "type": "pin",
        "length": f"{round(rng.uniform(3.5, 7.0), 2)} cm",
        "diameter": f"{diameter} cm",
        "tip_taper_length": f"{taper} cm",
        "tip_radius": f"{tip} cm",
    }
    insertion = spec["insertion"]
    insertion["d_f"] = f"{depth} cm"
    insertion["dr_ok"] = f"{round(hole / 2 + 0.8 * chamfer + tip / 2, 3)} cm"
    hand = spec["manipulator"]["hand_error"]
    for axis in ("x", "y", "z"):
        hand[axis] = f"{0.05 * hand_scale:.3f} in"
    for axis in ("rx", "ry", "rz"):
        hand[axis] = f"{0.25 * hand_scale:.3f} deg"
    name = f"v{index:02d}_{arm}_D{hole}_c{fit}_ch{chamfer}_box{box_scale}_hand{hand_scale}"
    spec["name"] = name
    return name, spec


def run(path: Path, proof_trials: int, replay_trials: int) -> dict[str, str]:
    """Plan and prove the task at ``path``, then replay its program at seed 1."""
    options = SynthesisOptions(proof=ProofOptions(trials=proof_trials, seed=0, workers=1))
    start = time.perf_counter()
    try:
        synthesis = synthesize(path, options)
    except NoStrategyError as exc:  # the planner's refusal: its root cause
        root = exc.root
        cause = "other" if root is None else root.cause
        why = "" if root is None or root.example is None else root.example.reason[:70]
        return {"decision": f"refused: {cause}", "kind": "refused", "first": why}
    except SynthError as exc:  # a spec the generator got wrong, refused at its field
        return {"decision": f"spec: {str(exc).splitlines()[0][:70]}", "kind": "spec"}
    planned = time.perf_counter() - start
    proof = synthesis.proof
    failures: list[TrialRecord] = []

    def keep(record: TrialRecord) -> None:
        if not failures:
            failures.append(record)

    report = replay_program(
        synthesis.program,
        path,
        trials=replay_trials,
        seed=1,
        on_trial=keep,
        failures_only=True,
    )
    monte_carlo = report.monte_carlo
    fresh = monte_carlo.successes if monte_carlo is not None else 0
    first = (
        f"trial {failures[0].index}: {failures[0].run.outcome}: {failures[0].run.message[:50]}"
        if failures
        else ""
    )
    return {
        "decision": synthesis.strategy.name,
        "kind": "proven" if fresh == replay_trials else "short",
        "time": f"{planned:.1f} s",
        "proof": f"{proof.outcomes.get('success', 0)}/{sum(proof.outcomes.values())}",
        "fresh": f"{fresh}/{replay_trials}",
        "first": first,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=7, help="seed of the variants' draws")
    parser.add_argument("--count", type=int, default=12, help="variants to make")
    parser.add_argument("--proof-trials", type=int, default=100, help="trials of each proof")
    parser.add_argument("--replay-trials", type=int, default=200, help="fresh trials (seed 1)")
    parser.add_argument("--out", type=Path, default=None, help="directory for the task files")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="synth-variants-"))
    out.mkdir(parents=True, exist_ok=True)
    rng = random.Random(args.seed)
    rows = []
    for index in range(args.count):
        name, spec = variant(rng, index)
        path = out / f"{name}.yaml"
        path.write_text(yaml.safe_dump(spec, sort_keys=False), encoding="utf-8")
        row = run(path, args.proof_trials, args.replay_trials)
        rows.append((name, row))
        print(
            f"{name:<44} {row['decision']:<40} {row.get('time', ''):>8} "
            f"{row.get('proof', ''):>8} {row.get('fresh', ''):>8}  {row.get('first', '')}",
            flush=True,
        )
    tally = Counter(row["kind"] for _, row in rows)
    print(
        f"tally: {tally['proven']} proven and passing {args.replay_trials} fresh trials, "
        f"{tally['short']} short of it, {tally['refused']} refused, {tally['spec']} spec errors; "
        f"tasks in {out}"
    )


if __name__ == "__main__":
    main()
