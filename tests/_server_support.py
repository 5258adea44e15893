"""Helpers shared by the server tests (not a test module)."""

from __future__ import annotations

import importlib.util
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from fastapi import FastAPI
from fastapi.testclient import TestClient

from server.main import create_app
from server.settings import Settings, get_settings

ROOT = Path(__file__).resolve().parents[1]
SEED = ROOT / "fixtures" / "tasks" / "seed_4_8.yaml"
YAML = {"Content-Type": "application/yaml"}


def have(module: str) -> bool:
    """True when ``module`` can be imported (a stage that has landed)."""
    try:
        return importlib.util.find_spec(module) is not None
    except ModuleNotFoundError:
        return False


HAVE_PLANNER = have("synth.strategies.planner") and have("synth.codegen.emitter")


def have_replay() -> bool:
    """True when synth.replay exposes the entry point the server calls."""
    from server.service import stages_available

    return stages_available()["replay"]


@contextmanager
def client_for(settings: Settings, **kwargs: object) -> Iterator[TestClient]:
    """A TestClient on a fresh app (workers started, stopped on exit)."""
    app = create_app(settings)
    with TestClient(app, **kwargs) as client:  # type: ignore[arg-type]
        yield client


@contextmanager
def overridden(app: FastAPI, **changes: object) -> Iterator[Settings]:
    """Settings changed for the duration (routes and middleware see them)."""
    before = app.dependency_overrides[get_settings]
    changed = before().with_(**changes)
    app.dependency_overrides[get_settings] = lambda: changed
    try:
        yield changed
    finally:
        app.dependency_overrides[get_settings] = before
