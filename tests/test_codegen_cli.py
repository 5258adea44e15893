"""``synth plan TASK.yaml -o PROGRAM.al [--preamble] [--json]``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from _paths import GOLDEN, SEED_TASK

from synth.al.parser import parse_program
from synth.cli import main


def test_plan_writes_the_program_and_still_prints_the_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out" / "seed_4_8.al"  # the directory is created
    assert main(["plan", str(SEED_TASK), "--proof-trials", "0", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "Decisions:" in printed and f"AL program written to {out}" in printed
    text = out.read_text(encoding="utf-8")
    parse_program(text)
    assert text == (GOLDEN / "seed_4_8.al").read_text(encoding="utf-8")


def test_plan_json_carries_the_program_and_preamble_makes_it_stand_alone(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["plan", str(SEED_TASK), "--proof-trials", "0", "--json", "--preamble"]) == 0
    document = json.loads(capsys.readouterr().out)
    program = document["program"]
    assert program.startswith("{ World binding of task seed_4_8")
    assert "FRAME BOX" in program and "MOVE PIN1 TO BH1*TRANS(" in program
    parse_program(program)
    assert document["strategy"]["search"] is not None


def test_plan_without_preamble_json_program_is_the_bare_program(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["plan", str(SEED_TASK), "--proof-trials", "0", "--json"]) == 0
    program = json.loads(capsys.readouterr().out)["program"]
    # The golden file is this very program (scripts/regen_golden.py: the nominal proof's
    # program, without a preamble), so the JSON carries it byte for byte.
    assert program.startswith("{ PIN-IN-HOLE STRATEGY")
    assert program == (GOLDEN / "seed_4_8.al").read_text(encoding="utf-8")


def test_plan_output_that_cannot_be_written_is_a_clean_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # Refused before any work (a plan with its proof takes seconds to minutes; Hunt A found the
    # path checked only after it): synthesize is never called, and nothing is made
    import synth.pipeline

    def no_work(*_args: object, **_kwargs: object) -> None:
        raise AssertionError("planned before checking the output path")

    monkeypatch.setattr(synth.pipeline, "synthesize", no_work)
    blocker = tmp_path / "file"
    blocker.write_text("x", encoding="utf-8")
    target = blocker / "sub" / "p.al"
    assert main(["plan", str(SEED_TASK), "-o", str(target)]) == 2
    err = capsys.readouterr().err
    assert err == f"synth plan: error: --output {target}: {blocker} is not a directory\n"
    assert main(["plan", str(SEED_TASK), "--svg", str(tmp_path)]) == 2
    assert capsys.readouterr().err == f"synth plan: error: --svg {tmp_path}: is a directory\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
    # a path under directories still to be made is fine: they are made at the end
    monkeypatch.undo()
    made = tmp_path / "a" / "b" / "p.al"
    assert main(["plan", str(SEED_TASK), "--proof-trials", "0", "-o", str(made)]) == 0
    assert made.read_text(encoding="utf-8") == (GOLDEN / "seed_4_8.al").read_text(encoding="utf-8")
