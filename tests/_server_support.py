"""Helpers shared by the server tests (not a test module)."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx2 as httpx
from fastapi import FastAPI
from fastapi.testclient import TestClient

from server.main import create_app
from server.settings import Settings, get_settings

YAML = {"Content-Type": "application/yaml"}
FINAL = frozenset({"done", "failed", "lost", "cancelled"})


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


def finished(
    client: TestClient | httpx.Client, submitted: httpx.Response, timeout: float = 300.0
) -> dict[str, Any]:
    """The job of a submission (202, 201) or a read of it (200), long-polled until final."""
    assert submitted.status_code in (200, 201, 202), submitted.text
    job: dict[str, Any] = submitted.json()
    location = job["links"]["self"]
    assert location == f"/v1/jobs/{job['id']}"
    if submitted.status_code != 200:  # a submission names its job
        assert submitted.headers["location"] == location
    deadline = time.monotonic() + timeout
    while job["state"] not in FINAL:
        assert time.monotonic() < deadline, f"job still {job['state']} after {timeout:g} s"
        answer = client.get(f"{location}?wait=10")
        assert answer.status_code == 200, answer.text
        job = answer.json()
    return job


def done(client: TestClient | httpx.Client, submitted: httpx.Response) -> dict[str, Any]:
    """The result of a submitted job that must succeed (a plan, or a replay report)."""
    job = finished(client, submitted)
    assert job["state"] == "done", job["problem"]
    result = job["result"]
    assert isinstance(result, dict)
    return result


def failed(client: TestClient | httpx.Client, submitted: httpx.Response, status: int) -> dict:
    """The problem of a submitted job that must fail with ``status``."""
    job = finished(client, submitted)
    assert job["state"] == "failed", job
    problem = job["problem"]
    assert problem["status"] == status, problem
    assert problem["title"] and problem["detail"] and problem["type"]
    return dict(problem)


def descendants(pid: int) -> list[int]:
    """The processes below ``pid`` (children first), from Linux's /proc/PID/task/TID/children."""
    found: list[int] = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        with contextlib.suppress(OSError):
            for child in map(int, (task / "children").read_text().split()):
                found += [child, *descendants(child)]
    return found


def is_running(pid: int) -> bool:
    """Whether ``pid`` is a live process (a zombie waiting for its reaper is not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rpartition(")")[2].split()[0] not in ("Z", "X")
