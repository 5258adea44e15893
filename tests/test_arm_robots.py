"""Built-in URDF arms (example-robot-data): names, the UR closed form, the Panda's own fingers,
the arm-agnostic rating and the collision-free park.

``make test`` installs the ``robots`` extra, so these run in CI; without it they fail with the
command that installs it rather than skipping.
"""

from __future__ import annotations

import math
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest
import trimesh
from _paths import SEED_TASK, TASKS
from pydantic import ValidationError

from synth.cli import main
from synth.exceptions import ArmModelError, SpecError
from synth.models.arm import (
    CollisionScene,
    HeldObject,
    IKOptions,
    build_ik,
    dexterity,
    example_robot_data_dir,
    grasp_rating,
    load_arm,
    manipulator_arm,
    nearest_solution,
    solve_ik,
)
from synth.models.arm.rating import SeedGraspRating, WorstDexterityRating, characteristic_length
from synth.models.arm.ur import URInverse
from synth.models.believed import believed_graph
from synth.models.catalog import BUILTIN_ARMS, ROBOTS_EXTRA
from synth.models.graph import pose_to_se3
from synth.models.loader import load_task
from synth.models.manipulator import ArmSpec, HandSpec, ManipulatorSpec
from synth.models.park import nominal_environment, park_configuration
from synth.replay.run import replay_context
from synth.strategies.context import plan_context
from synth.units import CM, INCH

ROBOTS = example_robot_data_dir()


@pytest.fixture(autouse=True)
def _robots_installed() -> None:
    if ROBOTS is None:
        pytest.fail(f"example-robot-data is not installed: {ROBOTS_EXTRA}")


def _pose_error(a: pin.SE3, b: pin.SE3) -> float:
    return float(np.linalg.norm(pin.log6(a.actInv(b)).vector))


# ---- names -----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(BUILTIN_ARMS))
def test_every_builtin_name_loads_with_its_hand(name: str):
    arm = load_arm(ArmSpec(model=name))
    assert arm.name == name
    names = [b.name for b in arm.bodies]
    # Exactly one hand: one palm and two fingers, whichever hand it is (never both).
    assert sorted(n for n in names if n in ("palm", "finger_left", "finger_right")) == [
        "finger_left",
        "finger_right",
        "palm",
    ]
    if BUILTIN_ARMS[name].fingers:
        assert not any("finger" in b.name and b.role == "arm" for b in arm.bodies)
        assert arm.nq == 7  # the Panda's finger joints are locked out of the configuration
    else:
        assert arm.closed_form is not None, "UR arms get ur_analytic_ik's closed form"


def test_unknown_model_names_the_builtins():
    with pytest.raises(ValidationError, match=r"unknown arm model 'ur99'.*ur5.*panda"):
        ArmSpec(model="ur99")
    with pytest.raises(ValidationError, match="remove srdf"):
        ArmSpec(model="ur5", srdf="x.srdf")


def test_missing_package_names_the_extra(monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setattr("synth.models.arm.robots.example_robot_data_dir", lambda: None)
    with pytest.raises(ArmModelError, match=r"not installed: pip install 'synth\[robots\]'"):
        load_arm(ArmSpec(model="ur5"))


def test_urdf_path_still_works_and_matches_the_builtin():
    assert ROBOTS is not None
    ur = ROBOTS / "ur_description"
    offset = HandSpec().finger_length + HandSpec().palm_size[2]
    by_path = load_arm(
        ArmSpec(
            urdf=str(ur / "urdf" / "ur5_robot.urdf"),
            tool_frame="tool0",
            package_dirs=(str(ROBOTS.parent.parent),),
            tool_offset={"translation": ["0 cm", "0 cm", f"{offset * 100} cm"]},
        )
    )
    builtin = load_arm(ArmSpec(model="ur5"))
    q = np.array([0.3, -1.2, 1.0, -1.0, -1.5, 0.2])
    # Same flange, same parametric hand bolted to it (palm's rear face on the flange).
    assert _pose_error(by_path.forward(q), builtin.forward(q)) < 1e-12


# ---- UR closed form --------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["ur3", "ur5", "ur10", "ur5_limited"])
def test_ur_closed_form_agrees_with_pinocchio_and_finds_every_branch(name: str):
    arm = load_arm(ArmSpec(model=name))
    assert isinstance(arm.closed_form, URInverse)
    rng = np.random.default_rng(7)
    lower, upper = arm.limits.lower, arm.limits.upper
    dls = IKOptions(starts=48)
    for _ in range(6):
        q = rng.uniform(np.maximum(lower, -math.pi), np.minimum(upper, math.pi))
        target = arm.forward(q)
        solutions = arm.inverse(target)
        assert 1 <= len(solutions) <= 8  # 2 shoulders × 2 elbows × 2 wrists
        for s in solutions:  # Pinocchio's forward kinematics is the check
            assert _pose_error(arm.forward(s), target) < 1e-9
            assert arm.limits.contains(s, 1e-12)
        # The configuration we started from is one of them, up to whole turns.
        wrapped = [np.angle(np.exp(1j * (s - q))) for s in solutions]
        assert min(float(np.max(np.abs(w))) for w in wrapped) < 1e-7
        # With a hint, its own branch comes back at the hint's turn: the nearest rule gives q.
        near = nearest_solution(arm, arm.inverse(target, hint=q), q)
        assert near is not None and float(np.max(np.abs(near - q))) < 1e-7
        # Every branch the multi-start DLS solver finds is one of the closed form's.
        found = solve_ik(build_ik(arm, target, dls), rng).solutions
        for s in found:
            gaps = [np.angle(np.exp(1j * (s - c))) for c in solutions]
            assert min(float(np.max(np.abs(g))) for g in gaps) < 1e-6


def test_ur_hint_picks_the_whole_turn_alias_nearest_the_arm():
    arm = load_arm(ArmSpec(model="ur5"))  # every joint but the elbow turns ±2π
    q = np.array([0.4, -1.1, 1.2, -1.6, -1.5, 0.3])
    target = arm.forward(q)
    hint = q + np.array([-2 * math.pi, 0.0, 0.0, 2 * math.pi, 0.0, -2 * math.pi])  # in ±2π
    near = nearest_solution(arm, arm.inverse(target, hint=hint), hint)
    assert near is not None and np.allclose(near, hint, atol=1e-7)


# ---- the Panda's own fingers -----------------------------------------------------------------


def test_panda_hand_is_read_from_its_fingers():
    assert ROBOTS is not None
    arm = load_arm(ArmSpec(model="panda"))
    hand = arm.hand
    # panda.urdf: each finger joint slides 0…0.04 m, the pads touch when closed.
    assert hand.max_opening == pytest.approx(0.08, abs=1e-9)
    # The rubber tip box is 17.5 × 15.2 × 18.5 mm (x across the pad, y its thickness, z along
    # the approach in the finger frame): the largest square pad is 17.5 mm, 15.2 mm thick.
    assert hand.finger_pad_radius == pytest.approx(0.0175 / 2, abs=1e-9)
    assert hand.finger_thickness == pytest.approx(0.0152, abs=1e-9)
    # The palm's front face, read off hand.stl directly: the pads' centre is 58.4 + 45.25 mm
    # down panda_hand's z, so L_f = 0.10365 − (the mesh's largest z).
    stl = ROBOTS / "panda_description" / "meshes" / "collision" / "hand.stl"
    mesh = trimesh.load(stl, force="mesh")
    assert hand.finger_length == pytest.approx(0.10365 - float(mesh.bounds[1][2]), abs=1e-9)
    # A parametric hand section on an arm with fingers is refused.
    with pytest.raises(ArmModelError, match=r"manipulator.hand.*own fingers"):
        load_arm(ArmSpec(model="panda"), HandSpec())
    # A tool_offset replaces the built-in's turn of 90° about z: the fingers then slide along
    # the hand frame's y. The refusal names the task's field, not the package's URDF file
    # (Hunt A), and says the offset replaces the built-in one.
    with pytest.raises(ArmModelError) as refused:
        load_arm(ArmSpec(model="panda", tool_offset={"translation": ["0 cm", "0 cm", "1 cm"]}))
    message = str(refused.value)
    assert message.startswith("manipulator.arm.tool_offset: finger joint 'panda_finger_joint1'")
    assert message.endswith("(it replaces the built-in panda's own hand offset)")
    assert "panda.urdf" not in message
    # the built-in's own offset given explicitly is the built-in arm
    given = load_arm(
        ArmSpec(
            model="panda",
            tool_offset={
                "translation": ["0 cm", "0 cm", "10.365 cm"],
                "rotation": [{"z": "90 deg"}],
            },
        )
    )
    q = np.array([0.1, -0.4, 0.2, -2.0, 0.1, 1.7, 0.6])
    assert _pose_error(given.forward(q), arm.forward(q)) < 1e-12


@pytest.mark.parametrize("opening", [0.01, 0.03, 0.07])
def test_panda_fingers_open_to_the_commanded_gap(opening: float):
    arm = load_arm(ArmSpec(model="panda"))
    q = np.array([0.0, -0.785398, 0.0, -2.35619, 0.0, 1.5707, 0.785398])  # the SRDF's default
    # A pin of diameter d between the pads at the hand origin: each flat pad face is
    # (w − d)/2 from it when the fingers stand at opening w.
    d = 0.005
    held = HeldObject.of("probe", coal.Cylinder(d / 2, 0.004), pin.SE3.Identity())
    scene = CollisionScene(arm, held=held, opening=opening)
    distances = dict(zip(scene.pairs, scene.distances(q), strict=True))
    for finger in ("finger_left", "finger_right"):
        pair = next(p for p in distances if set(p) == {finger, "probe"})
        assert distances[pair] == pytest.approx((opening - d) / 2, abs=2e-5)


# ---- the rating --------------------------------------------------------------------------------


def test_stanford_keeps_the_seed_rating_and_urdf_arms_the_dexterity():
    assert isinstance(grasp_rating(load_arm(ArmSpec(model="stanford"))), SeedGraspRating)
    assert isinstance(grasp_rating(load_arm(ArmSpec(model="ur5"))), WorstDexterityRating)


def test_dexterity_vanishes_at_a_wrist_singularity_and_rewards_mid_range():
    arm = load_arm(ArmSpec(model="ur5"))
    # θ5 = 0 lines the UR's wrist axes 4 and 6 up: the Jacobian loses rank, κ⁻¹ = 0, and the
    # dexterity is the joint margin's half alone. At q = 0 every ±2π joint is mid-range and
    # the elbow (±π) too: m = 1.
    q = np.array([0.0, -1.2, 1.4, -1.7, 0.0, 0.0])
    lim = arm.limits
    half = (lim.upper - lim.lower) / 2
    margin = float(np.min(np.minimum(q - lim.lower, lim.upper - q) / half))
    assert dexterity(arm, q) == pytest.approx(0.5 * margin, abs=1e-9)
    # Off the singularity κ⁻¹ > 0 and equals σ_min/σ_max of the L-scaled Jacobian computed by
    # finite differences of the forward kinematics (an independent Jacobian).
    q[4] = -1.5
    h = 1e-7
    columns = []
    for j in range(arm.nq):
        dq = np.zeros(arm.nq)
        dq[j] = h
        columns.append(pin.log6(arm.forward(q).actInv(arm.forward(q + dq))).vector / h)
    jac = np.array(columns).T
    jac[:3] /= characteristic_length(arm)
    sigma = np.linalg.svd(jac, compute_uv=False)
    margin = float(np.min(np.minimum(q - lim.lower, lim.upper - q) / half))
    expected = 0.5 * margin + 0.5 * sigma[-1] / sigma[0]
    assert dexterity(arm, q) == pytest.approx(expected, abs=1e-5)


# ---- the park --------------------------------------------------------------------------------


def _manipulator(model: str, base_cm: tuple[float, float], park_z_cm: float) -> ManipulatorSpec:
    return ManipulatorSpec.model_validate(
        {
            "arm": {
                "model": model,
                "base": {"translation": [f"{base_cm[0]} cm", f"{base_cm[1]} cm", "0 cm"]},
            },
            "park": {
                "pose": {
                    "translation": ["43.5 cm", "56.9 cm", f"{park_z_cm} cm"],
                    "rotation": [{"y": "180 deg"}],
                }
            },
        }
    )


def test_park_configuration_is_collision_free_or_named():
    graph_spec = load_task(SEED_TASK)
    graph = believed_graph(graph_spec)
    manip = _manipulator("ur5", (35, 80), 10.7)
    arm = manipulator_arm(manip)
    environment = nominal_environment(graph, arm)
    q = park_configuration(arm, pose_to_se3(manip.park.pose), environment)
    assert not CollisionScene(arm, environment, opening=0.0).in_collision(q)
    # The hand 2 cm into the table: every configuration touches it, and the error says so.
    low = _manipulator("ur5", (35, 80), -2.0)
    with pytest.raises(SpecError, match=r"manipulator.park.*touches.*table"):
        park_configuration(arm, pose_to_se3(low.park.pose), environment)
    # A base standing inside the box is a task error, whatever the park.
    inside = manipulator_arm(_manipulator("ur5", (45.2, 102), 10.7))
    with pytest.raises(SpecError, match=r"manipulator.arm.base.*inside BOX"):
        park_configuration(inside, pose_to_se3(manip.park.pose), nominal_environment(graph, inside))


def test_a_park_where_the_opening_fingers_touch_the_arm_is_refused_at_the_park() -> None:
    # The UR5's base 12.9 cm from the park (the fifth hunt's ur5_far60): clear with the fingers
    # closed, but the program's first OPEN (pin diameter + 1 in, L2139) swings finger_right
    # into the upper arm, and the planner said "every motion the task needs is obstructed"
    graph = believed_graph(load_task(SEED_TASK))
    manip = _manipulator("ur5", (49.05, 45.2), 10.7)
    arm = manipulator_arm(manip)
    environment = nominal_environment(graph, arm)
    park = pose_to_se3(manip.park.pose)
    q = park_configuration(arm, park, environment)  # the replay's start: fingers closed
    opening = 0.635 * CM + 1 * INCH
    touching = CollisionScene(arm, environment, opening=opening).collisions(q)
    assert ("upper_arm_link_0", "finger_right") in touching or (
        "finger_right",
        "upper_arm_link_0",
    ) in touching
    with pytest.raises(SpecError, match=r"^manipulator.park: .*opened to 3.17 cm .*finger_right"):
        park_configuration(arm, park, environment, opening=opening)
    # nearer the column's other side the same opening is clear: the seed's UR5 base
    clear = manipulator_arm(_manipulator("ur5", (25, 80), 10.7))
    park_configuration(clear, park, nominal_environment(graph, clear), opening=opening)


# ---- end to end --------------------------------------------------------------------------------


@pytest.mark.parametrize("arm", ["ur5", "panda"])
def test_seed_task_plans_emits_and_replays_on_a_urdf_arm(arm: str, tmp_path: Path, capsys):
    task = TASKS / f"seed_4_8_{arm}.yaml"
    program = tmp_path / f"{arm}.al"
    # A short proof (10 trials, no failure allowed) keeps the test quick; the fixtures' 500-trial
    # rates (`synth replay --trials 500`, `benchmarks/proof.py --tasks`) are in the CHANGELOG.
    assert (
        main(["plan", str(task), "-o", str(program), "--proof-trials", "10", "--workers", "1"]) == 0
    )
    out = capsys.readouterr().out
    assert "Proof: proven: 10 of 10" in out
    assert (
        main(["replay", str(program), "--task", str(task), "--trials", "3", "--workers", "1"]) == 0
    )
    # Trials 0–2 of seed 0 are the proof's first three (a trial is a function of program, task,
    # seed and index: synth/replay/proof.py), and the proof saw 10 of 10 succeed.
    out = capsys.readouterr().out
    assert "nominal: success: PIN1 seated in BH1" in out
    assert "Monte Carlo: 3 trials (seed 0): success 100.0%" in out


@pytest.mark.parametrize(
    "task",
    ["generality/block_tall_pin", "generality/tap_and_search", "seed_4_8_ur5", "seed_4_8_panda"],
)
def test_replay_starts_in_the_planners_park_configuration(task: str):
    # Before one rule served both, the replay took the park solution nearest q = 0 and the
    # planner the best-rated one; on block_tall_pin and tap_and_search those differ.

    path = TASKS / f"{task}.yaml"
    planned = plan_context(load_task(path), base_dir=path.parent).q_park
    replayed = replay_context("BEGIN END", path).q_park
    assert np.array_equal(planned, replayed)
