"""Output hygiene of the AL emitter: units, digits, names, strings, comments, the print guard."""

from __future__ import annotations

import importlib.util
import math
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_STRATEGIES, TASKS
from hypothesis import given, settings
from hypothesis import strategies as st
from jinja2 import UndefinedError

from synth.al import ast
from synth.al.interpreter import HAND_NAMES
from synth.al.names import RESERVED, UNITS, al_name_problem
from synth.al.parser import parse_program
from synth.codegen import literals as L
from synth.codegen.emitter import emit_program
from synth.codegen.environment import template_environment
from synth.exceptions import CodegenError, SpecError
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task, parse_task
from synth.strategies.records import Destination, PinInHoleStrategy

SEED_TASKS = ("seed_4_8", "seed_4_8_tap")


def _load(name: str, path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


SEED = _load("seed_strategies", SEED_STRATEGIES)


def task_path(task: str) -> Path:
    return TASKS / f"{task}.yaml"


def graph_of(task: str) -> AttributeGraph:
    return AttributeGraph(load_task(task_path(task)))


def strategy_of(task: str) -> PinInHoleStrategy:
    strategy: PinInHoleStrategy = SEED.STRATEGIES[task]()
    return strategy


def emitted_programs() -> list[ast.Program]:
    out = []
    for task in SEED_TASKS:
        for preamble in (False, True):
            text = emit_program(strategy_of(task), graph_of(task), preamble=preamble)
            out.append(parse_program(text))
    return out


# --------------------------------------------------------------------------------------------
# Units on every dimensioned number (walk the AST)


def with_parents(node: ast.Node, parents: tuple[ast.Node, ...] = ()) -> Iterator[Any]:
    yield node, parents
    for child in ast.children(node):
        yield from with_parents(child, (*parents, node))


def is_unit(node: ast.Node) -> bool:
    return isinstance(node, ast.Name) and node.name in UNITS


def scaled_by_unit(node: ast.Node | None, parent: ast.Node | None) -> bool:
    return (
        isinstance(parent, ast.BinOp)
        and parent.op == "*"
        and parent.left is node
        and is_unit(parent.right)
    )


def call_named(node: ast.Node | None, *names: str) -> bool:
    return isinstance(node, ast.Call) and node.func.name in names


def unit_problem(number: ast.Number, parents: tuple[ast.Node, ...]) -> str | None:
    """None when ``number`` carries a unit; else why not.

    A literal carries a unit when it (or its negation) is multiplied by a unit name, or is a
    component of a VECTOR(...) multiplied by a unit. The one dimensionless place is the axis
    of a rotation, ROT(VECTOR(a,b,c), angle).
    """
    chain = list(reversed(parents))
    node: ast.Node = number
    if chain and isinstance(chain[0], ast.UnaryOp) and chain[0].op == "-":
        node, chain = chain[0], chain[1:]
    parent = chain[0] if chain else None
    if scaled_by_unit(node, parent):
        return None
    if call_named(parent, "VECTOR"):
        grand = chain[1] if len(chain) > 1 else None
        if scaled_by_unit(parent, grand):
            return None
        if call_named(grand, "ROT", "ROTN") and grand.args[0] is parent:  # type: ignore[union-attr]
            return None
    return f"bare number {number.value} in {type(parent).__name__}"


def test_every_dimensioned_number_carries_a_unit() -> None:
    for program in emitted_programs():
        numbers = 0
        for node, parents in with_parents(program):
            if isinstance(node, ast.Number):
                numbers += 1
                assert unit_problem(node, parents) is None, node
        assert numbers > 30


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        # Bare: the number itself, each component of an unscaled VECTOR, and a number whose
        # parent multiplies it by a variable (the unit further up does not count).
        ("X ← 3.54;", ["bare number 3.54 in Assign"]),
        (
            "MOVE PIN1 TO BH1*TRANS(NILROTN,VECTOR(0,0,3))",
            ["bare number 0.0 in Call", "bare number 0.0 in Call", "bare number 3.0 in Call"],
        ),
        ("Y ← -2*R*CM;", ["bare number 2.0 in BinOp"]),
        # Carrying a unit: by its parent, through its VECTOR, or as a rotation's axis.
        ("Y ← -2*CM;", [None]),
        ("V ← VECTOR(1,2,3)*CM;", [None, None, None]),
        ("R ← ROT(VECTOR(0,0,1), 90*DEG);", [None, None, None, None]),
    ],
)
def test_the_unit_check_catches_bare_numbers_and_only_them(
    text: str, expected: list[str | None]
) -> None:
    program = parse_program(text)
    problems = [unit_problem(n, p) for n, p in with_parents(program) if isinstance(n, ast.Number)]
    assert problems == expected


# --------------------------------------------------------------------------------------------
# Numbers: significant digits, no exponent


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (0.169, "0.169"),
        (-1.21, "-1.21"),
        (-0.002, "-0.002"),
        (0.00106, "0.00106"),
        (60.16056848873644, "60.16"),
        (90.0, "90"),
        (180.0000000001, "180"),
        (1234.5678, "1235"),
        (123456.7, "123457"),
        (1e-9, "0"),
        (-1e-9, "0"),
        (0.0, "0"),
        (9.99996, "10"),
        (2.002, "2.002"),
    ],
)
def test_decimal_examples(value: float, text: str) -> None:
    assert L.decimal(value) == text


@settings(max_examples=300, deadline=None)
@given(st.floats(min_value=-1e7, max_value=1e7, allow_nan=False))
def test_decimal_keeps_significant_digits_and_parses_as_al(value: float) -> None:
    text = L.decimal(value)
    assert "e" not in text.lower()
    back = float(text)
    if abs(value) >= L.RESOLUTION:
        unit_in_last_place = 10.0 ** (math.floor(math.log10(abs(value))) - L.SIGNIFICANT_DIGITS + 1)
        assert abs(back - value) <= 0.5 * unit_in_last_place * (1 + 1e-9) + 1e-12
    else:
        assert back == 0.0
    magnitude = parse_program(f"X ← {text.lstrip('-')}*CM;").body[0]
    assert isinstance(magnitude, ast.Assign)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_numbers_are_refused(bad: float) -> None:
    with pytest.raises(CodegenError, match="non-finite"):
        L.length(bad, field="dtry")
    strategy = replace(strategy_of("seed_4_8"), success_threshold=bad)
    with pytest.raises(CodegenError) as info:
        emit_program(strategy, graph_of("seed_4_8"))
    assert info.value.field == "success_threshold"


def test_non_positive_thresholds_are_refused() -> None:
    for field, value in (("force_threshold", 0.0), ("success_threshold", -0.001)):
        changes: dict[str, Any] = {field: value}
        strategy = replace(strategy_of("seed_4_8"), **changes)
        with pytest.raises(CodegenError, match="positive") as info:
            emit_program(strategy, graph_of("seed_4_8"))
        assert info.value.field == field


def random_rotation(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.asarray(pin.exp3(rng.uniform(-math.pi, math.pi, 3)))


def rotation_of(text: str) -> np.ndarray:
    """Rebuild a printed rotation: NILROTN, ROT(hat, a*DEG) or ROT(VECTOR(..), a*DEG)."""
    if text == "NILROTN":
        return np.eye(3)
    assert text.startswith("ROT(") and text.endswith("*DEG)")
    head, degrees = text[4:-5].rsplit(",", 1)
    hats = {"XHAT": (1, 0, 0), "YHAT": (0, 1, 0), "ZHAT": (0, 0, 1)}
    if head in hats:
        axis = np.array(hats[head], dtype=float)
    else:
        axis = np.array([float(c) for c in head[len("VECTOR(") : -1].split(",")])
    axis /= np.linalg.norm(axis)
    return np.asarray(pin.exp3(axis * math.radians(float(degrees))))


@settings(max_examples=200, deadline=None)
@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_printed_rotations_round_trip_within_print_precision(seed: int) -> None:
    rotation = random_rotation(seed)
    back = rotation_of(L.rotation(rotation).text)
    error = float(np.linalg.norm(pin.log3(rotation.T @ back)))
    assert error < 2e-3  # four digits of axis and angle


@pytest.mark.parametrize(
    ("axis", "degrees", "text"),
    [
        ((0, 0, 1), 90, "ROT(ZHAT,90*DEG)"),
        ((0, 0, 1), -90, "ROT(ZHAT,-90*DEG)"),
        ((1, 0, 0), 180, "ROT(XHAT,180*DEG)"),
        ((0, -1, 0), 180, "ROT(YHAT,180*DEG)"),
        ((0, 0, 1), 0, "NILROTN"),
        ((-0.924, -0.383, -0.00106), 180, "ROT(VECTOR(0.9238,0.3829,0.00106),180*DEG)"),
    ],
)
def test_rotation_forms(axis: tuple[float, ...], degrees: float, text: str) -> None:
    a = np.asarray(axis, dtype=float)
    a /= np.linalg.norm(a)
    assert L.rotation(pin.exp3(a * math.radians(degrees))).text == text


# --------------------------------------------------------------------------------------------
# Names: only validated AL names of the task, the arm, AL itself, or the program's variables


def test_every_identifier_is_validated_and_known() -> None:
    for task in SEED_TASKS:
        graph = graph_of(task)
        frames = {n.upper() for n in graph.al_names.values()} | {"BPARK"}
        program = parse_program(emit_program(strategy_of(task), graph))
        assigned = {
            n.target.name for n in ast.walk(program) if isinstance(n, ast.Assign | ast.AssignExpr)
        }
        declared = {
            name.name
            for n in ast.walk(program)
            if isinstance(n, ast.Declaration)
            for name in n.names
        }
        for node in ast.walk(program):
            if isinstance(node, ast.Name) and node.name not in RESERVED:
                assert al_name_problem(node.name) is None
                assert node.name in frames | assigned | declared, node.name


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("pin", 'PIN1"); ABORT("x', "cannot be written in AL"),
        ("pin", "PIN1 }", "cannot be written in AL"),
        ("hole", "BEGIN", "keyword"),
        ("hole", "BH9", "not a frame of task"),
        ("pin", "X" * 41, "at most 40"),
        ("hand", "PIN1", "not a name of the arm"),
        ("fingers", "BH1", "not a name of the arm"),
        ("hand", "", "non-empty"),
    ],
)
def test_bad_record_names_are_rejected(field: str, value: str, message: str) -> None:
    changes: dict[str, Any] = {field: value}
    strategy = replace(strategy_of("seed_4_8"), **changes)
    with pytest.raises(CodegenError, match=message) as info:
        emit_program(strategy, graph_of("seed_4_8"))
    assert info.value.field == field


def test_bad_destination_names_are_rejected_with_their_field() -> None:
    s = strategy_of("seed_4_8")
    bad = Destination("approach", "PIN1", "BH1*TRANS", s.approach.xf)
    with pytest.raises(CodegenError) as info:
        emit_program(replace(s, approach=bad), graph_of("seed_4_8"))
    assert info.value.field == "approach.base"
    bad_grasp = Destination("grasp", "BMANIP; STOP", "PIN1", s.pickup.grasp_point.xf)
    pickup = replace(s.pickup, grasp_point=bad_grasp)
    with pytest.raises(CodegenError) as info:
        emit_program(replace(s, pickup=pickup), graph_of("seed_4_8"))
    assert info.value.field == "pickup.grasp_point.what"


def test_search_destinations_must_be_in_the_hole_frame() -> None:
    s = strategy_of("seed_4_8")
    elsewhere = Destination("target", "PIN1", "BH2", s.target.xf)
    with pytest.raises(CodegenError, match="hole frame BH1") as info:
        emit_program(replace(s, target=elsewhere), graph_of("seed_4_8"))
    assert info.value.field == "target.base"


def test_task_names_that_clash_with_program_variables_rename_the_variables() -> None:
    text = task_path("seed_4_8").read_text(encoding="utf-8")
    for old, new in (("BH2", "FLAG"), ("BH3", "SETPNT"), ("BH4", "R"), ("RTOP", "DISTANCE_OFF")):
        text = text.replace(f"al_name: {old}", f"al_name: {new}")
    graph = AttributeGraph(parse_task(text))
    program_text = emit_program(strategy_of("seed_4_8"), graph)
    program = parse_program(program_text)
    assigned = {n.target.name for n in ast.walk(program) if isinstance(n, ast.Assign)}
    assert {"FLAG1", "R1", "DISTANCE_OFF1"} <= assigned and "SETPNT1" in program_text
    assert not {"FLAG", "R", "DISTANCE_OFF", "SETPNT"} & assigned


def test_weird_task_names_never_reach_al_the_spec_rejects_them() -> None:
    text = task_path("seed_4_8").read_text(encoding="utf-8")
    for weird in ('PIN1"', "PIN-1", "PIN1 }", "BEGIN", "ZHAT", "CM"):
        with pytest.raises(SpecError) as info:
            parse_task(text.replace("al_name: PIN1", f"al_name: {weird}"))
        assert "al_name" in info.value.path


# --------------------------------------------------------------------------------------------
# Strings and comments


@pytest.mark.parametrize("value", ['say "hi"', '"', "", "PIN1 MISSED BH1 UNEXPECTEDLY.", "{x} !y!"])
def test_strings_are_escaped_and_parse_back(value: str) -> None:
    literal = L.string(value)
    (statement,) = parse_program(f"ABORT({literal.text});").body
    assert isinstance(statement, ast.Abort)
    (arg,) = statement.args
    assert isinstance(arg, ast.String) and arg.value == value


@pytest.mark.parametrize("value", ["two\nlines", "cr\r", "bell\x07", "nul\x00", "sep\u2028"])
def test_strings_with_line_breaks_or_control_characters_are_refused(value: str) -> None:
    with pytest.raises(CodegenError, match="one line"):
        L.string(value)


def test_hostile_strategy_name_and_remarks_stay_inside_their_comments() -> None:
    s = strategy_of("seed_4_8")
    name = '} ABORT("pwned"); {'
    remarks = "W = 315 } MOVE BMANIP TO NILTRANS; {\x1b[2J\n!bang!"
    strategy = replace(s, name=name, pickup=replace(s.pickup, remarks=remarks))
    text = emit_program(strategy, graph_of("seed_4_8"))
    program = parse_program(text)
    clean = parse_program(emit_program(s, graph_of("seed_4_8")))
    assert ast.without_positions(program) == ast.without_positions(clean)
    assert ') ABORT("pwned"); (' in text and "\x1b" not in text


def test_comment_fragments_cannot_close_a_comment() -> None:
    assert L.comment("a } b { c\r\nd\te\x00").text == "a ) b ( c\nd\te "


# --------------------------------------------------------------------------------------------
# The environment prints checked fragments only


@pytest.mark.parametrize("value", ["PIN1", 3.54, None, 0, ["A"], b"x"])
def test_templates_cannot_print_unchecked_values(value: object) -> None:
    template = template_environment("al").from_string("MOVE {{ x }};")
    with pytest.raises(CodegenError, match="unchecked"):
        template.render(x=value)


def test_templates_print_fragments_verbatim_and_fail_on_missing_fields() -> None:
    env = template_environment("al")
    fragment = L.Fragment('X < 1 & Y > "2"')
    assert env.from_string("{{ x }}").render(x=fragment) == 'X < 1 & Y > "2"'
    joined = env.from_string('{{ xs|join_al(", ") }}').render(xs=[L.length(0.01), L.angle(1.0)])
    assert joined == "1*CM, 57.3*DEG"
    with pytest.raises(UndefinedError, match="no attribute 'nope'"):
        env.from_string("{{ x.nope }}").render(x=fragment)


def test_the_environment_is_configured_once() -> None:
    env = template_environment("al")
    assert env is template_environment("al")
    assert env.trim_blocks and env.lstrip_blocks and env.keep_trailing_newline
    with pytest.raises(CodegenError, match="no template set"):
        template_environment("val")


def test_hand_names_known_to_the_interpreter_are_the_arm_names() -> None:
    assert {"BMANIP", "BHAND"} <= set(HAND_NAMES)
