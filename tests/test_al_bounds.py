"""AL inputs that once crashed or ran for hours: depth, huge literals, budgets."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest
from _paths import SEED_TASK

from synth.al import ast
from synth.al.interpreter import MAX_TIME, MAX_WALL_TIME, Interpreter
from synth.al.machine import IdealMachine
from synth.al.parser import parse_program
from synth.al.values import Scalar
from synth.exceptions import ALRuntimeError, ALSyntaxError
from synth.replay.machine import ReplayOptions
from synth.replay.run import replay_program

# The seed's grasp approach (tests/data/al/seed_4_8_search.al, line 26) and a point above it.
GRASP = "PIN1*TRANS(ROTN(VECTOR(.924,.383,.001),180.*DEG),VECTOR(0,0,{}))"
MOVE_LOOP = f"""SCALAR N;
WHILE TRUE DO
  BEGIN
    MOVE BMANIP TO {GRASP.format(8.62)};
    MOVE BMANIP TO {GRASP.format(12)};
  END;
"""


def nested(kind: str, depth: int) -> str:
    """A two-line program whose second line nests ``kind`` ``depth`` times."""
    inner = {
        "NOT": "B ← " + "NOT " * depth + "TRUE;",
        "ABS": "S ← " + "ABS(" * depth + "1" + ")" * depth + ";",
        "IF": "IF TRUE THEN " * depth + "S ← 1;",
        "BEGIN": "BEGIN " * depth + "S ← 1 " + "END " * depth,
    }[kind]
    return "SCALAR S; BOOLEAN B;\n" + inner + "\n"


@pytest.mark.parametrize("kind", ["NOT", "ABS", "IF", "BEGIN"])
def test_nesting_1000_deep_is_a_syntax_error_naming_the_line(kind: str) -> None:
    with pytest.raises(ALSyntaxError, match=f"nested more than {ast.MAX_NESTING} levels") as e:
        parse_program(nested(kind, 1000), filename="deep.al")
    assert e.value.line == 2 and e.value.column > 1 and "^" in e.value.context


@pytest.mark.parametrize("kind", ["NOT", "ABS", "IF", "BEGIN"])
def test_nesting_at_the_limit_parses_and_runs(kind: str) -> None:
    # The statement adds one level (two for the BEGIN's body), the literal one more.
    program = parse_program(nested(kind, ast.MAX_NESTING - 3), filename="deep.al")
    assert ast.too_deep(program) is None
    interpreter = Interpreter(IdealMachine())
    result = interpreter.run(program)  # no RecursionError
    assert result.completed
    # And the deep line computed what it says: 97 NOTs of TRUE are FALSE (odd count);
    # ABS(ABS(…1…)) is 1; the IF chain and the nested blocks reach S ← 1.
    if kind == "NOT":
        assert ast.MAX_NESTING - 3 == 97 and interpreter.value("B") is False
    else:
        assert interpreter.value("S") == Scalar(1.0)


def test_the_interpreter_refuses_a_deep_tree_built_by_code() -> None:
    expr: ast.Expr = ast.Name("TRUE", line=3, column=9)
    for _ in range(1000):
        expr = ast.UnaryOp("NOT", expr, line=3, column=5)
    program = ast.Program((ast.Assign(ast.Name("B"), expr, line=3, column=1),))
    with pytest.raises(ALRuntimeError, match="nested more than 100 levels") as e:
        Interpreter(IdealMachine()).run(program)
    assert (e.value.line, e.value.column) == (3, 5)


def test_too_deep_finds_the_first_node_past_the_limit() -> None:
    program = parse_program("B ← NOT NOT NOT TRUE;")
    # Program > Assign > NOT > NOT > NOT > TRUE: the TRUE is 5 levels down.
    assert ast.too_deep(program, 5) is None
    deep = ast.too_deep(program, 4)
    assert isinstance(deep, ast.Name) and deep.name == "TRUE"


def test_a_309_digit_literal_is_a_syntax_error_naming_the_line() -> None:
    assert parse_program("S ← " + "9" * 308 + ";").body[0].value.value > 1e307  # type: ignore[attr-defined]
    with pytest.raises(ALSyntaxError, match="309 digits") as e:
        parse_program("SCALAR S;\nS ← 2*" + "9" * 309 + ";\n", filename="big.al")
    assert (e.value.line, e.value.column) == (2, 7)
    assert str(e.value).startswith("big.al:2:7: ")


def test_simulated_time_budget_stops_a_loop_of_moves() -> None:
    interpreter = Interpreter(IdealMachine(), max_time=30.0)
    text = "WHILE TRUE DO\n  MOVE BMANIP TO BMANIP*TRANS(NILROTN, VECTOR(0,0,10));\n"
    with pytest.raises(ALRuntimeError, match="more than 30 s of simulated time") as e:
        interpreter.run(parse_program(text))
    assert e.value.line == 2
    # IdealMachine moves take 1 s each: 31 run (the clock passes 30 s), the 32nd is refused,
    # counted after the WHILE: 1 + 31 + 1 statements, not 10⁶.
    assert interpreter.statements == 1 + 31 + 1


def test_wall_clock_budget_stops_a_loop_that_takes_no_simulated_time() -> None:
    interpreter = Interpreter(IdealMachine(), max_statements=10**12, max_wall_time=0.5)
    start = time.monotonic()
    with pytest.raises(ALRuntimeError, match=r"more than 0\.5 s of computing time") as e:
        interpreter.run(parse_program("SCALAR X;\nWHILE TRUE DO\n  X ← 1;\n"))
    assert e.value.line in (2, 3)
    assert time.monotonic() - start < 30  # [s] a budget, not a speed test: generous
    assert MAX_TIME == 600 and MAX_WALL_TIME == 20  # the documented defaults


def test_replay_of_a_move_loop_ends_at_the_simulated_budget_naming_the_line() -> None:
    report = replay_program(
        MOVE_LOOP, SEED_TASK, options=ReplayOptions(max_time=20.0), filename="loop.al"
    )
    nominal = report.nominal
    assert nominal.outcome == "error" and nominal.line in (3, 4, 5)  # the loop body's lines
    assert "more than 20 s of simulated time" in nominal.message
    assert 20.0 < nominal.time < 25.0  # [s] stopped at the first statement past the budget


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "synth.cli", *args],
        capture_output=True,
        text=True,
        timeout=120,  # [s] generous; these fail in milliseconds after start-up
        check=False,
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (nested("NOT", 1000), "deep.al:2:"),
        ("SCALAR S;\nS ← 2*" + "9" * 309 + ";\n", "deep.al:2:7: the number literal"),
    ],
    ids=["deep-nesting", "309-digits"],
)
def test_cli_exits_2_on_deep_nesting_and_huge_literals(
    tmp_path: Path, text: str, message: str
) -> None:
    program = tmp_path / "deep.al"
    program.write_text(text, encoding="utf-8")
    done = _cli("replay", str(program), "--task", str(SEED_TASK), "--trials", "0")
    assert done.returncode == 2, done.stderr
    assert message in done.stderr and "Traceback" not in done.stderr


def test_a_byte_that_is_not_utf8_is_reported_at_line_and_column(tmp_path: Path) -> None:
    program = tmp_path / "bad.al"
    program.write_bytes("SCALAR S;\nS ← 1 ".encode() + b"\xff;\n")
    done = _cli("replay", str(program), "--task", str(SEED_TASK), "--trials", "0")
    assert done.returncode == 2
    assert f"{program}:2:7: byte 0xff is not UTF-8" in done.stderr
    assert "position" not in done.stderr  # the codec's byte offset


def test_lines_ended_by_a_lone_cr_are_counted_as_lines() -> None:
    with pytest.raises(ALSyntaxError) as e:
        parse_program("SCALAR S;\rS ← 1;\rS ← ;\r", filename="cr.al")
    assert (e.value.line, e.value.column) == (3, 5)  # was 1:22, an offset into the text
    with pytest.raises(ALSyntaxError) as e:
        parse_program("SCALAR S;\r\nS ← 1;\r\nS ← ;\r\n", filename="crlf.al")
    assert (e.value.line, e.value.column) == (3, 5)
