"""A real ``synth serve`` on loopback: answers, then survives ``kill -9`` with its plans intact,
and its jobs are never lost silently: after ``kill -9`` the running job is reported ``lost`` and
the queued one runs; after a clean stop the running job runs again."""

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

import httpx2 as httpx
from _paths import ROOT, SEED_TASK
from _server_support import YAML, descendants, done, finished, is_running

STARTUP = 60.0  # [s] bound on the server's start (imports, worker warm-up)
GOLDEN = (ROOT / "fixtures" / "golden" / "seed_4_8.al").read_text()
LONG = {"program": GOLDEN, "spec": SEED_TASK.read_text(), "trials": 200}  # about 12 s
QUICK = {"program": GOLDEN, "spec": SEED_TASK.read_text(), "trials": 0}


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

    def wait_running(self, client: httpx.Client, location: str) -> dict:
        """The job at ``location`` once it runs (bounded)."""
        deadline = time.monotonic() + STARTUP
        while time.monotonic() < deadline:
            job = client.get(location).json()
            if job["state"] == "running":
                return dict(job)
            assert job["state"] == "queued", job
            time.sleep(0.1)
        raise AssertionError(f"{location} did not start:\n" + "".join(self.log))

    def stop(self, sig: int) -> int:
        if self.process.poll() is None:
            self.process.send_signal(sig)
        code = self.process.wait(timeout=30)
        self._reader.join(timeout=5)
        return code


@contextmanager
def running(
    db: Path, *extra: str, headers: dict[str, str] | None = None
) -> Iterator[tuple[Server, httpx.Client]]:
    server = Server(db, *extra)
    try:
        with httpx.Client(base_url=server.url(), timeout=120.0, headers=headers) as client:
            yield server, client
    finally:
        if server.process.poll() is None:
            server.stop(signal.SIGKILL)


def test_a_served_database_lives_through_sigterm_and_kill_9(tmp_path: Path) -> None:
    """One database through three starts of the service (each start costs an interpreter and a
    worker, so the three stories share them):

    1. plans committed, and a long job running at a clean stop (SIGTERM);
    2. the plan is intact and the long job runs again; a quick job waits behind it; kill -9;
    3. the long job is reported lost, the queued one runs, the earlier results are intact;
       a running job is cancelled by DELETE.
    """
    db = tmp_path / "plans.db"
    token = ("--token", "s3cret")
    auth = {"Authorization": "Bearer s3cret"}
    with running(db, *token, headers=auth) as (server, client):
        assert client.get("/healthz").json()["database"] == "ok"
        anonymous = {"Authorization": ""}
        refused = client.post("/v1/plans", content=b"name: t\n", headers=YAML | anonymous)
        assert refused.status_code == 401
        server.wait_ready(client)
        bad = client.post("/v1/plans", content=b"name: t\nframes: []\n", headers=YAML)
        assert bad.status_code == 422 and bad.json()["path"] == "frames"
        submitted = client.post(
            "/v1/plans?validate=false", content=SEED_TASK.read_bytes(), headers=YAML | auth
        )
        plan = done(client, submitted)
        location = plan["links"]["self"]
        earlier = client.post("/v1/replays?wait=30", json=QUICK)
        assert earlier.status_code == 201 and earlier.json()["state"] == "done", earlier.text
        long = client.post("/v1/replays", json=LONG)
        assert long.status_code == 202
        first = server.wait_running(client, long.headers["location"])
        assert first["attempts"] == 1
        # Clean shutdown (uvicorn re-raises the signal once it has shut down).
        assert server.stop(signal.SIGTERM) in (0, -signal.SIGTERM)
        assert any("Application shutdown complete" in line for line in server.log)
        assert any("queued for the next start" in line for line in server.log)
    with running(db, *token, headers=auth) as (server, client):
        again = client.get(location)
        assert again.status_code == 200
        assert again.json() == plan
        assert client.get(f"{location}/program.al").text == plan["program"]
        assert client.get(submitted.headers["location"]).json()["state"] == "done"
        rerun = server.wait_running(client, long.headers["location"])
        assert rerun["attempts"] == 2 and rerun["started_at"] > first["started_at"]
        queued = client.post("/v1/replays", json=QUICK)  # one worker: it waits
        assert queued.status_code == 202
        assert client.get(queued.headers["location"]).json()["state"] == "queued"
        deadline = time.monotonic() + STARTUP  # "running" may precede the worker's fork
        while len(helpers := descendants(server.process.pid)) < 2 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert len(helpers) == 2, helpers  # the zygote and the busy worker
        server.stop(signal.SIGKILL)  # no shutdown: the running job's outcome is now unknown
        deadline = time.monotonic() + 10  # they go with it: no orphan keeps a core
        while any(map(is_running, helpers)) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not any(map(is_running, helpers)), helpers
    with running(db, *token, headers=auth) as (server, client):
        lost = client.get(long.headers["location"]).json()
        assert lost["state"] == "lost" and lost["finished_at"] is not None
        assert lost["problem"]["status"] == 503 and lost["problem"]["title"] == "Job lost"
        assert "submit the task again" in lost["problem"]["detail"]
        ran = finished(client, client.get(queued.headers["location"]), timeout=120)
        assert ran["state"] == "done" and ran["attempts"] == 1
        assert ran["result"]["nominal"]["outcome"] == "success"
        assert client.get(earlier.headers["location"]).json() == earlier.json()
        assert client.get(location).json() == plan  # kill -9: no checkpoint, still there
        assert any("was running when the server stopped: lost" in line for line in server.log)
        # a running job on a real server is cancelled by DELETE (its worker killed)
        again_long = client.post("/v1/replays", json=LONG)
        server.wait_running(client, again_long.headers["location"])
        cancelled = client.delete(again_long.headers["location"])
        assert cancelled.status_code == 200 and cancelled.json()["state"] == "cancelled"
