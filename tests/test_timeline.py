"""One timeline for every machine (issue 14, item 2): where the two former copies differed.

Before the shared :mod:`synth.al.timeline`, :class:`~synth.al.machine.IdealMachine` and the
replay's machine each had their own segment times, duration rule and monitor test, and they
disagreed in four places. The replay's reading is the right one in each (the fingers and the
contact force are continuous in time; a ``WITH DURATION`` is the motion's time whatever the
arm needs), and both machines now give it. Each test checks a closed-form number on the ideal
machine and, where the replay has the same motion, on the replay's machine too:

* an ``OPENING`` monitor fires where the linearly moving fingers cross its threshold, at
  T·(w − w₀)/(w₁ − w₀) (the ideal machine fired it at the end of the motion);
* ``WITH DURATION`` stretches a hand motion (the ideal machine ignored it there);
* a motion whose segments take no time and must take t takes t (the ideal machine took 0;
  the replay's took t·(1 − 2·10⁻⁶): its quintic time law was inverted by bisection onto the
  first τ where the flat law rounds to 1);
* a force monitor fires where the rising contact force crosses its threshold, and a ``STOP``
  then leaves the force there (the ideal machine jumped to the full contact force).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_PROGRAM, SEED_TASK

from synth.al.interpreter import Interpreter
from synth.al.machine import DurationConstraint, IdealMachine, MachineCommand
from synth.al.parser import parse_program
from synth.al.timeline import duration_conflict, segment_times
from synth.replay import machine_for, replay_context, replay_program
from synth.replay.truth import HandErrors, nominal_world

OZ = 0.27801385095378626  # [N] one ounce-force: 0.028349523125 kg × 9.80665 m/s²


def run_ideal(text: str, machine: IdealMachine) -> Interpreter:
    interpreter = Interpreter(machine)
    interpreter.run(parse_program(text, filename="t.al"))
    return interpreter


def run_replay(text: str) -> tuple[Interpreter, float]:
    """Run ``text`` on the replay's machine in the seed task's nominal world: (it, hand_time)."""
    context = replay_context(SEED_PROGRAM.read_text(encoding="utf-8"), SEED_TASK)
    machine = machine_for(context, nominal_world(context.graph), HandErrors.none())
    interpreter = context.binding.interpreter(machine)
    interpreter.run(parse_program(text, filename="t.al"))
    return interpreter, context.options.hand_time


OPEN_TO_4_STOP_AT_3 = "OPEN BHAND TO 4*CM ON OPENING > 3*CM DO STOP;"


def test_an_opening_monitor_fires_where_the_fingers_cross_its_threshold() -> None:
    # fingers 0 → 4 cm in T: the opening passes 3 cm at T·(3 − 0)/(4 − 0) = 0.75 T
    ideal = IdealMachine(hand_time=0.5)
    run_ideal(OPEN_TO_4_STOP_AT_3, ideal)
    assert ideal.time() == pytest.approx(0.75 * 0.5, abs=1e-12)  # the former copy: 0.5 s
    assert ideal.opening() == pytest.approx(0.03, abs=1e-12)  # the former copy: 4 cm
    replay, hand_time = run_replay(OPEN_TO_4_STOP_AT_3)
    assert replay.machine.time() == pytest.approx(0.75 * hand_time, abs=1e-12)
    assert replay.machine.opening() == pytest.approx(0.03, abs=1e-12)


def test_with_duration_stretches_a_hand_motion() -> None:
    ideal = IdealMachine(hand_time=0.5)
    run_ideal("OPEN BHAND TO 2*CM WITH DURATION = 1.5*SEC;", ideal)
    assert ideal.time() == pytest.approx(1.5)  # the former copy: 0.5 s
    replay, _ = run_replay("OPEN BHAND TO 2*CM WITH DURATION = 1.5*SEC;")
    assert replay.machine.time() == pytest.approx(1.5)


def test_a_motion_that_needs_no_time_takes_its_duration() -> None:
    assert segment_times([0.0, 0.0], [DurationConstraint("=", 2.0)]) == [0.0, 2.0]
    assert segment_times([0.0], [DurationConstraint("≥", 2.0)]) == [2.0]
    assert segment_times([0.0], [DurationConstraint("≤", 2.0)]) == [0.0]
    ideal = IdealMachine(segment_time=0.0)
    run_ideal("MOVE BLUE TO BLUE WITH DURATION = 2*SEC;", ideal)
    assert ideal.time() == pytest.approx(2.0)  # the former copy: 0 s
    # the replay's arm needs no time to go where it is: the constraint is its time (to the
    # last bit: a segment ends at its full duration, not where the flat quintic rounds to 1)
    replay, _ = run_replay("MOVE BARM TO BARM WITH DURATION = 2*SEC;")
    assert replay.machine.time() == pytest.approx(2.0, abs=1e-12)


class Blocked(IdealMachine):
    """Every move is stopped half-way by a contact pushing up with 10 oz."""

    def contact(
        self, command: MachineCommand, path: Sequence[pin.SE3], knots: Sequence[float]
    ) -> tuple[float, np.ndarray] | None:
        return 0.5 * knots[-1], np.array([0.0, 0.0, 10 * OZ])


def test_a_stop_on_a_force_monitor_keeps_the_force_where_it_fired() -> None:
    # the force rises 0 → 10 oz at the contact; FORCE > 8 oz fires just past 8 oz, and the
    # program stops the arm there
    blocked = Blocked(segment_time=2.0)
    run_ideal("MOVE BLUE TO BLUE+VECTOR(0,0,-4) ON FORCE(ZHAT) > 8*OZ DO STOP;", blocked)
    assert blocked.time() == pytest.approx(1.0)
    assert blocked.force(np.array([0.0, 0.0, 1.0])) == pytest.approx(8 * OZ, rel=1e-9)
    # nobody watching: the motion stalls there with the full contact force
    blocked = Blocked(segment_time=2.0)
    run_ideal("MOVE BLUE TO BLUE+VECTOR(0,0,-4);", blocked)
    assert blocked.force(np.array([0.0, 0.0, 1.0])) == pytest.approx(10 * OZ, rel=1e-12)


_UP = "MOVE BMANIP TO BPARK*TRANS(NILROTN,VECTOR(0,0,5)*CM)"


def test_a_duration_shorter_than_the_arms_fastest_is_a_violation() -> None:
    # The timeline scales a motion's segments to any WITH DURATION: 5 cm in 1 ms (50 m/s) ran,
    # and the replay reported success. The time-optimal motion at the joint limits (ruckig,
    # the time the replay gives an unconstrained move) is the least the arm can take.
    free = replay_program(f"{_UP};\n", SEED_TASK)
    # the program leaves the pin in its rack: the goal is unmet, the motion itself fine
    assert free.nominal.outcome == "failure" and free.nominal.violations == ()
    fastest = free.nominal.time
    fast = replay_program(f"{_UP} WITH DURATION = 0.001*SEC;\n", SEED_TASK).nominal
    assert fast.outcome == "violation" and fast.line == 1
    assert fast.violations[0].kind == "too_fast"
    assert f"the arm needs {fastest:.4g} s" in fast.message
    # A longer one stretches it: the run takes what it asks
    slow = replay_program(f"{_UP} WITH DURATION = {2 * fastest:.6f}*SEC;\n", SEED_TASK).nominal
    assert slow.outcome == "failure" and slow.violations == ()
    assert slow.time == pytest.approx(2 * fastest, abs=1e-6)


@pytest.mark.parametrize("seconds", ["0", "-3"])
def test_a_duration_that_is_not_positive_is_a_runtime_error(seconds: str) -> None:
    report = replay_program(f"{_UP} WITH DURATION = {seconds}*SEC;\n", SEED_TASK).nominal
    assert report.outcome == "error" and report.line == 1
    assert f"DURATION = {seconds} s: a motion takes a positive time" in report.message


def test_two_durations_no_time_meets_are_a_runtime_error_at_the_later() -> None:
    # `= 2` then `= 3` ran 3 s (each constraint applied in turn, the last one's time kept):
    # the program asked for two times at once. Bounds from below and above that leave an
    # interval are kept, and give the interval's clamp (the motion alone takes `fastest`).
    fastest = replay_program(f"{_UP};\n", SEED_TASK).nominal.time
    for clauses, earlier in [
        ("DURATION = 2*SEC,\n DURATION = 3*SEC", "DURATION = 2 s (line 1)"),
        ("DURATION >= 4*SEC,\n DURATION <= 3*SEC", "DURATION ≥ 4 s (line 1)"),
        ("DURATION <= 3*SEC WITH DURATION > 1*SEC,\n DURATION = 5*SEC", "DURATION ≤ 3 s"),
    ]:
        report = replay_program(f"{_UP} WITH {clauses};\n", SEED_TASK).nominal
        assert report.outcome == "error" and report.line == 2, report.message
        assert f"contradicts {earlier}" in report.message, report.message
    low, high = 3 * fastest, 4 * fastest
    for clauses, time in [
        (f"DURATION >= {low:.6f}*SEC, DURATION <= {high:.6f}*SEC", low),
        (f"DURATION <= {high:.6f}*SEC, DURATION >= {low:.6f}*SEC", low),
        (f"DURATION = {high:.6f}*SEC, DURATION >= {low:.6f}*SEC", high),
    ]:
        report = replay_program(f"{_UP} WITH {clauses};\n", SEED_TASK).nominal
        assert report.outcome == "failure" and report.violations == (), report.message
        assert report.time == pytest.approx(time, abs=1e-6)


def test_durations_of_different_segments_do_not_conflict() -> None:
    # a via segment's own DURATION and the whole motion's are different scopes
    c = [
        DurationConstraint("=", 2.0, segment=0, line=1),
        DurationConstraint("=", 3.0, segment=None, line=1),
        DurationConstraint("≥", 1.0, segment=0, line=1),
    ]
    assert duration_conflict(c) is None
    late = DurationConstraint("<", 1.5, segment=0, line=2)
    assert duration_conflict([*c, late]) == (c[0], late)


@pytest.mark.parametrize(("width", "statement"), [("100*CM", "OPEN"), ("-1*CM", "OPEN")])
def test_an_opening_beyond_the_fingers_travel_is_a_violation(width: str, statement: str) -> None:
    # The replay clamped OPEN BHAND TO 100*CM (or −1 cm) to the fingers' travel without a word:
    # the seed's hand opens from 0 to 4.5 in = 11.43 cm (HandSpec.max_opening)
    report = replay_program(f"{statement} BHAND TO {width};\n", SEED_TASK).nominal
    assert report.outcome == "violation" and report.line == 1
    assert report.violations[0].kind == "joint_limit"
    assert "the fingers open from 0 to 11.43 cm" in report.message
    # the full travel is within it
    widest = replay_program("OPEN BHAND TO 4.5*INCHES;\n", SEED_TASK).nominal
    assert widest.outcome == "failure" and widest.violations == ()  # the pin stays in RH1
