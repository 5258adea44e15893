"""``/v1/plans``: submit tasks (each a job), read and delete stored plans and their programs."""

from __future__ import annotations

import json
from typing import Annotated, Any

from fastapi import APIRouter, Query, Request, Response
from fastapi.encoders import jsonable_encoder
from fastapi.responses import JSONResponse, PlainTextResponse
from pydantic import ValidationError

from server.deps import JsonBody, Reader, ServiceDep, SettingsDep, Writer, client_key
from server.errors import PROBLEM_MEDIA_TYPE, problem_document, validation_problem
from server.exceptions import InvalidRequest
from server.routers.jobs import answer_submission
from server.schemas import (
    BatchIn,
    BatchOut,
    BatchTaskIn,
    JobOut,
    PlanOut,
    PlanPage,
    PlanSummary,
    problem_responses,
)
from server.service import PlanRequest
from server.settings import Settings
from server.views import (
    WaitQuery,
    checked_trials,
    checked_wait,
    job_out,
    job_url,
    plan_links,
    plan_out,
)
from synth.exceptions import SpecError
from synth.seeds import MAX_SEED

router = APIRouter(prefix="/v1/plans", tags=["plans"])


def _expected_time(result: dict[str, Any]) -> float | None:
    """A stored plan's expected time [s]: ``strategy.time.expected_time``, or a sequence's own.

    Rows stored before the times were named as in the text hold it as ``total``.
    """
    if "steps" in result:  # an assembly sequence (SequenceSynthesis.to_json)
        value = result.get("expected_time")
        return None if value is None else float(value)
    times = (result.get("strategy") or {}).get("time") or {}
    value = times.get("expected_time", times.get("total"))
    return None if value is None else float(value)


def _strategy_name(result: dict[str, Any]) -> str | None:
    """A stored plan's strategy name; a sequence's is its steps' names in order, ``; ``-joined."""
    if "steps" in result:
        names = [str((step.get("strategy") or {}).get("name") or "?") for step in result["steps"]]
        return "; ".join(names) or None
    return (result.get("strategy") or {}).get("name") or None


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


def _options(
    trials: int,
    seed: int,
    try_harder: bool,
    exhaustive: bool,
    validate: bool,
    parameter: str = "trials",
) -> PlanRequest:
    if validate and trials == 0:
        # a plan so asked was stored "validated" with no trial run (Wilson 0–1)
        raise InvalidRequest(
            f"{parameter}=0 leaves nothing to validate: give {parameter} ≥ 1, or validate=false "
            "for the nominal replay alone",
            parameter=parameter,
        )
    return PlanRequest(  # trials and seed mean nothing without a replay: same hash
        trials=trials if validate else 0,
        seed=seed if validate else 0,
        try_harder=try_harder,
        exhaustive=exhaustive,
        validate=validate,
    )


_SUBMITTED: dict[int | str, dict[str, Any]] = {
    202: {
        "model": JobOut,
        "description": "the job is queued or running: follow `Location` (GET /v1/jobs/{id})",
    },
    201: {
        "model": JobOut,
        "description": "the job is already final: it finished within `wait`, or an identical "
        "submission had been planned (`reused`)",
    },
}


@router.post(
    "",
    status_code=202,
    response_model=JobOut,
    dependencies=[Writer],
    openapi_extra=_SPEC_BODY,
    summary="Submit a task: a job plans it, generates its AL program and proves it by replay",
    responses={**_SUBMITTED, **problem_responses(400, 401, 408, 413, 415, 422, 429, 500, 503)},
)
async def create_plan(
    request: Request,
    response: Response,
    service: ServiceDep,
    settings: SettingsDep,
    trials: Annotated[
        int | None, Query(ge=0, description="Monte Carlo trials (default: the server's)")
    ] = None,
    seed: Annotated[int, Query(ge=0, le=MAX_SEED, description="seed of the trials")] = 0,
    try_harder: Annotated[bool, Query(description="planner: refine more candidates")] = False,
    exhaustive: Annotated[bool, Query(description="planner: refine every candidate")] = False,
    validate: Annotated[bool, Query(description="replay the program (false: skip)")] = True,
    wait: WaitQuery = 0,
) -> dict[str, Any]:
    """``202`` with the job (``Location: /v1/jobs/{id}``); the spec is checked first (``422``).

    Poll the job, or wait for it with ``?wait=S`` here or on the job; once ``done`` its
    ``result`` is the plan. An identical submission is answered from the store: ``201``, a job
    that is done at once with ``reused: true``.
    """
    options = _options(checked_trials(trials, settings), seed, try_harder, exhaustive, validate)
    wait = checked_wait(wait, settings)
    body = await request.body()
    job = await service.submit_plan(
        body, request.headers.get("content-type"), options, settings, client_key(request)
    )
    return await answer_submission(service, job, wait, response)


def _batch_item(index: int, raw: Any, settings: Settings) -> tuple[bytes, str, PlanRequest]:
    """The body, content type and options of task ``index`` of a batch (422 if invalid)."""
    task = BatchTaskIn.model_validate(raw)
    parameter = f"tasks[{index}].trials"
    trials = checked_trials(task.trials, settings, parameter=parameter)
    options = _options(
        trials, task.seed, task.try_harder, task.exhaustive, task.validate_, parameter
    )
    if isinstance(task.spec, dict):
        return json.dumps(task.spec).encode(), "application/json", options
    try:
        return task.spec.encode("utf-8"), "application/yaml", options
    except UnicodeEncodeError as exc:
        raise SpecError("", f"the spec is not valid Unicode text (character {exc.start})") from None


@router.post(
    "/batch",
    status_code=202,
    response_model=BatchOut,
    dependencies=[Writer, JsonBody],
    summary="Submit many tasks at once: each its own plan job, each answered on its own",
    responses={
        202: {"model": BatchOut, "description": "at least one task became a job"},
        **problem_responses(400, 401, 408, 413, 415, 422, 429, 500, 503),
    },
)
async def create_batch(
    batch: BatchIn, request: Request, service: ServiceDep, settings: SettingsDep
) -> Any:
    """One item per task, in order: its job and ``location``, or its ``problem``.

    An accepted task has ``status`` 202 (201 if reused); a refused one its own 422, 429, … —
    a bad task does not stop the others. When no task was accepted the answer is a problem
    document with the ``items``.
    """
    if len(batch.tasks) > settings.max_batch:
        raise InvalidRequest(
            f"{len(batch.tasks)} tasks in one batch; this server takes at most "
            f"{settings.max_batch} (SYNTH_MAX_BATCH)",
            parameter="tasks",
            maximum=settings.max_batch,
        )
    client = client_key(request)
    items: list[dict[str, Any]] = []
    for index, raw in enumerate(batch.tasks):
        try:
            body, content_type, options = _batch_item(index, raw, settings)
            job = await service.submit_plan(body, content_type, options, settings, client)
        except ValidationError as exc:
            errors = [{**e, "loc": ("tasks", index, *e["loc"])} for e in exc.errors()]
            items.append(_rejected(index, validation_problem(errors)))
        except Exception as exc:  # the task's own problem (a bug is logged, as a 500 item)
            items.append(_rejected(index, problem_document(exc)))
        else:
            plan = await service.job_plan(job)
            status = 201 if job.finished else 202
            items.append(
                {
                    "index": index,
                    "status": status,
                    "location": job_url(job.id),
                    "job": job_out(job, plan),
                    "problem": None,
                }
            )
    accepted = sum(1 for item in items if item["job"] is not None)
    document = {"accepted": accepted, "rejected": len(items) - accepted, "items": items}
    if accepted:
        return document
    statuses = {item["status"] for item in items}
    status = statuses.pop() if len(statuses) == 1 else 422
    problem = {
        "type": "urn:synth:problem:batch-rejected",
        "title": "No task of the batch was accepted",
        "status": status,
        "detail": f"all {len(items)} task(s) were refused; each item has its problem",
        **document,
    }
    headers = {"Retry-After": "5"} if status in (429, 503) else None
    return JSONResponse(
        jsonable_encoder(problem),
        status_code=status,
        headers=headers,
        media_type=PROBLEM_MEDIA_TYPE,
    )


def _rejected(index: int, problem: dict[str, Any]) -> dict[str, Any]:
    return {
        "index": index,
        "status": problem["status"],
        "location": None,
        "job": None,
        "problem": problem,
    }


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
            strategy=_strategy_name(p.result),
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


@router.delete(
    "/{plan_id}",
    status_code=204,
    dependencies=[Writer],
    summary="Delete a stored plan",
    responses={204: {"description": "deleted"}, **problem_responses(401, 404, 500)},
)
async def delete_plan(plan_id: str, service: ServiceDep) -> Response:
    """The plan is gone (``404`` afterwards); jobs that made it keep its id."""
    await service.delete_plan(plan_id)
    return Response(status_code=204)


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
