"""The Monte Carlo picture (``synth replay --trials N --svg``), read back from the SVG.

The run: the tap task's program (no search) replayed on seed_4_8, whose box may be ±0.3 in,
±0.2 in, ±5° off (L2566): many trials miss the hole and abort at the program's ABORT line.
Oracles: the task's tolerances, the program text (the labelled line is its ABORT), the report's
per-trial outcomes, and the geometry of a miss (BH1's displacement by the box error).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from _paths import SEED_TAP_TASK, SEED_TASK
from _svg import SvgFigure
from _tasks import synthesized

from synth.cli import main
from synth.models.loader import load_task
from synth.pictures.montecarlo import draw_montecarlo, montecarlo_picture
from synth.pictures.render import figure_bytes
from synth.replay.report import ReplayReport
from synth.replay.run import replay_graph, replay_program, world_errors

TRIALS = 24
INCH_CM = 2.54


@pytest.fixture(scope="module")
def program() -> str:
    return synthesized(SEED_TAP_TASK).program


@pytest.fixture(scope="module")
def run(program: str) -> tuple[ReplayReport, list[dict[str, dict[str, float]]], SvgFigure]:
    report = replay_program(program, SEED_TASK, trials=TRIALS, seed=3, filename="tap.al")
    graph = replay_graph(load_task(SEED_TASK))
    errors = [world_errors(graph, 3, i) for i in range(TRIALS)]
    svg = SvgFigure(figure_bytes(draw_montecarlo(montecarlo_picture(report, errors, graph))))
    return report, errors, svg


def test_points_are_the_trials_errors_split_by_outcome(run) -> None:
    report, errors, svg = run
    outcomes = [r.outcome for r in report.trials]
    assert {"success", "abort"} <= set(outcomes)
    # axes mc-0-1: BOX x across [cm], BOX y up [cm]
    for outcome in set(outcomes):
        drawn = svg.to_data("mc-0-1", svg.uses(f"mc-0-1-{outcome}"))
        expected = np.array(
            [
                [100 * e["box"]["x"], 100 * e["box"]["y"]]
                for e, o in zip(errors, outcomes, strict=True)
                if o == outcome
            ]
        )
        np.testing.assert_allclose(drawn, expected, atol=2e-3)
    # axes mc-0-2: BOX x [cm] against BOX rz [°], inside ±0.3 in × ±5° (L2566)
    every = np.vstack([svg.to_data("mc-0-2", svg.uses(f"mc-0-2-{o}")) for o in set(outcomes)])
    assert len(every) == TRIALS
    assert np.all(np.abs(every[:, 0]) <= 0.3 * INCH_CM + 1e-3)
    assert np.all(np.abs(every[:, 1]) <= 5.0 + 1e-3)
    assert np.max(np.abs(every[:, 1])) > 2.0  # degrees, not radians


def test_failing_trials_are_labelled_with_their_abort_line(run, program: str) -> None:
    report, _, svg = run
    lines = program.splitlines()
    failing = [k for k, r in enumerate(report.trials) if not r.success]
    assert failing
    for k in failing:
        r = report.trials[k]
        (text,) = svg.texts(f"mc-0-1-label-{k}")
        assert text == f"L{r.line} {r.outcome}"
        assert "ABORT" in lines[r.line - 1]
    successes = [k for k, r in enumerate(report.trials) if r.success]
    assert not any(svg.has(f"mc-0-1-label-{k}") for k in successes)


def test_the_misses_are_the_trials_that_move_the_hole_most(run) -> None:
    report, errors, _ = run

    # BH1 at (3.85, 3.20) cm in the box: its displacement by (x, y, rz) [cm]
    def shift(e: dict[str, dict[str, float]]) -> float:
        x, y, rz = (100 * e["box"]["x"], 100 * e["box"]["y"], e["box"]["rz"])
        return math.hypot(x - rz * 3.20, y + rz * 3.85)

    hit = [shift(e) for e, r in zip(errors, report.trials, strict=True) if r.success]
    miss = [shift(e) for e, r in zip(errors, report.trials, strict=True) if not r.success]
    # a program without a search seats the pin only when the hole stays within its mouth
    # (bore radius 0.32 cm + chamfer 0.25 cm) plus the hand's ±0.05 in
    assert max(hit) <= 0.32 + 0.25 + 0.05 * INCH_CM + 0.2
    assert np.median(miss) > np.median(hit)


def test_cli_writes_the_picture_and_needs_trials(tmp_path: Path, program: str) -> None:
    al = tmp_path / "tap.al"
    al.write_text(program, encoding="utf-8")
    out = tmp_path / "mc.svg"
    args = ["replay", str(al), "--task", str(SEED_TASK), "--workers", "1", "--svg", str(out)]
    assert main([*args, "--trials", "4"]) == 0
    assert SvgFigure(out.read_bytes()).has("mc-0-1")
    assert main([*args, "--trials", "0"]) == 2


def test_a_title_with_dollars_is_drawn_as_written(run) -> None:
    # mathtext between two $ made the picture fail ("$x^$"; exit 70 from synth replay --svg)
    report, errors, _ = run
    picture = montecarlo_picture(report, errors, replay_graph(load_task(SEED_TASK)))
    title = "tap.al on $x^$"
    svg = SvgFigure(figure_bytes(draw_montecarlo(dataclasses.replace(picture, title=title))))
    assert any(t.startswith(title) for t in svg.texts())
