"""``/v1/jobs/{id}``: follow a submitted plan or replay (poll, or wait), and cancel or delete it."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Response

from server.db import StoredJob
from server.deps import Reader, ServiceDep, SettingsDep, Writer
from server.schemas import JobOut, problem_responses
from server.service import PlanService
from server.views import WaitQuery, checked_wait, job_response

router = APIRouter(prefix="/v1/jobs", tags=["jobs"])


async def answer_submission(
    service: PlanService, job: StoredJob, wait: float, response: Response
) -> dict[str, Any]:
    """The answer to a submission: the job after at most ``wait`` [s], 202 or 201."""
    if wait > 0 and not job.finished:
        job = await service.get_job(job.id, wait)
    return job_response(job, await service.job_plan(job), created=True, response=response)


@router.get(
    "/{job_id}",
    response_model=JobOut,
    dependencies=[Reader],
    summary="A job: its state, and its result or problem once it is final",
    responses=problem_responses(401, 404, 422, 500),
)
async def get_job(
    job_id: str, response: Response, service: ServiceDep, settings: SettingsDep, wait: WaitQuery = 0
) -> dict[str, Any]:
    """The job now, or once it is final if that is within ``wait`` seconds (a long poll).

    An unfinished job's answer carries ``Retry-After``, the suggested poll interval.
    """
    job = await service.get_job(job_id, checked_wait(wait, settings))
    return job_response(job, await service.job_plan(job), created=False, response=response)


@router.delete(
    "/{job_id}",
    response_model=JobOut,
    dependencies=[Writer],
    summary="Cancel an unfinished job, or delete a finished one",
    responses={
        200: {"model": JobOut, "description": "the job was unfinished: it is now cancelled"},
        204: {"description": "the job was final: its record is deleted"},
        **problem_responses(401, 404, 500),
    },
)
async def delete_job(job_id: str, service: ServiceDep) -> Any:
    """Cancel or delete: an unfinished job is cancelled and kept, a final one is deleted.

    Cancelling a running job stops its worker. Deleting a plan job leaves its plan (delete
    that with ``DELETE /v1/plans/{id}``).
    """
    cancelled = await service.delete_job(job_id)
    if cancelled is None:
        return Response(status_code=204)
    return job_response(cancelled, None, created=False)


__all__ = ["answer_submission", "router"]
