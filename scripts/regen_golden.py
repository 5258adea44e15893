#!/usr/bin/env python3
"""Regenerate the golden AL programs ``fixtures/golden/<task>.al`` — the only way they change.

For each task in :data:`TASKS` (``fixtures/tasks/<task>.yaml``) the golden program is the one
:func:`synth.pipeline.synthesize` proves and writes (nominal proof, so that checking them stays
fast). ``tests/test_codegen.py`` regenerates them with :func:`golden_program` and compares byte
for byte, so a change in the planner's output is one reviewed run of this script.

Usage::

    python scripts/regen_golden.py           # rewrite, list what changed
    python scripts/regen_golden.py --check   # exit 1 if a golden file is out of date
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "fixtures" / "golden"
TASKS_DIR = ROOT / "fixtures" / "tasks"
MANIFEST = GOLDEN / "manifest.json"
TASKS: tuple[str, ...] = ("seed_4_8", "seed_4_8_tap", "seed_box_two_pins")
"""The seed's two tasks (seed §4.8, L2690–2844) and one assembly sequence."""


def golden_synthesis(task: str) -> Any:
    """The pipeline's synthesis of ``fixtures/tasks/<task>.yaml`` (nominal proof)."""
    from synth.pipeline import SynthesisOptions, synthesize
    from synth.replay.proof import ProofOptions

    path = TASKS_DIR / f"{task}.yaml"
    return synthesize(path, SynthesisOptions(proof=ProofOptions(trials=0)))


def golden_program(task: str) -> str:
    """The AL program the golden file ``fixtures/golden/<task>.al`` must hold."""
    return str(golden_synthesis(task).program)


def main(argv: list[str] | None = None) -> int:
    """Write (or with ``--check`` compare) every golden program; 1 if any is out of date."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[1])
    parser.add_argument("--check", action="store_true", help="compare only, write nothing")
    args = parser.parse_args(argv)
    stale = 0
    for task in TASKS:
        path = GOLDEN / f"{task}.al"
        text = golden_program(task)
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
            "tasks": list(TASKS),
            "note": "written by scripts/regen_golden.py; do not edit by hand",
        }
        MANIFEST.write_text(json.dumps(manifest, indent=2) + "\n", encoding="utf-8")
    return 1 if (args.check and stale) else 0


if __name__ == "__main__":
    sys.exit(main())
