"""A real ``synth serve`` on loopback: answers, then survives ``kill -9`` with its plans intact."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import httpx
import pytest
from _server_support import HAVE_PLANNER, ROOT, SEED, YAML

STARTUP = 60.0  # [s] bound on the server's start (imports, worker warm-up)


class Server:
    """A ``synth serve --port 0`` subprocess and the URL it reports."""

    def __init__(self, db: Path, *extra: str) -> None:
        env = {**os.environ, "SYNTH_WORKERS": "1", "PYTHONUNBUFFERED": "1"}
        env.pop("SYNTH_TOKEN", None)
        self.process = subprocess.Popen(
            [sys.executable, "-m", "synth.cli", "serve", "--port", "0", "--db", str(db), *extra],
            cwd=ROOT,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.log: list[str] = []
        self._url: str | None = None
        self._seen = threading.Event()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.process.stderr is not None
        for line in self.process.stderr:
            self.log.append(line)
            found = re.search(r"running on (http://127\.0\.0\.1:\d+)", line)
            if found:
                self._url = found.group(1)
                self._seen.set()
        self._seen.set()

    def url(self) -> str:
        assert self._seen.wait(STARTUP), "server did not start:\n" + "".join(self.log)
        assert self._url is not None, "server exited:\n" + "".join(self.log)
        return self._url

    def wait_ready(self, client: httpx.Client) -> None:
        """Until a worker is idle (bounded)."""
        deadline = time.monotonic() + STARTUP
        while time.monotonic() < deadline:
            health = client.get("/healthz").json()
            if health["workers"]["idle"] >= 1:
                return
            time.sleep(0.2)
        raise AssertionError("no worker became ready:\n" + "".join(self.log))

    def stop(self, sig: int) -> int:
        if self.process.poll() is None:
            self.process.send_signal(sig)
        code = self.process.wait(timeout=30)
        self._reader.join(timeout=5)
        return code


@contextmanager
def running(db: Path, *extra: str) -> Iterator[tuple[Server, httpx.Client]]:
    server = Server(db, *extra)
    try:
        with httpx.Client(base_url=server.url(), timeout=120.0) as client:
            yield server, client
    finally:
        if server.process.poll() is None:
            server.stop(signal.SIGKILL)


def test_serve_on_loopback_token_kill_9_and_restart(tmp_path: Path) -> None:
    db = tmp_path / "plans.db"
    auth = {**YAML, "Authorization": "Bearer s3cret"}
    with running(db, "--token", "s3cret") as (server, client):
        assert client.get("/healthz").json()["database"] == "ok"
        assert client.post("/v1/plans", content=b"name: t\n", headers=YAML).status_code == 401
        server.wait_ready(client)
        bad = client.post("/v1/plans", content=b"name: t\nframes: []\n", headers=auth)
        assert bad.status_code == 422 and bad.json()["path"] == "frames"
        if not HAVE_PLANNER:
            pytest.skip("planner/codegen not in this build: kill -9 persistence not tested")
        created = client.post("/v1/plans?validate=false", content=SEED.read_bytes(), headers=auth)
        assert created.status_code == 201, created.text
        location = created.headers["location"]
        server.stop(signal.SIGKILL)  # no shutdown, no checkpoint: only what was committed
    with running(db, "--token", "s3cret") as (server, client):
        again = client.get(location)
        assert again.status_code == 200
        assert again.json() == created.json()
        assert client.get(f"{location}/program.al").text == created.json()["program"]
        # Clean shutdown (uvicorn re-raises the signal once it has shut down).
        assert server.stop(signal.SIGTERM) in (0, -signal.SIGTERM)
        assert any("Application shutdown complete" in line for line in server.log)
