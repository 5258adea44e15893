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
DATA_AL = DATA / "al"
"""The seed's AL listings, transcribed (each file names its lines of the seed)."""
DATA_TASKS = DATA / "tasks"
"""Test-only task specs (variants the fixtures do not need)."""
SEED_STRATEGIES = DATA / "seed_strategies.py"
"""The seed's strategy records of §4.8, hand-built (loaded as a module by the codegen tests)."""
SEED_TASK = TASKS / "seed_4_8.yaml"
"""The seed's programming example (§4.8, L2690–2844): search, no tap."""
SEED_TAP_TASK = TASKS / "seed_4_8_tap.yaml"
"""The seed's variation with the box ±0.75 in in z: tap, no search."""
BOX_FIXTURE_TASK = TASKS / "box_in_fixture.yaml"
"""The seed's appendix A.1 boxes located by contacts in fixtures (L2938–3156)."""
SEED_PROGRAM = GOLDEN / "seed_4_8.al"
"""The golden program synth writes for :data:`SEED_TASK`."""
SEED_SEARCH = DATA_AL / "seed_4_8_search.al"
"""Taylor's generated program of §4.8 (search, no tap; L2715–2781)."""
SEED_FIRST_CUT = DATA_AL / "seed_4_8_first_cut.al"
"""A first-cut program for :data:`SEED_TASK` in the style of §2.3.4 (L1313–1330): no checks."""
SEED_FIXTURE_TASK = TASKS / "seed_4_8_fixture.yaml"
"""The seed's cell with the box standing in a fixture (A.1), its walls 1.9 cm below the face."""
