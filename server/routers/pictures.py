"""``/v1/plans/{id}/plan.svg``, ``view.html``, ``trace.json``: a stored plan, drawn."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query
from fastapi.responses import HTMLResponse, JSONResponse, Response

from server.db import StoredPlan
from server.deps import Reader, ServiceDep, SettingsDep
from server.pictures import pictured_strategy, plan_svg_job, trace_job, view_html_job
from server.schemas import Problem
from server.service import SpecKind
from synth.seeds import MAX_SEED

router = APIRouter(prefix="/v1/plans", tags=["pictures"])

_PROBLEM = {"model": Problem, "content": {"application/problem+json": {}}}
_ERRORS: dict[int | str, dict[str, Any]] = {
    401: _PROBLEM,
    404: _PROBLEM,
    503: _PROBLEM,
    504: _PROBLEM,
}


def _kind(plan: StoredPlan) -> SpecKind:
    return "json" if plan.spec_media_type == "json" else "yaml"


@router.get(
    "/{plan_id}/plan.svg",
    response_class=Response,
    dependencies=[Reader],
    summary="The plan picture: top view in the hole's frame, side view of the heights",
    responses={200: {"content": {"image/svg+xml": {}}}, **_ERRORS},
)
async def get_plan_svg(plan_id: str, service: ServiceDep, settings: SettingsDep) -> Response:
    """The ``synth plan --svg`` picture of a stored plan (``image/svg+xml``)."""
    plan = await service.get_plan(plan_id)
    strategy = pictured_strategy(plan.result)
    svg = await service.pool.run(
        plan_svg_job,
        plan.spec_text,
        _kind(plan),
        plan.options,
        strategy,
        tuple(str(d) for d in settings.model_dirs),
        timeout=settings.plan_timeout,
        what="drawing the plan",
    )
    return Response(svg, media_type="image/svg+xml")


@router.get(
    "/{plan_id}/view.html",
    response_class=HTMLResponse,
    dependencies=[Reader],
    summary="The 3-D view of the plan's program: one offline HTML page",
    responses={200: {"content": {"text/html": {}}}, **_ERRORS},
)
async def get_view(plan_id: str, service: ServiceDep, settings: SettingsDep) -> HTMLResponse:
    """The ``synth view`` page of a stored plan's program (its nominal run)."""
    plan = await service.get_plan(plan_id)
    page = await service.pool.run(
        view_html_job,
        plan.program,
        plan.spec_text,
        _kind(plan),
        tuple(str(d) for d in settings.model_dirs),
        timeout=settings.plan_timeout,
        what="the 3-D view",
    )
    return HTMLResponse(page)


@router.get(
    "/{plan_id}/trace.json",
    dependencies=[Reader],
    summary="The trace of the plan's program replayed: nominal, or one Monte Carlo trial",
    responses={200: {"description": "the trace (docs/trace.md)"}, 422: _PROBLEM, **_ERRORS},
)
async def get_trace(
    plan_id: str,
    service: ServiceDep,
    settings: SettingsDep,
    trial: Annotated[
        int | None, Query(ge=0, description="Monte Carlo trial (default: the nominal run)")
    ] = None,
    seed: Annotated[int, Query(ge=0, le=MAX_SEED, description="seed of the trials")] = 0,
) -> JSONResponse:
    """The ``synth replay --trace`` document of a stored plan's program."""
    plan = await service.get_plan(plan_id)
    trace = await service.pool.run(
        trace_job,
        plan.program,
        plan.spec_text,
        _kind(plan),
        trial,
        seed,
        tuple(str(d) for d in settings.model_dirs),
        timeout=settings.plan_timeout,
        what="the trace",
    )
    return JSONResponse(trace)


__all__ = ["router"]
