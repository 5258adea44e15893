"""The referee never turns the wrist in no time (tests/data/tasks/grasp_at_the_wrist_stop.yaml).

A grasp that leaves θ6 0.017° from its stop: in the worlds where the hand's error asks θ6 past
it, CENTER's centring move, or the arm complying as the pin leaves the rack's hole, can only be
made on the other wrist branch. The replay set that branch's joints between two instants (θ4,
θ6 turned 180°) and went on; a real arm cannot, so those are ``joint_limit`` violations now.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _paths import DATA_TASKS

import synth.replay.machine as machine
from synth.models.loader import load_task
from synth.pipeline import SynthesisOptions, synthesize
from synth.replay import replay_context, run_trial
from synth.replay.proof import ProofOptions
from synth.replay.reach import BRANCH_JUMP
from synth.replay.trace import record_run

TASK = DATA_TASKS / "grasp_at_the_wrist_stop.yaml"
PROGRAM = DATA_TASKS.parent / "written" / "grasp_at_the_wrist_stop.al"  # synth wrote it
SEED = 12345


@pytest.fixture(scope="module")
def context():
    return replay_context(PROGRAM.read_text(encoding="utf-8"), load_task(TASK))


def test_the_grasp_leaves_the_wrist_at_its_stop(context) -> None:
    # the nominal run's configuration at CENTER (line 11): θ6 within the hand's 0.25° rz error
    # of its lower stop, so a hand error turning the other way needs θ6 past it
    trace = record_run(context).to_json()
    at_center = [s["q"] for s in trace["samples"] if s["line"] == 11]
    theta6 = at_center[-1][5]
    lower = float(context.arm.limits.lower[5])
    assert math.degrees(lower) == pytest.approx(-165.0)
    assert 0.0 <= theta6 - lower < math.radians(0.25)


def test_centring_past_the_stop_is_a_joint_limit_violation(context) -> None:
    run = run_trial(context, SEED, 0)
    assert run.outcome == "violation" and run.line == 11, run.message
    assert run.violations[0].kind == "joint_limit"
    assert "centring the hand" in run.message and "theta6 by 180°" in run.message


def test_complying_past_the_stop_is_a_joint_limit_violation(context) -> None:
    # trial 17: the centring is made on the branch, but lifting the pin out of RH1 (line 15) the
    # hole turns the hand a little further: the arm left its branch there
    run = run_trial(context, SEED, 17)
    assert run.outcome == "violation" and run.line == 15, run.message
    assert run.violations[0].kind == "joint_limit" and "complying with RH1" in run.message


def test_no_trial_turns_a_joint_between_two_samples(context) -> None:
    # Independent of the check: the recorded joints of trials 0–19 (every 20 ms) never turn a
    # revolute joint more than BRANCH_JUMP between two samples; the successes kept their branch
    for trial in range(20):
        trace = record_run(context, trial=trial, seed=SEED).to_json()
        q = np.array([s["q"] for s in trace["samples"]])
        turned = np.abs(np.diff(q, axis=0))[:, [0, 1, 3, 4, 5]]  # S3 (index 2) slides
        assert float(turned.max()) < BRANCH_JUMP, trial


def test_a_denser_compliance_check_finds_nothing_more(context, monkeypatch) -> None:
    # The compliance is checked at 9 points of each guided phase, and not at all along segments
    # 5.7° from every stop: at 65 points on every segment, trials 0–39 end the same way
    def outcomes() -> list[tuple[str, int | None]]:
        return [(r.outcome, r.line) for r in (run_trial(context, SEED, i) for i in range(40))]

    sampled = outcomes()
    monkeypatch.setattr(machine, "_COMPLIANCE_POINTS", 65)
    monkeypatch.setattr(machine, "_STOP_MARGIN", math.inf)  # no segment skipped
    assert outcomes() == sampled
    assert 10 <= sum(o == "violation" for o, _ in sampled) <= 30  # about half (module docstring)


@pytest.mark.slow
def test_synth_no_longer_writes_the_program(tmp_path) -> None:
    # With proof seed 13 synth wrote this grasp (proven 100 of 100, every "success" with a wrist
    # turned in no time); its proof now fails and the next grasp is written
    made = synthesize(TASK, SynthesisOptions(proof=ProofOptions(trials=100, seed=13)))
    assert made.proof.passed
    assert made.strategy.pickup.grasp.omega != pytest.approx(math.radians(45))
