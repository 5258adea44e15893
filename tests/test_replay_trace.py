"""The replay's trace (``synth replay --trace``): the replay's own timeline, poses and lines.

Oracles: the replay's report (its clock, a trial's outcome), the program text (each event's
line holds its statement), the seed's poses (PIN1 starts at T_wp = trans(rot(ẑ, 90°), (24.1,
117, .537) cm), L2577, and ends seated d_f = 1.71 cm down BH1 at (45.2 + 3.85, 102 + 3.20, 4.90)
cm, L2575–2576) and the arm's forward kinematics.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_TASK
from _tasks import synthesized

from synth.cli import main
from synth.replay.run import replay_context, replay_program
from synth.replay.trace import SCHEMA, Trace, TraceRecorder, record_run

KEYWORDS = {"move": "MOVE", "open": "OPEN", "close": "CLOSE", "center": "CENTER"}


@pytest.fixture(scope="module")
def program() -> str:
    return synthesized(SEED_TASK).program


@pytest.fixture(scope="module")
def nominal(program: str) -> Trace:
    return record_run(replay_context(program, SEED_TASK), program="seed.al")


def test_the_trace_runs_on_the_replays_clock(program: str, nominal: Trace) -> None:
    report = replay_program(program, SEED_TASK, trials=3, seed=0)
    assert nominal.report == report.nominal
    times = np.array([s.t for s in nominal.samples])
    assert times[0] == 0.0 and np.all(np.diff(times) > 0)
    assert times[-1] == pytest.approx(report.nominal.time, abs=1e-12)
    assert np.max(np.diff(times)) <= nominal.dt + 1e-9
    # a trial's trace is that trial: same draw, same outcome and time
    context = replay_context(program, SEED_TASK)
    for index in range(3):
        trace = record_run(context, trial=index, seed=0)
        assert trace.report.outcome == report.trials[index].outcome
        assert trace.report.time == pytest.approx(report.trials[index].time, abs=1e-12)


def test_events_name_the_al_lines_of_their_statements(program: str, nominal: Trace) -> None:
    lines = program.splitlines()
    starts = [e for e in nominal.events if e.kind == "start"]
    assert [e.motion for e in starts][:3] == ["open", "move", "center"]  # the pickup, L2700
    for event in starts:
        assert event.line is not None
        assert KEYWORDS[event.motion] in lines[event.line - 1].upper(), event
    (monitor,) = [e for e in nominal.events if e.kind == "monitor"]
    statement = "\n".join(lines[monitor.line - 1 : monitor.line + 3])
    assert "ON FORCE" in statement  # the first attempt stops on force, seated (L2760)
    assert nominal.events[-1].kind == "outcome" and nominal.events[-1].detail == "success"
    for sample in nominal.samples:
        assert KEYWORDS[sample.motion] in lines[sample.line - 1].upper()


def test_poses_follow_the_arm_and_the_pin(nominal: Trace) -> None:
    context = replay_context(synthesized(SEED_TASK).program, SEED_TASK)
    arm = context.arm
    # no hand error in the nominal run: hand = FK(q), up to the grasp's re-registration of the
    # hand on the pin (CENTER: the reading becomes the centred pose, q solved to within the IK)
    for sample in nominal.samples[::5]:
        expected = arm.forward(np.array(sample.q))
        np.testing.assert_allclose(sample.hand.translation, expected.translation, atol=5e-5)
    start, end = nominal.samples[0].pins["PIN1"], nominal.samples[-1].pins["PIN1"]
    np.testing.assert_allclose(start.translation, [0.241, 1.17, 0.00537], atol=1e-9)
    np.testing.assert_allclose(start.rotation, pin.exp3(np.array([0, 0, np.pi / 2])), atol=1e-9)
    np.testing.assert_allclose(
        end.translation, [0.452 + 0.0385, 1.02 + 0.032, 0.049 - 0.0171], atol=2e-4
    )
    assert end.rotation[2, 2] == pytest.approx(1.0, abs=1e-6)  # upright in the hole
    # the pin rides with the hand between the grasp and the release
    held = [s for s in nominal.samples if s.motion == "move" and s.line > 12]
    offsets = [(s.hand.inverse() * s.pins["PIN1"]).translation for s in held if s.line < 60]
    assert np.ptp(np.array(offsets), axis=0).max() < 1e-6


def test_trace_json_and_cli(
    tmp_path: Path, program: str, capsys: pytest.CaptureFixture[str]
) -> None:
    al = tmp_path / "seed.al"
    al.write_text(program, encoding="utf-8")
    out = tmp_path / "trace.json"
    args = ["replay", str(al), "--task", str(SEED_TASK), "--workers", "1"]
    assert main([*args, "--trials", "0", "--trace", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["schema"] == SCHEMA and doc["trial"] is None
    assert len(doc["joints"]) == len(doc["samples"][0]["q"]) == 6
    assert set(doc["samples"][0]["hand"]) == {"translation", "quaternion"}
    assert doc["events"][-1]["kind"] == "outcome"
    assert main([*args, "--trace", str(out), "--trial", "2"]) == 0
    assert json.loads(out.read_text())["trial"] == 2
    assert f"trace of trial 2 written to {out}" in capsys.readouterr().out
    # Without --trace, --trial re-runs that trial alone (exit 0: trial 2 succeeds).
    assert main([*args, "--trial", "2"]) == 0


def test_recorder_rejects_a_bad_period(nominal: Trace) -> None:
    with pytest.raises(ValueError, match="dt"):
        TraceRecorder(None, {}, dt=0.0)  # type: ignore[arg-type]


def test_every_motion_is_sampled_though_freed_ids_come_back(nominal: Trace) -> None:
    # The recorder keys motions by id(); CPython hands a freed object's id to the next one of
    # the same size, and before the recorder kept its motions alive that next motion looked
    # already played and left no samples (a full-suite run's trace ended 1.1 s early).
    class Played:
        def __init__(self, start: float) -> None:
            self.start_time, self.line, self.kind = start, 1, "move"

    template = nominal.samples[0]
    recorder = TraceRecorder(None, {}, dt=0.02)  # type: ignore[arg-type]
    recorder._sample = (  # type: ignore[method-assign]
        lambda motion, elapsed: dataclasses.replace(template, t=motion.start_time + elapsed)
    )
    for k in range(200):
        motion = Played(0.1 * k)
        recorder.played(motion, 0.05, False)  # type: ignore[arg-type]
        del motion
    assert sum(1 for e in recorder.events if e.kind == "start") == 200
    assert len(recorder.samples) == 800  # 0, 0.02, 0.04 and 0.05 s into each motion
