"""Load the HTTP service on loopback and compare it with planning in process.

Usage: python benchmarks/server.py [--duration S] [--clients 8,32] [--workers N] [--validate]

Starts ``synth serve`` on 127.0.0.1 (a free port, a temporary SQLite file), waits until its
workers are warm, then for each client count runs that many concurrent clients for
``--duration`` seconds (default 5 s for a smoke run; the issue's figure is 20 s), each posting
the seed_4_8 task under a fresh name so every request is planned (no de-dup hits). Prints
requests, errors (any status but 201, or a transport error), throughput, p50/p99 latency and
the ratio of HTTP throughput to sequential in-process planning (parse + plan + emit, the same
work as one request) on this machine. Bounded: loopback only, ``--duration`` per level and at
most ``--max-requests`` per level, 120 s per request.
"""

from __future__ import annotations

import argparse
import asyncio
import importlib
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parent.parent
SEED = ROOT / "fixtures" / "tasks" / "seed_4_8.yaml"
STARTUP = 120.0  # [s] bound on server start and worker warm-up
REQUEST_TIMEOUT = 120.0  # [s]


@dataclass(frozen=True)
class Level:
    """What one load level measured (times in seconds)."""

    label: str
    clients: int
    elapsed: float
    latencies: list[float]
    errors: int

    @property
    def requests(self) -> int:
        return len(self.latencies) + self.errors

    @property
    def throughput(self) -> float:
        return len(self.latencies) / self.elapsed if self.elapsed > 0 else 0.0

    def percentile(self, q: float) -> float:
        if not self.latencies:
            return float("nan")
        if len(self.latencies) == 1:
            return self.latencies[0]
        return statistics.quantiles(self.latencies, n=100, method="inclusive")[int(q) - 1]


def unique_spec(text: str) -> bytes:
    """The seed task under a fresh name: a different content hash, so it is really planned."""
    return re.sub(
        r"^name: .*$", f"name: bench-{uuid.uuid4().hex[:12]}", text, count=1, flags=re.M
    ).encode()


def in_process(text: str, duration: float, trials: int | None) -> Level:
    """Sequential parse + plan + emit (+ replay with ``trials``) in this process (one core).

    The same work as one request; ``trials`` None: no replay.
    """
    from synth.models.loader import parse_task
    from synth.pipeline import SynthesisOptions, synthesize
    from synth.replay.proof import ProofOptions

    # The server's plan job: the pipeline with its proof on one worker (trials None: nominal).
    options = SynthesisOptions(proof=ProofOptions(trials=trials or 0, workers=1))

    def once() -> None:
        synthesize(parse_task(unique_spec(text).decode()), options)

    once()  # warm-up (imports, caches)
    latencies: list[float] = []
    start = time.perf_counter()
    while time.perf_counter() - start < duration or not latencies:
        t0 = time.perf_counter()
        once()
        latencies.append(time.perf_counter() - t0)
    return Level("in-process", 1, time.perf_counter() - start, latencies, 0)


class Server:
    """``synth serve --port 0`` on loopback, in a subprocess."""

    def __init__(self, db: Path, workers: int) -> None:
        env = {**os.environ, "SYNTH_WORKERS": str(workers)}
        env.pop("SYNTH_TOKEN", None)
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "synth.cli",
                "serve",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--db",
                str(db),
            ],
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


async def load(
    url: str, text: str, clients: int, duration: float, max_requests: int, query: str
) -> Level:
    """``clients`` concurrent posters for ``duration`` [s] (or ``max_requests`` in total)."""
    latencies: list[float] = []
    errors = 0
    started = 0
    limits = httpx.Limits(max_connections=clients, max_keepalive_connections=clients)
    async with httpx.AsyncClient(base_url=url, timeout=REQUEST_TIMEOUT, limits=limits) as http:
        start = time.perf_counter()

        async def client() -> None:
            nonlocal errors, started
            while time.perf_counter() - start < duration and started < max_requests:
                started += 1
                body = unique_spec(text)
                t0 = time.perf_counter()
                try:
                    answer = await http.post(
                        f"/v1/plans?{query}",
                        content=body,
                        headers={"Content-Type": "application/yaml"},
                    )
                    ok = answer.status_code == 201
                except httpx.HTTPError:
                    ok = False
                if ok:
                    latencies.append(time.perf_counter() - t0)
                else:
                    errors += 1

        await asyncio.gather(*(client() for _ in range(clients)))
        elapsed = time.perf_counter() - start
    return Level(f"HTTP, {clients} clients", clients, elapsed, latencies, errors)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=5.0, help="seconds per level")
    parser.add_argument("--clients", default="8,32", help="comma-separated client counts")
    parser.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="server worker processes (default: CPU count)",
    )
    parser.add_argument("--max-requests", type=int, default=5000, help="cap per level")
    parser.add_argument(
        "--validate", action="store_true", help="also replay each program (needs synth.replay)"
    )
    parser.add_argument("--trials", type=int, default=2, help="replay trials with --validate")
    args = parser.parse_args()
    try:
        needed = ["synth.strategies.planner", "synth.codegen.emitter"]
        for module in needed + (["synth.replay"] if args.validate else []):
            importlib.import_module(module)
    except ImportError as exc:
        raise SystemExit(f"benchmarks/server.py needs the planner and codegen: {exc}") from None
    counts = [int(c) for c in args.clients.split(",") if c.strip()]
    text = SEED.read_text()
    query = f"trials={args.trials}" if args.validate else "validate=false"

    base = in_process(text, args.duration, args.trials if args.validate else None)
    levels: list[Level] = []
    with tempfile.TemporaryDirectory(prefix="synth-bench-") as tmp:
        server = Server(Path(tmp) / "bench.db", args.workers)
        try:
            url = server.wait_ready(args.workers)
            # Warm every worker's caches (arm, meshes) once before measuring.
            asyncio.run(load(url, text, args.workers, STARTUP, args.workers, query))
            for n in counts:
                levels.append(
                    asyncio.run(load(url, text, n, args.duration, args.max_requests, query))
                )
        finally:
            server.stop()

    print(
        f"seed_4_8 plans, {args.workers} server workers, {os.cpu_count()} CPUs, "
        f"{args.duration:g} s per level{', with replay' if args.validate else ''}"
    )
    head = (
        f"{'mode':22}{'requests':>9}{'errors':>8}{'plans/s':>9}{'p50 [ms]':>10}"
        f"{'p99 [ms]':>10}{'HTTP/in-proc':>14}"
    )
    print(head)
    print("-" * len(head))
    for level in [base, *levels]:
        ratio = level.throughput / base.throughput if base.throughput else float("nan")
        print(
            f"{level.label:22}{level.requests:9d}{level.errors:8d}{level.throughput:9.2f}"
            f"{level.percentile(50) * 1e3:10.0f}{level.percentile(99) * 1e3:10.0f}"
            f"{ratio:14.2f}"
        )
    if any(level.errors for level in levels):
        raise SystemExit(1)


if __name__ == "__main__":
    main()
