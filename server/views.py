"""Response documents of stored records: a plan (:func:`plan_out`) and a job (:func:`job_out`).

The routes of plans, replays and jobs share them, so a plan reads the same whether it is
fetched by its own URL or as the result of the job that made it.
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import Query, Response

from server.db import StoredJob, StoredPlan
from server.exceptions import InvalidRequest
from server.schemas import JobLinks, PlanLinks
from server.settings import Settings

RETRY_AFTER = "1"  # [s] the poll interval suggested for an unfinished job

WaitQuery = Annotated[
    float,
    Query(
        ge=0,
        allow_inf_nan=False,  # NaN compares false with everything: "not ≥ 0" would mislead
        description="seconds to wait for the job to finish before answering, at most the "
        "server's SYNTH_MAX_WAIT (30 s); 0: answer at once",
    ),
]


def plan_links(plan_id: str) -> PlanLinks:
    """The ``links`` of a plan."""
    return PlanLinks(self=f"/v1/plans/{plan_id}", program=f"/v1/plans/{plan_id}/program.al")


def plan_out(plan: StoredPlan) -> dict[str, Any]:
    """The response document of a stored plan (planner keys first, then the server's)."""
    return {
        **plan.result,
        "id": plan.id,
        "task": plan.task_name,
        "created_at": plan.created_at,
        "content_hash": plan.content_hash,
        "options": plan.options,
        "program": plan.program,
        "validation": plan.validation,
        "links": plan_links(plan.id).model_dump(by_alias=True),
    }


def job_url(job_id: str) -> str:
    """The URL of a job."""
    return f"/v1/jobs/{job_id}"


def job_out(job: StoredJob, plan: StoredPlan | None = None) -> dict[str, Any]:
    """The response document of a job; ``plan``: the plan a done plan job made or reused."""
    links = JobLinks(self=job_url(job.id))
    result = job.result
    reused = None
    if job.kind == "plan":
        reused = None if result is None else bool(result.get("reused"))
        result = None if plan is None else plan_out(plan)
        if job.plan_id is not None:
            links.plan = plan_links(job.plan_id).self_
            links.program = plan_links(job.plan_id).program
    return {
        "id": job.id,
        "kind": job.kind,
        "state": job.state,
        "created_at": job.created_at,
        "started_at": job.started_at,
        "finished_at": job.finished_at,
        "attempts": job.attempts,
        "task": job.task_name,
        "options": job.options,
        "plan_id": job.plan_id,
        "reused": reused,
        "result": result,
        "problem": job.problem,
        "links": links.model_dump(by_alias=True, exclude_none=True),
    }


def job_response(
    job: StoredJob, plan: StoredPlan | None, *, created: bool, response: Response | None = None
) -> dict[str, Any]:
    """``job_out``, with the status and headers set on ``response``.

    A submission (``created``) answers 202 while the job is unfinished and 201 once it is
    final (it finished within ``wait``, or was answered from the store); ``Location`` is the
    job's URL. An unfinished job gets ``Retry-After``, the suggested poll interval.
    """
    if response is not None:
        if created:
            response.status_code = 201 if job.finished else 202
            response.headers["Location"] = job_url(job.id)
        if not job.finished:
            response.headers["Retry-After"] = RETRY_AFTER
    return job_out(job, plan)


def checked_wait(wait: float, settings: Settings) -> float:
    """``wait`` [s], or 422 naming it when it is over the server's ``max_wait``."""
    if wait > settings.max_wait:
        raise InvalidRequest(
            f"wait={wait:g} s is longer than this server waits ({settings.max_wait:g} s, "
            "SYNTH_MAX_WAIT); poll GET /v1/jobs/{id} again instead",
            parameter="wait",
            maximum=settings.max_wait,
        )
    return wait


def checked_trials(requested: int | None, settings: Settings, parameter: str = "trials") -> int:
    """The trials a request asked for (default: the server's), or 422 naming ``parameter``."""
    if requested is None:
        return settings.default_trials
    if requested > settings.max_trials:
        raise InvalidRequest(
            f"{parameter}={requested} is more than this server allows ({settings.max_trials}, "
            "SYNTH_MAX_TRIALS)",
            parameter=parameter,
            maximum=settings.max_trials,
        )
    return requested


__all__ = [
    "RETRY_AFTER",
    "WaitQuery",
    "checked_trials",
    "checked_wait",
    "job_out",
    "job_response",
    "job_url",
    "plan_links",
    "plan_out",
]
