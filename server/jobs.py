"""Jobs: long work (a plan with its proof, a replay with many trials) runs after its request.

A submitted job (:meth:`JobManager.submit`) is committed to the store as ``queued`` and takes
its place in the client's fair lane (:mod:`server.lanes`) at once, so the request is answered
``202`` in milliseconds whatever the workers are doing. A task on the server's event loop then
waits for a lane slot, marks the job ``running``, and has the job's *executor* (per kind, given
by :mod:`server.service`) run it in a worker process (:mod:`server.workers`).

States::

    queued ──► running ──► done        result (plan jobs: the stored plan)
       │          ├──────► failed      the problem document the work raised (422, 504, …)
       │          └──────► lost        the server stopped abruptly while it ran
       └──────────┴──────► cancelled   DELETE /v1/jobs/{id} stopped it

Restarts, never silent:

- A clean shutdown (SIGTERM, Ctrl-C) stops the running jobs and puts them back to ``queued``;
  queued jobs stay queued.
- At startup, jobs still marked ``running`` were running when the server died (``kill -9``, a
  crash, a power cut): they become ``lost``, with a problem document saying so, and are not run
  again: the job may be what brought the server down, and re-running it could crash the server
  in a loop. Their clients resubmit. Queued jobs are queued again, oldest first, in the lanes
  of the clients that submitted them (whose caps they passed when they were accepted).
- ``attempts`` counts the runs a job started, so a job re-run after a clean restart shows 2.

One server process owns the jobs of its database: a second server on the same database would
take the first one's running jobs for lost at its startup.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from server.db import NewJob, PlanStore, StoredJob
from server.errors import problem_document
from server.exceptions import JobCancelled, JobLost, ServiceBusy
from server.lanes import Lanes
from server.settings import Settings

log = logging.getLogger("server.jobs")


@dataclass(frozen=True)
class Outcome:
    """What an executor returns: the job's result document and, for a plan, the plan's id."""

    result: dict[str, Any] | None = None
    plan_id: str | None = None


Executor = Callable[[StoredJob, Settings], Awaitable[Outcome]]
"""Runs one job of its kind (normally in a worker); raises to fail the job."""

LOST = JobLost(
    "the server stopped while this job was running (a crash, kill -9 or power loss), so its "
    "outcome is unknown; submit the task again"
)


@dataclass(eq=False)
class _Live:
    """A job this server runs or queues: its lane ticket, task and done event."""

    job: StoredJob
    settings: Settings
    ticket: asyncio.Future[None]
    done: asyncio.Event = field(default_factory=asyncio.Event)
    task: asyncio.Task[None] | None = None
    cancelling: bool = False


class JobManager:
    """Queues, runs, waits on and cancels jobs; persists every change in ``store``."""

    def __init__(
        self,
        store: PlanStore,
        lanes: Lanes,
        executors: Mapping[str, Executor],
        settings: Settings,
    ) -> None:
        self.store = store
        self.lanes = lanes
        self.executors = dict(executors)
        self.settings = settings
        self._live: dict[str, _Live] = {}

    # -- state ------------------------------------------------------------------------------

    @property
    def unfinished(self) -> int:
        """Jobs queued or running in this server."""
        return len(self._live)

    def is_live(self, job_id: str) -> bool:
        """True while this server queues or runs the job ``job_id``."""
        return job_id in self._live

    # -- lifecycle --------------------------------------------------------------------------

    async def start(self) -> tuple[list[StoredJob], list[StoredJob]]:
        """Recover after a restart (module rule): mark lost, queue again; both lists."""
        lost, queued = await asyncio.to_thread(self.store.recover_jobs, problem_document(LOST))
        for job in lost:
            log.warning(
                "job %s (%s, %s) was running when the server stopped: lost",
                job.id,
                job.kind,
                job.task_name,
            )
        for job in queued:
            if job.kind not in self.executors:  # written by another version of the server
                unknown = JobLost(f"this server cannot run jobs of kind {job.kind!r}")
                await self._finish(job.id, "lost", problem=problem_document(unknown))
                continue
            self._launch(job, self.settings, self.lanes.enqueue(job.client, check=False))
        if queued:
            log.info("%d queued job(s) queued again after the restart", len(queued))
        return lost, queued

    async def close(self) -> None:
        """Stop every job; put running ones back to ``queued`` for the next start."""
        live = list(self._live.values())
        for entry in live:
            if entry.task is not None:
                entry.task.cancel()
        tasks = [e.task for e in live if e.task is not None]
        if tasks:
            await asyncio.gather(*tasks, return_exceptions=True)
        self._live.clear()
        requeued = await asyncio.to_thread(self.store.requeue_running)
        if requeued:
            log.info("%d running job(s) stopped and queued for the next start", requeued)

    # -- submission ---------------------------------------------------------------------------

    async def submit(self, job: NewJob, settings: Settings) -> StoredJob:
        """Commit ``job`` as queued and start it; raises 429 or 503 instead of accepting it.

        :class:`~server.exceptions.TooManyRequests` when the client already has its jobs
        running and queued (:mod:`server.lanes`), :class:`ServiceBusy` when the server holds
        ``max_jobs`` unfinished jobs.
        """
        if job.kind not in self.executors:
            raise ValueError(f"no executor for jobs of kind {job.kind!r}")
        if len(self._live) >= settings.max_jobs:
            raise ServiceBusy(
                f"the server already holds {len(self._live)} unfinished jobs (its limit, "
                "SYNTH_MAX_JOBS); retry later"
            )
        ticket = self.lanes.enqueue(job.client)
        try:
            stored = await asyncio.to_thread(self.store.add_job, job)
        except BaseException:
            self.lanes.abandon(job.client, ticket)
            raise
        self._launch(stored, settings, ticket)
        return stored

    async def record_done(self, job: NewJob, outcome: Outcome) -> StoredJob:
        """Commit ``job`` as done at once with ``outcome`` (work answered from the store)."""
        return await asyncio.to_thread(
            self.store.add_job, job, state="done", plan_id=outcome.plan_id, result=outcome.result
        )

    def _launch(self, job: StoredJob, settings: Settings, ticket: asyncio.Future[None]) -> None:
        entry = _Live(job, settings, ticket)
        self._live[job.id] = entry
        entry.task = asyncio.get_running_loop().create_task(self._run(entry), name=f"job-{job.id}")

    # -- running ------------------------------------------------------------------------------

    async def _run(self, entry: _Live) -> None:
        job = entry.job
        try:
            async with self.lanes.slot(job.client, None, entry.ticket):
                running = await asyncio.to_thread(self.store.start_job, job.id)
                if running is None:  # no longer queued in the store (deleted meanwhile)
                    return
                outcome = await self.executors[job.kind](running, entry.settings)
            await self._finish(job.id, "done", plan_id=outcome.plan_id, result=outcome.result)
        except asyncio.CancelledError:
            if not entry.cancelling:
                raise  # shutdown: the row stays queued or running (module rule)
            await self._finish(job.id, "cancelled", problem=_cancelled())
        except Exception as exc:
            await self._finish(job.id, "failed", problem=problem_document(exc))
        finally:
            self._settle(entry)

    async def _finish(self, job_id: str, state: str, **outcome: Any) -> None:
        try:
            await asyncio.to_thread(self.store.finish_job, job_id, state, **outcome)
        except Exception:  # the job stays unfinished in the store: lost at the next start
            log.exception("could not record job %s as %s", job_id, state)

    def _settle(self, entry: _Live) -> None:
        if self._live.get(entry.job.id) is entry:
            del self._live[entry.job.id]
        entry.done.set()

    # -- waiting and cancelling ---------------------------------------------------------------

    async def wait(self, job_id: str, seconds: float) -> None:
        """Return once the job ``job_id`` is final or after ``seconds`` [s], whichever is first."""
        entry = self._live.get(job_id)
        if entry is None or seconds <= 0:
            return
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(entry.done.wait(), seconds)

    async def cancel(self, job_id: str) -> None:
        """Cancel the unfinished job ``job_id``: stop its worker (if running), mark it cancelled.

        A job this server does not hold (another server's, on the same database) is marked
        cancelled in the store only.
        """
        entry = self._live.get(job_id)
        if entry is None or entry.task is None:
            await self._finish(job_id, "cancelled", problem=_cancelled())
            return
        entry.cancelling = True
        entry.task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await entry.task
        if self._live.get(job_id) is entry:  # cancelled before it ever ran
            self.lanes.abandon(entry.job.client, entry.ticket)
            await self._finish(job_id, "cancelled", problem=_cancelled())
            self._settle(entry)


def _cancelled() -> dict[str, Any]:
    return problem_document(JobCancelled("the job was cancelled (DELETE) before it finished"))


__all__ = ["LOST", "Executor", "JobManager", "Outcome"]
