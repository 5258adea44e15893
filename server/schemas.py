"""Request and response bodies of the HTTP API, split by role (``…In`` read, ``…Out`` written).

Planner output (``strategy``, ``candidates``, ``rejected``, …) is passed through as the planner
writes it, the same shape as ``synth plan --json``; these models pin down what the server adds.
"""

from __future__ import annotations

from datetime import datetime
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, model_validator


class Problem(BaseModel):
    """An error (RFC 9457): ``type``, ``title``, ``status``, ``detail`` and structured extras.

    Extras are e.g. ``path`` and ``line`` (spec errors) or ``reasons`` (no feasible strategy).
    """

    model_config = ConfigDict(
        extra="allow",
        json_schema_extra={
            "example": {
                "type": "urn:synth:problem:spec",
                "title": "Invalid task specification",
                "status": 422,
                "detail": "frames[0].pose.translation[0] (line 12): 45.2 has no unit",
                "path": "frames[0].pose.translation[0]",
                "line": 12,
                "message": "45.2 has no unit",
            }
        },
    )

    type: str
    title: str
    status: int
    detail: str


_PROBLEM_MEANINGS = {
    400: "the body could not be read as the endpoint's media type (e.g. JSON that is not UTF-8)",
    401: "a token is configured and the request lacks it",
    404: "no such plan",
    408: "the request body did not arrive within the server's body timeout",
    413: "the request body is over the server's limit",
    415: "the body's media type is not accepted",
    422: "the request or the task is invalid, or no program can be made for it",
    429: "this client already has as many jobs running and queued as the server allows",
    500: "an internal error (logged with the request id); never caused by the input alone",
    503: "no worker became free within the time budget, or a stage is missing from this build",
    504: "the job ran past the time budget and was stopped",
}


def problem_responses(*statuses: int) -> dict[int | str, dict[str, Any]]:
    """OpenAPI ``responses`` entries for ``statuses``: problem documents with their meaning."""
    return {
        status: {
            "model": Problem,
            "content": {"application/problem+json": {}},
            "description": _PROBLEM_MEANINGS[status],
        }
        for status in statuses
    }


class PlanOptionsOut(BaseModel):
    """The options a plan was made with."""

    trials: int = Field(description="Monte Carlo trials of the replay")
    seed: int = Field(description="random seed of the replay's trials")
    try_harder: bool
    exhaustive: bool
    validate_: bool = Field(alias="validate", description="whether the program was replayed")

    model_config = ConfigDict(populate_by_name=True)


class PlanLinks(BaseModel):
    """Where to find a plan and its program."""

    self_: str = Field(alias="self")
    program: str

    model_config = ConfigDict(populate_by_name=True)


class PlanOut(BaseModel):
    """A stored plan: the ``synth plan --json`` document plus ``id`` and ``validation``.

    Besides the fields below it carries the planner's own keys unchanged: ``strategy`` (the
    chosen pin-in-hole strategy), ``candidates``, ``rejected``, ``refined``, ``planning_time``
    [s] and ``counters``. All quantities are SI (m, rad, s, N).
    """

    model_config = ConfigDict(extra="allow")

    id: str
    task: str = Field(description="the task's name")
    created_at: datetime
    content_hash: str = Field(description="SHA-256 of the submission (body, kind, options)")
    options: PlanOptionsOut
    program: str = Field(description="the generated AL program")
    validation: dict[str, Any] | None = Field(
        description="the replay report (nominal run and Monte Carlo trials); null when the "
        "plan was made with validate=false"
    )
    links: PlanLinks


class PlanSummary(BaseModel):
    """One line of the plan listing."""

    id: str
    task: str
    created_at: datetime
    strategy: str | None = Field(description="name of the chosen strategy")
    expected_time: float | None = Field(description="the strategy's expected time [s]")
    validated: bool
    links: PlanLinks


class PlanPage(BaseModel):
    """A page of plans, newest first; follow ``next`` for older ones."""

    items: list[PlanSummary]
    limit: int
    next_cursor: int | None = Field(description="pass as ?cursor= for the next page")
    next: str | None = Field(description="URL of the next page, or null on the last one")


class ReplayIn(BaseModel):
    """A program to replay and the task to replay it against.

    Give ``program`` and ``spec`` (the task as a JSON object, or YAML text), or ``plan_id`` to
    use a stored plan's task (and its program, unless ``program`` is given too).
    """

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {"plan_id": "3f2c0a9e5b7d4e1f8a6c2b0d9e7f5a31", "trials": 20, "seed": 1},
                {"program": "BEGIN ... END", "spec": "name: t\nframes: [...]", "trials": 8},
            ]
        },
    )

    program: str | None = Field(default=None, description="AL program text")
    spec: dict[str, Any] | str | None = Field(
        default=None, description="task spec: a JSON object, or YAML text"
    )
    plan_id: str | None = Field(default=None, description="a stored plan's id")
    trials: int | None = Field(
        default=None, ge=0, description="Monte Carlo trials (default: the server's)"
    )
    seed: int = Field(default=0, ge=0, le=2**32 - 1, description="random seed of the trials")

    @model_validator(mode="after")
    def _one_task(self) -> ReplayIn:
        if self.plan_id is not None and self.spec is not None:
            raise ValueError("give either 'spec' or 'plan_id', not both")
        if self.plan_id is None and (self.spec is None or self.program is None):
            raise ValueError("give 'program' and 'spec', or 'plan_id'")
        return self


class HealthOut(BaseModel):
    """Liveness and what this build can do."""

    status: str = Field(description="'ok', or 'degraded' when the database or workers are down")
    version: str
    database: str
    workers: dict[str, int]
    stages: dict[str, bool] = Field(description="planner, codegen, replay: present in this build")


__all__ = [
    "HealthOut",
    "PlanLinks",
    "PlanOptionsOut",
    "PlanOut",
    "PlanPage",
    "PlanSummary",
    "Problem",
    "ReplayIn",
    "problem_responses",
]
