"""``synth replay --export-trajectory``: the nominal run's joint trajectory, ROS YAML and CSV.

The oracle is the replay machine itself, observed independently of the exporter: a plain
:class:`ReplayMachine` subclass in this test notes the clock and the configuration each time a
motion settles; the exported files, read back, must hold those configurations at those times.
"""

from __future__ import annotations

import csv
import itertools
from pathlib import Path

import numpy as np
import pytest
import yaml
from _paths import SEED_PROGRAM, SEED_TASK

from synth.cli import main
from synth.replay.machine import ReplayMachine
from synth.replay.run import replay_context, run_machine
from synth.replay.truth import HandErrors, nominal_world


class Observer(ReplayMachine):
    """Notes (time, configuration, AL line) where each motion ends."""

    ends: list[tuple[float, np.ndarray, int]]

    def _settle(self, motion, elapsed):  # type: ignore[no-untyped-def]
        super()._settle(motion, elapsed)
        self.ends.append((self.time(), self.configuration, motion.line))


@pytest.fixture(scope="module")
def observed() -> list[tuple[float, np.ndarray, int]]:
    context = replay_context(SEED_PROGRAM.read_text(encoding="utf-8"), SEED_TASK)
    world = nominal_world(context.graph)
    workcell = context.workcell.place(world)
    pins = {f: world.pose(f) for f in workcell.pins}
    machine = Observer(
        context.arm, workcell, pins, context.q_park, HandErrors.none(), context.options
    )
    machine.ends = []
    report, _ = run_machine(context, machine)
    assert report.outcome == "success"
    return machine.ends


def _check(times: list[float], rows: list[list[float]], observed) -> None:  # type: ignore[no-untyped-def]
    assert times[0] == 0.0
    assert all(b > a for a, b in itertools.pairwise(times))
    assert times[-1] == pytest.approx(observed[-1][0], abs=1e-9)
    for t, q, _ in observed:
        k = int(np.argmin(np.abs(np.array(times) - t)))
        assert times[k] == pytest.approx(t, abs=1e-9)
        np.testing.assert_allclose(rows[k], q, atol=1e-9)


def test_yaml_and_csv_round_trip(tmp_path: Path, observed, capsys) -> None:  # type: ignore[no-untyped-def]
    out_yaml, out_csv = tmp_path / "nominal.yaml", tmp_path / "nominal.csv"
    for out in (out_yaml, out_csv):
        code = main(
            ["replay", str(SEED_PROGRAM), "--task", str(SEED_TASK), "--trials", "0",
             "--export-trajectory", str(out)]
        )  # fmt: skip
        assert code == 0 and f"written to {out}" in capsys.readouterr().out

    doc = yaml.safe_load(out_yaml.read_text(encoding="utf-8"))
    assert doc["joint_names"] == ["theta1", "theta2", "S3", "theta4", "theta5", "theta6"]
    times = [p["time_from_start"]["sec"] + p["time_from_start"]["nanosec"] * 1e-9
             for p in doc["points"]]  # fmt: skip
    assert all(0 <= p["time_from_start"]["nanosec"] < 10**9 for p in doc["points"])
    _check(times, [p["positions"] for p in doc["points"]], observed)
    marks = doc["synth_segments"]
    assert len(marks) == len(doc["points"])

    with out_csv.open(encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    joints = doc["joint_names"]
    _check(
        [float(r["time_from_start"]) for r in rows],
        [[float(r[j]) for j in joints] for r in rows],
        observed,
    )
    # the guarded moves are the program's MOVEs with a FORCE monitor, by AL line
    text = SEED_PROGRAM.read_text(encoding="utf-8").splitlines()
    guarded_lines = {int(r["al_line"]) for r in rows if r["guarded"] == "1"}
    # In the nominal world the pin is where it is believed to be: the first attempt at BH1
    # seats it, and the search's guarded MOVE (at SETPNT) never runs.
    first_attempt = next(i for i, line in enumerate(text, 1) if line.startswith("MOVE PIN1 TO BH1"))
    assert guarded_lines == {first_attempt}
    for line in guarded_lines:
        statement = "\n".join(text[line - 1 : line + 4])
        assert statement.startswith("MOVE") and "ON FORCE(" in statement.split(";")[0]
    free_moves = {int(r["al_line"]) for r in rows if r["segment"] == "free"}
    assert free_moves and not free_moves & guarded_lines
    assert {r["segment"] for r in rows} >= {"free", "guarded", "open", "center"}
    assert [m["guarded"] for m in marks] == [r["guarded"] == "1" for r in rows]


def test_export_makes_its_directory_as_every_output_does(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    # --trace, --svg, plan -o and view -o made a missing directory; the export was refused
    out = tmp_path / "new" / "dir" / "nominal.csv"
    code = main(
        ["replay", str(SEED_PROGRAM), "--task", str(SEED_TASK), "--trials", "0",
         "--export-trajectory", str(out)]
    )  # fmt: skip
    assert code == 0 and f"written to {out}" in capsys.readouterr().out
    assert out.read_text(encoding="utf-8").startswith("time_from_start,theta1")


def test_export_refuses_an_unknown_suffix(capsys) -> None:  # type: ignore[no-untyped-def]
    code = main(
        ["replay", str(SEED_PROGRAM), "--task", str(SEED_TASK), "--export-trajectory", "x.txt"]
    )
    assert code == 2 and ".yaml or .csv" in capsys.readouterr().err
