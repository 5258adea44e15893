"""Fair lanes (server/lanes.py): one client's long jobs leave a worker for everybody else, the
queue serves clients in turn, and a flood is refused with 429 instead of queued without end."""

from __future__ import annotations

import asyncio
import operator
import time
from pathlib import Path

import pytest
from _paths import SEED_TASK
from _server_support import YAML, client_for, finished
from fastapi.testclient import TestClient

from server.db import NewJob, PlanStore, StoredJob
from server.exceptions import ServiceBusy, TooManyRequests
from server.jobs import JobManager, Outcome
from server.lanes import Lanes
from server.settings import Settings
from server.workers import WorkerPool

SEED_TEXT = SEED_TASK.read_text()


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


def test_a_job_is_queued_at_submission_and_can_be_abandoned() -> None:
    async def scenario() -> None:
        lanes = Lanes(capacity=1, per_client=1, queue_per_client=1)
        first = lanes.enqueue("a")  # granted at once: the slot is free
        second = lanes.enqueue("a")  # queued behind it
        assert first.done() and not second.done()
        with pytest.raises(TooManyRequests):  # refused at submission, synchronously
            lanes.enqueue("a")
        again = lanes.enqueue("a", check=False)  # a job accepted before a restart
        lanes.abandon("a", second)
        lanes.abandon("a", again)
        assert lanes.held_by("a") == (1, 0)
        ticket = lanes.enqueue("b")
        with pytest.raises(ServiceBusy):  # a holds the one slot: b's queued job times out
            async with lanes.slot("b", timeout=0.05, ticket=ticket):
                pass
        assert lanes.held_by("b") == (0, 0)  # and leaves its queue
        lanes.abandon("a", first)  # releases its slot
        assert lanes.running == 0 and lanes.waiting == 0

    asyncio.run(scenario())


@pytest.mark.parametrize("per_client", [1, 2])
def test_a_normal_job_runs_while_one_client_holds_long_ones(
    per_client: int, tmp_path: Path
) -> None:
    """Two workers; client a submits two 3 s jobs, then client b a quick one."""

    async def scenario() -> float:
        pool = WorkerPool(2)
        await pool.start()
        store = PlanStore(f"sqlite:///{tmp_path / 'jobs.db'}")
        store.create_schema()

        async def sleep(job: StoredJob, _settings: Settings) -> Outcome:
            await pool.run(time.sleep, job.payload["seconds"], timeout=30, what="sleeping")
            return Outcome(result={"slept": job.payload["seconds"]})

        async def add(job: StoredJob, _settings: Settings) -> Outcome:
            total = await pool.run(operator.add, *job.payload["terms"], timeout=30, what="adding")
            return Outcome(result={"sum": total})

        settings = Settings(db_url=str(tmp_path / "jobs.db"), workers=2)
        jobs = JobManager(store, Lanes(2, per_client, 4), {"sleep": sleep, "add": add}, settings)

        def new(kind: str, client: str, **payload: object) -> NewJob:
            return NewJob(kind, client, None, None, {}, dict(payload))

        try:
            deadline = time.monotonic() + 60
            while pool.ready < 2 and time.monotonic() < deadline:
                await asyncio.sleep(0.05)
            for _ in range(2):
                await jobs.submit(new("sleep", "a", seconds=3.0), settings)
            await asyncio.sleep(0.2)
            started = time.monotonic()
            quick = await jobs.submit(new("add", "b", terms=[2, 3]), settings)
            await jobs.wait(quick.id, 30)
            waited = time.monotonic() - started
            finished = store.get_job(quick.id)
            assert finished is not None and finished.state == "done"
            assert finished.result == {"sum": 5}
            return waited
        finally:
            await jobs.close()
            await pool.close()
            store.close()

    waited = asyncio.run(scenario())
    if per_client == 1:  # the lane: b is served at once
        assert waited < 1.0
    else:  # without it a holds both workers, and b's job waits for one of a's to end
        assert waited > 2.0


def test_the_routes_count_jobs_per_peer_address(tmp_path: Path) -> None:
    settings = Settings(db_url=str(tmp_path / "lanes.db"), workers=1, queue_per_client=0)
    with client_for(settings) as client:
        flooder = TestClient(client.app, client=("10.9.9.9", 4000))  # type: ignore[arg-type]
        # The app's running event loop, not a loop of its own per request: jobs outlive the
        # request that submitted them, and a request-scoped loop would end them with it.
        flooder.portal = client.portal
        first = flooder.post("/v1/plans?validate=false", content=SEED_TEXT, headers=YAML)
        assert first.status_code == 202, first.text  # its one job: queued or running
        answer = flooder.post("/v1/plans?validate=false&seed=1", content=SEED_TEXT)
        assert answer.status_code == 429, answer.text  # refused at submission
        assert answer.headers["retry-after"] == "5"
        assert answer.headers["content-type"].startswith("application/problem+json")
        assert answer.json()["running"] + answer.json()["waiting"] == 1
        # Another address is served: its job is accepted, and runs after the flooder's.
        other = client.post("/v1/replays", json={"program": "BEGIN END", "spec": SEED_TEXT})
        assert other.status_code == 202, other.text
        assert finished(client, other)["state"] == "done"
        assert finished(client, first)["state"] == "done"
