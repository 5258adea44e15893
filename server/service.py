"""The one place where the server calls synth: parse, plan, emit, replay, store.

Routes call :class:`PlanService`; it runs every synth call as a job in a worker process
(:mod:`server.workers`) under the time budget and stores results through
:mod:`server.db`. The module-level ``*_job`` functions are those jobs: they run in the workers,
take and return plain picklable values, and are the only functions that import synth's stages.
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
from server.exceptions import NotFound, ReplayUnavailable, UnsupportedMediaType
from server.lanes import Lanes
from server.modelpaths import confine_model_files
from server.settings import Settings
from server.workers import WorkerPool
from synth.exceptions import SpecError
from synth.models.spec import TaskSpec
from synth.models.yamlread import YamlLimits

if TYPE_CHECKING:  # the store is the server's; jobs in worker processes never load it
    from server.db import PlanStore, StoredPlan

SpecKind = Literal["yaml", "json"]

MAX_NESTING = 32  # deepest mapping/sequence nesting accepted in a spec (the schema needs ~6)
YAML_LIMITS = YamlLimits(max_depth=MAX_NESTING, max_aliases=0)  # the CLI's, without aliases

YAML_MEDIA_TYPES = frozenset(
    {"application/yaml", "application/x-yaml", "text/yaml", "text/x-yaml", "text/plain"}
)
JSON_MEDIA_TYPES = frozenset({"application/json"})
ACCEPTED_MEDIA_TYPES = tuple(sorted(YAML_MEDIA_TYPES | JSON_MEDIA_TYPES))


# -- spec bodies ------------------------------------------------------------------------------


def spec_kind(content_type: str | None) -> SpecKind:
    """``"yaml"`` or ``"json"`` for a request's ``Content-Type``; 415 for anything else.

    No content type means YAML (of which JSON is a subset).
    """
    media = (content_type or "").split(";", 1)[0].strip().lower()
    if not media or media in YAML_MEDIA_TYPES:
        return "yaml"
    if media in JSON_MEDIA_TYPES or media.endswith("+json"):
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
            data = json.loads(text, parse_constant=_reject_non_finite)
        except json.JSONDecodeError as exc:
            raise SpecError("", f"JSON syntax error: {exc.msg}", exc.lineno) from None
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


# -- the stages (imported lazily: some land after the server) --------------------------------


def _stage(module: str) -> Any | None:
    try:
        return importlib.import_module(module)
    except ImportError:
        return None


def stages_available() -> dict[str, bool]:
    """Which synth stages this build has (planner, codegen, replay)."""
    return {
        "planner": _stage("synth.strategies.planner") is not None,
        "codegen": _stage("synth.codegen.emitter") is not None,
        "replay": _replay_function() is not None,
    }


def _replay_function() -> Callable[..., Any] | None:
    """The replay entry point of ``synth.replay``, or None when this build has none."""
    module = _stage("synth.replay")
    return getattr(module, "replay_program", None) if module is not None else None


def replay_not_available() -> None:
    """Raise 503: this build cannot replay AL programs (``synth.replay`` has no entry point)."""
    raise ReplayUnavailable(
        "replay not available in this build: synth.replay has no replay entry point yet, so "
        "programs cannot be validated; plan with validate=false to get an unvalidated program"
    )


def warm_up() -> dict[str, bool]:
    """Import the heavy modules once per worker; return :func:`stages_available` for health."""
    for module in (
        "synth.models.loader",
        "synth.models.graph",
        "synth.models.arm",
        "synth.errors.estimate",
        "synth.strategies.planner",
        "synth.codegen.emitter",
        "synth.replay",
        "synth.al.parser",
    ):
        _stage(module)
    return stages_available()


# -- jobs (run in worker processes) ----------------------------------------------------------


def _spec_for_server(
    body: bytes | str | dict[str, Any], kind: SpecKind, model_dirs: tuple[str, ...]
) -> TaskSpec:
    return confine_model_files(parse_spec(body, kind), [Path(d) for d in model_dirs])


def _replay(program: str, spec: TaskSpec, trials: int, seed: int) -> dict[str, Any]:
    replay = _replay_function()
    if replay is None:
        replay_not_available()
    assert replay is not None
    report = replay(program, spec, trials=trials, seed=seed)
    return dict(report.to_json())


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
    from synth.strategies.options import PlanOptions as PlannerOptions

    trials = options["trials"] if options["validate"] else 0
    synthesis = synthesize(
        spec,
        SynthesisOptions(
            plan=PlannerOptions(try_harder=options["try_harder"], exhaustive=options["exhaustive"]),
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
    if _replay_function() is None:
        replay_not_available()
    spec = _spec_for_server(spec_body, kind, model_dirs)
    return _replay(program, spec, trials, seed)


# -- orchestration (runs in the server) -------------------------------------------------------


@dataclass(frozen=True)
class PlanOptions:
    """Options of one planning request.

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


class PlanService:
    """Plans and replays for the routes: validation, budgets, de-duplication, storage.

    Every job first takes a slot of :attr:`lanes` for its client (:mod:`server.lanes`), then
    runs in :attr:`pool`: it waits at most ``plan_timeout`` for a slot and then runs at most
    ``plan_timeout``.
    """

    def __init__(self, store: PlanStore, pool: WorkerPool, lanes: Lanes | None = None) -> None:
        self.store = store
        self.pool = pool
        self.lanes = lanes if lanes is not None else Lanes(pool.size, pool.size, 0)

    async def run_job(
        self, client: str, fn: Callable[..., Any], *args: Any, timeout: float, what: str
    ) -> Any:
        """``fn(*args)`` in a worker, once ``client`` holds a lane slot (module rule)."""
        async with self.lanes.slot(client, timeout):
            return await self.pool.run(fn, *args, timeout=timeout, what=what)

    async def create_plan(
        self,
        body: bytes,
        content_type: str | None,
        options: PlanOptions,
        settings: Settings,
        client: str = "-",
    ) -> tuple[StoredPlan, bool]:
        """Plan the task in ``body``; return the stored plan and whether it is new.

        An identical earlier submission (same body, kind and options) is returned as stored.
        The new plan is committed before this returns.
        """
        from server.db import NewPlan

        kind = spec_kind(content_type)
        key = content_hash(body, kind, options.to_json())
        twin = await asyncio.to_thread(self.store.by_hash, key)
        if twin is not None:
            return twin, False
        outcome = await self.run_job(
            client,
            plan_job,
            body,
            kind,
            options.to_json(),
            tuple(str(d) for d in settings.model_dirs),
            timeout=settings.plan_timeout,
            what="planning",
        )
        new = NewPlan(
            content_hash=key,
            task_name=outcome["task"],
            spec_text=body.decode("utf-8"),
            spec_media_type=kind,
            spec=_finite_json(outcome["spec"]),
            options=options.to_json(),
            result=_finite_json(outcome["result"]),
            program=outcome["program"],
            validation=_finite_json(outcome["validation"]),
        )
        return await asyncio.to_thread(self.store.add, new)

    async def get_plan(self, plan_id: str) -> StoredPlan:
        """The stored plan ``plan_id``; :class:`NotFound` otherwise."""
        plan = None
        if len(plan_id) == 32 and all(c in "0123456789abcdef" for c in plan_id):
            plan = await asyncio.to_thread(self.store.get, plan_id)
        if plan is None:
            raise NotFound(f"no plan with id {plan_id[:64]!r}")
        return plan

    async def list_plans(
        self, limit: int, cursor: int | None
    ) -> tuple[list[StoredPlan], int | None]:
        """A page of plans, newest first, and the cursor of the next page."""
        return await asyncio.to_thread(self.store.page, limit, cursor)

    async def replay(
        self,
        program: str | None,
        spec: str | dict[str, Any] | None,
        plan_id: str | None,
        trials: int,
        seed: int,
        settings: Settings,
        client: str = "-",
    ) -> dict[str, Any]:
        """Replay ``program`` (default: the stored plan's) against ``spec`` or the stored task."""
        kind: SpecKind = "yaml"
        spec_body: bytes | str | dict[str, Any]
        if plan_id is not None:
            plan = await self.get_plan(plan_id)
            spec_body = plan.spec_text
            kind = "json" if plan.spec_media_type == "json" else "yaml"
            program = plan.program if program is None else program
        else:
            assert spec is not None and program is not None  # the request schema ensures it
            spec_body = spec
        report = await self.run_job(
            client,
            replay_job,
            program,
            spec_body,
            kind,
            trials,
            seed,
            tuple(str(d) for d in settings.model_dirs),
            timeout=settings.plan_timeout,
            what="the replay",
        )
        return dict(_finite_json(report))

    async def health(self) -> dict[str, Any]:
        """Database and worker state, and which stages this build has."""
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
            "stages": dict(self.pool.info),
        }


__all__ = [
    "ACCEPTED_MEDIA_TYPES",
    "PlanOptions",
    "PlanService",
    "content_hash",
    "parse_spec",
    "plan_job",
    "replay_job",
    "replay_not_available",
    "spec_kind",
    "stages_available",
    "warm_up",
]
