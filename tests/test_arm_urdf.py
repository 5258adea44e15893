"""Any URDF arm: a hand-written planar arm checked against its closed form, and the UR5 of the
optional ``example-robot-data`` package checked against Universal Robots' published DH table."""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_TASK

from synth.exceptions import ArmModelError, SpecError
from synth.models.arm import (
    CollisionScene,
    build_ik,
    example_robot_data_dir,
    load_arm,
    load_urdf_arm,
    solve_ik,
    task_arm,
)
from synth.models.arm.native_stderr import captured_stderr, native_detail
from synth.models.catalog import ROBOTS_EXTRA
from synth.models.loader import load_task
from synth.models.manipulator import ArmSpec, HandSpec

ROBOTS = example_robot_data_dir()


@pytest.fixture
def _robots() -> None:
    # make test installs the robots extra: a missing package is a failure, not a skip.
    if ROBOTS is None:
        pytest.fail(f"example-robot-data is not installed: {ROBOTS_EXTRA}")


needs_ur5 = pytest.mark.usefixtures("_robots")

L1, L2 = 0.4, 0.3  # [m] link lengths of the planar test arm

PLANAR = f"""<?xml version="1.0"?>
<robot name="planar">
  <link name="base"/>
  <link name="upper"><collision><origin xyz="{L1 / 2} 0 0"/>
    <geometry><box size="{L1} 0.04 0.04"/></geometry></collision></link>
  <link name="fore"><collision><origin xyz="{L2 / 2} 0 0"/>
    <geometry><box size="{L2} 0.04 0.04"/></geometry></collision></link>
  <link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="2" effort="10"/></joint>
  <joint name="j2" type="revolute"><parent link="upper"/><child link="fore"/>
    <origin xyz="{L1} 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" velocity="3" effort="10"/></joint>
  <joint name="j3" type="prismatic"><parent link="fore"/><child link="tip"/>
    <origin xyz="{L2} 0 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.1" velocity="0.5" effort="10"/></joint>
</robot>
"""


@pytest.fixture
def planar(tmp_path: Path) -> Path:
    path = tmp_path / "planar.urdf"
    path.write_text(PLANAR)
    return path


def test_planar_urdf_forward_kinematics_matches_closed_form(planar: Path):
    base = pin.SE3(pin.utils.rotate("z", 0.3), np.array([1.0, 2.0, 0.5]))
    arm = load_urdf_arm(planar, "tip", HandSpec(), world_from_base=base)
    rng = np.random.default_rng(21)
    for _ in range(50):
        q = rng.uniform(arm.limits.lower, arm.limits.upper)
        # Closed form in the base frame: a planar RR arm with a prismatic extension of the forearm.
        reach = L2 + q[2]
        x = L1 * math.cos(q[0]) + reach * math.cos(q[0] + q[1])
        y = L1 * math.sin(q[0]) + reach * math.sin(q[0] + q[1])
        expected = base * pin.SE3(pin.utils.rotate("z", q[0] + q[1]), np.array([x, y, 0.0]))
        got = arm.forward(q)
        assert np.allclose(got.homogeneous, expected.homogeneous, atol=1e-12)


def test_planar_urdf_limits_and_ik_round_trip(planar: Path):
    arm = load_urdf_arm(planar, "tip", HandSpec())
    assert arm.limits.kinds == ("revolute", "revolute", "prismatic")
    assert np.allclose(arm.limits.velocity, [2, 3, 0.5])
    # No acceleration limits in a URDF: v / 0.25 s by default.
    assert np.allclose(arm.limits.acceleration, [8, 12, 2])
    q = np.array([0.5, -0.7, 0.05])
    target = arm.forward(q)
    # A 3-joint arm cannot follow an arbitrary 6-D pose, but this one is reachable.
    result = solve_ik(build_ik(arm, target), np.random.default_rng(0))
    for s in result.solutions:
        assert np.linalg.norm(pin.log6(arm.forward(s).actInv(target)).vector) < 1e-9


def test_a_tool_link_named_like_its_joint_is_the_tool(tmp_path: Path):
    # URDF links and joints are named apart, so a fixed joint may carry its child link's name
    # (example-robot-data's Unitree Z1: gripperStator). Pinocchio then has a FIXED_JOINT and a
    # BODY frame "tool", and looking the name up alone raised "several frames match": every
    # command exited 70. The tool is the link, 5 cm out along the tip's x (a closed form).
    offset = 0.05
    text = PLANAR.replace(
        "</robot>",
        '  <link name="tool"><collision><origin xyz="0.01 0 0"/>\n'
        '    <geometry><box size="0.02 0.02 0.02"/></geometry></collision></link>\n'
        '  <joint name="tool" type="fixed"><parent link="tip"/><child link="tool"/>'
        f'<origin xyz="{offset} 0 0"/></joint>\n</robot>',
    )
    path = tmp_path / "same_name.urdf"
    path.write_text(text)
    arm = load_urdf_arm(path, "tool", HandSpec())
    q = np.array([0.5, -0.7, 0.05])
    reach = L2 + q[2] + offset
    x = L1 * math.cos(q[0]) + reach * math.cos(q[0] + q[1])
    y = L1 * math.sin(q[0]) + reach * math.sin(q[0] + q[1])
    assert np.allclose(arm.forward(q).translation, [x, y, 0.0], atol=1e-12)
    # the tool link's box and the hand hang from the link's frame, not the joint's
    scene = CollisionScene(arm, [])
    frames = arm.model.frames
    parents = {g.name: frames[g.parentFrame] for g in scene.geometry_model.geometryObjects}
    for name in ("tool_0", "palm", "finger_left"):
        assert (parents[name].name, parents[name].type) == ("tool", pin.FrameType.BODY)


@pytest.mark.parametrize(("speed", "shown"), [("1e9", "1e+09"), ("1e-6", "1e-06")])
def test_a_urdf_speed_limit_out_of_range_is_refused_like_an_override(
    tmp_path: Path, speed: str, shown: str
) -> None:
    # An override must lie in RATE_RANGE (1e-3 to 1e6 per s); the URDF's own limit was not
    # checked, and 1e9 crashed the trajectory timing (exit 70), 1e-6 timed a half turn at 36 days.
    path = tmp_path / "fast.urdf"
    path.write_text(PLANAR.replace('velocity="3"', f'velocity="{speed}"'))
    with pytest.raises(
        ArmModelError, match=f"joint j2's velocity limit {re.escape(shown)} rad/s lies outside"
    ):
        load_urdf_arm(path, "tip", HandSpec())
    # the task's own speeds replace the file's, and then it loads
    arm = load_urdf_arm(path, "tip", HandSpec(), velocity=[2.0, 3.0, 0.5])
    assert np.allclose(arm.limits.velocity, [2.0, 3.0, 0.5])


def test_unknown_tool_frame_and_missing_file_are_reported(planar: Path, tmp_path: Path):
    with pytest.raises(ArmModelError, match="no frame 'flange'"):
        load_urdf_arm(planar, "flange", HandSpec())
    with pytest.raises(ArmModelError, match="not found"):
        load_urdf_arm(tmp_path / "nope.urdf", "tip", HandSpec())


def test_urdfdoms_own_report_is_in_the_message_not_on_stderr(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # urdfdom wrote "Error:   Error=XML_ERROR_PARSING_TEXT … at line 103 in
    # /project/urdfdom/…/model.cpp" to descriptor 2 above synth's one-line message; the useful
    # part (what is wrong, and where in the user's file) now is in the message, and the C++
    # source position is dropped
    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='x'>\n<link name='a'>\n</robot>\n", encoding="utf-8")
    with pytest.raises(ArmModelError) as refused:
        load_urdf_arm(broken, "a", HandSpec())
    assert "(urdfdom: Error=XML_ERROR_" in refused.value.message
    assert "model.cpp" not in refused.value.message
    limitless = tmp_path / "limitless.urdf"
    limitless.write_text(
        PLANAR.replace('<limit lower="-3" upper="3" velocity="2" effort="10"/>', "", 1),
        encoding="utf-8",
    )
    with pytest.raises(ArmModelError, match="does not specify limits"):
        load_urdf_arm(limitless, "tip", HandSpec())
    assert capfd.readouterr().err == ""


def test_captured_native_stderr_is_passed_on_when_the_call_succeeds(
    capfd: pytest.CaptureFixture[str],
) -> None:
    # nothing written to descriptor 2 during a capture is lost: a clean exit writes it back
    with captured_stderr() as native:
        os.write(2, b"Warning: a native note\n")
    assert native.text == "Warning: a native note\n"
    assert capfd.readouterr().err == "Warning: a native note\n"
    with pytest.raises(RuntimeError), captured_stderr() as native:
        os.write(2, b"Error:   Error=BAD\n         at line 3 in /src/x.cpp\n")
        raise RuntimeError
    assert capfd.readouterr().err == ""
    assert native_detail(native.text) == "Error=BAD"


def test_continuous_joint_is_rejected(tmp_path: Path):
    path = tmp_path / "wheel.urdf"
    path.write_text(
        PLANAR.replace(
            'type="revolute"><parent link="base"/>', 'type="continuous"><parent link="base"/>'
        )
    )
    # named by the URDF's word, not Pinocchio's class (it said "JointModelRUBZ")
    with pytest.raises(ArmModelError, match=r"'j1' is continuous .* only revolute and prismatic"):
        load_urdf_arm(path, "tip", HandSpec())


def test_a_mimic_joint_is_refused_not_driven_on_its_own(tmp_path: Path):
    # Pinocchio builds a <mimic> joint as a free one: the program drove j2 apart from j1
    # (1.49 rad apart in the hunt's export) on an arm where j2 follows j1.
    path = tmp_path / "mimic.urdf"
    j2_end = '<limit lower="-2.5" upper="2.5" velocity="3" effort="10"/></joint>'
    assert PLANAR.count(j2_end) == 1
    path.write_text(
        PLANAR.replace(j2_end, j2_end.replace("</joint>", '<mimic joint="j1"/></joint>'))
    )
    with pytest.raises(ArmModelError, match="joint 'j2' mimics 'j1'"):
        load_urdf_arm(path, "tip", HandSpec())


def test_an_arm_without_collision_shapes_is_refused(tmp_path: Path):
    # With only <visual> shapes no link was checked: a program was proven with the arm's base
    # standing inside the box.
    path = tmp_path / "ghost.urdf"
    path.write_text(PLANAR.replace("<collision>", "<visual>").replace("</collision>", "</visual>"))
    with pytest.raises(ArmModelError, match="no link has a <collision> shape"):
        load_urdf_arm(path, "tip", HandSpec())


def test_a_urdf_without_joints_is_an_arm_model_error(tmp_path: Path):
    path = tmp_path / "plank.urdf"
    path.write_text("<?xml version='1.0'?>\n<robot name='plank'><link name='base'/></robot>\n")
    with pytest.raises(ArmModelError, match="no movable joints"):
        load_urdf_arm(path, "base", HandSpec())


def test_task_spec_names_a_urdf_with_relative_paths_and_overrides(planar: Path):
    spec = ArmSpec(
        urdf="planar.urdf",
        tool_frame="tip",
        base={"translation": ["10 cm", "0 cm", "0 cm"]},
        velocity_limits=["1 rad/s", "90 deg/s", "10 cm/s"],
    )
    arm = load_arm(spec, HandSpec(), base_dir=planar.parent)
    assert np.allclose(arm.limits.velocity, [1.0, math.pi / 2, 0.1])
    assert np.allclose(arm.forward(np.zeros(3)).translation, [0.1 + L1 + L2, 0, 0])
    with pytest.raises(ArmModelError, match=r"velocity_limits: 2 values for 3 joints"):
        load_arm(
            spec.model_copy(update={"velocity_limits": (1.0, 1.0)}),
            HandSpec(),
            base_dir=planar.parent,
        )


def ur5_spec(**extra) -> ArmSpec:
    assert ROBOTS is not None
    ur = ROBOTS / "ur_description"
    return ArmSpec(
        urdf=str(ur / "urdf" / "ur5_robot.urdf"),
        tool_frame="tool0",
        package_dirs=(str(ROBOTS.parent.parent),),
        srdf=str(ur / "srdf" / "ur5.srdf"),
        # The hand's palm is bolted to the bare flange: the hand frame sits L_f + h_palm ahead.
        tool_offset={
            "translation": ["0 cm", "0 cm", f"{(HandSpec().finger_length + 0.03) * 100} cm"]
        },
        **extra,
    )


def ur5_dh_position(q: np.ndarray) -> np.ndarray:
    """tool0 origin by Universal Robots' published UR5 DH table (d1, a2, a3, d4, d5, d6)."""
    d = [0.089159, 0, 0, 0.10915, 0.09465, 0.0823]
    a = [0, -0.425, -0.39225, 0, 0, 0]
    alpha = [math.pi / 2, 0, 0, math.pi / 2, -math.pi / 2, 0]
    T = np.eye(4)
    for i in range(6):
        ct, st, ca, sa = math.cos(q[i]), math.sin(q[i]), math.cos(alpha[i]), math.sin(alpha[i])
        T = T @ np.array(
            [
                [ct, -st * ca, st * sa, a[i] * ct],
                [st, ct * ca, -ct * sa, a[i] * st],
                [0, sa, ca, d[i]],
                [0, 0, 0, 1],
            ]
        )
    return T[:3, 3]


@needs_ur5
def test_ur5_matches_published_dh_and_solves_ik():
    arm = load_arm(ur5_spec())
    assert arm.nq == 6
    data = arm.model.createData()
    tool0 = arm.model.getFrameId("tool0")
    rz_pi = pin.utils.rotate("z", math.pi)  # ur_description's base_link faces the DH base backwards
    rng = np.random.default_rng(31)
    for _ in range(30):
        q = rng.uniform(-math.pi, math.pi, 6)
        pin.framesForwardKinematics(arm.model, data, q)
        assert np.allclose(data.oMf[tool0].translation, rz_pi @ ur5_dh_position(q), atol=1e-9)
    # Hand frame = tool0 · tool_offset (pure translation along the flange axis).
    q = np.array([0.3, -1.2, 1.0, -1.0, -1.5, 0.2])
    offset = HandSpec().finger_length + 0.03
    pin.framesForwardKinematics(arm.model, data, q)
    expected = data.oMf[tool0] * pin.SE3(np.eye(3), np.array([0, 0, offset]))
    assert np.allclose(arm.forward(q).homogeneous, expected.homogeneous, atol=1e-12)
    # DLS round trip on random reachable poses.
    for _ in range(5):
        q = rng.uniform(-math.pi, math.pi, 6)
        target = arm.forward(q)
        solutions = arm.inverse(target, rng=rng)
        assert solutions
        for s in solutions:
            err = pin.log6(arm.forward(s).actInv(target)).vector
            assert np.linalg.norm(err[:3]) < 1e-9 and np.linalg.norm(err[3:]) < 1e-9
            assert arm.limits.contains(s)


@needs_ur5
def test_ur5_collision_pairs_follow_srdf_and_adjacency():
    arm = load_arm(ur5_spec())
    scene = CollisionScene(arm)
    checked = {frozenset(p) for p in scene.pairs}
    # SRDF-disabled (base_link, upper_arm_link) and adjacent (shoulder, upper arm) are not checked.
    assert frozenset(("base_link_0", "upper_arm_link_0")) not in checked
    assert frozenset(("shoulder_link_0", "upper_arm_link_0")) not in checked
    assert scene.excluded[frozenset(("base_link_0", "upper_arm_link_0"))] == "srdf"
    # Stretched out along the DH x axis nothing touches: no false positives at the home pose.
    assert scene.collisions(np.zeros(6)) == []
    assert scene.clearance(np.zeros(6)).distance > 0.01


@needs_ur5
def test_ur5_mesh_distances_bounded_by_hulls_and_swept_check():
    import coal

    from synth.models.arm import swept_segment

    arm = load_arm(ur5_spec())
    table = ("table", coal.Box(2.0, 2.0, 0.05), pin.SE3(np.eye(3), np.array([0.0, 0.0, -0.025])))
    scene = CollisionScene(arm, [table])
    rng = np.random.default_rng(33)
    for _ in range(10):
        q = rng.uniform(-math.pi, math.pi, 6)
        exact = scene.distances(q)
        bound = scene.distance_bounds(q, exact_below=-1.0)  # convex hulls contain the meshes
        positive = exact > 0
        assert np.all(bound[positive] <= exact[positive] + 1e-5)
    # A free move above the table: conservative advancement agrees with dense sampling.
    q0 = np.array([0.0, -1.2, 1.2, -1.57, -1.57, 0.0])
    q1 = np.array([1.2, -1.0, 1.0, -1.57, -1.57, 0.5])
    result = swept_segment(scene, q0, q1)
    dense = min(scene.distances(q0 + t * (q1 - q0)).min() for t in np.linspace(0, 1, 201))
    assert result.free and dense > 0.01 and result.checks < 100


@needs_ur5
def test_pinocchio_reads_the_srdf_pairs_the_file_lists():
    # Independent reading: every <disable_collisions> element of ur5.srdf, by the standard
    # library's XML parser; Pinocchio's reading must hold exactly those between links on
    # different joints (pairs on one joint are adjacent and never paired).
    import xml.etree.ElementTree as ET

    assert ROBOTS is not None
    srdf = ROBOTS / "ur_description" / "srdf" / "ur5.srdf"
    listed = {
        frozenset((e.attrib["link1"], e.attrib["link2"]))
        for e in ET.parse(srdf).getroot().iter("disable_collisions")
    }
    arm = load_arm(ur5_spec())
    joint_of = {b.link: b.joint for b in arm.bodies}
    apart = {p for p in listed if len({joint_of.get(link) for link in p}) == 2}
    assert arm.disabled_pairs == apart and len(apart) >= 8
    with pytest.raises(ArmModelError, match="SRDF file not found"):
        load_arm(ur5_spec().model_copy(update={"srdf": "nosuch.srdf"}))


def test_a_task_whose_urdf_is_not_one_names_its_field_and_line(tmp_path: Path) -> None:
    # The message named the file only ("/…/arm.urdf: cannot build the model: …"), not the
    # task's field and line; a tool frame the file lacks is the tool_frame's fault
    (tmp_path / "arm.urdf").write_text("not a robot\n", encoding="utf-8")
    text = SEED_TASK.read_text(encoding="utf-8")
    old = "    model: stanford\n"
    assert text.count(old) == 1
    task = tmp_path / "task.yaml"
    task.write_text(text.replace(old, "    urdf: arm.urdf\n    tool_frame: tip\n"), "utf-8")
    line = task.read_text(encoding="utf-8").splitlines().index("    urdf: arm.urdf") + 1
    with pytest.raises(SpecError) as refused:
        task_arm(load_task(task), tmp_path)
    assert (refused.value.path, refused.value.line) == ("manipulator.arm.urdf", line)
    assert "arm.urdf: cannot build the model" in refused.value.detail
    (tmp_path / "arm.urdf").write_text(PLANAR, encoding="utf-8")
    task.write_text(task.read_text(encoding="utf-8").replace("tool_frame: tip", "tool_frame: x"))
    with pytest.raises(SpecError) as refused:
        task_arm(load_task(task), tmp_path)
    assert refused.value.path == "manipulator.arm.tool_frame"
    assert "no frame 'x'" in refused.value.detail
    # a finger joint the file lacks is the fingers' fault (the error says which field, the
    # loader no longer reads it from the message's words)
    task.write_text(
        task.read_text(encoding="utf-8").replace(
            "tool_frame: x", "tool_frame: tip\n    fingers: [left, right]"
        )
    )
    with pytest.raises(SpecError) as refused:
        task_arm(load_task(task), tmp_path)
    assert refused.value.path == "manipulator.arm.fingers"
    assert "no finger joint 'left'" in refused.value.detail
