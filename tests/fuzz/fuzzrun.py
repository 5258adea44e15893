"""``make fuzz``: N hostile cases per surface, counted by outcome, reproducers kept.

Surfaces:

- ``spec``: a mutated task (:func:`fuzzgen.task_specs`) × ``synth errors|locate|plan``;
- ``al``: a mutated golden program (:func:`fuzzgen.al_programs`) × ``synth replay --trials 0``;
- ``api``: schemathesis cases from the service's OpenAPI schema (positive and negative), and
  mutated tasks posted to ``POST /v1/plans?validate=false``, against the real app under uvicorn
  with the ``synth serve`` configuration.

CLI cases run in-process (``synth.cli.main``, ``SystemExit`` caught) in a forked child that
already imported synth; a case that runs past the timeout is a *hang*, one whose resident
memory goes over the limit is *over-memory* (both: the child is killed and re-forked). An exit
code other than 0, 1 (``replay``: the program failed) and 2 (a clear refusal) is a *crash*
(``exit 70``: the CLI's internal error). In the API a
status 500 or a dropped connection is an *HTTP 500*, a 504 a *hang*, a memory-budget 422
*over-memory*; a 202 (a plan or replay job) is followed to its end, and its problem, if it
failed, counts by its status (a *lost* job is a crash). Each case is a Hypothesis example
(generation only, no shrinking).

Usage: ``python tests/fuzz/fuzzrun.py [--cases N] [--timeout S] [--memory-mib M]
[--surface spec,al,api] [--out DIR] [--seed K]``. Exit status 1 when any count but ``ok`` is
not zero.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import multiprocessing
import os
import re
import socket
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # forked children must not inherit BLAS threads
os.environ.setdefault("OMP_NUM_THREADS", "1")

# Run as a script: fuzzgen sits beside this file, and _paths (the project's paths) one up.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import fuzzgen
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import seed as hypothesis_seed
from hypothesis import strategies as st

OUTCOMES = ("ok", "crash", "hang", "http500", "memory")
DEFAULT_TIMEOUT = 30.0
"""[s] per case: above the AL interpreter's own wall-clock budget (MAX_WALL_TIME, 20 s), so a
run that the budget stops in time is not counted as a hang; a hang outlives every budget."""
HEADINGS = {
    "ok": "ok",
    "crash": "exit 70 / tracebacks",
    "hang": "hangs",
    "http500": "HTTP 500",
    "memory": "over-memory",
}
SURFACES = ("spec", "al", "api")


@dataclass(frozen=True)
class Result:
    """How one case ended: an outcome of :data:`OUTCOMES` and a short class key."""

    outcome: str
    key: str = ""


@dataclass
class Tally:
    """Counts of one surface, and one reproducer file per (outcome, class)."""

    surface: str
    counts: Counter[str] = field(default_factory=Counter)
    classes: dict[tuple[str, str], list[Any]] = field(default_factory=dict)
    seconds: float = 0.0

    @property
    def cases(self) -> int:
        """Cases run."""
        return sum(self.counts.values())

    def add(self, result: Result, reproducer: Callable[[], str], out: Path) -> None:
        """Count ``result``; keep the first reproducer of each new failure class in ``out``."""
        self.counts[result.outcome] += 1
        if result.outcome == "ok":
            return
        slot = (result.outcome, result.key)
        if slot not in self.classes:
            out.mkdir(parents=True, exist_ok=True)
            path = out / f"{self.surface}-{result.outcome}-{len(self.classes) + 1:03d}.txt"
            path.write_text(f"# {result.outcome}: {result.key}\n{reproducer()}")
            self.classes[slot] = [0, path]
        self.classes[slot][0] += 1


def class_key(text: str) -> str:
    """A failure's class: its last ``Type: message`` line with numbers and quotes blurred."""
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    line = lines[-1] if lines else "(no output)"
    line = line.split("internal error: ", 1)[-1]
    line = re.sub(r"'[^']*'|\"[^\"]*\"", "'…'", line)
    return re.sub(r"\d+(\.\d+)?(e[-+]?\d+)?", "N", line)[:120]


# -- CLI surfaces: a forked child runs synth.cli.main ------------------------------------------


def _child(conn: Connection, memory_cap: int, entry: Callable[[list[str]], int] | None) -> None:
    """Run ``(argv, files)`` cases until EOF: write the files, call main, send back the result."""
    with contextlib.suppress(ImportError, ValueError, OSError):
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (memory_cap, memory_cap))
    if entry is None:
        from synth.cli import main as entry

    while True:
        try:
            argv, files = conn.recv()
        except (EOFError, OSError):
            return
        with tempfile.TemporaryDirectory(prefix="fuzz-") as tmp:
            for name, text in files.items():
                Path(tmp, name).write_text(text, encoding="utf-8", errors="surrogatepass")
            args = [a.replace("{tmp}", tmp) for a in argv]
            out = io.StringIO()
            try:
                with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
                    code = entry(args)
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 2
            except BaseException as exc:  # main catches Exception: this is worse
                code = -1
                out.write(f"\nescaped main: {type(exc).__name__}: {exc}")
        conn.send((code, out.getvalue()[-4000:]))


class Sandbox:
    """A forked child that runs CLI cases under a timeout [s] and a resident-memory cap [MiB].

    ``entry`` is the command line's main (default ``synth.cli.main``).
    """

    def __init__(
        self, timeout: float, memory_mib: int, entry: Callable[[list[str]], int] | None = None
    ) -> None:
        self.timeout = timeout
        self.memory = memory_mib * 2**20
        self.entry = entry
        self._context = multiprocessing.get_context("fork")
        self._process: Any = None
        self._conn: Connection | None = None
        self._baseline = 0

    def _start(self) -> None:
        parent, child = self._context.Pipe()
        # RLIMIT_AS as a hard stop well above the resident cap (address space exceeds RSS).
        self._process = self._context.Process(
            target=_child, args=(child, 4 * self.memory + 2**31, self.entry), daemon=True
        )
        self._process.start()
        child.close()
        self._conn = parent
        # A forked child starts with the parent's resident pages (all of pytest's imports when
        # run from the test suite): the cap is on what the case itself adds.
        self._baseline = self._resident()

    def _kill(self) -> None:
        if self._process is not None:
            self._process.kill()
            self._process.join(5)
        self._process = self._conn = None

    def close(self) -> None:
        """Stop the child."""
        self._kill()

    def _resident(self) -> int:
        try:
            pages = int(Path(f"/proc/{self._process.pid}/statm").read_text().split()[1])
        except (OSError, ValueError, IndexError):
            return 0
        return pages * os.sysconf("SC_PAGE_SIZE")

    def run(self, argv: list[str], files: dict[str, str]) -> Result:
        """One case; ``{tmp}`` in ``argv`` is the directory ``files`` are written to."""
        if self._process is None or not self._process.is_alive():
            self._start()
        assert self._conn is not None
        self._conn.send((argv, files))
        deadline = time.monotonic() + self.timeout
        while not self._conn.poll(0.05):
            if self._resident() - self._baseline > self.memory:
                self._kill()
                return Result("memory", f"{argv[0]}: resident memory over the cap")
            if time.monotonic() > deadline or not self._process.is_alive():
                alive = self._process.is_alive()
                code = self._process.exitcode
                self._kill()
                if alive:
                    return Result("hang", f"{argv[0]}: over {self.timeout:g} s")
                return Result("crash", f"{argv[0]}: the process died (exit code {code})")
        try:
            code, output = self._conn.recv()
        except (EOFError, OSError):
            self._kill()
            return Result("crash", f"{argv[0]}: the process died")
        if code in (0, 1, 2):  # done; failed as a program (replay: 1); refused (2)
            return Result("ok")
        key = f"{argv[0]}: {class_key(output)}"
        if "MemoryError" in output:
            return Result("memory", key)
        return Result("crash", key)


def _drive(strategy: st.SearchStrategy[Any], cases: int, seed: int, budget: float) -> Iterator[Any]:
    """Up to ``cases`` examples of ``strategy`` (generation only), within ``budget`` [s]."""
    examples: list[Any] = []

    @settings(
        max_examples=cases,
        database=None,
        deadline=None,
        phases=[Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    @hypothesis_seed(seed)
    @given(strategy)
    def collect(example: Any) -> None:
        examples.append(example)

    # Hypothesis generates in one go (fast); cases then run one by one under the budget.
    collect()
    started = time.monotonic()
    for example in examples[:cases]:
        if time.monotonic() - started > budget:
            return
        yield example


def fuzz_spec(cases: int, sandbox: Sandbox, out: Path, seed: int, budget: float) -> Tally:
    """The ``spec`` surface (module docstring)."""
    tally = Tally("spec")
    started = time.monotonic()
    for case in _drive(fuzzgen.task_specs(), cases, seed, budget):
        argv = [case.argv_tail[0], "{tmp}/task.yaml", *case.argv_tail[1:]]
        result = sandbox.run(argv, {"task.yaml": case.text})
        tally.add(
            result,
            lambda case=case, argv=argv: (
                f"# from {case.source}: synth {' '.join(argv)}\n" + case.text
            ),
            out,
        )
    tally.seconds = time.monotonic() - started
    return tally


def fuzz_al(cases: int, sandbox: Sandbox, out: Path, seed: int, budget: float) -> Tally:
    """The ``al`` surface (module docstring)."""
    tally = Tally("al")
    started = time.monotonic()
    for case in _drive(fuzzgen.al_programs(), cases, seed, budget):
        argv = ["replay", "{tmp}/p.al", "--task", str(case.task), "--trials", "0", "--workers", "1"]
        result = sandbox.run(argv, {"p.al": case.program})
        tally.add(
            result,
            lambda case=case: (
                f"# from {case.source}: synth replay P.al --task {case.task}"
                " --trials 0\n" + case.program
            ),
            out,
        )
    tally.seconds = time.monotonic() - started
    return tally


# -- API surface: the real app under uvicorn ---------------------------------------------------


@contextlib.contextmanager
def serving(timeout: float, db: Path) -> Iterator[str]:
    """The service on a free loopback port, configured as ``synth serve`` does; its base URL."""
    import uvicorn

    from server.connections import uvicorn_config
    from server.main import create_app
    from server.settings import Settings

    config_settings = Settings(
        db_url=str(db), workers=1, plan_timeout=timeout, default_trials=2, max_trials=4
    )
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    app = create_app(config_settings)
    server = uvicorn.Server(
        uvicorn_config(app, config_settings, "127.0.0.1", 0, log_level="critical")
    )
    thread = threading.Thread(target=server.run, kwargs={"sockets": [listener]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 120
    while not server.started and time.monotonic() < deadline:
        time.sleep(0.05)
    host, port = listener.getsockname()
    try:
        yield f"http://{host}:{port}"
    finally:
        server.should_exit = True
        thread.join(30)


def _http_result(status: int | None, body: str, what: str) -> Result:
    if status is None:
        return Result("http500", f"{what}: {body}")
    if status == 500 or status >= 505 or status in (501, 502):
        return Result("http500", f"{what}: {status} {class_key(body)}")
    if status == 504:
        return Result("hang", f"{what}: 504")
    if status == 422 and "memory-budget-exceeded" in body:
        return Result("memory", f"{what}: memory budget")
    return Result("ok")


def _job_result(http: Any, status: int, body: str, what: str, timeout: float) -> Result:
    """The outcome of an answer, following a 202's job to its end (the service runs plans and
    replays as jobs): a failed job's problem counts as that status, a lost one as a crash."""
    if status != 202:
        return _http_result(status, body, what)
    try:
        url = json.loads(body)["links"]["self"]
    except (ValueError, KeyError, TypeError):
        return Result("http500", f"{what}: 202 without a job link")
    deadline = time.monotonic() + timeout + 60
    while time.monotonic() < deadline:
        answer = http.get(url, params={"wait": 20})
        if answer.status_code != 200:
            return _http_result(answer.status_code, answer.text, f"GET job of {what}")
        job = answer.json()
        if job["state"] in ("queued", "running"):
            continue
        if job["state"] == "lost":
            return Result("crash", f"{what}: job lost")
        problem = job.get("problem") or {}
        if job["state"] == "failed":
            return _http_result(int(problem.get("status", 500)), json.dumps(problem), what)
        return Result("ok")
    return Result("hang", f"{what}: job unfinished after {timeout + 60:.0f} s")


def fuzz_api(cases: int, timeout: float, out: Path, seed: int, budget: float) -> Tally:
    """The ``api`` surface (module docstring): half schemathesis, half mutated tasks."""
    import httpx2 as httpx
    import schemathesis
    from schemathesis import GenerationMode

    tally = Tally("api")
    started = time.monotonic()
    with tempfile.TemporaryDirectory() as tmp, serving(timeout, Path(tmp) / "fuzz.db") as url:
        schema = schemathesis.openapi.from_url(f"{url}/openapi.json")
        generated = schema.as_strategy(GenerationMode.POSITIVE) | schema.as_strategy(
            GenerationMode.NEGATIVE
        )
        mixed = st.one_of(
            generated.map(lambda c: ("schema", c)),
            fuzzgen.task_specs().map(lambda c: ("spec", c)),
        )
        with httpx.Client(base_url=url, timeout=timeout + 30) as http:
            for kind, case in _drive(mixed, cases, seed, budget):
                if kind == "spec":
                    what = "POST /v1/plans"
                    try:
                        answer = http.post(
                            "/v1/plans?validate=false",
                            content=case.text.encode("utf-8", "surrogatepass"),
                            headers={"Content-Type": "application/yaml"},
                        )
                        result = _job_result(http, answer.status_code, answer.text, what, timeout)
                    except httpx.HTTPError as exc:
                        result = Result("http500", f"{what}: {type(exc).__name__}")
                    tally.add(result, lambda case=case: case.text, out)
                    continue
                what = f"{case.method} {case.path}"
                try:
                    response = case.call(base_url=url, timeout=timeout + 30)
                    result = _job_result(http, response.status_code, response.text, what, timeout)
                except Exception as exc:  # requests' errors: a dropped connection
                    result = Result("http500", f"{what}: {type(exc).__name__}")
                tally.add(result, lambda case=case: case.as_curl_command(), out)
    tally.seconds = time.monotonic() - started
    return tally


# -- the table ----------------------------------------------------------------------------------


def table(tallies: list[Tally]) -> str:
    """Counts per surface and outcome, then each failure class with its count and reproducer."""
    head = ["surface", "cases", *(HEADINGS[o] for o in OUTCOMES), "seconds"]
    rows = [
        [t.surface, str(t.cases), *(str(t.counts[o]) for o in OUTCOMES), f"{t.seconds:.0f}"]
        for t in tallies
    ]
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in [head, *rows]]
    for t in tallies:
        for (outcome, key), (count, path) in sorted(
            t.classes.items(), key=lambda item: -item[1][0]
        ):
            lines.append(f"  {t.surface:5} {outcome:8} {count:5}  {key}  [{path}]")
    return "\n".join(lines)


def run(
    cases: int,
    surfaces: tuple[str, ...] = SURFACES,
    timeout: float = DEFAULT_TIMEOUT,
    memory_mib: int = 1024,
    out: Path = Path("out/fuzz"),
    seed: int = 0,
    budget: float = float("inf"),
) -> list[Tally]:
    """Fuzz each of ``surfaces`` with ``cases`` cases (each surface within ``budget`` [s])."""
    tallies = []
    sandbox = Sandbox(timeout, memory_mib)
    try:
        if "spec" in surfaces:
            tallies.append(fuzz_spec(cases, sandbox, out, seed, budget))
        if "al" in surfaces:
            tallies.append(fuzz_al(cases, sandbox, out, seed, budget))
    finally:
        sandbox.close()
    if "api" in surfaces:
        tallies.append(fuzz_api(cases, timeout, out, seed, budget))
    return tallies


def main(argv: list[str] | None = None) -> int:
    """Command line of ``make fuzz`` (module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=int(os.environ.get("FUZZ_CASES", "200")))
    parser.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT, help="per case [s]")
    parser.add_argument("--memory-mib", type=int, default=1024, help="resident cap [MiB]")
    parser.add_argument("--surface", default=",".join(SURFACES))
    parser.add_argument("--out", type=Path, default=Path("out/fuzz"))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--budget", type=float, default=float("inf"), help="per surface [s]")
    parser.add_argument("--json", action="store_true", help="also print the counts as JSON")
    args = parser.parse_args(argv)
    surfaces = tuple(s for s in args.surface.split(",") if s)
    unknown = set(surfaces) - set(SURFACES)
    if unknown:
        parser.error(f"unknown surface(s): {', '.join(sorted(unknown))}")
    from server.service import warm_up

    warm_up()  # synth's stages imported before forking, so every child starts warm

    tallies = run(
        args.cases, surfaces, args.timeout, args.memory_mib, args.out, args.seed, args.budget
    )
    print(table(tallies))
    if args.json:
        print(json.dumps({t.surface: dict(t.counts) for t in tallies}))
    return 1 if any(t.counts[o] for t in tallies for o in OUTCOMES if o != "ok") else 0


if __name__ == "__main__":
    sys.exit(main())
