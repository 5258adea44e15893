"""The one place where the server calls synth: parse, plan, emit, replay, store.

Routes call :class:`PlanService`. It checks a submission at once (the task spec is parsed and
validated in a thread of the server, so a bad spec is a 422 answer, not a failed job), then
hands the work to the job manager (:mod:`server.jobs`), which runs it in a worker process
(:mod:`server.workers`) under the time budget; results are stored through :mod:`server.db`.
The module-level ``*_job`` functions are the workers' side: they take and return plain
picklable values.
"""

from __future__ import annotations

import asyncio
import hashlib
import importlib
import json
import math
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import synth
from server.exceptions import NotFound, UnsupportedMediaType
from server.lanes import Lanes
from server.modelpaths import confine_model_files
from server.settings import Settings
from server.workers import STARTUP_TIMEOUT, WorkerPool
from synth.exceptions import SpecError
from synth.models.spec import TaskSpec
from synth.models.yamlread import YamlLimits

if TYPE_CHECKING:  # the server's side only: worker processes never import the store or jobs
    from server.db import PlanStore, StoredJob, StoredPlan
    from server.jobs import Outcome

SpecKind = Literal["yaml", "json"]

MAX_NESTING = 32  # deepest mapping/sequence nesting accepted in a spec (the schema needs ~6)
YAML_LIMITS = YamlLimits(max_depth=MAX_NESTING, max_aliases=0)  # the CLI's, without aliases

YAML_MEDIA_TYPES = frozenset(
    {"application/yaml", "application/x-yaml", "text/yaml", "text/x-yaml", "text/plain"}
)
JSON_MEDIA_TYPES = frozenset({"application/json"})
ACCEPTED_MEDIA_TYPES = tuple(sorted(YAML_MEDIA_TYPES | JSON_MEDIA_TYPES))


# -- spec bodies ------------------------------------------------------------------------------


def media_type(content_type: str | None) -> str:
    """A ``Content-Type`` header's media type, lower case, without its parameters ("" if none)."""
    return (content_type or "").split(";", 1)[0].strip().lower()


def is_json_media(media: str) -> bool:
    """Whether a :func:`media_type` is JSON (``application/json`` or any ``+json`` type)."""
    return media in JSON_MEDIA_TYPES or media.endswith("+json")


def spec_kind(content_type: str | None) -> SpecKind:
    """``"yaml"`` or ``"json"`` for a request's ``Content-Type``; 415 for anything else.

    No content type means YAML (of which JSON is a subset).
    """
    media = media_type(content_type)
    if not media or media in YAML_MEDIA_TYPES:
        return "yaml"
    if is_json_media(media):
        return "json"
    raise UnsupportedMediaType(
        f"cannot read a task spec sent as {media!r}; send YAML (Content-Type: application/yaml) "
        "or JSON (application/json)",
        accepted=list(ACCEPTED_MEDIA_TYPES),
    )


def _nesting(value: Any) -> int:
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, level = stack.pop()
        if isinstance(item, dict | list):
            deepest = max(deepest, level)
            if deepest > MAX_NESTING:
                return deepest
            children = item.values() if isinstance(item, dict) else item
            stack.extend((c, level + 1) for c in children)
    return deepest


def _reject_non_finite(value: str) -> float:
    raise ValueError(f"{value} is not a JSON number")


class _DuplicateKey(ValueError):
    def __init__(self, key: str) -> None:
        super().__init__(key)
        self.key = key


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object's members, refusing a key given twice (json keeps the last silently).

    The same task as YAML is refused at the key's line (the loader's rule); as JSON its second
    ``insertion`` won, and the program went into another hole.
    """
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(key)
        out[key] = value
    return out


def parse_spec(body: bytes | str | dict[str, Any], kind: SpecKind = "yaml") -> TaskSpec:
    """A validated :class:`TaskSpec` from a request body (bytes/str) or an inline JSON object.

    Every problem is a :class:`SpecError` with the field path and, for YAML, the line.
    """
    from synth.models.loader import parse_task, validate_task

    if isinstance(body, dict):
        if _nesting(body) > MAX_NESTING:
            raise SpecError("", f"nested deeper than {MAX_NESTING} levels")
        return validate_task(body)
    if isinstance(body, bytes):
        try:
            text = body.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise SpecError("", f"the body is not UTF-8 text (byte {exc.start})") from None
    else:
        text = body
    if not text.strip():
        raise SpecError("", "empty body: send a task spec (YAML or JSON)")
    if kind == "json":
        try:
            data = json.loads(
                text, parse_constant=_reject_non_finite, object_pairs_hook=_unique_keys
            )
        except json.JSONDecodeError as exc:
            raise SpecError("", f"JSON syntax error: {exc.msg}", exc.lineno) from None
        except _DuplicateKey as exc:
            raise SpecError(
                exc.key, f"the key {exc.key!r} is given twice in one JSON object"
            ) from None
        except (ValueError, RecursionError) as exc:
            raise SpecError("", f"invalid JSON: {exc}") from None
        if not isinstance(data, dict):
            raise SpecError("", "a task is a JSON object with 'name' and 'frames'", 1)
        return parse_spec(data)
    return parse_task(text, source="<request>", limits=YAML_LIMITS)


def content_hash(body: bytes, kind: SpecKind, options: dict[str, Any]) -> str:
    """SHA-256 of (synth version, body kind, body bytes, options): the de-dup key of a plan."""
    digest = hashlib.sha256()
    header = {"synth": synth.__version__, "kind": kind, "options": options}
    digest.update(json.dumps(header, sort_keys=True).encode())
    digest.update(b"\0")
    digest.update(body)
    return digest.hexdigest()


# -- warm-up (each worker, once) -------------------------------------------------------------


WARM_MODULES = (
    "synth.models.loader",
    "synth.models.graph",
    "synth.models.arm",
    "synth.errors.estimate",
    "synth.strategies.planner",
    "synth.codegen.emitter",
    "synth.replay",
    "synth.replay.run",
    "synth.al.parser",
    "synth.pipeline",
)


def warm_up() -> None:
    """Import synth's heavy modules once, so a worker's first job does not pay for them."""
    for module in WARM_MODULES:
        importlib.import_module(module)


def warm_up_parser() -> None:
    """Import the spec loader in the server, so the first submission is checked at once."""
    importlib.import_module("synth.models.loader")


# -- jobs (run in worker processes) ----------------------------------------------------------


def _spec_for_server(
    body: bytes | str | dict[str, Any], kind: SpecKind, model_dirs: tuple[str, ...]
) -> TaskSpec:
    return confine_model_files(parse_spec(body, kind), [Path(d) for d in model_dirs])


def plan_job(
    body: bytes, kind: SpecKind, options: dict[str, Any], model_dirs: tuple[str, ...]
) -> dict[str, Any]:
    """Parse one task and take it to a proven program (:func:`synth.pipeline.synthesize`).

    The proof runs ``options["trials"]`` Monte Carlo trials (none when ``validate`` is false:
    the nominal replay still proves the program); ``validation`` is the proof in the replay
    report's shape, so it can be compared with ``POST /v1/replays``.
    """
    spec = _spec_for_server(body, kind, model_dirs)
    from synth.pipeline import SynthesisOptions, synthesize
    from synth.replay.proof import ProofOptions
    from synth.strategies.options import PlanOptions

    trials = options["trials"] if options["validate"] else 0
    synthesis = synthesize(
        spec,
        SynthesisOptions(
            plan=PlanOptions(try_harder=options["try_harder"], exhaustive=options["exhaustive"]),
            # One worker: the job already runs in a worker process of the server's pool.
            proof=ProofOptions.for_task(spec, trials=trials, seed=options["seed"], workers=1),
        ),
    )
    document = synthesis.to_json()
    program = document.pop("program")
    return {
        "task": spec.name,
        "spec": spec.model_dump(mode="json"),
        "result": document,
        "program": program,
        "validation": synthesis.proof.as_replay_json() if options["validate"] else None,
    }


def replay_job(
    program: str,
    spec_body: bytes | str | dict[str, Any],
    kind: SpecKind,
    trials: int,
    seed: int,
    model_dirs: tuple[str, ...],
) -> dict[str, Any]:
    """Replay ``program`` against the task in ``spec_body``: the replay report as JSON."""
    from synth.replay import replay_program

    spec = _spec_for_server(spec_body, kind, model_dirs)
    return dict(replay_program(program, spec, trials=trials, seed=seed).to_json())


# -- orchestration (runs in the server) -------------------------------------------------------


@dataclass(frozen=True)
class PlanRequest:
    """Options of one planning request (the planner's own: :class:`synth.strategies.PlanOptions`).

    ``trials``: Monte Carlo trials of the replay; ``seed``: its random seed; ``validate``:
    replay at all; ``try_harder`` and ``exhaustive`` are passed to the planner.
    """

    trials: int
    seed: int = 0
    try_harder: bool = False
    exhaustive: bool = False
    validate: bool = True

    def to_json(self) -> dict[str, Any]:
        """JSON form (also the options part of the content hash)."""
        return asdict(self)


def _finite_json(value: Any) -> Any:
    """``value`` with non-finite floats as strings (JSON has no NaN or infinity)."""
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, dict):
        return {k: _finite_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite_json(v) for v in value]
    return value


def _model_dirs(settings: Settings) -> tuple[str, ...]:
    return tuple(str(d) for d in settings.model_dirs)


def _kind_of(plan: StoredPlan) -> SpecKind:
    return "json" if plan.spec_media_type == "json" else "yaml"


class PlanService:
    """Plans and replays for the routes: validation, jobs, de-duplication, storage.

    A submission is checked at once (the spec parses and validates, its model files resolve,
    the options are within bounds: else 4xx) and then becomes a job (:mod:`server.jobs`) that
    runs in :attr:`pool` once its client's lane (:mod:`server.lanes`) has a slot, for at most
    ``plan_timeout`` [s].
    """

    def __init__(
        self, store: PlanStore, pool: WorkerPool, lanes: Lanes, settings: Settings
    ) -> None:
        self.store = store
        self.pool = pool
        self.lanes = lanes
        from server.jobs import JobManager

        self.jobs = JobManager(
            store, lanes, {"plan": self._run_plan, "replay": self._run_replay}, settings
        )

    # -- executors (the jobs' work, run by the job manager) -----------------------------------

    async def _in_worker(
        self, settings: Settings, fn: Callable[..., Any], *args: Any, what: str
    ) -> Any:
        # The job holds a lane slot, so a worker is free unless one is being replaced (or a
        # picture route holds it): wait for one as long as a worker takes to start.
        return await self.pool.run(
            fn, *args, timeout=settings.plan_timeout, wait=STARTUP_TIMEOUT, what=what
        )

    async def _run_plan(self, job: StoredJob, settings: Settings) -> Outcome:
        from server.db import NewPlan
        from server.jobs import Outcome

        body, kind = job.payload["body"], job.payload["kind"]
        outcome = await self._in_worker(
            settings,
            plan_job,
            body.encode("utf-8"),
            kind,
            job.options,
            _model_dirs(settings),
            what="planning",
        )
        new = NewPlan(
            content_hash=str(job.content_hash),
            task_name=outcome["task"],
            spec_text=body,
            spec_media_type=kind,
            spec=_finite_json(outcome["spec"]),
            options=job.options,
            result=_finite_json(outcome["result"]),
            program=outcome["program"],
            validation=_finite_json(outcome["validation"]),
        )
        plan, created = await asyncio.to_thread(self.store.add, new)
        return Outcome(plan_id=plan.id, result={"reused": not created})

    async def _run_replay(self, job: StoredJob, settings: Settings) -> Outcome:
        from server.jobs import Outcome

        payload = job.payload
        report = await self._in_worker(
            settings,
            replay_job,
            payload["program"],
            payload["spec"],
            payload["kind"],
            job.options["trials"],
            job.options["seed"],
            _model_dirs(settings),
            what="the replay",
        )
        return Outcome(result=dict(_finite_json(report)))

    # -- submissions --------------------------------------------------------------------------

    async def _checked_spec(
        self, body: bytes | str | dict[str, Any], kind: SpecKind, settings: Settings
    ) -> TaskSpec:
        """The task in ``body``, validated now (422 at once, not a failed job)."""
        return await asyncio.to_thread(_spec_for_server, body, kind, _model_dirs(settings))

    async def submit_plan(
        self,
        body: bytes,
        content_type: str | None,
        options: PlanRequest,
        settings: Settings,
        client: str = "-",
    ) -> StoredJob:
        """A job that plans the task in ``body``; the spec is checked first (422 at once).

        An identical earlier submission (same body, kind and options) is answered from the
        store: the job is ``done`` at once, with ``reused`` in its result.
        """
        from server.db import NewJob
        from server.jobs import Outcome

        kind = spec_kind(content_type)
        spec = await self._checked_spec(body, kind, settings)
        key = content_hash(body, kind, options.to_json())
        job = NewJob(
            kind="plan",
            client=client,
            task_name=spec.name,
            content_hash=key,
            options=options.to_json(),
            payload={"body": body.decode("utf-8"), "kind": kind},
        )
        twin = await asyncio.to_thread(self.store.by_hash, key)
        if twin is not None:
            return await self.jobs.record_done(
                job, Outcome(plan_id=twin.id, result={"reused": True})
            )
        return await self.jobs.submit(job, settings)

    async def submit_replay(
        self,
        program: str | None,
        spec: str | dict[str, Any] | None,
        plan_id: str | None,
        trials: int,
        seed: int,
        settings: Settings,
        client: str = "-",
    ) -> StoredJob:
        """A job that replays ``program`` against ``spec``, or against a stored plan's task.

        With ``plan_id`` the program defaults to the plan's. The plan must exist and the spec
        validate (404, 422 at once).
        """
        from server.db import NewJob

        kind: SpecKind = "yaml"
        spec_body: str | dict[str, Any]
        if plan_id is not None:
            plan = await self.get_plan(plan_id)
            spec_body, kind = plan.spec_text, _kind_of(plan)
            program = plan.program if program is None else program
        else:
            assert spec is not None and program is not None  # the request schema ensures it
            spec_body = spec
        task = await self._checked_spec(spec_body, kind, settings)
        job = NewJob(
            kind="replay",
            client=client,
            task_name=task.name,
            content_hash=None,
            options={"trials": trials, "seed": seed, "plan_id": plan_id},
            payload={"program": program, "spec": spec_body, "kind": kind},
        )
        return await self.jobs.submit(job, settings)

    # -- jobs ---------------------------------------------------------------------------------

    async def get_job(self, job_id: str, wait: float = 0.0) -> StoredJob:
        """The job ``job_id`` once it is final or ``wait`` [s] have passed; 404 if unknown."""
        if not _is_id(job_id):
            raise NotFound(f"no job with id {job_id[:64]!r}")
        await self.jobs.wait(job_id, wait)
        job = await asyncio.to_thread(self.store.get_job, job_id)
        if job is None:
            raise NotFound(f"no job with id {job_id[:64]!r}")
        return job

    async def job_plan(self, job: StoredJob) -> StoredPlan | None:
        """The plan a finished plan job made or reused (None: none, or deleted since)."""
        if job.plan_id is None:
            return None
        return await asyncio.to_thread(self.store.get, job.plan_id)

    async def delete_job(self, job_id: str) -> StoredJob | None:
        """Cancel the job if unfinished (return it, cancelled), else delete it (None); 404."""
        job = await self.get_job(job_id)
        if job.finished:
            await asyncio.to_thread(self.store.delete_job, job_id)
            return None
        await self.jobs.cancel(job_id)
        return await self.get_job(job_id)

    # -- plans --------------------------------------------------------------------------------

    async def get_plan(self, plan_id: str) -> StoredPlan:
        """The stored plan ``plan_id``; :class:`NotFound` otherwise."""
        plan = None
        if _is_id(plan_id):
            plan = await asyncio.to_thread(self.store.get, plan_id)
        if plan is None:
            raise NotFound(f"no plan with id {plan_id[:64]!r}")
        return plan

    async def delete_plan(self, plan_id: str) -> None:
        """Delete the stored plan ``plan_id``; :class:`NotFound` when there is none."""
        if not (_is_id(plan_id) and await asyncio.to_thread(self.store.delete_plan, plan_id)):
            raise NotFound(f"no plan with id {plan_id[:64]!r}")

    async def list_plans(
        self, limit: int, cursor: int | None
    ) -> tuple[list[StoredPlan], int | None]:
        """A page of plans, newest first, and the cursor of the next page."""
        return await asyncio.to_thread(self.store.page, limit, cursor)

    async def health(self) -> dict[str, Any]:
        """Database, worker and job state."""
        database = await asyncio.to_thread(self.store.ping)
        return {
            "status": "ok" if database and self.pool.alive > 0 else "degraded",
            "version": synth.__version__,
            "database": "ok" if database else "unreachable",
            "workers": {
                "size": self.pool.size,
                "alive": self.pool.alive,
                "idle": self.pool.ready,
                "running": self.lanes.running,
                "waiting": self.lanes.waiting,
            },
            "jobs": {
                "unfinished": self.jobs.unfinished,
                "running": self.lanes.running,
                "queued": self.lanes.waiting,
            },
        }


def _is_id(text: str) -> bool:
    """True for a public id: 32 lower-case hex digits (anything else is unknown: 404)."""
    return len(text) == 32 and all(c in "0123456789abcdef" for c in text)


__all__ = [
    "ACCEPTED_MEDIA_TYPES",
    "PlanRequest",
    "PlanService",
    "content_hash",
    "parse_spec",
    "plan_job",
    "replay_job",
    "spec_kind",
    "warm_up",
    "warm_up_parser",
]
