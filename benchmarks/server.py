"""Load the HTTP service's job flow on loopback: jobs/s and submit→done latency at 16 clients.

Usage: python benchmarks/server.py [--duration S] [--clients 16] [--workers N] [--validate]
                                   [--modes sync,jobs]

Starts ``synth serve`` on 127.0.0.1 (a free port, a temporary SQLite file), waits until its
workers are warm, then for each client count runs that many concurrent clients for
``--duration`` seconds (default 20 s), each submitting the seed_4_8 task under a fresh name (so
every job is really planned, no de-dup hits) and following the job to its end, one job at a
time. Two modes, the same load, in the same run:

- ``jobs``: ``POST /v1/plans`` (answered 202 at once), then long polls ``GET /v1/jobs/{id}?wait``
  until the job is final: the documented flow;
- ``sync``: ``POST /v1/plans?wait=30``, the request itself waiting for the job (then long polls
  if it is not final within the wait): the baseline of a client that wants one call.

Prints, per mode: jobs finished, errors (a job not ``done``, or any HTTP error), jobs/s,
p50/p99 of submit→done latency, and p99 of the submission's own answer (how long the service
makes a client wait before it has its job's URL), with sequential in-process planning (parse +
plan + emit + proof, the same work as one job, one core) as the reference row. Bounded:
loopback only, ``--duration`` per level plus the drain of the jobs in flight, at most
``--max-jobs`` per level, 120 s per request.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parent.parent
SEED = ROOT / "fixtures" / "tasks" / "seed_4_8.yaml"
STARTUP = 120.0  # [s] bound on server start and worker warm-up
REQUEST_TIMEOUT = 120.0  # [s]
WAIT = 30  # [s] each long poll (the server's default SYNTH_MAX_WAIT)
FINAL = {"done", "failed", "lost", "cancelled"}


@dataclass
class Level:
    """What one load level measured (times in seconds)."""

    label: str
    clients: int
    elapsed: float = 0.0
    latencies: list[float] = field(default_factory=list)  # submit → done
    submits: list[float] = field(default_factory=list)  # the POST's own answer
    errors: int = 0

    @property
    def jobs(self) -> int:
        return len(self.latencies) + self.errors

    @property
    def throughput(self) -> float:
        return len(self.latencies) / self.elapsed if self.elapsed > 0 else 0.0

    @staticmethod
    def percentile(values: list[float], q: int) -> float:
        if not values:
            return float("nan")
        if len(values) == 1:
            return values[0]
        return statistics.quantiles(values, n=100, method="inclusive")[q - 1]


def unique_spec(text: str) -> bytes:
    """The seed task under a fresh name: a different content hash, so it is really planned."""
    return re.sub(
        r"^name: .*$", f"name: bench-{uuid.uuid4().hex[:12]}", text, count=1, flags=re.M
    ).encode()


def in_process(text: str, duration: float, trials: int | None) -> Level:
    """Sequential parse + plan + emit + proof in this process (one core): one job's work."""
    from synth.models.loader import parse_task
    from synth.pipeline import SynthesisOptions, synthesize
    from synth.replay.proof import ProofOptions

    # The server's plan job: the pipeline with its proof on one worker (trials None: nominal).
    options = SynthesisOptions(proof=ProofOptions(trials=trials or 0, workers=1))

    def once() -> None:
        synthesize(parse_task(unique_spec(text).decode()), options)

    once()  # warm-up (imports, caches)
    level = Level("in-process", 1)
    start = time.perf_counter()
    while time.perf_counter() - start < duration or not level.latencies:
        t0 = time.perf_counter()
        once()
        level.latencies.append(time.perf_counter() - t0)
    level.elapsed = time.perf_counter() - start
    return level


class Server:
    """``synth serve --port 0`` on loopback, in a subprocess."""

    def __init__(self, db: Path, workers: int, clients: int) -> None:
        env = {
            **os.environ,
            "SYNTH_WORKERS": str(workers),
            # Every benchmark client is 127.0.0.1, one lane: let it use every worker and
            # queue a job per client (the defaults keep a worker for other clients).
            "SYNTH_JOBS_PER_CLIENT": str(workers),
            "SYNTH_QUEUE_PER_CLIENT": str(2 * clients),
        }
        env.pop("SYNTH_TOKEN", None)
        self.process = subprocess.Popen(
            [sys.executable, "-m", "synth.cli", "serve", "--port", "0", "--db", str(db)],
            cwd=ROOT,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.url: str | None = None
        self._seen = threading.Event()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.process.stderr is not None
        for line in self.process.stderr:
            found = re.search(r"running on (http://127\.0\.0\.1:\d+)", line)
            if found:
                self.url = found.group(1)
                self._seen.set()
        self._seen.set()

    def wait_ready(self, workers: int) -> str:
        if not self._seen.wait(STARTUP) or self.url is None:
            raise SystemExit("synth serve did not start")
        deadline = time.monotonic() + STARTUP
        with httpx.Client(base_url=self.url, timeout=10) as client:
            while time.monotonic() < deadline:
                if client.get("/healthz").json()["workers"]["idle"] >= workers:
                    return self.url
                time.sleep(0.2)
        raise SystemExit("the server's workers did not become ready")

    def stop(self) -> None:
        self.process.terminate()
        try:
            self.process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(timeout=10)


async def one_job(http: httpx.AsyncClient, text: str, query: str, sync: bool) -> tuple[float, bool]:
    """Submit one task and follow its job to the end: (the POST's answer time, done?)."""
    t0 = time.perf_counter()
    answer = await http.post(
        f"/v1/plans?{query}{f'&wait={WAIT}' if sync else ''}",
        content=unique_spec(text),
        headers={"Content-Type": "application/yaml"},
    )
    submitted = time.perf_counter() - t0
    if answer.status_code not in (201, 202):
        return submitted, False
    job = answer.json()
    while job["state"] not in FINAL:
        polled = await http.get(f"{answer.headers['location']}?wait={WAIT}")
        if polled.status_code != 200:
            return submitted, False
        job = polled.json()
    return submitted, job["state"] == "done"


async def load(
    url: str, text: str, clients: int, duration: float, max_jobs: int, query: str, sync: bool
) -> Level:
    """``clients`` concurrent clients, one job at a time each, submitting for ``duration``."""
    level = Level(f"{'sync' if sync else 'jobs'}, {clients} clients", clients)
    started = 0
    limits = httpx.Limits(max_connections=clients, max_keepalive_connections=clients)
    async with httpx.AsyncClient(base_url=url, timeout=REQUEST_TIMEOUT, limits=limits) as http:
        start = time.perf_counter()

        async def client() -> None:
            nonlocal started
            while time.perf_counter() - start < duration and started < max_jobs:
                started += 1
                t0 = time.perf_counter()
                try:
                    submitted, ok = await one_job(http, text, query, sync)
                except httpx.HTTPError:
                    submitted, ok = float("nan"), False
                if ok:
                    level.latencies.append(time.perf_counter() - t0)
                    level.submits.append(submitted)
                else:
                    level.errors += 1

        await asyncio.gather(*(client() for _ in range(clients)))
        level.elapsed = time.perf_counter() - start
    return level


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0, help="seconds per level")
    parser.add_argument("--clients", default="16", help="comma-separated client counts")
    parser.add_argument(
        "--workers", type=int, default=os.cpu_count() or 1, help="server workers (CPU count)"
    )
    parser.add_argument("--max-jobs", type=int, default=5000, help="cap per level")
    parser.add_argument(
        "--modes", default="sync,jobs", help="modes in the order run (the machine's load drifts)"
    )
    parser.add_argument("--validate", action="store_true", help="also prove each program")
    parser.add_argument("--trials", type=int, default=2, help="proof trials with --validate")
    args = parser.parse_args()
    counts = [int(c) for c in args.clients.split(",") if c.strip()]
    modes = [m.strip() for m in args.modes.split(",") if m.strip()]
    if not modes or set(modes) - {"sync", "jobs"}:
        parser.error("--modes: a comma-separated list of 'sync' and 'jobs'")
    text = SEED.read_text()
    query = f"trials={args.trials}" if args.validate else "validate=false"

    base = in_process(text, args.duration, args.trials if args.validate else None)
    levels: list[Level] = []
    with tempfile.TemporaryDirectory(prefix="synth-bench-") as tmp:
        server = Server(Path(tmp) / "bench.db", args.workers, max(counts))
        try:
            url = server.wait_ready(args.workers)
            # Warm every worker's caches (arm, meshes) once before measuring.
            asyncio.run(load(url, text, args.workers, STARTUP, args.workers, query, False))
            for n in counts:
                for mode in modes:
                    sync = mode == "sync"
                    levels.append(
                        asyncio.run(load(url, text, n, args.duration, args.max_jobs, query, sync))
                    )
        finally:
            server.stop()

    print(
        f"seed_4_8 plan jobs, {args.workers} server workers, {os.cpu_count()} CPUs, "
        f"{args.duration:g} s of submissions per level"
        f"{f', proof with {args.trials} trials' if args.validate else ', nominal proof'}"
    )
    head = (
        f"{'mode':20}{'jobs':>6}{'errors':>8}{'jobs/s':>8}{'p50 [ms]':>10}{'p99 [ms]':>10}"
        f"{'submit p99 [ms]':>17}{'vs in-proc':>12}"
    )
    print(head)
    print("-" * len(head))
    for level in [base, *levels]:
        ratio = level.throughput / base.throughput if base.throughput else float("nan")
        submit = Level.percentile(level.submits, 99) * 1e3 if level.submits else float("nan")
        print(
            f"{level.label:20}{level.jobs:6d}{level.errors:8d}{level.throughput:8.2f}"
            f"{Level.percentile(level.latencies, 50) * 1e3:10.0f}"
            f"{Level.percentile(level.latencies, 99) * 1e3:10.0f}"
            f"{submit:17.0f}{ratio:12.2f}"
        )
    print(
        "p50/p99: submit → done, per job; submit p99: until the POST answered (jobs: the 202 "
        "with the job's URL; sync: the job's end, or 202 after 30 s)"
    )
    if any(level.errors for level in levels):
        raise SystemExit(1)


if __name__ == "__main__":
    main()
