"""The Stanford arm: Pinocchio model vs the seed's forward equations, closed-form inverse round
trips, the parameter file's sources, and the base placement for the seed's workcell."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_TASK

from synth.exceptions import ArmModelError, SpecError
from synth.models.arm import (
    build_stanford_arm,
    load_arm,
    load_stanford_parameters,
    stanford_inverse,
    stanford_inverse_all,
    task_arm,
)
from synth.models.arm.stanford import STANFORD_PARAMETERS_PATH, THETA5, build_stanford_model
from synth.models.loader import load_task
from synth.models.manipulator import ArmSpec, HandSpec
from synth.units import CM, DEG, INCH

P = load_stanford_parameters()


def seed_forward(q: np.ndarray) -> np.ndarray:
    """Seed eqs. (2)–(13), L867–891, transcribed term by term: the 3×4 hand transform."""
    t1, t2, s3, t4, t5, t6 = q
    S1, S2, S6 = P.s1, P.s2, P.s6
    s, c = math.sin, math.cos
    s1, c1, s2, c2 = s(t1), c(t1), s(t2), c(t2)
    s4, c4, s5, c5, s6, c6 = s(t4), c(t4), s(t5), c(t5), s(t6), c(t6)
    T = np.zeros((3, 4))
    T[0, 0] = s1 * (-s4 * s6 + c4 * c5 * c6) + c1 * (
        -s2 * s5 * c6 + c2 * s4 * c5 * c6 + c2 * c4 * s6
    )  # (2)
    T[0, 1] = -s1 * (s4 * c6 + c4 * c5 * s6) + c1 * (
        s2 * s5 * s6 - c2 * s4 * c5 * s6 + c2 * c4 * c6
    )  # (3)
    T[0, 2] = s1 * c4 * s5 + c1 * (s2 * c5 + c2 * s4 * s5)  # (4)
    T[0, 3] = s1 * (c4 * s5 * S6 - S2) + c1 * (s2 * c5 * S6 + s2 * s3 + c2 * s4 * s5 * S6)  # (5)
    T[1, 0] = s1 * (-s2 * s5 * c6 + c2 * s4 * c5 * c6 + c2 * c4 * s6) + c1 * (
        s4 * s6 - c4 * c5 * c6
    )  # (6)
    T[1, 1] = s1 * (s2 * s5 * s6 - c2 * s4 * c5 * s6 + c2 * c4 * c6) + c1 * (
        s4 * c6 + c4 * c5 * s6
    )  # (7)
    T[1, 2] = s1 * (s2 * c5 + c2 * s4 * s5) - c1 * c4 * s5  # (8)
    T[1, 3] = s1 * (s2 * c5 * S6 + s2 * s3 + c2 * s4 * s5 * S6) + c1 * (-c4 * s5 * S6 + S2)  # (9)
    T[2, 0] = -(s2 * s4 * c5 * c6 + s2 * c4 * s6 + c2 * s5 * c6)  # (10)
    T[2, 1] = s2 * s4 * c5 * s6 - s2 * c4 * c6 + c2 * s5 * s6  # (11)
    T[2, 2] = -s2 * s4 * s5 + c2 * c5  # (12)
    T[2, 3] = -s2 * s4 * s5 * S6 + c2 * c5 * S6 + c2 * s3 + S1  # (13)
    return T


def pose_error(a: pin.SE3, b: pin.SE3) -> tuple[float, float]:
    """Position [m] and rotation [rad] distance between two poses."""
    return float(np.linalg.norm(a.translation - b.translation)), float(
        np.linalg.norm(pin.log3(a.rotation.T @ b.rotation))
    )


@pytest.fixture(scope="module")
def base_arm():
    """The arm at the base frame (identity placement), for the seed's base-frame equations."""
    return build_stanford_arm(HandSpec(), pin.SE3.Identity())


def test_pinocchio_model_reproduces_seed_forward_equations():
    model = build_stanford_model(P)
    data = model.createData()
    hand = model.getFrameId("hand")
    rng = np.random.default_rng(1)
    for _ in range(500):
        # Beyond the limits too: the equations hold for any joint values.
        q = rng.uniform(
            [-np.pi, -np.pi, -1.0, -np.pi, -np.pi, -np.pi], [np.pi, np.pi, 1.0, np.pi, np.pi, np.pi]
        )
        pin.framesForwardKinematics(model, data, q)
        assert np.allclose(data.oMf[hand].homogeneous[:3], seed_forward(q), atol=1e-14)


def test_partial_transforms_match_seed_L995():
    # Frame 3 (end of the boom) in the base frame, seed L995: columns (s1, −c1, 0), (c1c2, s1c2,
    # −s2), (c1s2, s1s2, c2) and origin (−s1·S2 + c1·s2·S3, s1·s2·S3 + c1·S2, c2·S3 + S1).
    model = build_stanford_model(P)
    data = model.createData()
    q = np.array([0.7, -1.1, 0.45, 0.3, -0.2, 1.0])
    pin.forwardKinematics(model, data, q)
    t1, t2, s3 = q[:3]
    s1, c1, s2, c2 = math.sin(t1), math.cos(t1), math.sin(t2), math.cos(t2)
    expected_rotation = np.array([[s1, c1 * c2, c1 * s2], [-c1, s1 * c2, s1 * s2], [0, -s2, c2]])
    expected_origin = [-s1 * P.s2 + c1 * s2 * s3, s1 * s2 * s3 + c1 * P.s2, c2 * s3 + P.s1]
    frame3 = data.oMi[4]  # joint 4 sits at the end of the boom with the seed's frame-3 axes
    assert np.allclose(
        frame3.rotation @ pin.utils.rotate("z", q[3]).T, expected_rotation, atol=1e-14
    )
    assert np.allclose(frame3.translation, expected_origin, atol=1e-14)


def test_closed_form_round_trip_thousands_of_poses(base_arm):
    rng = np.random.default_rng(2)
    lim = P.limits
    worst_p = worst_r = 0.0
    counts = {0: 0, 1: 0, 2: 0}
    for _ in range(3000):
        q = rng.uniform(lim.lower, lim.upper)
        target = base_arm.forward(q)
        solutions = base_arm.inverse(target)
        counts[len(solutions)] += 1
        # The sampled configuration is one of the returned solutions.
        assert min(float(np.max(np.abs(s - q))) for s in solutions) < 1e-9
        for s in solutions:
            assert lim.contains(s)
            ep, er = pose_error(base_arm.forward(s), target)
            worst_p, worst_r = max(worst_p, ep), max(worst_r, er)
    assert worst_p < 1e-9 and worst_r < 1e-9
    # "Due to physical stop limits only two of these eight can ever be attained" (L895).
    assert counts[0] == 0 and counts[2] > 0


def test_eight_algebraic_solutions_two_attainable(base_arm):
    # Seed L893–895: at least eight joint sets satisfy (2)–(13); only two can be attained.
    q = np.array([0.4, -1.3, 0.5, -0.5, 0.6, -0.3])  # flip θ4 + 180° = 2.64 rad is inside ±165°
    target = base_arm.forward(q)
    algebraic = stanford_inverse_all(P, target.rotation, target.translation)
    assert len(algebraic) == 8
    for cand in algebraic:
        assert np.allclose(seed_forward(np.array(cand)), target.homogeneous[:3], atol=1e-12)
    attainable = stanford_inverse(P, target.rotation, target.translation)
    assert len(attainable) == 2
    # The two are the wrist flip {θ4 + 180°, −θ5, θ6 + 180°} of each other (L961).
    a, b = attainable
    assert np.allclose(a[:3], b[:3])
    assert math.isclose(a[4], -b[4], abs_tol=1e-12)
    assert math.isclose(
        math.remainder(a[3] - b[3], 2 * math.pi), math.pi, abs_tol=1e-9
    ) or math.isclose(math.remainder(a[3] - b[3], 2 * math.pi), -math.pi, abs_tol=1e-9)


def test_atan2_forms_equal_seed_half_angle_and_wrist_formulas(base_arm):
    # θ1 by the seed's tangent-half-angle form (17) with the "−" root, θ4 by (28), θ6 by (32):
    # evaluated literally here, compared with the implementation's atan2/residual forms.
    rng = np.random.default_rng(3)
    lim = P.limits
    for _ in range(200):
        q = rng.uniform(lim.lower, lim.upper)
        T = base_arm.forward(q).homogeneous
        a = T[:3, 2]
        tx, ty, tz = T[:3, 3] - P.s6 * a  # (14)–(16)
        if abs(P.s2 + ty) < 1e-3:
            continue
        tan_half = (-tx - math.sqrt(tx * tx + ty * ty - P.s2**2)) / (P.s2 + ty)  # (17)
        s1, c1 = 2 * tan_half / (1 + tan_half**2), (1 - tan_half**2) / (1 + tan_half**2)  # (19)
        s2 = -math.sqrt(tx * tx + ty * ty - P.s2**2)  # (20) × S3
        c2 = tz - P.s1
        th2 = math.atan2(s2, c2)
        s2, c2 = math.sin(th2), math.cos(th2)
        T11, T21, T31 = T[0, 0], T[1, 0], T[2, 0]
        T12, T22, T32 = T[0, 1], T[1, 1], T[2, 1]
        T13, T23, T33 = T[0, 2], T[1, 2], T[2, 2]
        s5 = math.hypot((T13 * c1 + T23 * s1) * c2 - T33 * s2, T13 * s1 - T23 * c1)  # (26), + root
        th4 = math.atan2(
            ((T13 * c1 + T23 * s1) * c2 - T33 * s2) / s5, (T13 * s1 - T23 * c1) / s5
        )  # (28)
        th6 = math.atan2(
            ((T12 * c1 + T22 * s1) * s2 + T32 * c2) / s5,
            -((T11 * c1 + T21 * s1) * s2 + T31 * c2) / s5,
        )  # (32)
        solutions = stanford_inverse_all(P, T[:3, :3], T[:3, 3])
        mine = next(s for s in solutions if s[2] > 0 and s[1] < 0 and s[4] > 0)
        assert math.isclose(
            math.remainder(mine[0] - math.atan2(s1, c1), 2 * math.pi), 0, abs_tol=1e-9
        )
        assert math.isclose(math.remainder(mine[3] - th4, 2 * math.pi), 0, abs_tol=1e-9)
        assert math.isclose(math.remainder(mine[5] - th6, 2 * math.pi), 0, abs_tol=1e-9)


def test_degenerate_wrist_keeps_theta4_and_reaches_pose(base_arm):
    # θ5 = 0: joints 4 and 6 are collinear and only θ4 + θ6 matters (L963, eq. 27).
    q = np.array([0.3, -1.4, 0.6, 0.5, 0.0, 0.25])
    target = base_arm.forward(q)
    solutions = base_arm.inverse(target)
    assert len(solutions) >= 1
    for s in solutions:
        ep, er = pose_error(base_arm.forward(s), target)
        assert ep < 1e-9 and er < 1e-9
    assert any(math.isclose(s[3] + s[5], q[3] + q[5], abs_tol=1e-9) for s in solutions)


def test_out_of_reach_returns_no_solution(base_arm):
    # The wrist centre can be at most √(S2² + S3max²) from the shoulder point: 2 m away is out.
    target = pin.SE3(np.eye(3), np.array([2.0, 0.0, 0.4]))
    assert base_arm.inverse(target) == []


def test_parameter_file_documents_every_value():
    assert STANFORD_PARAMETERS_PATH.is_file()
    for key in ("S1", "S2", "S6", "theta1", "theta2", "S3", "theta4", "theta5", "theta6"):
        assert len(P.sources[key]) > 20, key
    # Values stated in the seed: θ2 ∈ [−175°, −5°] (L909), θ5 ∈ [−110°, 110°] (L963).
    assert np.allclose(np.degrees([P.limits.lower[1], P.limits.upper[1]]), [-175, -5])
    assert np.allclose(np.degrees([P.limits.lower[4], P.limits.upper[4]]), [-110, 110])
    # S3: 6 in to 35 in, 29 in ≈ 75 cm of travel as in Scheinman's specification.
    assert math.isclose(P.limits.lower[2], 6 * INCH) and math.isclose(P.limits.upper[2], 35 * INCH)
    assert abs((P.limits.upper[2] - P.limits.lower[2]) - 0.75) < 0.02


def seed_workcell_poses(gamma_deg: float) -> list[pin.SE3]:
    """Hand poses of the seed's task (L2575–2595): grasp PIN1, lift, insert into BH1, park."""
    rz = lambda a: pin.utils.rotate("z", a)  # noqa: E731
    rx = lambda a: pin.utils.rotate("x", a)  # noqa: E731
    pin1 = pin.SE3(rz(90 * DEG), np.array([24.1, 117, 0.537]) * CM)
    bh1 = pin.SE3(np.eye(3), np.array([45.2 + 3.85, 102 + 3.20, 4.90]) * CM)
    up = lambda z: pin.SE3(np.eye(3), np.array([0, 0, z]))  # noqa: E731
    poses = [pin.SE3(pin.utils.rotate("y", np.pi), np.array([43.5, 56.9, 10.7]) * CM)]
    for k in range(8):
        grasp = pin.SE3(rz(k * 45 * DEG) @ rx(gamma_deg * DEG), np.array([0, 0, 3.54 * CM]))
        poses += [pin1 * grasp, up(2 * INCH + CM) * pin1 * grasp]
        poses += [bh1 * up(z) * grasp for z in (-1.71 * CM, INCH, 2 * INCH)]
    return poses


def limit_margin(q: np.ndarray) -> float:
    """Smallest distance of θ1, θ2, S3, θ5 to their limits, as a fraction of each range."""
    joints = [0, 1, 2, THETA5]
    lower, upper = P.limits.lower[joints], P.limits.upper[joints]
    return float(np.min(np.minimum(q[joints] - lower, upper - q[joints]) / (upper - lower)))


def test_default_base_reaches_seed_workcell_with_hand_down():
    # The criteria fixtures/arms/stanford.yaml places the base by, measured at (20, 70) cm, 225°.
    arm = load_arm(ArmSpec(model="stanford"))
    assert np.allclose(arm.world_from_base.translation, [0.20, 0.70, 0.0])
    margins = []
    for target in seed_workcell_poses(180.0):
        solutions = arm.inverse(target)
        assert solutions, target
        q = solutions[0]
        ep, er = pose_error(arm.forward(q), target)
        assert ep < 1e-9 and er < 1e-9
        # θ1 stays well inside ±150°: the column's dead zone faces away from the work
        # (θ1 spans −39.2°…59.1° over these poses).
        assert abs(q[0]) < 65 * DEG
        # A hand pointing down needs |θ5| = 180° − |θ2| (c5 = z3·a = −c2): check the geometry.
        assert math.isclose(abs(q[THETA5]), math.pi - abs(q[1]), abs_tol=1e-9)
        margins.append(max(limit_margin(s) for s in solutions))
    # best solution per pose, worst pose: 0.098 of the range, S3 at BPARK, 26.9 cm from the
    # column (0.101 at the old (20, 80) cm, θ5 binding)
    assert min(margins) > 0.09
    tilted = sum(bool(arm.inverse(t)) for t in seed_workcell_poses(135.0))
    # 29 of 41 for the seed's γ = 135°: 28 of the 40 tilted poses, plus park (counted once,
    # hand down); 30 at the old (20, 80) cm
    assert tilted >= 29


def test_seed_task_fixture_names_the_stanford_arm():
    task = load_task(SEED_TASK)
    assert task.manipulator is not None
    arm = load_arm(task.manipulator.arm, task.manipulator.hand)
    park = pin.SE3(pin.utils.rotate("y", np.pi), np.array([43.5, 56.9, 10.7]) * CM)
    assert arm.inverse(park)
    assert arm.name == "stanford" and arm.nq == 6


def test_tool_offset_and_rate_overrides_from_the_task_spec():
    spec = ArmSpec(
        model="stanford",
        base={"translation": ["0 cm", "0 cm", "0 cm"]},
        tool_offset={"translation": ["0 cm", "0 cm", "2 cm"], "rotation": [{"z": "90 deg"}]},
        velocity_limits=["1 rad/s", "1 rad/s", "25 cm/s", "1 rad/s", "1 rad/s", "1 rad/s"],
    )
    arm = load_arm(spec)
    assert np.allclose(arm.limits.velocity, [1, 1, 0.25, 1, 1, 1])
    assert np.allclose(arm.limits.acceleration, P.limits.acceleration)
    q = np.array([0.2, -1.4, 0.5, 0.3, 0.8, -0.6])
    # Hand frame = Paul's T6 (eqs. 2–13) · trans(rot(z, 90°), (0, 0, 2 cm)).
    t6 = np.vstack([seed_forward(q), [0, 0, 0, 1]])
    offset = pin.SE3(pin.utils.rotate("z", math.pi / 2), np.array([0, 0, 0.02]))
    assert np.allclose(arm.forward(q).homogeneous, t6 @ offset.homogeneous, atol=1e-14)
    solutions = arm.inverse(arm.forward(q))
    assert min(float(np.max(np.abs(s - q))) for s in solutions) < 1e-9


def test_an_unreadable_parameter_file_is_named_once_with_the_line(tmp_path: Path) -> None:
    """The parameter file goes through the task loader (synth/models/yamlread.py): a syntax
    slip is reported with its file and line, a missing file with its file."""
    broken = tmp_path / "arm.yaml"
    broken.write_text("kinematics:\n  S1: {source: L960\njoints: []\n", encoding="utf-8")
    with pytest.raises(ArmModelError) as caught:
        load_stanford_parameters(broken)
    message = str(caught.value)
    assert message.count(str(broken)) == 1 and "(line " in message, message
    with pytest.raises(ArmModelError, match="No such file"):
        load_stanford_parameters(tmp_path / "missing.yaml")


@pytest.mark.parametrize(
    ("index", "rate", "kind"),
    [(5, "3 cm/s", "revolute"), (2, "50 rad/s", "prismatic"), (0, "2 m/s", "revolute")],
)
def test_a_rate_in_the_other_kind_of_unit_is_refused_at_its_entry(
    tmp_path: Path, index: int, rate: str, kind: str
) -> None:
    # The Stanford arm's joints are R R P R R R (θ1, θ2, S3, θ4–θ6): a linear rate for a
    # revolute joint was read as its SI number in rad/s (3 cm/s as 0.03 rad/s, a tenth of the
    # slowest joint's own limit) and the plan went on with it
    text = SEED_TASK.read_text(encoding="utf-8")
    rates = ["1 rad/s", "1 rad/s", "25 cm/s", "1 rad/s", "1 rad/s", "1 rad/s"]
    rates[index] = rate
    listed = "".join(f"\n      - {r}" for r in rates)
    marker = "  arm:\n    model: stanford\n"
    assert marker in text
    changed = text.replace(marker, f"{marker}    velocity_limits:{listed}\n", 1)
    path = tmp_path / "rates.yaml"
    path.write_text(changed, encoding="utf-8")
    spec = load_task(path)
    with pytest.raises(SpecError) as refused:
        task_arm(spec, SEED_TASK.parent)
    assert refused.value.path == f"manipulator.arm.velocity_limits[{index}]"
    assert f"is {kind}" in str(refused.value)
    # the entry's own line in the task's text
    lines = changed.splitlines()
    assert lines[refused.value.line - 1].strip() == f"- {rate}"
