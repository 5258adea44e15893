"""Request and response bodies of the HTTP API, split by role (``…In`` read, ``…Out`` written).

Planner output (``strategy``, ``candidates``, ``rejected``, …) is passed through as the planner
writes it, the same shape as ``synth plan --json``; these models pin down what the server adds.
"""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    WithJsonSchema,
    model_validator,
)
from pydantic_core import PydanticCustomError

from synth.seeds import MAX_SEED

_JSON_KINDS = {bool: "a boolean", int: "a number", float: "a number", list: "an array"}


def _spec_body(value: Any, *, optional: bool) -> Any:
    """A spec field's value: YAML text or a JSON object, else one error naming what it was.

    Left to the union, a number came back as two errors under pydantic's branch names
    (``spec.dict[str,any]``, ``spec.str``).
    """
    if isinstance(value, dict | str) or (optional and value is None):
        return value
    kind = "null" if value is None else _JSON_KINDS.get(type(value), type(value).__name__)
    raise PydanticCustomError(
        "spec_type", "a task spec is YAML text or a JSON object, not {kind}", {"kind": kind}
    )


SpecBody = Annotated[
    dict[str, Any] | str, BeforeValidator(lambda value: _spec_body(value, optional=False))
]
"""A request's task spec: YAML text or a JSON object."""
OptionalSpecBody = Annotated[
    dict[str, Any] | str | None, BeforeValidator(lambda value: _spec_body(value, optional=True))
]


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
    404: "no such plan or job",
    408: "the request body did not arrive within the server's body timeout",
    413: "the request body is over the server's limit",
    415: "the body's media type is not accepted",
    422: "the request or the task is invalid, or no program can be made for it",
    429: "this client already has as many jobs running and queued as the server allows",
    500: "an internal error (logged with the request id); never caused by the input alone",
    503: "the server holds as many unfinished jobs as it may (SYNTH_MAX_JOBS), or no worker "
    "became free in time",
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
        strict=True,  # JSON true is not 1 trial, nor "8" eight
        json_schema_extra={
            "examples": [
                {"plan_id": "3f2c0a9e5b7d4e1f8a6c2b0d9e7f5a31", "trials": 20, "seed": 1},
                {"program": "BEGIN ... END", "spec": "name: t\nframes: [...]", "trials": 8},
            ]
        },
    )

    program: str | None = Field(default=None, description="AL program text")
    spec: OptionalSpecBody = Field(
        default=None, description="task spec: a JSON object, or YAML text"
    )
    plan_id: str | None = Field(default=None, description="a stored plan's id")
    trials: int | None = Field(
        default=None, ge=0, description="Monte Carlo trials (default: the server's)"
    )
    seed: int = Field(default=0, ge=0, le=MAX_SEED, description="random seed of the trials")

    @model_validator(mode="after")
    def _one_task(self) -> ReplayIn:
        if self.plan_id is not None and self.spec is not None:
            raise ValueError("give either 'spec' or 'plan_id', not both")
        if self.plan_id is None and (self.spec is None or self.program is None):
            raise ValueError("give 'program' and 'spec', or 'plan_id'")
        return self


class HealthOut(BaseModel):
    """Liveness: the database, the workers and the jobs."""

    status: str = Field(description="'ok', or 'degraded' when the database or workers are down")
    version: str
    database: str
    workers: dict[str, int] = Field(
        description="size, alive, idle (started and free), running, waiting"
    )
    jobs: dict[str, int] = Field(description="unfinished, running, queued (in this server)")


JobState = Literal["queued", "running", "done", "failed", "lost", "cancelled"]


class JobLinks(BaseModel):
    """Where to find a job and, once a plan job is done, its plan and program."""

    self_: str = Field(alias="self")
    plan: str | None = Field(default=None, description="the plan (plan jobs, once done)")
    program: str | None = Field(default=None, description="its AL program")

    model_config = ConfigDict(populate_by_name=True)


class JobOut(BaseModel):
    """A job: a plan (with its proof) or a replay, run after the request that submitted it.

    ``state`` is ``queued`` or ``running`` until it is final: ``done`` (``result``), ``failed``
    (``problem``: the problem document the work raised, e.g. 422 no feasible strategy, 504 over
    the time budget), ``lost`` (the server stopped abruptly while it ran) or ``cancelled``
    (``DELETE``). Times are UTC.
    """

    model_config = ConfigDict(
        json_schema_extra={
            "example": {
                "id": "0c5d3f8e9a7b4c2d1e6f8a9b0c1d2e3f",
                "kind": "plan",
                "state": "queued",
                "created_at": "2026-11-22T03:35:57.795112Z",
                "started_at": None,
                "finished_at": None,
                "attempts": 0,
                "task": "seed_4_8",
                "options": {"trials": 8, "seed": 0, "validate": True},
                "plan_id": None,
                "reused": None,
                "result": None,
                "problem": None,
                "links": {"self": "/v1/jobs/0c5d3f8e9a7b4c2d1e6f8a9b0c1d2e3f"},
            }
        }
    )

    id: str
    kind: Literal["plan", "replay"]
    state: JobState
    created_at: datetime
    started_at: datetime | None = Field(description="when its last run started")
    finished_at: datetime | None
    attempts: int = Field(description="runs started (2 after a clean restart re-ran it)")
    task: str | None = Field(description="the task's name")
    options: dict[str, Any] = Field(description="the options it runs with (trials, seed, …)")
    plan_id: str | None = Field(description="plan jobs, once done: the plan made or reused")
    reused: bool | None = Field(
        description="plan jobs, once done: true when an identical earlier submission's plan "
        "was returned instead of planning again"
    )
    result: dict[str, Any] | None = Field(
        description="done: a plan job's plan (as GET /v1/plans/{id}; null if deleted since), "
        "a replay job's report (as `synth replay --json`)"
    )
    problem: Problem | None = Field(description="failed, lost or cancelled: why")
    links: JobLinks


class BatchTaskIn(BaseModel):
    """One task of a batch: the spec and its planning options (the query of POST /v1/plans)."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True, strict=True)

    spec: SpecBody = Field(description="task spec: a JSON object, or YAML text")
    trials: int | None = Field(
        default=None, ge=0, description="Monte Carlo trials (default: the server's)"
    )
    seed: int = Field(default=0, ge=0, le=MAX_SEED, description="random seed of the trials")
    try_harder: bool = Field(default=False, description="planner: refine more candidates")
    exhaustive: bool = Field(default=False, description="planner: refine every candidate")
    validate_: bool = Field(
        default=True, alias="validate", description="replay the program (false: skip)"
    )


class BatchIn(BaseModel):
    """Many tasks in one request; each becomes its own plan job.

    Items are checked one by one, so a bad item is answered with its own problem and does not
    stop the others.
    """

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "example": {
                "tasks": [
                    {"spec": "name: seed_4_8\nframes: [...]", "trials": 8},
                    {"spec": {"name": "other", "frames": []}, "validate": False},
                ]
            }
        },
    )

    tasks: list[Annotated[Any, WithJsonSchema(BatchTaskIn.model_json_schema())]] = Field(
        min_length=1, description="the tasks, at most the server's SYNTH_MAX_BATCH"
    )


class BatchItemOut(BaseModel):
    """The answer for one task of a batch: its job, or its problem."""

    index: int = Field(description="position of the task in the request")
    status: int = Field(description="202 queued, 201 done at once (reused), or a 4xx/503")
    location: str | None = Field(description="the job's URL")
    job: JobOut | None
    problem: Problem | None


class BatchOut(BaseModel):
    """One answer per task, in request order."""

    accepted: int
    rejected: int
    items: list[BatchItemOut]


__all__ = [
    "BatchIn",
    "BatchItemOut",
    "BatchOut",
    "BatchTaskIn",
    "HealthOut",
    "JobLinks",
    "JobOut",
    "JobState",
    "PlanLinks",
    "PlanOptionsOut",
    "PlanOut",
    "PlanPage",
    "PlanSummary",
    "Problem",
    "ReplayIn",
    "problem_responses",
]
