"""The package layering of docs/design.md, checked by importing each layer alone in a fresh
interpreter: a lower layer must not load a higher one."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from _paths import SEED_PROGRAM, SEED_TASK

LOADS_NOTHING_ABOVE = [
    # AL knows no task: the binding of a task's world to AL names lives in codegen.
    ("synth.al.interpreter", ("synth.models", "synth.errors", "synth.strategies", "synth.replay")),
    ("synth.al.parser", ("synth.models", "synth.codegen")),
    # Loading a task imports no estimator, planner or replay (the believed graph's LP is lazy).
    ("synth.models.loader", ("synth.errors", "synth.strategies", "synth.replay", "synth.codegen")),
    ("synth.models.believed", ("synth.errors", "synth.strategies")),
    # The estimator knows no strategy; the replay (the referee) knows no planner.
    ("synth.errors.estimate", ("synth.strategies", "synth.replay", "synth.codegen")),
    ("synth.replay.run", ("synth.strategies", "synth.pipeline")),
    # The text renderings: ``synth replay`` imports them for its summary, so the records of the
    # estimator and the planner are named there for the type checker only.
    ("synth.report", ("synth.errors", "synth.strategies", "synth.pipeline")),
]


@pytest.fixture(scope="module")
def loaded_above() -> dict[str, list[str]]:
    """Per layer, the forbidden modules that importing it alone loads.

    One fresh interpreter serves every layer: before each import it drops every ``synth``
    module from ``sys.modules``, so the layer is imported as if alone (the forbidden names are
    all ``synth`` modules; third-party modules staying loaded changes nothing about them).
    """
    code = (
        "import importlib, json, sys\n"
        f"layers = {LOADS_NOTHING_ABOVE!r}\n"
        "found = {}\n"
        "for module, forbidden in layers:\n"
        "    for name in [m for m in sys.modules if m == 'synth' or m.startswith('synth.')]:\n"
        "        del sys.modules[name]\n"
        "    importlib.import_module(module)\n"
        "    found[module] = sorted(m for m in sys.modules if m.startswith(tuple(forbidden)))\n"
        "print(json.dumps(found))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    return json.loads(out)


@pytest.mark.parametrize(("module", "forbidden"), LOADS_NOTHING_ABOVE)
def test_a_layer_loads_nothing_above_it(
    loaded_above: dict[str, list[str]], module: str, forbidden: tuple[str, ...]
) -> None:
    assert all(name.startswith("synth.") for name in forbidden)  # what the fixture relies on
    assert loaded_above[module] == [], f"importing {module} loads {loaded_above[module]}"


def test_synth_replay_loads_no_planner_and_of_the_estimator_only_the_sampler() -> None:
    # The command itself, run in a fresh interpreter: what it imports is what `synth replay`
    # pays for at start-up. The referee draws its true worlds from the task's error blocks
    # with synth.errors.parameters (synth/replay/truth.py), and nothing else of synth.errors;
    # scipy.stats (~0.25 s) only for a normal distribution, which the seed task does not use.
    watched = ("synth.errors", "synth.strategies", "synth.pipeline", "scipy.stats")
    argv = ["replay", str(SEED_PROGRAM), "--task", str(SEED_TASK), "--trials", "0"]
    code = (
        "import contextlib, io, json, sys\n"
        "from synth.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    code = main({argv!r})\n"
        f"print(json.dumps([code, sorted(m for m in sys.modules if m.startswith({watched!r}))]))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    code, loaded = json.loads(out)
    assert code == 0  # the golden program's nominal run succeeds (test_codegen's golden tests)
    assert loaded == ["synth.errors", "synth.errors.parameters"]
