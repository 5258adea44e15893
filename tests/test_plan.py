"""``synth plan`` end to end on the seed's §4.8 example and its variation (seed L2562–2855).

The decisions must be the seed's: a search and no tap for seed_4_8 (L2645–2650), a tap close
to the hole and no search for seed_4_8_tap (L2797–2855). Times differ from the seed's (its arm
stood somewhere the seed does not say, see fixtures/arms/stanford.yaml); the decisions and
the error figures do not depend on that.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from _paths import SEED_TAP_TASK, SEED_TASK, TASKS
from _tasks import plannable

from synth.cli import main
from synth.errors.chain import chain_between
from synth.errors.estimate import estimate_errors
from synth.exceptions import NoStrategyError
from synth.models.believed import believed_graph
from synth.models.loader import load_task, parse_task
from synth.models.spec import WORLD
from synth.strategies import PlanOptions, plan_task
from synth.strategies.context import plan_context
from synth.units import CM, INCH


@pytest.fixture(scope="module")
def seed():
    spec = load_task(SEED_TASK)
    return plan_task(spec), plan_task(spec, options=PlanOptions(exhaustive=True))


@pytest.fixture(scope="module")
def tap():
    spec = load_task(SEED_TAP_TASK)
    return plan_task(spec), plan_task(spec, options=PlanOptions(exhaustive=True))


def test_seed_4_8_searches_and_does_not_tap(seed) -> None:
    result, _ = seed
    s = result.strategy
    assert s.tap is None and s.search is not None
    e = s.errors
    assert e is not None
    # L2645–2650: "Δz is thus small enough ... we don't have to tap" and "the error footprint
    # is bigger than Δr_ok, so we will have to search". Δz is the hand's alone (the box has no
    # z error): at most 0.05 in·(|sin γ| + |cos γ|) ≤ .180 cm (L2648) ≪ 0.75·1.71 = 1.28 cm.
    assert e.first_order["dz"] <= 0.05 * INCH * math.sqrt(2) + 1e-12
    assert e.dr > 0.762 * CM
    # Every in-plane footprint contains the box's own ±0.3 in × ±0.2 in: Δx ≥ 0.3 in.
    assert e.dx >= 0.3 * INCH
    text = " ".join(s.decisions)
    assert "no tap" in text and "search" in text and "exceeds Δr_ok" in text
    # The success test: Δz/τ (L2738: .169 = .127/.75).
    assert s.success_threshold == pytest.approx(e.dz / 0.75)
    assert s.search.step == pytest.approx(0.75 * 0.762 * CM)
    assert s.fine_time == pytest.approx(s.search.time)
    # the seed's TTIME + FINETIME (L1888) and the let-go and get-clear the program ends with:
    # OPEN's 50 jiffies (L3854) and the 2 in move back, a fraction of a second at the limits
    assert s.expected_time == pytest.approx(s.gross_time + s.fine_time + s.release_time)
    assert 50 / 60 < s.release_time < 50 / 60 + 1.0


def test_seed_4_8_tap_taps_near_the_hole_and_does_not_search(tap) -> None:
    result, _ = tap
    s = result.strategy
    assert s.search is None and s.tap is not None
    e = s.errors
    assert e is not None
    # L2797: the box is ±0.75 in along z: Δz ≥ 1.905 cm > τ(d_f − d_s) = 1.28 cm: tap.
    assert e.dz >= 0.75 * INCH > 0.75 * 1.71 * CM
    # In the plane only the hand errs: FPX/FPY ≤ .25 cm (L2805) < Δr_ok: no search.
    assert e.dr < 0.3 * CM < 0.762 * CM
    # The tapping place: ring 1 of radius .450 + .762 = 1.21 cm (L2341), like the seed's
    # (−1.21, .02) cm (L2360) but at 216° instead of 180° (see test_plan_refine.py: the
    # seed's box had features there that the seed does not describe).
    x, y, z = s.tap.offset
    assert math.hypot(x, y) == pytest.approx(1.212 * CM, abs=0.001 * CM)
    assert z == 0.0
    assert s.tap.surface == "BTOP"
    # After the tap Δz is the hand's at tap and insertion: ≤ 2 × 0.1796 cm (the seed's
    # .180 at L2362 counts the insertion's only); far below 1.28 cm.
    assert s.tap.dz_after <= 2 * 0.05 * INCH * math.sqrt(2) + 0.002 * CM
    assert s.success_threshold == pytest.approx(s.tap.dz_after / 0.75)
    assert s.fine_time == pytest.approx(s.tap.time) and s.tap.time > 0
    # The tap's guarded move: 2 in above the surface to 2 in below (L2852), at the tap point.
    assert s.tap.via.xf.translation[2] == pytest.approx(2 * INCH)
    assert s.tap.target.xf.translation[2] == pytest.approx(-2 * INCH)
    text = " ".join(s.decisions)
    assert "tap:" in text and "no search" in text
    assert result.counters["lp"] > 0  # the corrected Δz is a real LP


def test_best_first_and_exhaustive_agree(seed, tap) -> None:
    for best_first, exhaustive in (seed, tap):
        assert best_first.strategy.name == exhaustive.strategy.name
        assert best_first.strategy.expected_time == pytest.approx(exhaustive.strategy.expected_time)
        assert best_first.mode == "best-first" and exhaustive.mode == "exhaustive"
        # every candidate is refined: those listed, and those their refinement rejected (a
        # pickup lifted over the box from the park, whose fingers would then land on BH1's face)
        n = len(exhaustive.candidates)
        at_refine = [r for r in exhaustive.rejected if r.stage == "refine"]
        assert exhaustive.refined == n + len(at_refine)
        assert 1 <= best_first.refined <= n + len(at_refine)
        # the chosen strategy is the cheapest refined one, and no unrefined candidate could
        # have beaten it: gross + release + minimum refinement cost ≥ the best total
        best = best_first.strategy.expected_time
        for c in best_first.candidates:
            if c.refined:
                assert c.expected_time >= best - 1e-12
            else:
                bound = c.gross_time + c.release_time + best_first.minimum_refinement_cost
                assert bound >= best
    # The cutoff saves work where a cheap candidate's refinement beats the gross times of the
    # rest: on the fixture-located box (1 of 5 refined, benchmarks/plan.py); the seed tasks'
    # candidates now all pass within the cutoff, so there it saves nothing.
    located = load_task(TASKS / "seed_4_8_fixture.yaml")
    bf, ex = plan_task(located), plan_task(located, options=PlanOptions(exhaustive=True))
    assert bf.strategy.name == ex.strategy.name and bf.refined < ex.refined


def test_decisions_do_not_depend_on_the_timing_rule() -> None:
    spec = load_task(SEED_TASK)
    result = plan_task(spec, options=PlanOptions(timing_rule="seed"))
    assert result.strategy.search is not None and result.strategy.tap is None


def test_cli_json_and_text(capsys) -> None:
    assert main(["plan", str(SEED_TASK), "--json", "--proof-trials", "0"]) == 0
    doc = json.loads(capsys.readouterr().out)
    strategy = doc["strategy"]
    assert strategy["tap"] is None
    assert set(strategy["search"]) >= {"dx", "dy", "zeta", "step", "rings"}
    assert set(strategy["errors"]) >= {"dx", "dy", "dz", "zeta", "dtheta"}
    assert set(strategy["time"]) == {
        "pickup_time",
        "transport_time",
        "gross_time",
        "fine_time",
        "release_time",
        "expected_time",
    }
    t = strategy["time"]
    assert t["pickup_time"] + t["transport_time"] == pytest.approx(t["gross_time"])
    total = t["gross_time"] + t["fine_time"] + t["release_time"]
    assert total == pytest.approx(t["expected_time"])
    assert set(strategy["grasp"]) == {"omega", "gamma", "distance"}
    assert strategy["dtry"] == pytest.approx(0.0425) and strategy["standoff"] == 0.0254
    # the insertion as planned, under the glossary's names (a client could read Δθ_ok's clip to
    # the wedging limit only from a sentence): the seed's d_f 1.71 cm, d_s 0, Δr_ok 0.3 in;
    # Δθ_ok = c/μ with c = (0.64 − 0.635)/0.64 and μ = 0.3 (Whitney), below the task's 10°
    assert strategy["d_f"] == pytest.approx(0.0171) and strategy["d_s"] == 0.0
    assert strategy["dr_ok"] == pytest.approx(0.762e-2)
    assert strategy["dtheta_ok"] == pytest.approx((0.64 - 0.635) / 0.64 / 0.3, rel=1e-9)
    assert strategy["lead"] == pytest.approx(0.0044) and strategy["preliminaries"] == []
    assert doc["refined"] >= 1 and doc["planning_time"] > 0
    assert doc["counters"]["ik"] > 0
    assert all({"candidate", "reason", "cause", "stage"} == set(r) for r in doc["rejected"])

    assert (
        main(
            [
                "plan",
                str(SEED_TAP_TASK),
                "--exhaustive",
                "--records",
                "--proof-trials",
                "0",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "PHL SPEC" in out and "TAP: PIN1=BH1*TRANS(" in out and "SEARCH: NULL_RECORD" in out
    assert "tap: Δz" in out and "no search" in out and "exhaustive refined" in out
    assert "pruned" in out  # rejections are listed with reasons


def _variant(tmp_path: Path, old: str, new: str) -> Path:
    text = SEED_TASK.read_text()
    assert old in text
    path = tmp_path / "variant.yaml"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize("rx_deg", [1.46, 3.0])
def test_a_hole_that_leans_past_the_tilt_limit_is_refused_before_any_candidate(
    tmp_path: Path, rx_deg: float
) -> None:
    # The box may turn ±rx about x, so BH1's axis may lean rx off the vertical (a part's
    # rotation, which no grasp, tap or search corrects): past Δθ_ok (the task's 10° clipped to
    # the wedging limit, 1.492° for this pin and hole) every candidate fails seed §4.5.1
    # (L2290). The refusal compares, and quotes, the certified tilt of world → BH1, the figure
    # `synth errors` prints. At 1.46° the first-order tilt passes and the certified one
    # (asin(sin 1.46° / cos 15°) and its remainder, ≈ 1.51°: the six tilt directions are 30°
    # apart) does not; candidates compare the certified figure of a larger chain, so all of
    # them would fail too, but each only after its motions were swept.
    path = _variant(tmp_path, "      rz: 5 deg\n", f"      rz: 5 deg\n      rx: {rx_deg} deg\n")
    spec = load_task(path)
    hole = next(f.name for f in spec.frames if f.al_name == "BH1")
    errors = estimate_errors(chain_between(believed_graph(spec), WORLD, hole), WORLD, hole)
    limit = plan_context(spec).insertion.dtheta_ok
    assert math.degrees(limit) == pytest.approx(1.492, abs=5e-4)
    assert errors.certified.tilt > limit
    assert errors.first_order.tilt == pytest.approx(math.radians(rx_deg), rel=1e-9)
    if rx_deg < 1.492:
        assert errors.first_order.tilt < limit
    with pytest.raises(NoStrategyError) as info:
        plan_task(spec)
    ((name, reason),) = info.value.reasons
    assert name == "task" and info.value.root.cause == "tilt"
    assert f"may tilt {math.degrees(errors.certified.tilt):.3f}°" in reason, reason


def test_no_strategy_when_the_tilt_is_never_good_enough(tmp_path, capsys) -> None:
    # Δθ_ok = 0.1°: the hand's ±0.25° alone tilts the pin by ≥ .354° (L2287).
    path = _variant(tmp_path, "dtheta_ok: 10 deg", "dtheta_ok: 0.1 deg")
    with pytest.raises(NoStrategyError) as info:
        plan_task(parse_task(path.read_text()))
    tilt = [r for _, r in info.value.reasons if "exceeds Δθ_ok" in r]
    # Every candidate with clear gross motions reached refinement and failed there: the 9
    # pickups that survive ω pruning (3 per γ, L2122) less those whose moves are obstructed.
    obstructed = [r for _, r in info.value.reasons if " sweeps " in r]
    assert tilt and len(tilt) + len(obstructed) == 9
    assert info.value.root.cause == "tilt"  # the deepest stage reached is refinement's tilt
    assert main(["plan", str(path), "--workers", "1"]) == 2  # refused before any proof
    err = capsys.readouterr().err
    first = err.splitlines()[0]
    assert "no proven pin-in-hole strategy" in first and "tilt" in first, first
    assert "exceeds Δθ_ok = 0.100°" in first
    assert "--try-harder keeps them" not in err  # more ω cannot cure a hand that tilts too much


def test_no_strategy_when_the_box_is_out_of_reach(tmp_path, capsys) -> None:
    path = _variant(
        tmp_path, "translation: [45.2 cm, 102 cm, 0 cm]", "translation: [245.2 cm, 102 cm, 0 cm]"
    )
    assert main(["plan", str(path), "--json", "--workers", "1"]) == 2  # no proof is reached
    err = capsys.readouterr().err
    assert "has arm solutions at the approach and destination points of BH1" in err


@pytest.mark.parametrize(
    "path",
    [p for p in plannable() if p.stem not in ("seed_4_8", "seed_4_8_tap")],  # those: above
    ids=lambda p: p.stem,
)
def test_every_other_fixture_best_first_equals_exhaustive(path: Path) -> None:
    spec = load_task(path)
    best_first, exhaustive = plan_task(spec), plan_task(spec, options=PlanOptions(exhaustive=True))
    assert best_first.strategy.name == exhaustive.strategy.name
    assert best_first.strategy.expected_time == pytest.approx(exhaustive.strategy.expected_time)
    # every candidate refined is kept or refused at refine (seed_4_8_fixture's searching
    # candidates are: their search reaches over FIX's walls, 1.9 cm below the face)
    refused = sum(1 for r in exhaustive.rejected if r.stage == "refine")
    assert best_first.refined <= exhaustive.refined == len(exhaustive.candidates) + refused


def test_a_given_dr_ok_beyond_the_parts_lead_is_remarked(seed) -> None:
    # seed_4_8 gives the seed's measured Δr_ok = 0.762 cm (L2584); its parts' lead is
    # chamfer + hole radius − tip radius = 0.25 + 0.32 − 0.13 = 0.44 cm (docs/task-spec.md).
    result, _ = seed
    # (The other note of seed_4_8 is the given Δθ_ok clipped to the wedging limit.)
    notes = [d for d in result.strategy.decisions if d.startswith("note:") and "Δr_ok" in d]
    assert len(notes) == 1 and "0.762 cm" in notes[0] and "0.440 cm" in notes[0]
    # Without the given value Δr_ok is the lead itself, and nothing is remarked.
    spec = load_task(SEED_TASK)
    assert spec.insertion is not None
    derived = spec.model_copy(
        update={"insertion": spec.insertion.model_copy(update={"dr_ok": None})}
    )
    plan = plan_task(derived)
    assert not [d for d in plan.strategy.decisions if d.startswith("note:") and "Δr_ok" in d]
