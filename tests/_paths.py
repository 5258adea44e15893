"""Where the tests find the project's files: absolute, so no test depends on the working
directory (tests/conftest.py runs every test from an empty temporary one)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
"""The project's root."""
TASKS = ROOT / "fixtures" / "tasks"
"""The fixture task specs."""
GOLDEN = ROOT / "fixtures" / "golden"
"""The golden AL programs (scripts/regen_golden.py)."""
DATA = ROOT / "tests" / "data"
"""Test-only data: seed listings, extra tasks, hand-built records."""
SEED_TASK = TASKS / "seed_4_8.yaml"
"""The seed's programming example (§4.8, L2690–2844): search, no tap."""
SEED_TAP_TASK = TASKS / "seed_4_8_tap.yaml"
"""The seed's variation with the box ±0.75 in in z: tap, no search."""
BOX_FIXTURE_TASK = TASKS / "box_in_fixture.yaml"
"""The seed's appendix A.1 boxes located by contacts in fixtures (L2938–3156)."""
