"""The package layering of docs/design.md, checked by importing each layer alone in a fresh
interpreter: a lower layer must not load a higher one."""

from __future__ import annotations

import subprocess
import sys

import pytest

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
]


@pytest.mark.parametrize(("module", "forbidden"), LOADS_NOTHING_ABOVE)
def test_a_layer_loads_nothing_above_it(module: str, forbidden: tuple[str, ...]) -> None:
    code = (
        f"import sys, {module}\n"
        f"print('\\n'.join(m for m in sys.modules if m.startswith({forbidden!r})))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.split()
    assert out == [], f"importing {module} loads {out}"
