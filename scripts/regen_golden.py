#!/usr/bin/env python3
"""Regenerate the golden AL programs ``fixtures/golden/<task>.al`` — the only way they change.

For each task in :data:`TASKS` (``fixtures/tasks/<task>.yaml``) the program is the one
:func:`synth.pipeline.synthesize` proves (``--source auto``, the default, when the planner
exists), otherwise the emission of the seed's hand-built records
(``tests/data/seed_strategies.py``, seed §4.8 L2690–2844), without preamble. The source used
is recorded in ``fixtures/golden/manifest.json``, and
``tests/test_codegen.py`` regenerates with :func:`golden_program` from the recorded source, so
golden files written from the seed's records stay valid while the planner is being built, and
switching them to the planner is one reviewed run of this script.

Usage::

    python scripts/regen_golden.py                 # rewrite from the best source, list changes
    python scripts/regen_golden.py --source seed   # rewrite from the hand-built records
    python scripts/regen_golden.py --check         # exit 1 if a golden file is out of date
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "fixtures" / "golden"
TASKS_DIR = ROOT / "fixtures" / "tasks"
SEED_RECORDS = ROOT / "tests" / "data" / "seed_strategies.py"
MANIFEST = GOLDEN / "manifest.json"
TASKS: tuple[str, ...] = ("seed_4_8", "seed_4_8_tap")
"""The seed's two tasks (the seed's records exist for these)."""
SEQUENCE_TASKS: tuple[str, ...] = ("seed_box_two_pins",)
"""Golden assembly sequences (one program each); from the planner only."""
SOURCES = ("auto", "planner", "seed")


def seed_records() -> ModuleType:
    """The hand-built records module (loaded by path; tests/ is not a package)."""
    spec = importlib.util.spec_from_file_location("seed_strategies", SEED_RECORDS)
    if spec is None or spec.loader is None:  # pragma: no cover
        raise ImportError(f"cannot load {SEED_RECORDS}")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def planner_available() -> bool:
    """True when ``synth.strategies.planner`` can be imported."""
    return importlib.util.find_spec("synth.strategies.planner") is not None


def resolve_source(source: str = "auto") -> str:
    """``planner`` or ``seed``: what ``auto`` means right now."""
    if source not in SOURCES:
        raise ValueError(f"source is one of {SOURCES}, not {source!r}")
    if source == "auto":
        return "planner" if planner_available() else "seed"
    return source


def recorded_source() -> str:
    """The source the committed golden files were written from (``seed`` or ``planner``)."""
    if not MANIFEST.exists():
        return "seed"
    source = json.loads(MANIFEST.read_text(encoding="utf-8"))["source"]
    if source not in ("planner", "seed"):
        raise ValueError(f"{MANIFEST}: unknown source {source!r}")
    return str(source)


def golden_strategy(task: str, source: str = "auto") -> tuple[Any, Any]:
    """The strategy record and attribute graph the golden program of ``task`` comes from."""
    from synth.models.believed import believed_graph
    from synth.models.loader import load_task

    path = TASKS_DIR / f"{task}.yaml"
    if resolve_source(source) == "planner":
        synthesis = _synthesis(path)
        return synthesis.strategy, synthesis.graph
    return seed_records().STRATEGIES[task](), believed_graph(load_task(path))


def _synthesis(path: Path) -> Any:
    """The pipeline's proven program for ``path`` (nominal proof: goldens stay fast to check)."""
    from synth.pipeline import SynthesisOptions, synthesize
    from synth.replay.proof import ProofOptions

    return synthesize(path, SynthesisOptions(proof=ProofOptions(trials=0)))


def golden_program(task: str, source: str = "auto") -> str:
    """The AL program the golden file ``fixtures/golden/<task>.al`` must hold.

    From the planner: the program :func:`synth.pipeline.synthesize` proves and writes; from
    the seed's records: :func:`synth.codegen.emitter.emit_program` of the hand-built record.
    """
    if resolve_source(source) == "planner":
        return str(_synthesis(TASKS_DIR / f"{task}.yaml").program)
    from synth.codegen.emitter import emit_program

    strategy, graph = golden_strategy(task, source)
    return str(emit_program(strategy, graph))


def main(argv: list[str] | None = None) -> int:
    """Write (or with ``--check`` compare) every golden program; 1 if any is out of date."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[1])
    parser.add_argument("--check", action="store_true", help="compare only, write nothing")
    parser.add_argument(
        "--source",
        choices=SOURCES,
        default=None,
        help="where strategies come from (default: auto when writing, the recorded source "
        "with --check)",
    )
    args = parser.parse_args(argv)
    if args.check:
        source = resolve_source(args.source) if args.source else recorded_source()
    else:
        source = resolve_source(args.source or "auto")
    print(f"strategies from: {source}")
    stale = 0
    for task in TASKS + (SEQUENCE_TASKS if source == "planner" else ()):
        path = GOLDEN / f"{task}.al"
        text = golden_program(task, source)
        old = path.read_text(encoding="utf-8") if path.exists() else None
        if old == text:
            print(f"  unchanged   {path.relative_to(ROOT)}")
            continue
        stale += 1
        if args.check:
            print(f"  OUT OF DATE {path.relative_to(ROOT)}")
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8", newline="\n")
            print(f"  written     {path.relative_to(ROOT)}")
    if not args.check:
        manifest = {
            "source": source,
            "tasks": list(TASKS + (SEQUENCE_TASKS if source == "planner" else ())),
            "note": "written by scripts/regen_golden.py; do not edit by hand",
        }
        MANIFEST.write_text(json.dumps(manifest, indent=2) + "\n", encoding="utf-8")
    return 1 if (args.check and stale) else 0


if __name__ == "__main__":
    sys.exit(main())
