"""A pin gone beside a tilted part meets the table where the success test reads a seat.

Found by a task hunt (``tests/data/tasks/tilted_plate_low_edge.yaml``): a 1.2 cm plate tilted
10° about its x axis, a through hole 0.9 cm from its low edge, the plate known to ±0.35 in
across that edge. synth wrote ``tests/data/written/tilted_plate_low_edge.al`` as proven 50 of
50, and 2 of 200 independent trials (seed 7) ended with the pin on the table, read as seated.
The planner checked tops beside a part only for an upright one; for a tilted one it now finds
the table along the hole's axis (:func:`synth.strategies.beside._tilted_table_landings`).

Oracles: the replay, whose trial 37 of seed 7 ends with the pin on the table and the program's
test passed (a ``failure``, not an ``abort``); and the depth in closed form: the pin aimed at
the believed mouth, P_z = 1.352 − 6.6·sin 10° + 1.2·cos 10° = 1.388 cm above the table, comes
down the hole's axis, tilted 10°, for P_z / cos 10° = 1.409 cm, less what its own error (the
hand's and the grasp's, a few mm) turns that by: c·e with |c| = |(−a_x, −a_y, 1/a_z − a_z)|
= 0.176.
"""

from __future__ import annotations

import math
import re

import pytest
from _paths import DATA_TASKS, ROOT

from synth.exceptions import NoStrategyError
from synth.models.loader import load_task
from synth.replay.run import replay_context, run_trial
from synth.strategies import plan_task

TASK = DATA_TASKS / "tilted_plate_low_edge.yaml"
WRITTEN = ROOT / "tests" / "data" / "written" / "tilted_plate_low_edge.al"
TILT = math.radians(10.0)
MOUTH_Z = 1.352 - 6.6 * math.sin(TILT) + 1.2 * math.cos(TILT)  # [cm] the believed mouth


def test_the_program_written_without_the_check_reads_a_pin_on_the_table_as_seated() -> None:
    context = replay_context(WRITTEN.read_text(encoding="utf-8"), TASK)
    run = run_trial(context, 7, 37)
    assert run.outcome == "failure"  # the program's own success test passed it
    assert run.message == "PIN1 is not in PH1: it rests on table"


def test_every_candidate_is_refused_before_the_proof_for_the_table() -> None:
    with pytest.raises(NoStrategyError) as info:
        plan_task(load_task(TASK))
    tables = [r for r in info.value.rejections if "comes down on the table" in r.reason]
    assert tables and all(r.stage == "refine" for r in tables)
    nominal = MOUTH_Z / math.cos(TILT)  # 1.409 cm along the axis from the mouth to the table
    for r in tables:
        found = re.search(
            r"on the table ([\d.]+) cm below the face, within the success test's ([\d.]+) cm "
            r"\(± Δz ([\d.]+) cm\) of d_f = ([\d.]+) cm",
            r.reason,
        )
        assert found is not None, r.reason
        depth, t, dz, d_f = (float(g) for g in found.groups())
        assert abs(d_f - depth) <= t + dz + 0.005  # read as a seat (3 significant figures)
        # The first attempt, at the believed mouth, is the first beside the face: its depth is
        # the nominal one turned by the pin's error, a few mm times 0.176, never deeper.
        assert nominal - 0.1 <= depth <= nominal + 0.005, (depth, nominal)
