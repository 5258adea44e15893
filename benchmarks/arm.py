"""Time the arm layer: kinematics, closed-form and DLS inverse, collisions, swept check, timing.

Usage: python benchmarks/arm.py [--repeat N]
Prints microseconds per call (median) for the Stanford arm and the built-in UR5 (closed form by
``ur_analytic_ik``) and Panda (7 joints, DLS, its own fingers) from the ``robots`` extra; ratio
columns compare each operation with one forward-kinematics call on the same arm, and the DLS
inverse with the closed form. ``arm.inverse`` with a hint is the call the planner and the
replay make for every target (the hint's own descent first, :mod:`synth.models.arm.ik`).
The scene is the seed's workcell: a table slab and the seed's box; the swept check carries the
hand 25 cm past a 1 mm plate (blocked) and, with the plate moved away, through free space.
"""

from __future__ import annotations

import argparse
import math

import coal
import numpy as np
import pinocchio as pin
from _timing import per_call_us

from synth.models.arm import (
    Arm,
    CollisionScene,
    IKOptions,
    build_ik,
    build_stanford_arm,
    example_robot_data_dir,
    load_arm,
    motion_time,
    solve_ik,
    swept_segment,
)
from synth.models.manipulator import ArmSpec, HandSpec


def environment(plate_x: float) -> list[tuple[str, coal.CollisionGeometry, pin.SE3]]:
    return [
        ("table", coal.Box(2.0, 2.0, 0.05), pin.SE3(np.eye(3), np.array([0.4, 0.9, -0.025]))),
        (
            "BOX",
            coal.Box(0.0898, 0.076, 0.049),
            pin.SE3(np.eye(3), np.array([0.452, 1.02, 0.0245])),
        ),
        ("plate", coal.Box(0.001, 0.3, 0.12), pin.SE3(np.eye(3), np.array([plate_x, 1.0, 0.06]))),
    ]


def hand_down(
    arm: Arm, scene: CollisionScene, xyz: tuple[float, float, float], near: np.ndarray
) -> np.ndarray:
    """A collision-free solution for the hand pointing down at ``xyz``, nearest to ``near``."""
    rotation = pin.utils.rotate("y", math.pi) @ pin.utils.rotate("z", math.pi / 2)
    solutions = arm.inverse(pin.SE3(rotation, np.array(xyz)), hint=near)
    free = [s for s in solutions if not scene.in_collision(s)]
    return min(free, key=lambda s: float(np.max(np.abs(s - near))))


def bench_arm(name: str, arm: Arm, home: np.ndarray, repeat: int) -> list[tuple[str, float, str]]:
    rng = np.random.default_rng(0)
    blocked = CollisionScene(arm, environment(0.50))
    free = CollisionScene(arm, environment(0.80))
    q0 = hand_down(arm, free, (0.40, 1.0, 0.08), home)
    q1 = hand_down(arm, free, (0.65, 1.0, 0.08), q0)
    target = arm.forward(q1)
    rows: list[tuple[str, float, str]] = []
    fk = per_call_us(lambda: arm.forward(q1), repeat)
    rows.append((f"{name}: forward kinematics", fk, "1.0"))
    if arm.closed_form is not None:
        cf = per_call_us(lambda: arm.inverse(target), repeat)
        rows.append((f"{name}: closed-form IK (all solutions)", cf, f"{cf / fk:.1f}"))
    else:
        cf = math.nan
    near = per_call_us(lambda: arm.inverse(target, hint=q1 + 0.05), repeat)
    rows.append((f"{name}: arm.inverse with a hint (planner, replay)", near, f"{near / fk:.1f}"))
    hinted = build_ik(arm, target, IKOptions(starts=1), hint=q1 + 0.05)
    dls1 = per_call_us(lambda: solve_ik(hinted, rng), repeat)
    rows.append((f"{name}: DLS IK, 1 start near the answer", dls1, f"{dls1 / fk:.1f}"))
    multi = build_ik(arm, target, IKOptions(starts=24))
    dls = per_call_us(lambda: solve_ik(multi, np.random.default_rng(1)), max(repeat // 20, 5))
    ratio = f"{dls / fk:.0f}" + (f" ({dls / cf:.0f}× CF)" if not math.isnan(cf) else "")
    rows.append((f"{name}: DLS IK, 24 starts (all found)", dls, ratio))
    coll = per_call_us(lambda: blocked.in_collision(q1), repeat)
    rows.append((f"{name}: collision query ({len(blocked.pairs)} pairs)", coll, f"{coll / fk:.1f}"))
    dist = per_call_us(lambda: blocked.distances(q1), repeat)
    rows.append((f"{name}: distances, all pairs", dist, f"{dist / fk:.1f}"))
    hit = swept_segment(blocked, q0, q1)
    sw_hit = per_call_us(lambda: swept_segment(blocked, q0, q1), max(repeat // 10, 5))
    rows.append(
        (f"{name}: swept check, hits plate ({hit.checks} checks)", sw_hit, f"{sw_hit / fk:.0f}")
    )
    ok = swept_segment(free, q0, q1)
    sw_free = per_call_us(lambda: swept_segment(free, q0, q1), max(repeat // 10, 5))
    rows.append((f"{name}: swept check, free ({ok.checks} checks)", sw_free, f"{sw_free / fk:.0f}"))
    assert not hit.free and ok.free
    via = q0 + 0.5 * (q1 - q0) + 0.05
    mq = per_call_us(lambda: motion_time(arm.limits, [q0, via, q1]), repeat)
    rows.append((f"{name}: motion time, quintic (the replay's), 1 via", mq, f"{mq / fk:.1f}"))
    mt = per_call_us(lambda: motion_time(arm.limits, [q0, q1], rule="ruckig"), repeat)
    rows.append((f"{name}: motion time, ruckig, 2 points", mt, f"{mt / fk:.1f}"))
    mtv = per_call_us(
        lambda: motion_time(arm.limits, [q0, via, q1], rule="ruckig"), max(repeat // 10, 5)
    )
    rows.append((f"{name}: motion time, ruckig, 1 via", mtv, f"{mtv / fk:.1f}"))
    seed = per_call_us(lambda: motion_time(arm.limits, [q0, via, q1], rule="seed"), repeat)
    rows.append((f"{name}: motion time, seed rule, 1 via", seed, f"{seed / fk:.1f}"))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=400)
    args = parser.parse_args()
    stanford_home = np.array([0.0, -1.6, 0.5, 0.0, 1.5, 0.0])
    rows = bench_arm("stanford", build_stanford_arm(HandSpec()), stanford_home, args.repeat)
    if example_robot_data_dir() is None:
        raise SystemExit("example-robot-data is not installed: pip install -e '.[robots]'")
    base = {"translation": ["20 cm", "80 cm", "0 cm"]}
    ur5_home = np.array([0.8, -1.2, 1.8, -2.2, -1.57, 0.0])  # elbow up, hand down
    rows += bench_arm("ur5", load_arm(ArmSpec(model="ur5", base=base)), ur5_home, args.repeat)
    panda_home = np.array([0.9, 0.3, 0.0, -2.0, 0.0, 2.3, 0.785])  # hand down, forward
    panda = load_arm(ArmSpec(model="panda", base=base))
    rows += bench_arm("panda", panda, panda_home, args.repeat)
    print(f"{'operation':48}{'µs/call':>12}{'× FK':>16}")
    for label, us, ratio in rows:
        print(f"{label:48}{us:12.1f}{ratio:>16}")


if __name__ == "__main__":
    main()
