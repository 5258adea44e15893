#!/usr/bin/env python3
"""Scan where an arm can stand in the seed's workcell: reachability and replays.

Reproduces the choice of ``default_base`` in ``fixtures/arms/stanford.yaml`` and of the ``base``
the seed_4_8 task fixtures give the arm, and (``--arm ur5``, ``--arm panda``) of the bases of
``fixtures/tasks/seed_4_8_ur5.yaml`` and ``seed_4_8_panda.yaml``. For every base (x, y on the
table, yaw about z) of the grid it measures, with the arm of ``fixtures/tasks/seed_4_8.yaml``
(or the named built-in arm) moved there:

* reach (joint limits only, the closed-form inverse): ``required`` — every hand-down pose
  (γ = 180°, all eight ω of seed L2096, grasp at d = 3.54 cm, L2595) at the rack (at the grasp
  and lifted 2 in + 1 cm), at BH1 (pin inserted by d_f, 1 in and 2 in above) and BPARK itself
  has an attainable solution; ``tilted`` — how many of the same 40 poses with the seed's
  γ = 135° (L2108) do; ``margin`` — over the required poses, the smallest (worst pose) of the
  best solution's smallest distance of θ1, θ2, S3, θ5 to their limits, as a fraction of each
  range; the span of θ1 over the required poses;
* replay (``synth replay`` in the believed world): the seed's listings
  ``tests/data/al/seed_4_8_search.al`` and ``seed_4_8_first_cut.al`` on seed_4_8 and
  ``seed_4_8_tap.al`` on seed_4_8_tap, then the planner's programs for seed_4_8, seed_4_8_tap
  and seed_4_8_fixture; a base passes when all six end in ``success``. The first failure is
  reported and the rest are skipped.

For a URDF arm the margin is the worst, over the required poses, of the best solution's
dexterity (:func:`synth.models.arm.dexterity`: joint-limit margin and Jacobian conditioning);
the seed's listings are not replayed (they were written for the Stanford arm's motions) and
only seed_4_8 is planned; a base passes when the required poses are reachable, the arm's base
touches no part and the planned program replays. The best passing base (largest margin) is
printed last.

Usage::

    python scripts/scan_arm_base.py                     # x 10..30 cm, y 65..85 cm, yaw 225°
    python scripts/scan_arm_base.py --x 20 --y 70 --yaw 210,225,240
    python scripts/scan_arm_base.py --jobs 2 --json     # one JSON object per base
    python scripts/scan_arm_base.py --arm ur5 --x 25,35,45 --y 70,80,90 --yaw 0 --jobs 2

The default grid takes about 15 s with ``--jobs 2``. The table ends with the bases where both
required criteria hold; the exit status is 1 when there is none. Yaw only offsets θ1, so it
changes a base's figures only where θ1 would reach its ±150° stops.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import yaml

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run from a checkout without installing synth
    sys.path.insert(0, str(ROOT))

from synth.exceptions import SynthError  # noqa: E402
from synth.models.arm import Arm, dexterity, manipulator_arm  # noqa: E402
from synth.models.graph import AttributeGraph, pose_to_se3  # noqa: E402
from synth.models.loader import load_task, validate_task  # noqa: E402
from synth.models.spec import TaskSpec  # noqa: E402
from synth.models.spec_fields import Pose  # noqa: E402
from synth.pipeline import SynthesisOptions, synthesize  # noqa: E402
from synth.replay import replay_program  # noqa: E402
from synth.replay.proof import ProofOptions  # noqa: E402
from synth.units import CM, DEG, INCH  # noqa: E402

TASKS_DIR = ROOT / "fixtures" / "tasks"
NOMINAL_PROOF = SynthesisOptions(proof=ProofOptions(trials=0))
LISTINGS_DIR = ROOT / "tests" / "data" / "al"
LISTINGS: tuple[tuple[str, str], ...] = (
    ("seed_4_8", "seed_4_8_search.al"),
    ("seed_4_8", "seed_4_8_first_cut.al"),
    ("seed_4_8_tap", "seed_4_8_tap.al"),
)
PLANNED: tuple[str, ...] = ("seed_4_8", "seed_4_8_tap", "seed_4_8_fixture")
GRASP_DISTANCE = 3.54 * CM  # L2595
REACH_JOINTS = [0, 1, 2, 4]  # θ1, θ2, S3, θ5


def with_base(
    spec: TaskSpec, x_cm: float, y_cm: float, yaw_deg: float, arm_model: str = "stanford"
) -> TaskSpec:
    """``spec`` with its arm (or built-in ``arm_model``) at (x, y) cm, turned ``yaw`` about z."""
    manipulator = spec.manipulator
    if manipulator is None:
        raise SystemExit(f"task {spec.name!r} has no manipulator section")
    base = {
        "translation": [f"{x_cm} cm", f"{y_cm} cm", "0 cm"],
        "rotation": [{"z": f"{yaw_deg} deg"}],
    }
    if arm_model == "stanford":
        arm = manipulator.arm.model_copy(update={"base": Pose.model_validate(base)})
        return spec.model_copy(update={"manipulator": manipulator.model_copy(update={"arm": arm})})
    # The arm section is replaced whole (a built-in arm has its own hand): from the task file,
    # whose quantities keep their units, not from the spec, whose floats are SI.
    data = yaml.safe_load((TASKS_DIR / f"{spec.name}.yaml").read_text(encoding="utf-8"))
    data["manipulator"]["arm"] = {"model": arm_model, "base": base}
    data["manipulator"].pop("hand", None)
    return validate_task(data)


def workcell_poses(spec: TaskSpec, gamma_deg: float) -> list[pin.SE3]:
    """Hand poses of the seed's task for grasp angle γ: at the rack and BH1, all eight ω."""
    graph = AttributeGraph(spec)
    world_pin, world_hole = graph.world_from("pin1"), graph.world_from("bh1")
    if spec.insertion is None or spec.insertion.d_f is None:
        raise SystemExit(f"task {spec.name!r} gives no insertion depth d_f")
    d_f = spec.insertion.d_f

    def up(z: float) -> pin.SE3:
        return pin.SE3(np.eye(3), np.array([0.0, 0.0, z]))

    poses = []
    for k in range(8):
        rotation = pin.utils.rotate("z", k * 45 * DEG) @ pin.utils.rotate("x", gamma_deg * DEG)
        grasp = pin.SE3(rotation, np.array([0.0, 0.0, GRASP_DISTANCE]))
        poses += [world_pin * grasp, up(2 * INCH + CM) * world_pin * grasp]
        poses += [world_hole * up(z) * grasp for z in (-d_f, INCH, 2 * INCH)]
    return poses


def limit_margin(arm: Arm, q: np.ndarray) -> float:
    """Smallest distance of θ1, θ2, S3, θ5 to their limits, as a fraction of each range.

    For a URDF arm: its dexterity at ``q`` (joint margin and conditioning, in [0, 1]).
    """
    if arm.grasp_joint is None:
        return dexterity(arm, q)
    lower = arm.limits.lower[REACH_JOINTS]
    upper = arm.limits.upper[REACH_JOINTS]
    values = q[REACH_JOINTS]
    return float(np.min(np.minimum(values - lower, upper - values) / (upper - lower)))


def reach(spec: TaskSpec) -> dict[str, Any]:
    """The reachability criteria of ``default_base`` (module docstring) for ``spec``'s arm."""
    manipulator = spec.manipulator
    assert manipulator is not None
    arm = manipulator_arm(manipulator, TASKS_DIR)
    park = pose_to_se3(manipulator.park.pose)
    required = [park, *workcell_poses(spec, 180.0)]
    solutions = [arm.inverse(target) for target in required]
    missing = sum(1 for found in solutions if not found)
    margins = [max(limit_margin(arm, q) for q in found) for found in solutions if found]
    theta1 = [math.degrees(found[0][0]) for found in solutions if found]
    tilted = workcell_poses(spec, 135.0)
    return {
        "required": missing == 0,
        "required_missing": missing,
        "tilted": sum(1 for target in tilted if arm.inverse(target)),
        "tilted_of": len(tilted),
        "margin": round(min(margins), 4) if margins else None,
        "theta1_deg": [round(min(theta1), 1), round(max(theta1), 1)] if theta1 else None,
    }


def replays(x: float, y: float, yaw: float, arm_model: str = "stanford") -> dict[str, Any]:
    """The six nominal replays at base (x, y, yaw): the first failure, the planned strategies."""
    out: dict[str, Any] = {"failure": None, "planned": {}}
    stanford = arm_model == "stanford"
    try:
        for task, listing in LISTINGS if stanford else ():
            spec = with_base(load_task(TASKS_DIR / f"{task}.yaml"), x, y, yaw)
            text = (LISTINGS_DIR / listing).read_text(encoding="utf-8")
            run = replay_program(text, spec, filename=listing, base_dir=TASKS_DIR).nominal
            if run.outcome != "success":
                out["failure"] = f"{listing}: {run.outcome} at line {run.line}: {run.message}"
                return out
        for task in PLANNED if stanford else PLANNED[:1]:
            spec = with_base(load_task(TASKS_DIR / f"{task}.yaml"), x, y, yaw, arm_model)
            # The pipeline writes only a program whose nominal replay succeeds (else it raises).
            synthesis = synthesize(spec, NOMINAL_PROOF, base_dir=TASKS_DIR)
            strategy = synthesis.strategy
            out["planned"][task] = f"{strategy.name}, {strategy.expected_time:.2f} s"
    except SynthError as exc:  # the first line: a refusal's root cause
        out["failure"] = f"{type(exc).__name__}: {str(exc).splitlines()[0]}"
    return out


def judge(base: tuple[float, float, float, str]) -> dict[str, Any]:
    """Reach and replay figures of one base."""
    x, y, yaw, arm_model = base
    spec = with_base(load_task(TASKS_DIR / "seed_4_8.yaml"), x, y, yaw, arm_model)
    try:
        reached = reach(spec)
    except SynthError as exc:  # the base stands in a part, or the park has no clear solution
        reached = {"required": False, "required_missing": None, "tilted": 0, "tilted_of": 40}
        reached |= {"margin": None, "theta1_deg": None, "failure": f"{type(exc).__name__}: {exc}"}
        return {"base": [x, y, yaw], **reached, "planned": {}, "passes": False}
    result: dict[str, Any] = {
        "base": [x, y, yaw],
        **reached,
        **replays(x, y, yaw, arm_model),
    }
    result["passes"] = bool(result["required"]) and result["failure"] is None
    return result


def numbers(text: str) -> list[float]:
    """``10,15,20`` → [10.0, 15.0, 20.0]."""
    return [float(v) for v in text.split(",") if v.strip()]


def label(value: float) -> str:
    """20.0 → ``20``."""
    return f"{value:g}"


def main(argv: list[str] | None = None) -> int:
    """Scan the grid and print one row (or JSON object) per base; 0 when any base passes."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--x", type=numbers, default=numbers("10,15,20,25,30"), help="cm, a,b,…")
    parser.add_argument("--y", type=numbers, default=numbers("65,70,75,80,85"), help="cm, a,b,…")
    parser.add_argument("--yaw", type=numbers, default=[225.0], help="deg about z, a,b,…")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes")
    parser.add_argument("--json", action="store_true", help="one JSON object per base")
    parser.add_argument("--arm", default="stanford", help="stanford or a built-in URDF arm")
    args = parser.parse_args(argv)
    grid = [(x, y, yaw, args.arm) for x in args.x for y in args.y for yaw in args.yaw]
    if args.jobs > 1:
        with get_context("spawn").Pool(args.jobs) as pool:
            results = pool.map(judge, grid)
    else:
        results = [judge(base) for base in grid]
    for r in results:
        if args.json:
            print(json.dumps(r, ensure_ascii=False))
            continue
        x, y, yaw = (label(v) for v in r["base"])
        theta1 = r["theta1_deg"] or ["-", "-"]
        print(
            f"({x}, {y}) cm {yaw}°: required {'yes' if r['required'] else 'NO'}, "
            f"tilted {r['tilted']}/{r['tilted_of']}, margin {r['margin']}, "
            f"θ1 {theta1[0]}…{theta1[1]}°"
        )
        for task, strategy in r["planned"].items():
            print(f"    planned {task}: {strategy}")
        done = "all six replays succeed" if args.arm == "stanford" else "the plan replays"
        print(f"    {done if r['failure'] is None else r['failure']}")
    passing = [r for r in results if r["passes"]]
    if not args.json:
        where = (
            f"({label(x)}, {label(y)}) cm {label(yaw)}°"
            for x, y, yaw in (r["base"] for r in passing)
        )
        print("passing:", ", ".join(where) or "none")
        if passing:
            best = max(passing, key=lambda r: (r["margin"], -r["base"][0], -r["base"][1]))
            x, y, yaw = (label(v) for v in best["base"])
            print(f"best: ({x}, {y}) cm {yaw}°, margin {best['margin']}")
    return 0 if passing else 1


if __name__ == "__main__":
    sys.exit(main())
