"""``/v1/replays``: replay an AL program against a task (nominal run + Monte Carlo trials)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from server.deps import ServiceDep, SettingsDep, Writer
from server.exceptions import InvalidRequest
from server.schemas import Problem, ReplayIn

router = APIRouter(prefix="/v1/replays", tags=["replays"])

_PROBLEM = {"model": Problem, "content": {"application/problem+json": {}}}


@router.post(
    "",
    dependencies=[Writer],
    summary="Replay an AL program against a task spec or a stored plan's task",
    responses={
        200: {"description": "the replay report (same shape as `synth replay --json`)"},
        401: _PROBLEM,
        404: _PROBLEM,
        413: _PROBLEM,
        422: _PROBLEM,
        503: _PROBLEM,
        504: _PROBLEM,
    },
)
async def create_replay(
    request: ReplayIn, service: ServiceDep, settings: SettingsDep
) -> dict[str, Any]:
    """The replay report of the program."""
    trials = settings.default_trials if request.trials is None else request.trials
    if trials > settings.max_trials:
        raise InvalidRequest(
            f"trials={trials} is more than this server allows ({settings.max_trials})",
            parameter="trials",
        )
    return await service.replay(
        request.program, request.spec, request.plan_id, trials, request.seed, settings
    )


__all__ = ["router"]
