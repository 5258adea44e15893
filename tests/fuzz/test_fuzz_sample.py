"""The fuzz harness in the ordinary test run: it tells crashes, hangs and memory blow-ups apart,
and a small fixed sample of every surface (task specs, AL programs, the API) comes out clean."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import fuzzgen
import fuzzrun
import pytest
import yaml
from _paths import GOLDEN, TASKS

from synth.al.parser import parse_program


def _fake_main(argv: list[str]) -> int:
    """A stand-in CLI whose first argument says how it ends."""
    what = argv[0]
    if what == "hang":
        time.sleep(60)
    if what == "memory":
        hog = b"x" * (400 * 2**20)  # written, so resident
        time.sleep(60)
        return len(hog)
    if what == "crash":
        print("synth x: internal error: ValueError: zero-size array 3", file=sys.stderr)
        return 70
    if what == "die":
        import os

        os._exit(9)
    if what == "usage":
        raise SystemExit(2)
    return 0


def test_the_sandbox_tells_outcomes_apart() -> None:
    sandbox = fuzzrun.Sandbox(timeout=1.0, memory_mib=200, entry=_fake_main)
    # the hog needs time to become resident on a loaded machine (within 1 s it was seen to
    # be a "hang" with the whole suite running beside it); it ends as soon as it passes the cap
    roomy = fuzzrun.Sandbox(timeout=20.0, memory_mib=200, entry=_fake_main)
    try:
        started = time.monotonic()
        outcomes = {w: sandbox.run([w], {}) for w in ("ok", "usage", "crash", "hang")}
        outcomes["memory"] = roomy.run(["memory"], {})
        outcomes["die"] = sandbox.run(["die"], {})
        outcomes["after"] = sandbox.run(["ok"], {})  # a fresh child after the kills
    finally:
        sandbox.close()
        roomy.close()
    assert {w: r.outcome for w, r in outcomes.items()} == {
        "ok": "ok",
        "usage": "ok",
        "crash": "crash",
        "hang": "hang",
        "memory": "memory",
        "die": "crash",
        "after": "ok",
    }
    assert outcomes["crash"].key == "crash: ValueError: zero-size array N"
    assert time.monotonic() - started < 30


def test_mutations_edit_one_node_of_a_copy() -> None:
    tree = {"frames": [{"name": "a"}, {"name": "b"}], "x": "1 cm"}
    assert fuzzgen._replace(tree, ("frames", 1, "name"), lambda _n: "TRUE") == {
        "frames": [{"name": "a"}, {"name": "TRUE"}],
        "x": "1 cm",
    }
    assert fuzzgen._replace(tree, ("frames", 0), lambda _n: fuzzgen._DROP)["frames"] == [
        {"name": "b"}
    ]
    assert len(fuzzgen._replace(tree, ("frames", 0), lambda _n: fuzzgen._DUPLICATE)["frames"]) == 3
    assert fuzzgen._replace(tree, ("x",), lambda n: fuzzgen._scale(n, 300))["x"] == "1e+300 cm"
    assert tree == {"frames": [{"name": "a"}, {"name": "b"}], "x": "1 cm"}  # unchanged
    assert ("frames", 1, "name") in fuzzgen._paths(tree)


def test_deep_nests_reach_the_yaml_text_but_never_the_python_tree() -> None:
    # Walking a tree 1 200 deep raised RecursionError at a stack-dependent depth, which made
    # Hypothesis abort 10 000-case runs with FlakyStrategyDefinition: the nest is text only.
    tree = fuzzgen._replace({"x": "1 cm"}, ("x",), lambda _n: fuzzgen._nest_marker(1200))
    assert fuzzgen._paths(tree) == [(), ("x",)]
    loaded = yaml.safe_load(fuzzgen._dump({"a": fuzzgen._nest_marker(3), "b": [2]}))
    assert loaded == {"a": [[["1 cm"]]], "b": [2]}
    assert fuzzgen._dump(tree).count("[") == 1200


def test_the_unmutated_golden_programs_parse() -> None:
    # The AL generator starts from every golden program (the manifest regen_golden.py
    # writes), each valid and replayed against the fixture task of its name.
    manifest = json.loads((GOLDEN / "manifest.json").read_text(encoding="utf-8"))
    assert [path.stem for path in fuzzgen.GOLDEN] == sorted(manifest["tasks"])
    for path in fuzzgen.GOLDEN:
        assert parse_program(path.read_text()).body, path
        assert fuzzgen._golden_task(path) == TASKS / f"{path.stem}.yaml"
        assert fuzzgen._golden_task(path).is_file()


@pytest.mark.parametrize("surface", fuzzrun.SURFACES)
def test_a_fixed_sample_of_each_surface_is_clean(surface: str, tmp_path: Path) -> None:
    (tally,) = fuzzrun.run(8, (surface,), timeout=20.0, out=tmp_path, seed=19, budget=20.0)
    assert tally.cases >= 4, tally
    assert fuzzrun.table([tally]).splitlines()[1].split()[0] == surface
    bad = {o: tally.counts[o] for o in fuzzrun.OUTCOMES if o != "ok" and tally.counts[o]}
    assert not bad, fuzzrun.table([tally])
