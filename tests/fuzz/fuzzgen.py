"""Hypothesis generators of hostile inputs: task specs, AL programs (the API's come from its
OpenAPI schema through schemathesis, in :mod:`fuzzrun`).

Task specs are *structural mutations* of the fixture tasks: one to three edits, each replacing a
node with an extreme value (numbers that overflow after unit conversion, zero, NaN, unknown
units, expressions, wrong dimensions), a hostile name (AL keywords, predeclared names, control
characters), a deep nest, or deleting or duplicating a node. AL programs are mutations of the
golden programs: lines deleted, duplicated or swapped, numbers made extreme, names replaced by
keywords, deep nesting, endless loops, truncation and stray characters.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from _paths import DATA_TASKS, TASKS
from _paths import GOLDEN as GOLDEN_DIR
from hypothesis import strategies as st

TASK_FILES = tuple(sorted(TASKS.glob("*.yaml")) + sorted(DATA_TASKS.glob("*.yaml")))
GOLDEN = tuple(sorted(GOLDEN_DIR.glob("*.al")))
"""The golden programs the AL mutations start from."""

EXTREME_QUANTITIES = (
    "1e300 lightyear",
    "1e308 m",
    "1e-300 cm",
    "1e-9 cm",
    "0 cm",
    "-0 cm",
    "-5 cm",
    "nan cm",
    "inf deg",
    "9**9**9 cm",
    "2 * 3 cm",
    "1e400 cm",
    "181 deg",
    "720 deg",
    "-1e-300 deg",
    "5 furlong",
    "3 kg",
    "1 cm/s",
    "8 oz",
    "1 parsec",
    "0x10 cm",
    "1_000 cm",
    "cm",
    "",
    " 1 cm ",
    "1 cm\n",
    "1e300 rad/s",
    "1e-300 rad/s**3",
)
HOSTILE_NAMES = (
    "TRUE",
    "FALSE",
    "ZHAT",
    "XHAT",
    "NILROTN",
    "BHAND",
    "BMANIP",
    "CM",
    "DEG",
    "END",
    "BEGIN",
    "MOVE",
    "IF",
    "BH1",
    "BH1\n",
    "CM\n",
    "END\n",
    "A\x00B",
    "A B",
    "A;B",
    "{X}",
    '"X"',
    "Ä",
    "_",
    "1ABC",
    "",
    "A" * 300,
    "world",
)
SCALARS: st.SearchStrategy[Any] = (
    st.sampled_from(EXTREME_QUANTITIES)
    | st.sampled_from(HOSTILE_NAMES)
    | st.none()
    | st.booleans()
    | st.integers(-(2**70), 2**70)
    | st.floats()
    | st.text(max_size=12)
)


@dataclass(frozen=True)
class SpecCase:
    """A mutated task: its YAML text, the fixture it came from, and a CLI command for it."""

    source: str
    text: str
    argv_tail: tuple[str, ...]  # the command's arguments after the task path


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every path (keys and indices) to a node of a YAML tree, the root included."""
    found = [prefix]
    if isinstance(node, dict):
        for key, value in node.items():
            found.extend(_paths(value, (*prefix, key)))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            found.extend(_paths(value, (*prefix, i)))
    return found


def _replace(node: Any, path: tuple[Any, ...], edit: Any) -> Any:
    """``node`` with the subtree at ``path`` passed through ``edit`` (a copy; None drops it)."""
    if not path:
        return edit(node)
    head, rest = path[0], path[1:]
    if isinstance(node, dict):
        copy = dict(node)
        new = _replace(node[head], rest, edit)
        if new is _DROP:
            del copy[head]
        else:
            copy[head] = new
        return copy
    copy_list = list(node)
    new = _replace(node[head], rest, edit)
    if new is _DROP:
        del copy_list[head]
    elif new is _DUPLICATE:
        copy_list.insert(head, node[head])
    else:
        copy_list[head] = new
    return copy_list


_DROP = object()
_DUPLICATE = object()


def _nest_marker(depth: int) -> str:
    """A placeholder for a list nested ``depth`` deep, spliced in as flow YAML by :func:`_dump`.

    The nest itself never enters the Python tree: walking or dumping a tree 1 200 deep raises
    RecursionError at a depth that depends on the caller's stack, and Hypothesis (rightly)
    reports a strategy whose draws change with the stack as flaky.
    """
    return f"NEST{depth}NEST"


_NEST = re.compile(r"NEST(\d+)NEST")


def _dump(tree: Any) -> str:
    """The mutated tree as YAML text, each nest marker replaced by its nested flow list."""
    text = yaml.safe_dump(tree, sort_keys=False, allow_unicode=True)
    return _NEST.sub(lambda m: "[" * int(m[1]) + "1 cm" + "]" * int(m[1]), text)


def _scale(node: Any, exponent: int) -> Any:
    """A quantity string with its number times 10**exponent; other nodes unchanged."""
    if isinstance(node, str):
        number, _, unit = node.strip().partition(" ")
        try:
            return f"{float(number) * 10.0**exponent!r} {unit}".strip()
        except (ValueError, OverflowError):
            return f"{number}e{exponent} {unit}".strip()
    return node


@st.composite
def _mutation(draw: st.DrawFn, tree: Any) -> Any:
    path = draw(st.sampled_from(_paths(tree)))
    kind = draw(
        st.sampled_from(("value", "value", "scale", "name", "drop", "duplicate", "nest", "empty"))
    )
    if kind == "value":
        value = draw(SCALARS)
        return _replace(tree, path, lambda _n: value)
    if kind == "scale":
        exponent = draw(st.integers(-320, 320))
        return _replace(tree, path, lambda n: _scale(n, exponent))
    if kind == "name":
        name = draw(st.sampled_from(HOSTILE_NAMES))
        return _replace(tree, path, lambda _n: name)
    if kind in ("drop", "duplicate") and path:
        marker = _DROP if kind == "drop" else _DUPLICATE
        if kind == "duplicate" and not isinstance(path[-1], int):
            return tree
        return _replace(tree, path, lambda _n: marker)
    if kind == "nest":
        depth = draw(st.sampled_from((2, 10, 50, 300, 1200)))
        return _replace(tree, path, lambda _n: _nest_marker(depth))
    if kind == "empty":
        empty = draw(st.sampled_from(([], {}, "", None)))
        return _replace(tree, path, lambda _n: empty)
    return tree


def _load(path: Path) -> Any:
    return yaml.safe_load(path.read_text())


_TREES = {path: _load(path) for path in TASK_FILES}


def _frame_names(tree: Any) -> list[str]:
    frames = tree.get("frames") if isinstance(tree, dict) else None
    names = [f["name"] for f in frames or () if isinstance(f, dict) and "name" in f]
    return [str(n) for n in names] or ["world"]


@st.composite
def task_specs(draw: st.DrawFn) -> SpecCase:
    """A fixture task with 1–3 structural mutations, and an ``errors``/``locate``/``plan`` run."""
    source = draw(st.sampled_from(TASK_FILES))
    original = _TREES[source]
    tree = original
    for _ in range(draw(st.integers(1, 3))):
        tree = draw(_mutation(tree))
    try:
        text = _dump(tree)
    except yaml.YAMLError:
        text = repr(tree)
    command = draw(st.sampled_from(("errors", "errors", "locate", "plan")))
    if command == "errors":
        names = _frame_names(original)
        tail: tuple[str, ...] = (
            "--from",
            draw(st.sampled_from(names)),
            "--to",
            draw(st.sampled_from(names)),
        )
    elif command == "plan":
        tail = ("--proof-trials", "0", "--workers", "1")
    else:
        tail = ()
    return SpecCase(source.name, text, (command, *tail))


# -- AL programs --------------------------------------------------------------------------------

AL_NUMBERS = ("1e309", "9" * 309, "0", "-0", "1e-300", "0.0000001", "1E30", "999999999999")
AL_WORDS = ("TRUE", "ZHAT", "NILROTN", "BHAND", "END", "BEGIN", "CM", "PIN1", "BH1", "X", "UNDEF")


@dataclass(frozen=True)
class ALCase:
    """A mutated AL program and the task it is replayed against."""

    source: str
    program: str
    task: Path


def _golden_task(program: Path) -> Path:
    return TASKS / f"{program.stem}.yaml"


_PROGRAMS = {path: path.read_text() for path in GOLDEN}


@st.composite
def _al_edit(draw: st.DrawFn, text: str) -> str:
    lines = text.split("\n")
    i = draw(st.integers(0, max(0, len(lines) - 1)))
    kind = draw(
        st.sampled_from(
            ("drop", "duplicate", "swap", "number", "word", "nest", "loop", "cut", "chars")
        )
    )
    if kind == "drop":
        del lines[i]
    elif kind == "duplicate":
        lines.insert(i, lines[i])
    elif kind == "swap":
        j = draw(st.integers(0, len(lines) - 1))
        lines[i], lines[j] = lines[j], lines[i]
    elif kind == "number":
        numbers = list(re.finditer(r"\d+(\.\d+)?", text))
        if numbers:
            hit = draw(st.sampled_from(numbers))
            new = draw(st.sampled_from(AL_NUMBERS))
            return text[: hit.start()] + new + text[hit.end() :]
    elif kind == "word":
        words = list(re.finditer(r"\b[A-Z][A-Z0-9_]*\b", text))
        if words:
            hit = draw(st.sampled_from(words))
            return text[: hit.start()] + draw(st.sampled_from(AL_WORDS)) + text[hit.end() :]
    elif kind == "nest":
        depth = draw(st.sampled_from((5, 50, 400, 1100)))
        form = draw(st.sampled_from(("NOT", "ABS", "IF", "BEGIN")))
        if form == "NOT":
            stmt = "FLAG ← " + "NOT " * depth + "TRUE;"
        elif form == "ABS":
            stmt = "R ← " + "ABS(" * depth + "1" + ")" * depth + ";"
        elif form == "IF":
            stmt = "IF TRUE THEN " * depth + "R ← 1;"
        else:
            stmt = "BEGIN " * depth + "R ← 1;" + " END" * depth + ";"
        lines.insert(i, stmt)
    elif kind == "loop":
        lines.insert(
            i, "WHILE TRUE DO BEGIN MOVE BMANIP TO BMANIP*TRANS(NILROTN,VECTOR(0,0,0.1)*CM); END;"
        )
    elif kind == "cut":
        return text[: draw(st.integers(0, len(text)))]
    else:
        at = draw(st.integers(0, len(text)))
        junk = draw(st.text(alphabet="{}();←\"'\\\x00\n*.,<>=", min_size=1, max_size=4))
        return text[:at] + junk + text[at:]
    return "\n".join(lines)


@st.composite
def al_programs(draw: st.DrawFn) -> ALCase:
    """A golden program with 1–3 edits, replayed against its own task."""
    source = draw(st.sampled_from(GOLDEN))
    text = _PROGRAMS[source]
    for _ in range(draw(st.integers(1, 3))):
        text = draw(_al_edit(text))
    return ALCase(source.name, text, _golden_task(source))


__all__ = ["GOLDEN", "TASK_FILES", "ALCase", "SpecCase", "al_programs", "task_specs"]
