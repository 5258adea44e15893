"""The one task loader (CLI and service): YAML bombs, depth and size limits."""

from __future__ import annotations

import subprocess
import sys
import tracemalloc
from pathlib import Path

import pytest
import yaml
from _paths import DATA, SEED_TASK, TASKS

from server.service import YAML_LIMITS, parse_spec
from synth.exceptions import SpecError
from synth.models.loader import load_task, parse_task
from synth.models.yamlread import DEFAULT_LIMITS, WITH_LIBYAML, YamlLimits, read_yaml

TASK_FILES = sorted(TASKS.rglob("*.yaml")) + sorted(DATA.glob("*.yaml"))


def billion_laughs(levels: int = 9) -> str:
    """The classic: each level's list repeats the previous level's anchor nine times."""
    text = "a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n"
    for i in range(1, levels):
        name, prev = chr(ord("a") + i), chr(ord("a") + i - 1)
        text += f"{name}: &{name} [{', '.join([f'*{prev}'] * 9)}]\n"
    return text


DEEP_FLOW = "name: t\nframes: " + "[" * 1000 + "]" * 1000 + "\n"
DEEP_BLOCK = "".join("  " * i + "k:\n" for i in range(1000)) + "  " * 1000 + "x\n"
HUGE_LIST = "name: t\nframes:\n" + "- {name: f}\n" * 50_000

BOMBS = {
    "billion laughs": (billion_laughs(), "expands to more than"),
    "recursive alias": ("name: t\nframes: &f [*f]\n", "recursive alias"),
    "recursive mapping alias": ("name: t\nm: &m {self: *m}\n", "recursive alias"),
    "deep flow nesting": (DEEP_FLOW, "nested deeper than 32 levels"),
    "deep block nesting": (DEEP_BLOCK, "nested deeper than 32 levels"),
    "huge list": (HUGE_LIST, "list longer than 10000 items"),
}


def test_the_parser_is_libyaml_when_pyyaml_has_it() -> None:
    assert hasattr(yaml, "CSafeLoader") == WITH_LIBYAML


@pytest.mark.parametrize("path", TASK_FILES, ids=lambda p: p.name)
def test_values_are_those_of_safe_load(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    assert read_yaml(text).data == yaml.safe_load(text)


def test_lines_name_where_each_field_starts() -> None:
    doc = read_yaml("name: t\nframes:\n  - name: a\n    parent: world\n  - name: b\n")
    assert doc.lines[()] == 1 and doc.lines[("name",)] == 1 and doc.lines[("frames",)] == 2
    assert doc.lines[("frames", 0)] == 3 and doc.lines[("frames", 0, "parent")] == 4
    assert doc.lines[("frames", 1, "name")] == 5


@pytest.mark.parametrize("name", sorted(BOMBS))
def test_bombs_are_refused_naming_the_problem(name: str) -> None:
    text, fragment = BOMBS[name]
    with pytest.raises(SpecError, match=fragment) as caught:
        parse_task(text)
    assert caught.value.line == BOMB_LINES[name]


BOMB_LINES = {
    # Levels a, b, c, … expand to 10, 91, 820, 7381, 66430, 597871 nodes (n_k = 1 + 9·n_{k−1},
    # test_expansion_is_counted_through_aliases): with the root and its keys, 74 738 nodes
    # after line 5 (e) and over the 100 000 limit at line 6 (f).
    "billion laughs": 6,
    "recursive alias": 2,
    "recursive mapping alias": 2,
    "deep flow nesting": 2,  # all 1000 brackets are on the frames line
    "deep block nesting": 33,  # line k opens the k-th nested mapping; 32 is the limit
    "huge list": 3 + 10_000,  # items start on line 3; item 10 001 is one too many
}


def test_billion_laughs_is_refused_in_bounded_memory() -> None:
    tracemalloc.start()
    try:
        with pytest.raises(SpecError):
            read_yaml(billion_laughs())
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 4 << 20  # [byte]; expanded, the document is 10^9 strings


def test_expansion_is_counted_through_aliases() -> None:
    # 4 levels. As expanded: the root mapping and its 4 keys; a = 1 list + 9 scalars = 10;
    # b = 1 + 9·10 = 91; c = 1 + 9·91 = 820; d = 1 + 9·820 = 7381. In all 5 + 8302 = 8307.
    text = billion_laughs(4)
    assert read_yaml(text, limits=YamlLimits(max_nodes=8307)).data["d"][0][0][0][0] == "lol"
    with pytest.raises(SpecError, match="more than 8306 nodes"):
        read_yaml(text, limits=YamlLimits(max_nodes=8306))


def test_a_few_aliases_are_fine_in_a_task_file_but_not_in_the_service() -> None:
    text = "a: &x [1, 2]\nb: *x\nc: {<<: {d: 1}}\n"
    assert read_yaml(text).data == {"a": [1, 2], "b": [1, 2], "c": {"d": 1}}
    with pytest.raises(SpecError, match=r"aliases \(\*name\) are not accepted") as caught:
        read_yaml(text, limits=YAML_LIMITS)
    assert caught.value.line == 2
    with pytest.raises(SpecError, match="more than 1 YAML aliases"):
        read_yaml("a: &x 1\nb: *x\nc: *x\n", limits=YamlLimits(max_aliases=1))


def test_the_service_parses_with_the_same_loader() -> None:
    with pytest.raises(SpecError, match="list longer than 10000 items"):
        parse_spec(HUGE_LIST.encode())
    with pytest.raises(SpecError, match="aliases"):
        parse_spec(billion_laughs().encode())
    assert parse_spec(SEED_TASK.read_bytes()).name == load_task(SEED_TASK).name


def test_mapping_entries_are_bounded_too() -> None:
    text = "".join(f"k{i}: {i}\n" for i in range(11))
    with pytest.raises(SpecError, match="more than 10 entries"):
        read_yaml(text, limits=YamlLimits(max_items=10))


def test_one_document_only_and_aliases_need_an_anchor() -> None:
    with pytest.raises(SpecError, match="single YAML document"):
        read_yaml("a: 1\n---\nb: 2\n")
    with pytest.raises(SpecError, match=r"\*b names no anchor"):
        read_yaml("a: *b\n")


def test_an_integer_of_thousands_of_digits_is_refused_at_its_line() -> None:
    # int() of over 4 300 digits raises a ValueError naming no line (a 500 in the service)
    with pytest.raises(SpecError, match=r"5000 characters \(more than 100\)") as refused:
        read_yaml("a: 1\nb:\n  c: " + "7" * 5000 + "\n")
    assert (refused.value.path, refused.value.line) == ("b.c", 3)
    assert read_yaml("a: " + "7" * 100 + "\n").data == {"a": int("7" * 100)}
    assert read_yaml("a: '" + "7" * 5000 + "'\n").data == {"a": "7" * 5000}  # a string is not


def test_a_key_given_twice_is_refused_where_the_second_one_starts() -> None:
    # YAML keeps the last of two equal keys without a word: a second `uncertainty:` under the
    # seed's box frame would silently drop its first tolerances (found by a generated task).
    text = SEED_TASK.read_text(encoding="utf-8")
    lines = text.splitlines(keepends=True)
    first = next(i for i, line in enumerate(lines) if line.lstrip().startswith("uncertainty:"))
    indent = lines[first][: len(lines[first]) - len(lines[first].lstrip())]
    twice = "".join(
        [*lines[: first + 1], f"{indent}uncertainty: {{rz: 1 deg}}\n", *lines[first + 1 :]]
    )
    with pytest.raises(SpecError) as refused:
        parse_task(twice)
    assert refused.value.line == first + 2  # the inserted line, 1-based
    assert refused.value.path.endswith(".uncertainty")
    assert f"given twice in one mapping (first at line {first + 1})" in str(refused.value)
    with pytest.raises(SpecError, match="'name' is given twice") as top:
        read_yaml("name: a\nname: b\n")
    assert (top.value.path, top.value.line) == ("name", 2)
    # Equal keys in different mappings, and YAML's merge key, are not duplicates.
    assert read_yaml("a: {x: 1}\nb: {x: 2}\n").data == {"a": {"x": 1}, "b": {"x": 2}}
    assert read_yaml("base: &b {x: 1}\nm: {<<: *b, y: 2}\n").data["m"] == {"x": 1, "y": 2}


def test_a_file_over_the_size_limit_is_not_read_whole(tmp_path: Path) -> None:
    big = tmp_path / "big.yaml"
    big.write_text("name: " + "x" * DEFAULT_LIMITS.max_bytes + "\n")
    with pytest.raises(SpecError, match="over the limit of 1048576 bytes"):
        load_task(big)
    with pytest.raises(SpecError, match="over the limit of 100 bytes"):
        parse_task("name: " + "x" * 100, limits=YamlLimits(max_bytes=100))


@pytest.mark.parametrize("name", ["billion laughs", "recursive alias", "deep flow nesting"])
def test_cli_exits_2_on_yaml_bombs(tmp_path: Path, name: str) -> None:
    text, fragment = BOMBS[name]
    task = tmp_path / "bomb.yaml"
    task.write_text(text)
    done = subprocess.run(
        [sys.executable, "-m", "synth.cli", "errors", str(task), "--from", "a", "--to", "b"],
        capture_output=True,
        text=True,
        timeout=60,  # [s] generous: the refusal itself takes milliseconds
        check=False,
    )
    assert done.returncode == 2, done.stderr
    assert fragment in done.stderr and "line" in done.stderr


def test_a_file_that_is_not_utf8_is_refused_at_its_line_and_column(tmp_path: Path) -> None:
    # Latin-1's é (0xe9) on line 2, after "description: caf" (16 characters): the codec's own
    # message gave only a byte offset into the file, which no editor shows
    latin = tmp_path / "latin1.yaml"
    latin.write_bytes(b"name: x\ndescription: caf\xe9 au lait\nframes: []\n")
    with pytest.raises(SpecError) as refused:
        load_task(latin)
    assert refused.value.line == 2
    assert "byte 0xe9 at column 17 is not UTF-8" in refused.value.detail
    # UTF-16's byte-order mark is the first byte of the first line
    wide = tmp_path / "utf16.yaml"
    wide.write_bytes("name: x\n".encode("utf-16"))
    with pytest.raises(SpecError) as refused:
        load_task(wide)
    assert refused.value.line == 1 and "column 1" in refused.value.detail
