"""Fair lanes (server/lanes.py): one client's long jobs leave a worker for everybody else, the
queue serves clients in turn, and a flood is refused with 429 instead of queued without end."""

from __future__ import annotations

import asyncio
import operator
import time
from pathlib import Path

import pytest
from _server_support import client_for
from fastapi.testclient import TestClient

from server.exceptions import ServiceBusy, TooManyRequests
from server.lanes import Lanes
from server.service import PlanService
from server.settings import Settings
from server.workers import WorkerPool


def test_one_client_cannot_take_every_slot() -> None:
    async def scenario() -> None:
        lanes = Lanes(capacity=2, per_client=1, queue_per_client=4)
        async with lanes.slot("a", timeout=1):
            # a's second job waits although a slot is free: it is kept for other clients
            with pytest.raises(ServiceBusy):
                async with lanes.slot("a", timeout=0.05):
                    pass
            async with lanes.slot("b", timeout=0.05):
                assert lanes.running == 2
        assert lanes.running == 0 and lanes.waiting == 0

    asyncio.run(scenario())


def test_waiting_clients_are_served_in_turn() -> None:
    async def scenario() -> list[str]:
        lanes = Lanes(capacity=1, per_client=1, queue_per_client=8)
        served: list[str] = []
        gate = asyncio.Event()

        async def job(client: str) -> None:
            async with lanes.slot(client, timeout=5):
                served.append(client)
                await gate.wait()

        first = asyncio.ensure_future(job("a"))
        await asyncio.sleep(0)
        queued = [asyncio.ensure_future(job(c)) for c in ("a", "a", "a", "b", "c")]
        await asyncio.sleep(0)
        gate.set()
        await asyncio.gather(first, *queued)
        return served

    # FIFO would serve a, a, a, a, b, c; the round robin lets b and c in after a's next job.
    assert asyncio.run(scenario()) == ["a", "a", "b", "c", "a", "a"]


def test_a_flood_is_refused_at_once_and_leaves_no_trace() -> None:
    async def scenario() -> None:
        lanes = Lanes(capacity=1, per_client=1, queue_per_client=1)
        gate = asyncio.Event()

        async def hold() -> None:
            async with lanes.slot("a", timeout=5):
                await gate.wait()

        holders = [asyncio.ensure_future(hold()) for _ in range(2)]  # one runs, one waits
        await asyncio.sleep(0)
        started = time.monotonic()
        with pytest.raises(TooManyRequests) as refused:
            async with lanes.slot("a", timeout=5):
                pass
        assert time.monotonic() - started < 0.5
        assert refused.value.extra == {"running": 1, "waiting": 1}
        gate.set()
        await asyncio.gather(*holders)
        assert lanes.running == 0 and lanes.waiting == 0 and lanes.held_by("a") == (0, 0)

    asyncio.run(scenario())


@pytest.mark.parametrize("per_client", [1, 2])
def test_a_normal_job_runs_while_one_client_holds_long_ones(per_client: int) -> None:
    """Two workers; client a sends two 3 s jobs, then client b a quick one."""

    async def scenario() -> float | None:
        pool = WorkerPool(2)
        await pool.start()
        service = PlanService(store=None, pool=pool, lanes=Lanes(2, per_client, 4))  # type: ignore[arg-type]
        try:
            deadline = time.monotonic() + 60
            while pool.ready < 2 and time.monotonic() < deadline:
                await asyncio.sleep(0.05)
            slow = [
                asyncio.ensure_future(
                    service.run_job("a", time.sleep, 3.0, timeout=30, what="sleeping")
                )
                for _ in range(2)
            ]
            await asyncio.sleep(0.2)
            started = time.monotonic()
            try:
                assert await service.run_job("b", operator.add, 2, 3, timeout=1, what="adding") == 5
                waited: float | None = time.monotonic() - started
            except ServiceBusy:
                waited = None
            await asyncio.gather(*slow)
            return waited
        finally:
            await pool.close()

    waited = asyncio.run(scenario())
    if per_client == 1:  # the lane: b is served at once
        assert waited is not None and waited < 1.0
    else:  # without it (a may hold both workers) b gets 503, as before the lanes
        assert waited is None


def test_the_routes_count_jobs_per_peer_address(tmp_path: Path) -> None:
    settings = Settings(db_url=str(tmp_path / "lanes.db"), workers=1, queue_per_client=0)
    with client_for(settings) as client:
        lanes = client.app.state.service.lanes  # type: ignore[attr-defined]
        flooder = TestClient(client.app, client=("10.9.9.9", 4000))  # type: ignore[arg-type]

        async def occupy() -> None:  # the flooder's one slot, held while it asks for more
            async with lanes.slot("10.9.9.9", timeout=1):
                answer = await asyncio.to_thread(
                    flooder.post, "/v1/plans", content=b"name: t\nframes: []\n"
                )
                assert answer.status_code == 429, answer.text
                assert answer.headers["retry-after"] == "5"
                assert answer.headers["content-type"].startswith("application/problem+json")

        client.portal.call(occupy)  # type: ignore[union-attr]
        other = client.post("/v1/plans", content=b"name: t\nframes: []\n")
        assert other.status_code == 422  # another address is served: its job ran and failed
