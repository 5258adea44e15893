"""Time how long the server waits for a new worker: forked from a warm zygote, against cold.

Usage: python benchmarks/workers.py [--repeat N]

The server's pool starts a worker at start-up and again for every worker it replaces (after a
job overran its budget, was cancelled, crashed or hit the memory cap). Timed here, from asking
for a worker until it reports ready on its job socket, with the server's warm-up
(``server.service:warm_up``: numpy, scipy, Pinocchio, Coal and synth's planner imported):

- ``warm``: a fork of one zygote that has already warmed up (what every worker after the first
  costs the server now);
- ``cold``: a new zygote each time, so the wait includes a fresh interpreter and its warm-up
  (what every worker cost when each was a fresh ``python -m`` interpreter): the reference row.

Prints the median and the worst of ``--repeat`` runs of each, and the ratio of the medians.
"""

from __future__ import annotations

import argparse
import socket
import statistics
import sys
import time
from multiprocessing.connection import Connection
from pathlib import Path

# This script's folder comes first on sys.path, and its server.py would shadow the package.
sys.path[0] = str(Path(__file__).resolve().parent.parent)
from server.zygote import Zygote  # noqa: E402

WARMUP = "server.service:warm_up"


def ready_after(zygote: Zygote) -> float:
    """Seconds from asking ``zygote`` for a worker until the worker says it is ready."""
    parent, child = socket.socketpair()
    started = time.perf_counter()
    with child:
        process = zygote.fork(child.fileno(), 0)
    conn = Connection(parent.detach())
    kind, _ = conn.recv()
    elapsed = time.perf_counter() - started
    assert kind == "ready", kind
    conn.send(None)  # the worker's loop ends
    process.wait(timeout=10)
    process.close()
    conn.close()
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="workers timed per row")
    args = parser.parse_args()

    cold: list[float] = []
    for _ in range(args.repeat):
        fresh = Zygote(WARMUP)
        cold.append(ready_after(fresh))
        fresh.close()
    zygote = Zygote(WARMUP)
    ready_after(zygote)  # its warm-up: the first worker of a server
    warm = [ready_after(zygote) for _ in range(args.repeat)]
    zygote.close()

    rows = [("warm (fork of a warmed zygote)", warm), ("cold (fresh interpreter)", cold)]
    print(f"{'worker ready after':<34}{'median':>12}{'worst':>12}  runs")
    print("-" * 66)
    for label, times in rows:
        print(
            f"{label:<34}{statistics.median(times) * 1e3:>9.1f} ms{max(times) * 1e3:>9.1f} ms"
            f"  {len(times)}"
        )
    print(
        f"{'cold / warm (medians)':<34}{statistics.median(cold) / statistics.median(warm):>11.0f}×"
    )


if __name__ == "__main__":
    main()
