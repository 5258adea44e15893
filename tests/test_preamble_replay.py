"""A stand-alone program (the world binding printed before it) replays like the bare one.

``synth plan --preamble`` writes :func:`synth.codegen.binding.preamble` before the program; the
replay binds the same frames from the task. A top-level declaration of a bound frame with its
type adopts it, so both texts run the same motions: the same outcome and simulated time, and
the preamble's statements on top of the bare program's count.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from _paths import SEED_FIRST_CUT, SEED_TASK

from synth.al import ast
from synth.al.parser import parse_program
from synth.cli import main
from synth.codegen.binding import bind_world, preamble
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task
from synth.replay import replay_program


def top_level(text: str) -> tuple[ast.Stmt, ...]:
    """The statements of a flat program (no blocks: each runs once)."""
    program = parse_program(text)
    assert all(not isinstance(s, ast.Block) for s in program.body)
    return program.body


def test_preamble_before_a_program_replays_like_the_program() -> None:
    graph = AttributeGraph(load_task(SEED_TASK))
    bare = SEED_FIRST_CUT.read_text(encoding="utf-8")
    head = preamble(graph)
    alone = replay_program(bare, SEED_TASK)
    with_head = replay_program(head + "\n" + bare, SEED_TASK)
    assert alone.nominal.outcome == with_head.nominal.outcome == "success"
    assert with_head.nominal.time == pytest.approx(alone.nominal.time, abs=1e-9)
    # Each preamble statement runs once: the declarations, then one assignment or AFFIX a frame.
    statements = top_level(head)
    assert with_head.nominal.statements - alone.nominal.statements == len(statements)
    assigned = [s for s in statements if not isinstance(s, ast.Declaration)]
    assert len(assigned) == len(bind_world(graph).frames)


@pytest.mark.parametrize(
    ("program", "message"),
    [
        ("FRAME BOX, BOX;", "BOX is declared twice"),
        ("FRAME BOX; BEGIN FRAME RACK; END; FRAME BOX;", "BOX is declared twice"),
        ("VECTOR BOX;", "BOX is the task's FRAME; it cannot be a VECTOR"),
    ],
)
def test_a_bound_frame_is_adopted_once_and_only_with_its_type(program: str, message: str) -> None:
    report = replay_program(program, SEED_TASK)
    assert report.nominal.outcome == "error"
    assert message in report.nominal.message


def test_a_program_may_still_declare_its_own_frames_twice_in_nested_blocks() -> None:
    # Shadowing in an inner block is a new variable, not the binding's frame.
    report = replay_program(
        "BEGIN FRAME BOX; BOX ← FRAME(NILROTN, VECTOR(0,0,1)*CM); END;", SEED_TASK
    )
    assert report.nominal.outcome != "error", report.nominal.message


def test_cli_plan_preamble_output_replays(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Before: "BOX is declared twice in this block" (exit 2) for every --preamble output.
    out = tmp_path / "x.al"
    args = ["--preamble", "-o", str(out), "--proof-trials", "0", "--workers", "1"]
    assert main(["plan", str(SEED_TASK), *args]) == 0, capsys.readouterr().err
    assert out.read_text(encoding="utf-8").startswith("{ World binding of task seed_4_8")
    capsys.readouterr()
    replayed = ["replay", str(out), "--task", str(SEED_TASK), "--trials", "0", "--workers", "1"]
    assert main(replayed) == 0
    assert "nominal: success: PIN1 seated in BH1" in capsys.readouterr().out
