"""A first attempt that may come down off the face backs out and searches, as a search point does.

The seed's first attempt aborts on arrival (L2736, "EXPECTED A FORCE HERE"): on its face the
pin always meets the part. Where the footprint reaches past the face's edge the first attempt
can go down beside the part and feel nothing, though the search would find the hole
(:func:`synth.strategies.beside.first_attempt_may_go_beside`).
"""

from __future__ import annotations

import dataclasses

import pytest
from _paths import DATA_TASKS, SEED_TASK

from synth.codegen.emitter import emit_program
from synth.models.believed import believed_graph
from synth.models.loader import load_task
from synth.replay.run import replay_context, run_trial
from synth.strategies.beside import first_attempt_may_go_beside
from synth.strategies.context import plan_context
from synth.strategies.landing import landing
from synth.strategies.planner import plan_task

INCH_BOX = DATA_TASKS / "box_known_to_an_inch.yaml"
# seed 1: trials whose first attempt went beside the box (the program with the seed's arrival
# abort aborted 8 of 100 at seed 1, 12 and 17 the first two; every candidate was refused)
BESIDE_TRIALS = (12, 17)


@pytest.fixture(scope="module")
def inch_box():
    spec = load_task(INCH_BOX)
    return spec, plan_task(spec).strategy


def test_the_first_attempt_off_the_face_backs_out_and_the_search_finds_the_hole(inch_box) -> None:
    spec, strategy = inch_box
    assert strategy.search is not None and strategy.search.first_off_surface == "retract"
    graph = believed_graph(spec)
    program = emit_program(strategy, graph)
    attempt = program.split("{ FIRST ATTEMPT }")[1].split("DISTANCE_OFF ←")[0]
    assert "ON FORCE" in attempt and "ON ARRIVAL" not in attempt
    missed = program.split("BEGIN { PIN1 MISSED BH1 }")[1].split("WHILE")[0]
    assert "BEGIN { NOTHING FELT: PIN1 WENT BESIDE }" in missed
    assert "MOVE PIN1 TO BH1*TRANS(" in missed  # back to the approach over the believed hole
    context = replay_context(program, spec)
    # the seed's arrival abort in the same program: the worlds where the first attempt went
    # beside abort, and the search would have found the hole
    search = dataclasses.replace(strategy.search, first_off_surface="abort")
    aborting = emit_program(dataclasses.replace(strategy, search=search), graph)
    abort_context = replay_context(aborting, spec)
    for trial in BESIDE_TRIALS:
        aborted = run_trial(abort_context, 1, trial)
        assert (aborted.outcome, aborted.message) == ("abort", "EXPECTED A FORCE HERE"), trial
        assert run_trial(context, 1, trial).outcome == "success", trial


def test_the_seeds_first_attempt_backs_out_too() -> None:
    # BH1 of seed_4_8 is 0.6 cm from two edges of a box that may be 1.4 cm off: the footprint
    # about the believed hole reaches past the face, so the golden program's first attempt
    # backs out as its search points do, where the seed's listing aborts (L2736)
    spec = load_task(SEED_TASK)
    ctx = plan_context(spec)
    strategy = plan_task(spec).strategy
    where = landing(ctx, strategy)
    assert where is not None and first_attempt_may_go_beside(ctx, where)
    assert strategy.search is not None and strategy.search.first_off_surface == "retract"
    # the tapping program's footprint, after the tap, stays on the face: the seed's abort
    tap_spec = load_task(SEED_TASK.with_name("seed_4_8_tap.yaml"))
    tapped = plan_task(tap_spec).strategy
    text = emit_program(tapped, believed_graph(tap_spec))
    assert tapped.search is None and 'ON ARRIVAL DO ABORT("EXPECTED A FORCE HERE")' in text
