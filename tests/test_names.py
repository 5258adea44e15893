"""AL names a task can set: one validator, full matches, no predeclared meaning rebound.

The reserved words come from the AL sources the project follows (seed-al-subset.md §1,
al-language.md §4 and §6) and from what synth's own parser and interpreter give a meaning to;
the tests check both directions: each such word is refused in every name field, with the
field named, and the interpreter knows no name the validator would let through.
"""

from __future__ import annotations

import copy
import functools
from pathlib import Path
from typing import Any

import pytest
import yaml
from _paths import SEED_TASK

from synth.al import interpreter as interpreter_module
from synth.al.builtins import BUILTINS
from synth.al.builtins import CONSTANTS as VALUE_CONSTANTS
from synth.al.evaluation import SENSORS
from synth.al.names import (
    ARM_NAMES,
    CONSTANTS,
    FUNCTIONS,
    KEYWORDS,
    RESERVED,
    UNITS,
    al_name_problem,
)
from synth.al.parser import grammar_keywords
from synth.cli import main
from synth.exceptions import SpecError
from synth.models.loader import validate_task

DOCUMENTED_PREDECLARED = (
    # seed-al-subset.md §1 and al-language.md §4: constants and the blue arm
    "XHAT YHAT ZHAT NILROTN NILROT NILTRANS NILVECT TRUE FALSE PI STATION NILDEPROACH "
    "BLUE BMANIP BARM BHAND BFINGERS BPARK "
    # al-language.md §6: the yellow arm, by symmetry
    "YELLOW YARM YMANIP YHAND YFINGERS YPARK"
).split()
DOCUMENTED_UNITS = "CM MM INCHES INCH IN DEG DEGREES RAD SEC OZ LBS GM".split()
SOME_KEYWORDS = "BEGIN END MOVE AFFIX ARRIVAL DURATION FORCE TORQUE OPENING FRAME".split()
SOME_FUNCTIONS = "ROT ROTN INV POS DISPL ORIENT TAN SQRT ATAN2 ABS".split()
EVERY_WORD = sorted(set(DOCUMENTED_PREDECLARED + DOCUMENTED_UNITS + SOME_KEYWORDS + SOME_FUNCTIONS))

CONTROL = [
    "\n",
    "\r",
    "\r\n",
    "\t",
    "\x00",
    "\x0b",
    "\x0c",
    "\x1b",
    "\x7f",
    "\x85",
    "\xa0",
    "\u2028",
    "\u2029",
    "\ufeff",
    " ",
]
"""Line breaks, C0/C1 controls, DEL, no-break and Unicode line/paragraph separators, BOM."""


@functools.cache
def _seed_parsed() -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load(SEED_TASK.read_text(encoding="utf-8"))
    return data


def seed() -> dict[str, Any]:
    """The seed task as loaded from YAML: a fresh copy each call (the tests edit it)."""
    return copy.deepcopy(_seed_parsed())


def frame_index(data: dict[str, Any], al_name: str) -> int:
    return next(i for i, f in enumerate(data["frames"]) if f["al_name"] == al_name)


FIELDS = ("frame", "manipulator", "park")


def with_name(field: str, value: str) -> tuple[dict[str, Any], str]:
    """The seed task with ``value`` as the AL name in ``field``, and that field's path."""
    data = copy.deepcopy(seed())
    if field == "frame":
        i = frame_index(data, "BH1")
        data["frames"][i]["al_name"] = value
        return data, f"frames[{i}].al_name"
    if field == "manipulator":
        data["manipulator"]["al_name"] = value
        return data, "manipulator.al_name"
    data["manipulator"]["park"]["al_name"] = value
    return data, "manipulator.park.al_name"


def refusal(data: dict[str, Any]) -> SpecError:
    with pytest.raises(SpecError) as info:
        validate_task(data)
    return info.value


# --------------------------------------------------------------------------------------------
# The reserved set covers what the parser and interpreter give a meaning to


def test_reserved_covers_every_name_the_interpreter_and_parser_define() -> None:
    interpreted = set(VALUE_CONSTANTS) | set(BUILTINS) | {"OPENING", "ARRIVAL", "DURATION"}
    interpreted |= set(SENSORS) | set(interpreter_module.HAND_NAMES)
    assert interpreted - RESERVED == set()
    assert set(grammar_keywords()) - RESERVED == set()
    assert set(DOCUMENTED_PREDECLARED) <= RESERVED
    assert set(DOCUMENTED_UNITS) == UNITS
    assert set(SOME_KEYWORDS) <= KEYWORDS and set(SOME_FUNCTIONS) <= FUNCTIONS | KEYWORDS
    assert {"TRUE", "FALSE", "ZHAT", "NILROTN"} <= CONSTANTS


# --------------------------------------------------------------------------------------------
# Every predeclared word, in every field


def own_meaning(field: str, word: str) -> bool:
    """The one exception: the arm by one of its own names, the park as BPARK."""
    return (field == "manipulator" and word in ARM_NAMES) or (field == "park" and word == "BPARK")


@pytest.mark.parametrize(
    ("field", "word"),
    [(f, w) for f in FIELDS for w in EVERY_WORD if not own_meaning(f, w)],  # those: tested below
)
def test_reserved_words_are_refused_in_every_name_field(field: str, word: str) -> None:
    for spelling in (word, word.lower(), word.capitalize()):
        data, path = with_name(field, spelling)
        error = refusal(data)
        assert error.path == path
        assert repr(spelling) in error.detail


@pytest.mark.parametrize("field", FIELDS)
def test_the_field_own_meaning_is_accepted_and_nothing_else_predeclared(field: str) -> None:
    accepted = [w for w in sorted(RESERVED) if al_name_problem(w, role=_role(field)) is None]
    expected = {"frame": [], "manipulator": sorted(ARM_NAMES), "park": ["BPARK"]}[field]
    assert accepted == expected


def _role(field: str) -> Any:
    return {"frame": "frame", "manipulator": "arm", "park": "park"}[field]


@pytest.mark.parametrize(("field", "value"), [("manipulator", "BHAND"), ("park", "bpark")])
def test_predeclared_names_of_their_own_meaning_load(field: str, value: str) -> None:
    data, _ = with_name(field, value)
    spec = validate_task(data)
    assert spec.manipulator is not None
    got = spec.manipulator.al_name if field == "manipulator" else spec.manipulator.park.al_name
    assert got == value.upper()


# --------------------------------------------------------------------------------------------
# Full matches: no control character anywhere


@pytest.mark.parametrize("field", (*FIELDS, "frame name"))
@pytest.mark.parametrize("char", CONTROL, ids=[f"U+{ord(c[0]):04X}{len(c)}" for c in CONTROL])
def test_control_characters_are_refused_anywhere_in_a_name(field: str, char: str) -> None:
    for value in (f"BH9{char}", f"{char}BH9", f"BH{char}9"):
        if field == "frame name":
            data = copy.deepcopy(seed())
            i = frame_index(data, "BH1")
            data["frames"][i]["name"] = value.lower()
            path = f"frames[{i}].name"
        else:
            data, path = with_name(field, value)
        error = refusal(data)
        assert error.path == path
        assert "control character" in error.detail


@pytest.mark.parametrize("value", ["BH1\n", "END\n", "CM\n", "TRUE\n", "ΒH1", "BH1²", "ＢＨ1"])
def test_a_name_must_match_in_full_and_be_ascii(value: str) -> None:
    # re.match(r"^…$") accepted "BH1\n" ($ matches before a final newline); Unicode letters and
    # digits (Greek capital beta, superscript two, full-width letters) are not AL identifiers.
    # Refused as such, for every role, before the keyword or unit tables are consulted
    # ("END\n" would otherwise be "an AL keyword", whatever the full match said).
    why = (
        f"{value!r} is not an AL identifier: an ASCII letter followed by letters, digits and "
        "'_', with no space or control character"
    )
    assert al_name_problem(value) == why
    assert al_name_problem(value, role="arm") == why
    assert al_name_problem(value, role="park") == why


def test_a_frame_name_may_not_be_another_frame_al_name() -> None:
    # Before: the loader read insertion.hole 'BH1' as frame bh1 (by AL name) while the graph
    # resolved 'BH1' to the frame *named* BH1 (bh2): one spelling, two frames.
    data = copy.deepcopy(seed())
    i = next(k for k, f in enumerate(data["frames"]) if f["name"] == "bh2")
    data["frames"][i]["name"] = "bh1_alias"
    validate_task(data)  # a distinct name is fine
    for clash in ("BH1", "bh1", "BPARK", "BMANIP"):
        data["frames"][i]["name"] = clash if clash != "bh1" else "Bh1"
        error = refusal(data)
        assert error.path == f"frames[{i}].name"
        assert "AL name of" in error.detail


def test_a_frame_may_share_its_own_al_name() -> None:
    data = copy.deepcopy(seed())
    i = frame_index(data, "BH1")
    data["frames"][i]["name"] = "BH1"
    assert validate_task(data).frames[i].name == "BH1"


# --------------------------------------------------------------------------------------------
# The interpreter refuses a constant as the hand, whoever builds it


def test_the_interpreter_refuses_a_constant_as_the_hand() -> None:
    from synth.al.interpreter import Interpreter

    with pytest.raises(ValueError, match="TRUE is predeclared"):
        Interpreter(machine=None, hand_names=("TRUE", *ARM_NAMES))  # type: ignore[arg-type]


# --------------------------------------------------------------------------------------------
# End to end: exit 2 naming the field, never a program


def run_cli(
    tmp_path: Path, data: dict[str, Any], capsys: pytest.CaptureFixture[str]
) -> tuple[int, str]:
    """``synth plan`` on ``data`` in this process: (exit code, stderr)."""
    task = tmp_path / "task.yaml"
    task.write_text(yaml.safe_dump(data, allow_unicode=True), encoding="utf-8")
    out = tmp_path / "x.al"
    code = main(["plan", str(task), "-o", str(out), "--proof-trials", "0", "--workers", "1"])
    return code, capsys.readouterr().err


@pytest.mark.parametrize(
    ("field", "value"), [("manipulator", "TRUE"), ("frame", "BH1\n"), ("park", "ZHAT")]
)
def test_cli_plan_refuses_a_name_that_rewrites_the_program(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], field: str, value: str
) -> None:
    # With TRUE as the arm, `FLAG ← TRUE` in the search loop assigned the hand (exit 0 before).
    data, path = with_name(field, value)
    code, stderr = run_cli(tmp_path, data, capsys)
    assert code == 2, stderr
    assert path in stderr and "Traceback" not in stderr
    assert not (tmp_path / "x.al").exists()
