"""Shared test set-up.

* Every test runs from an empty temporary working directory, so that a path relative to the
  checkout fails at once instead of passing only when pytest is started from the root; tests
  find the project's files through :mod:`_paths`.
* ``slow`` tests (long Monte Carlo runs) are left out by default (``addopts`` in
  pyproject.toml: ``-m "not slow"``); ``make test-slow`` runs them.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest


@pytest.fixture(autouse=True)
def _run_from_an_empty_directory(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    where = tmp_path_factory.mktemp("cwd")
    before = Path.cwd()
    os.chdir(where)
    try:
        yield where
    finally:
        os.chdir(before)
