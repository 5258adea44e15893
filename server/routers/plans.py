"""``/v1/plans``: submit a task spec, read stored plans and their AL programs."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Request, Response
from fastapi.responses import PlainTextResponse

from server.db import StoredPlan
from server.deps import Reader, ServiceDep, SettingsDep, Writer, client_key
from server.exceptions import InvalidRequest
from server.schemas import PlanLinks, PlanOut, PlanPage, PlanSummary, problem_responses
from server.service import PlanOptions
from server.settings import Settings

router = APIRouter(prefix="/v1/plans", tags=["plans"])


def _expected_time(result: dict[str, Any]) -> float | None:
    """A stored plan's expected time [s]: ``strategy.time.expected_time``.

    Rows stored before the times were named as in the text hold it as ``total``.
    """
    times = (result.get("strategy") or {}).get("time") or {}
    value = times.get("expected_time", times.get("total"))
    return None if value is None else float(value)


MAX_CURSOR = 2**63 - 1  # plan sequence numbers are SQL 64-bit integers

_SPEC_EXAMPLE = """\
name: seed_4_8
frames:
  - name: box
    al_name: BOX
    parent: world
    pose: {translation: [45.2 cm, 102 cm, 0 cm]}
    uncertainty: {x: 0.3 in, y: 0.2 in, rz: 5 deg}
    shape: {type: box, size: [8.90 cm, 7.60 cm, 4.90 cm]}
  # ... the rest of fixtures/tasks/seed_4_8.yaml
insertion: {pin: PIN1, hole: BH1, start_hole: RH1, d_f: 1.71 cm, dr_ok: 0.762 cm}
"""

_SPEC_BODY: dict[str, Any] = {
    "requestBody": {
        "required": True,
        "description": "A task spec (docs/task-spec.md) as YAML or JSON; quantities carry units.",
        "content": {
            "application/yaml": {"schema": {"type": "string"}, "example": _SPEC_EXAMPLE},
            "application/json": {"schema": {"type": "object", "additionalProperties": True}},
        },
    }
}


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


def _trials(requested: int | None, settings: Settings) -> int:
    if requested is None:
        return settings.default_trials
    if requested > settings.max_trials:
        raise InvalidRequest(
            f"trials={requested} is more than this server allows ({settings.max_trials})",
            parameter="trials",
        )
    return requested


@router.post(
    "",
    status_code=201,
    response_model=PlanOut,
    dependencies=[Writer],
    openapi_extra=_SPEC_BODY,
    summary="Plan a task, generate its AL program and validate it by replay",
    responses={
        200: {"model": PlanOut, "description": "an identical submission was already planned"},
        **problem_responses(400, 401, 408, 413, 415, 422, 429, 500, 503, 504),
    },
)
async def create_plan(
    request: Request,
    response: Response,
    service: ServiceDep,
    settings: SettingsDep,
    trials: Annotated[
        int | None, Query(ge=0, description="Monte Carlo trials (default: the server's)")
    ] = None,
    seed: Annotated[int, Query(ge=0, le=2**32 - 1, description="seed of the trials")] = 0,
    try_harder: Annotated[bool, Query(description="planner: refine more candidates")] = False,
    exhaustive: Annotated[bool, Query(description="planner: refine every candidate")] = False,
    validate: Annotated[bool, Query(description="replay the program (false: skip)")] = True,
) -> dict[str, Any]:
    """Plan the task in the body; ``201`` with ``Location``, or ``200`` for a duplicate."""
    trials = _trials(trials, settings)
    options = PlanOptions(  # trials and seed mean nothing without a replay: same hash
        trials=trials if validate else 0,
        seed=seed if validate else 0,
        try_harder=try_harder,
        exhaustive=exhaustive,
        validate=validate,
    )
    body = await request.body()
    plan, created = await service.create_plan(
        body, request.headers.get("content-type"), options, settings, client_key(request)
    )
    response.headers["Location"] = f"/v1/plans/{plan.id}"
    if not created:
        response.status_code = 200
    return plan_out(plan)


@router.get(
    "",
    response_model=PlanPage,
    dependencies=[Reader],
    summary="List plans, newest first",
    responses=problem_responses(401, 422, 500),
)
async def list_plans(
    service: ServiceDep,
    limit: Annotated[int, Query(ge=1, le=100, description="plans per page")] = 20,
    cursor: Annotated[
        int | None, Query(ge=1, le=MAX_CURSOR, description="next_cursor of the previous page")
    ] = None,
) -> PlanPage:
    """A page of plan summaries and the link to the next page."""
    plans, next_cursor = await service.list_plans(limit, cursor)
    items = [
        PlanSummary(
            id=p.id,
            task=p.task_name,
            created_at=p.created_at,
            strategy=(p.result.get("strategy") or {}).get("name") or None,
            expected_time=_expected_time(p.result),
            validated=p.validation is not None,
            links=plan_links(p.id),
        )
        for p in plans
    ]
    next_url = None if next_cursor is None else f"/v1/plans?limit={limit}&cursor={next_cursor}"
    return PlanPage(items=items, limit=limit, next_cursor=next_cursor, next=next_url)


@router.get(
    "/{plan_id}",
    response_model=PlanOut,
    dependencies=[Reader],
    summary="A stored plan",
    responses=problem_responses(401, 404, 500),
)
async def get_plan(plan_id: str, service: ServiceDep) -> dict[str, Any]:
    """The plan as it was answered when it was created."""
    return plan_out(await service.get_plan(plan_id))


@router.get(
    "/{plan_id}/program.al",
    response_class=PlainTextResponse,
    dependencies=[Reader],
    summary="A stored plan's AL program",
    responses={200: {"content": {"text/plain": {}}}, **problem_responses(401, 404, 500)},
)
async def get_program(plan_id: str, service: ServiceDep) -> PlainTextResponse:
    """The generated AL program as ``text/plain``."""
    plan = await service.get_plan(plan_id)
    return PlainTextResponse(
        plan.program,
        headers={"Content-Disposition": f'inline; filename="{plan.id}.al"'},
    )


__all__ = ["router"]
