"""The generality suite's fast subset: the benchmark's own judgement, nominal proof.

``benchmarks/generality.py`` runs every task of ``fixtures/tasks/generality/expected.yaml``
with a 500-trial proof; here the tasks marked ``fast`` run with the nominal proof only (a
program must still replay, and a refusal's first line must name the task's root cause). The
judgement is the benchmark's :func:`judge`, so the test and the benchmark cannot disagree.
"""

from __future__ import annotations

import importlib.util
import sys
from types import ModuleType

import pytest
from _paths import ROOT


def _benchmark() -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        "generality", ROOT / "benchmarks" / "generality.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["generality"] = module  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module


GENERALITY = _benchmark()
ENTRIES = GENERALITY.load_manifest()
FAST = [e for e in ENTRIES if e.fast]


def test_the_suite_is_varied_and_every_task_states_its_outcome() -> None:
    # At least 20 tasks, plannable and impossible ones, each with its expectation.
    assert len(ENTRIES) >= 20
    kinds = {e.expect for e in ENTRIES}
    assert kinds == {"plan", "refuse"}
    assert all(e.cause for e in ENTRIES if e.expect == "refuse")
    files = {p.stem for p in GENERALITY.SUITE.glob("*.yaml")} - {"expected"}
    assert files == {e.task for e in ENTRIES}  # no task without an expectation, and back
    assert {e.expect for e in FAST} == {"plan", "refuse"}


@pytest.mark.parametrize("entry", FAST, ids=lambda e: e.task)
def test_fast_task_meets_its_expectation(entry) -> None:
    row = GENERALITY.judge(entry, 0, 1)
    assert row.passed, (row.decision, row.note)
