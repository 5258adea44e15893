"""``/v1/replays``: replay an AL program against a task (nominal run + Monte Carlo trials)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request

from server.deps import ServiceDep, SettingsDep, Writer, client_key
from server.exceptions import InvalidRequest
from server.schemas import ReplayIn, problem_responses

router = APIRouter(prefix="/v1/replays", tags=["replays"])


@router.post(
    "",
    dependencies=[Writer],
    summary="Replay an AL program against a task spec or a stored plan's task",
    responses={
        200: {"description": "the replay report (same shape as `synth replay --json`)"},
        **problem_responses(400, 401, 404, 408, 413, 422, 429, 500, 503, 504),
    },
)
async def create_replay(
    replay: ReplayIn, request: Request, service: ServiceDep, settings: SettingsDep
) -> dict[str, Any]:
    """The replay report of the program."""
    trials = settings.default_trials if replay.trials is None else replay.trials
    if trials > settings.max_trials:
        raise InvalidRequest(
            f"trials={trials} is more than this server allows ({settings.max_trials})",
            parameter="trials",
        )
    return await service.replay(
        replay.program,
        replay.spec,
        replay.plan_id,
        trials,
        replay.seed,
        settings,
        client_key(request),
    )


__all__ = ["router"]
