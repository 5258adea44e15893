"""synth replay: the seed's programs in the believed world, programs
the arm cannot run, and the command line.

Oracles: poses composed by hand from the seed's numbers (BH1 at (49.05, 105.2, 4.90) cm, the
grasp trans(rotn((.924,.383,.001),180°),(0,0,3.54) cm), d_f = 1.71 cm), the Stanford arm's
inverse kinematics re-derived by hand from the seed's eqs. (14)–(21) for the reach test, and the
issue's JSON shape written out.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from _paths import DATA_AL, SEED_PROGRAM, SEED_TAP_TASK, SEED_TASK
from _tasks import with_base

from synth.al.parser import parse_program
from synth.cli import main
from synth.exceptions import ALSyntaxError
from synth.models.graph import pose_to_se3
from synth.models.loader import load_task
from synth.replay import (
    HandErrors,
    machine_for,
    nominal_world,
    replay_context,
    replay_program,
    run_machine,
)
from synth.replay.trace import Trace, record_run
from synth.units import CM, INCH


def axis_angle(axis: tuple[float, float, float], rad: float) -> np.ndarray:
    """Rodrigues' formula, written out."""
    k = np.array(axis, dtype=float)
    k /= np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(rad) * K + (1 - math.cos(rad)) * K @ K


# Where the seed_4_8 fixtures stand the arm (fixtures/arms/stanford.yaml says why): (20, 70) cm,
# turned 225° about z. The base used to be (20, 80) cm, where the tap listing's grasp approach
# (L2817) needs the boom shorter than its 6 in stop (see the tests below).
FIXTURE_BASE = (20.0, 70.0, 225.0)
OLD_BASE = (20.0, 80.0, 225.0)


# --------------------------------------------------------------------------------------------
# The seed's listings in the believed world


def test_search_listing_seats_the_pin_in_the_nominal_world() -> None:
    path = DATA_AL / "seed_4_8_search.al"
    context = replay_context(path.read_text(encoding="utf-8"), SEED_TASK, filename=str(path))
    machine = machine_for(context, nominal_world(context.graph), HandErrors.none())
    report, interpreter = run_machine(context, machine)
    assert report.outcome == "success", report.message
    assert report.violations == () and report.line is None
    # the first attempt bottoms at d_f: the program's own test reads 0 (S:2737)
    assert abs(interpreter.value("DISTANCE_OFF").value) < 1e-9  # type: ignore[union-attr]
    # the pin: tip 1.71 cm below BH1's mouth, on its axis, turned 90° about it
    pin1 = machine.pins["pin1"]
    assert not pin1.held and pin1.hole is not None and pin1.hole.name == "BH1"
    bh1 = np.array([45.2 + 3.85, 102 + 3.20, 4.90]) * CM
    assert np.allclose(pin1.pose.translation, bh1 - np.array([0, 0, 1.71 * CM]), atol=1e-9)
    assert np.allclose(pin1.pose.rotation[:, 2], [0, 0, 1], atol=1e-9)
    # the hand let go and withdrew 5.08 cm along its own -z (up), from 3.54 cm above the tip
    grasp = axis_angle((0.924, 0.383, 0.001), math.pi)
    seated = axis_angle((0, 0, 1), math.pi / 2)  # PIN1 = BH1*TRANS(ROTN(ZHAT,90*DEG), ...)
    approach = seated @ grasp[:, 2]
    assert np.allclose(machine.hand_pose().rotation[:, 2], approach, atol=1e-6)
    hand_z = 4.90 - 1.71 + 3.54 - 5.08 * approach[2]
    assert math.isclose(machine.hand_pose().translation[2], hand_z * CM, abs_tol=1e-4)
    # the timeline ends where the report does, after at least the time the velocity limits allow
    trace = record_run(context, program=path.name)
    assert trace.samples[-1].t == pytest.approx(report.time, abs=1e-9)
    assert report.time >= least_time(context.arm.limits.velocity, trace)


def least_time(velocity: np.ndarray, trace: Trace) -> float:
    """Σ max_j |Δq_j| / v_j over a trace's samples [s]: no run through them can be faster."""
    q = np.array([sample.q for sample in trace.samples])
    return float(np.sum(np.max(np.abs(np.diff(q, axis=0)) / velocity, axis=1)))


def test_no_joint_moves_faster_than_its_velocity_limit() -> None:
    # Sampled every 20 ms along the replay's own timeline: the limits alone, not the timing rule
    # that produced the motions, bound each joint's displacement between two samples. Played
    # with ruckig's durations the quintic reached 1.43 × joint 1's 2 rad/s on the listing's
    # first move (line 28). A mean speed over 20 ms never exceeds the peak speed.
    path = DATA_AL / "seed_4_8_search.al"
    context = replay_context(path.read_text(encoding="utf-8"), SEED_TASK, filename=str(path))
    trace = record_run(context, program=path.name)
    q = np.array([sample.q for sample in trace.samples])
    t = np.array([sample.t for sample in trace.samples])
    limits = context.arm.limits
    dt = np.diff(t)
    speed = np.abs(np.diff(q, axis=0)) / np.maximum(dt, 1e-12)[:, None]
    assert np.all(speed <= limits.velocity * (1 + 1e-6) + 1e-9)
    # the quintic at the limit reaches it: some joint comes within 2 % of its speed limit
    assert np.max(speed / limits.velocity) > 0.98
    # the acceleration and jerk of the quintic rule: tests/test_arm_timing.py


def test_tap_listing_seats_the_pin_in_the_nominal_world() -> None:
    path = DATA_AL / "seed_4_8_tap.al"
    context = replay_context(path.read_text(encoding="utf-8"), SEED_TAP_TASK, filename=str(path))
    machine = machine_for(context, nominal_world(context.graph), HandErrors.none())
    report, interpreter = run_machine(context, machine)
    assert report.outcome == "success", report.message
    # In the believed world the tap lands where the box is believed to be: CORR is the pin's
    # stand-off when the tap stopped (the contact clearance, 20 µm, plus the tip face's edge
    # dipping r_tip·sin(tilt), a few µm for the path's ~0.2° tilt); the pin then bottoms at
    # d_f, so the program's DISTANCE_OFF reads exactly −CORR.
    corr = interpreter.value("CORR").value  # type: ignore[union-attr]
    assert 0.0 <= corr <= 2e-5 + 0.13 * CM * math.sin(math.radians(0.5))
    distance_off = interpreter.value("DISTANCE_OFF").value  # type: ignore[union-attr]
    assert abs(distance_off + corr) < 1e-9


def tap_via_point_boom_extension(x_cm: float, y_cm: float, yaw_deg: float) -> float:
    """S3 [m] the tap listing's grasp approach via point (L2817) needs with the base at (x, y).

    By hand (seed eqs. 14–21): wrist centre w = p − S6·a in the base frame; ρ² = wx² + wy² −
    S2²; boom extension S3 = √(ρ² + (wz − S1)²).
    """
    pin1 = pin.SE3(axis_angle((0, 0, 1), math.pi / 2), np.array([24.1, 117.0, 0.537]) * CM)
    # TRANS(rot, vec): rotation rot, translation vec (not rotated), L2817
    rotation = axis_angle((0.679, 0.679, 0.281), math.radians(149))
    via = pin1 * pin.SE3(rotation, np.array([-3.59, 0.0, 7.13]) * CM)
    base = pin.SE3(axis_angle((0, 0, 1), math.radians(yaw_deg)), np.array([x_cm, y_cm, 0]) * CM)
    local = base.inverse() * via
    s1, s2, s6 = 0.412, 0.154, 0.263  # Paul's Stanford arm (fixtures/arms/stanford.yaml)
    w = local.translation - s6 * local.rotation[:, 2]
    return math.sqrt(w[0] ** 2 + w[1] ** 2 - s2**2 + (w[2] - s1) ** 2)


def test_tap_listing_via_point_is_within_the_boom_travel_at_the_fixture_base() -> None:
    # The fixture stands the arm where this test's hand computation puts it
    manipulator = load_task(SEED_TAP_TASK).manipulator
    assert manipulator is not None and manipulator.arm.base is not None
    x, y, yaw = FIXTURE_BASE
    expected = pin.SE3(axis_angle((0, 0, 1), math.radians(yaw)), np.array([x, y, 0.0]) * CM)
    base = manipulator.arm.base
    assert np.allclose(pose_to_se3(base).homogeneous, expected.homogeneous, atol=1e-12)
    # 24.93 cm: 9.7 cm clear of the 6 in (15.24 cm) stop, far below the 35 in one
    s3 = tap_via_point_boom_extension(*FIXTURE_BASE)
    assert 6 * INCH + 9 * CM < s3 < 35 * INCH
    text = (DATA_AL / "seed_4_8_tap.al").read_text(encoding="utf-8")
    report = replay_program(text, SEED_TAP_TASK)
    assert report.nominal.outcome == "success", report.nominal.message


def test_tap_listing_at_the_old_base_reaches_past_the_boom_stop() -> None:
    # At (20, 80) cm the via point needs S3 = 14.94 cm < 6 in: the replay names that pose as
    # unreachable at its line, the grasp approach.
    s3 = tap_via_point_boom_extension(*OLD_BASE)
    assert math.isclose(s3, 14.94 * CM, abs_tol=0.005 * CM) and s3 < 6 * INCH
    text = (DATA_AL / "seed_4_8_tap.al").read_text(encoding="utf-8")
    report = replay_program(text, with_base(load_task(SEED_TAP_TASK), *OLD_BASE))
    assert report.nominal.outcome == "violation"
    (violation,) = report.nominal.violations
    line = line_of(text, "MOVE BMANIP TO PIN1*TRANS(ROTN(VECTOR(.679,.679,.281),149*DEG)")
    assert line == 20 and (violation.kind, violation.line) == ("unreachable", line)
    assert "via point 1" in violation.detail


def test_first_cut_program_seats_the_pin_in_the_nominal_world() -> None:
    text = (DATA_AL / "seed_4_8_first_cut.al").read_text(encoding="utf-8")
    report = replay_program(text, SEED_TASK)
    assert report.nominal.outcome == "success", report.nominal.message


# --------------------------------------------------------------------------------------------
# Programs the arm cannot run


def line_of(text: str, fragment: str) -> int:
    return next(i for i, t in enumerate(text.splitlines(), 1) if fragment in t)


def test_a_target_out_of_the_workspace_is_unreachable_at_its_line() -> None:
    # 3 m above the park frame: farther from the shoulder than the boom (35 in) and the wrist
    # (S6 = 26.3 cm) reach together
    text = "OPEN BHAND TO 2*CM;\n{ reach up }\nMOVE BMANIP TO BPARK + VECTOR(0,0,300)*CM;\n"
    report = replay_program(text, SEED_TASK)
    assert report.nominal.outcome == "violation" and not report.ok
    (violation,) = report.nominal.violations
    assert violation.kind == "unreachable" and violation.line == 3
    assert report.nominal.line == 3 and "destination" in violation.detail


@pytest.mark.parametrize("digits", [170, 180, 300])
def test_a_target_astronomically_far_is_unreachable_not_a_crash(digits: int) -> None:
    # 10^180 cm: the Stanford inverse squared it to infinity and crashed on a NaN angle, exit 70
    # (the fourth hunt; 10^170 already was "unreachable"). No arm reaches a kilometre.
    far = "1" + "0" * digits
    text = f"MOVE BMANIP TO BPARK*TRANS(NILROTN,VECTOR(0,0,{far})*CM);\n"
    report = replay_program(text, SEED_TASK)
    (violation,) = report.nominal.violations
    assert violation.kind == "unreachable" and violation.line == 1
    assert "is out of the arm's reach" in violation.detail and f"e+{digits}" in violation.detail


def test_a_kept_joint_path_replays_as_a_fresh_one() -> None:
    # Every trial's first MOVE commands the same targets from the park, so its joint path is
    # kept (synth.replay.machine._joint_path). A trial run with the kept paths must end exactly
    # as one run after forgetting them (outcome, line, time to the bit), and the kept lists
    # must not be the ones a run holds (a motion must not change what the next trial reads).
    from synth.replay import machine as replay_machine
    from synth.replay import run_trial

    context = replay_context(SEED_PROGRAM.read_text(encoding="utf-8"), SEED_TASK)
    first = [run_trial(context, 0, i) for i in range(3)]
    assert replay_machine._PATHS  # the first motion's path is kept
    arm, park = context.arm, context.q_park
    targets = [arm.forward(park) * pin.SE3(np.eye(3), np.array([0.0, 0.0, -0.02]))]
    fresh, times, problem = replay_machine._joint_path(arm, park, targets)
    assert problem is None and len(fresh) == 2 and len(times) == 1
    fresh[1][:] = np.nan  # what a caller does to its list must not reach the kept one
    kept, kept_times, _ = replay_machine._joint_path(arm, park, targets)
    assert not np.isnan(kept[1]).any() and kept_times == times
    replay_machine._PATHS.clear()
    again = [run_trial(context, 0, i) for i in range(3)]
    assert [(r.outcome, r.line, r.time) for r in first] == [
        (r.outcome, r.line, r.time) for r in again
    ]


def test_a_hand_turned_back_at_the_arm_needs_theta5_beyond_its_limit() -> None:
    # At BPARK with the approach vector pointing up: the boom is about level there, so the
    # hand's z makes more than 110° with it (θ5 ∈ [−110°, 110°], seed L963)
    text = "MOVE BMANIP TO BPARK*TRANS(ROT(YHAT,180*DEG),NILVECT);\n"
    report = replay_program(text, SEED_TASK)
    (violation,) = report.nominal.violations
    assert violation.kind == "joint_limit" and violation.line == 1
    assert "theta5" in violation.detail


def test_a_motion_into_the_table_is_a_collision_at_its_line() -> None:
    # BPARK is 10.7 cm above the table, hand pointing down; 12 cm lower puts the fingertips
    # (one pad radius, 0.635 cm, past the hand origin) below the table top
    text = "OPEN BHAND TO 2*CM;\nMOVE BMANIP TO BPARK - VECTOR(0,0,12)*CM;\nOPEN BHAND TO 1*CM;\n"
    report = replay_program(text, SEED_TASK)
    (violation,) = report.nominal.violations
    assert violation.kind == "collision" and violation.line == 2
    assert "table" in violation.detail and "finger" in violation.detail
    # the run stops at the collision: the third statement never runs
    assert report.nominal.statements == 2


def test_a_seated_pin_dragged_sideways_out_of_its_rack_jams_at_the_drag() -> None:
    # The golden program with one line after AFFIX: the pin, seated in RH1, carried 4 cm
    # sideways. The bore stops it 1 cm off the axis (the replay's compliance): a jam at that
    # line. It used to pass as a stall at the rack hole's bottom (the move's bow pushes the
    # seated tip a few µm deeper first), and the program went on to succeed.
    text = SEED_PROGRAM.read_text(encoding="utf-8")
    affix = "AFFIX PIN1 TO BMANIP;\n"
    assert text.count(affix) == 1
    line = text[: text.index(affix)].count("\n") + 2
    text = text.replace(affix, affix + "MOVE PIN1 TO PIN1*TRANS(NILROTN,VECTOR(4,0,0)*CM);\n")
    report = replay_program(text, SEED_TASK)
    (violation,) = report.nominal.violations
    assert (violation.kind, violation.line) == ("collision", line)
    assert "PIN1 jammed in RH1" in violation.detail and "1.00 cm sideways" in violation.detail


def test_a_guarded_motion_onto_the_table_stops_without_violation() -> None:
    text = (
        "OPEN BHAND TO 2*CM;\n"
        "MOVE BMANIP TO BPARK - VECTOR(0,0,12)*CM\n"
        "  ON FORCE(ZHAT) > 8*OZ DO STOP;\n"
        "Z = ZHAT . DISPL(BMANIP);\n"
    )
    context = replay_context(text, SEED_TASK)
    machine = machine_for(context, nominal_world(context.graph), HandErrors.none())
    report, interpreter = run_machine(context, machine)
    # no violation (the task's pin stays in its rack, so the goal is not met)…
    assert report.outcome == "failure" and report.violations == ()
    # …and the hand stopped with its fingertips (0.635 cm past the origin) within the sweep's
    # 1 mm clearance of the table top
    z = interpreter.value("Z").value  # type: ignore[union-attr]
    assert 0.635 * CM < z <= 0.635 * CM + 1e-3 + 1e-9


def test_unknown_frame_is_an_error_with_its_line() -> None:
    report = replay_program("OPEN BHAND TO 2*CM;\nMOVE BMANIP TO NOSUCH;\n", SEED_TASK)
    assert report.nominal.outcome == "error"
    assert report.nominal.line == 2 and "NOSUCH" in report.nominal.message


def test_syntax_error_names_its_line() -> None:
    with pytest.raises(ALSyntaxError) as caught:
        replay_program("OPEN BHAND TO 2*CM;\nMOVE BMANIP TO BPARK VIA;\n", SEED_TASK)
    assert caught.value.line == 2


# --------------------------------------------------------------------------------------------
# The report and the command line


def test_report_json_has_the_issue_shape() -> None:
    text = (DATA_AL / "seed_4_8_search.al").read_text(encoding="utf-8")
    document = replay_program(text, SEED_TASK, trials=3, seed=5).to_json()
    assert set(document) == {"ok", "nominal", "monte_carlo"}
    assert set(document["nominal"]) == {
        "outcome",
        "message",
        "line",
        "time",
        "statements",
        "violations",
    }
    assert set(document["monte_carlo"]) == {
        "trials",
        "seed",
        "success_rate",
        "outcomes",
        "time",
    }
    assert set(document["monte_carlo"]["time"]) == {"mean", "p95"}
    assert document["monte_carlo"]["trials"] == 3 and document["monte_carlo"]["seed"] == 5
    assert sum(document["monte_carlo"]["outcomes"].values()) == 3
    json.dumps(document)  # serialisable as it is


def run_cli(*args: str, capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(["replay", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_exit_codes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    search = str(DATA_AL / "seed_4_8_search.al")
    code, out, _ = run_cli(search, "--task", str(SEED_TASK), "--trials", "0", capsys=capsys)
    assert code == 0 and "nominal: success" in out
    bad = tmp_path / "table.al"
    bad.write_text("MOVE BMANIP TO BPARK - VECTOR(0,0,12)*CM;\n", encoding="utf-8")
    code, out, _ = run_cli(
        str(bad), "--task", str(SEED_TASK), "--trials", "0", "--json", capsys=capsys
    )
    assert code == 1
    document = json.loads(out)
    assert document["ok"] is False
    assert document["nominal"]["violations"][0]["kind"] == "collision"
    broken = tmp_path / "broken.al"
    broken.write_text("MOVE BMANIP TO;\n", encoding="utf-8")
    code, _, err = run_cli(str(broken), "--task", str(SEED_TASK), capsys=capsys)
    assert code == 2 and "broken.al:1:" in err
    code, _, err = run_cli(str(tmp_path / "missing.al"), "--task", str(SEED_TASK), capsys=capsys)
    assert code == 2 and "no such program file" in err
    code, _, err = run_cli(search, "--task", str(tmp_path / "missing.yaml"), capsys=capsys)
    assert code == 2
    unknown = tmp_path / "unknown.al"
    unknown.write_text("MOVE BMANIP TO NOSUCH;\n", encoding="utf-8")
    code, out, _ = run_cli(str(unknown), "--task", str(SEED_TASK), "--trials", "0", capsys=capsys)
    assert code == 2 and "NOSUCH" in out


def test_cli_distribution_override_is_stated_and_checked(
    capsys: pytest.CaptureFixture[str],
) -> None:
    search = str(DATA_AL / "seed_4_8_search.al")
    args = (search, "--task", str(SEED_TASK), "--trials", "2", "--workers", "1")
    code, out, _ = run_cli(*args, "--distribution", "normal", capsys=capsys)
    assert code == 0 and "every block sampled normal (--distribution)" in out
    code, out, _ = run_cli(*args, capsys=capsys)
    assert code == 0 and "--distribution" not in out
    with pytest.raises(SystemExit) as exit_info:  # argparse names the option and the choices
        main(["replay", *args, "--distribution", "triangular"])
    assert exit_info.value.code == 2
    assert "--distribution: invalid choice: 'triangular'" in capsys.readouterr().err


def test_cli_preamble_is_the_binding_as_al(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli("--preamble", "--task", str(SEED_TASK), capsys=capsys)
    assert code == 0
    program = parse_program(out)
    names = {d.name for decl in program.body if hasattr(decl, "names") for d in decl.names}
    assert {"BOX", "BH1", "PIN1", "RH1", "BPARK"} <= names
    assert "AFFIX PIN1 TO RH1 AT" in out


def test_cli_progress_bar_goes_to_stderr_when_asked(capsys: pytest.CaptureFixture[str]) -> None:
    search = str(DATA_AL / "seed_4_8_search.al")
    code, out, err = run_cli(
        search, "--task", str(SEED_TASK), "--trials", "20", "--workers", "1", "--progress",
        capsys=capsys,
    )  # fmt: skip
    assert code == 0 and "| 20/20 [" in err and "trial/s]" in err and "trials" in out


def test_console_script_runs_as_a_process(tmp_path: Path) -> None:
    completed = subprocess.run(
        [sys.executable, "-m", "synth.cli", "replay", "--preamble", "--task", str(SEED_TASK)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert completed.returncode == 0 and "PIN1" in completed.stdout
