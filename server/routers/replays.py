"""``/v1/replays``: replay an AL program against a task (nominal run + Monte Carlo trials)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request, Response

from server.deps import JsonBody, ServiceDep, SettingsDep, Writer, client_key
from server.routers.jobs import answer_submission
from server.schemas import JobOut, ReplayIn, problem_responses
from server.views import WaitQuery, checked_trials, checked_wait

router = APIRouter(prefix="/v1/replays", tags=["replays"])


@router.post(
    "",
    status_code=202,
    response_model=JobOut,
    dependencies=[Writer, JsonBody],
    summary="Submit a replay of an AL program against a task spec or a stored plan's task",
    responses={
        202: {
            "model": JobOut,
            "description": "the job is queued or running: follow `Location` (GET /v1/jobs/{id})",
        },
        201: {"model": JobOut, "description": "the job finished within `wait`"},
        **problem_responses(400, 401, 404, 408, 413, 415, 422, 429, 500, 503),
    },
)
async def create_replay(
    replay: ReplayIn,
    request: Request,
    response: Response,
    service: ServiceDep,
    settings: SettingsDep,
    wait: WaitQuery = 0,
) -> dict[str, Any]:
    """``202`` with the job; once ``done`` its ``result`` is the replay report.

    The request is checked first: the trials against the server's maximum, the plan
    (``404``), the spec (``422``). A program that does not parse fails the job (its
    ``problem`` names the line).
    """
    trials = checked_trials(replay.trials, settings)
    wait = checked_wait(wait, settings)
    job = await service.submit_replay(
        replay.program,
        replay.spec,
        replay.plan_id,
        trials,
        replay.seed,
        settings,
        client_key(request),
    )
    return await answer_submission(service, job, wait, response)


__all__ = ["router"]
