"""The proof (synth.replay.proof) and the pipeline that writes only proven programs.

Oracles: the fixed-size rate test the sequential test must agree with (an exhaustive check
over every failure pattern of a small budget, and random long sequences), the Wilson bound's
closed form for k = n (lower = n/(n + z²)), the seed's first-cut listing whose capture rate
test_replay_montecarlo.py measures at 32% against an independent numpy model, and the
sampled-world generator itself for the errors a failed trial reports.
"""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
from _paths import DATA_TASKS, SEED_FIRST_CUT, SEED_PROGRAM, SEED_TASK, TASKS
from _tasks import synthesized

from synth.cli import DEFAULT_MIN_SUCCESS as CLI_MIN_SUCCESS
from synth.cli import DEFAULT_PROOF_TRIALS as CLI_PROOF_TRIALS
from synth.cli import main
from synth.exceptions import NoStrategyError
from synth.models.loader import load_task, parse_task
from synth.models.spec import TaskSpec
from synth.replay.proof import (
    DEFAULT_MIN_SUCCESS,
    DEFAULT_PROOF_TRIALS,
    MIN_TRIALS_FOR_BOUND,
    PASSING,
    Z_95,
    ProofOptions,
    _decide,
    prove,
)
from synth.replay.report import wilson_interval
from synth.replay.run import replay_context, run_trial, trial_seed
from synth.replay.trials import TrialPool
from synth.replay.truth import sample_world
from synth.strategies import PlanOptions, plan_task
from synth.strategies.causes import root_cause
from synth.strategies.planner import AT_THE_LEAD
from synth.strategies.records import Rejection


def _sequential(options: ProofOptions, outcomes: list[bool]) -> tuple[bool, int]:
    """The proof's rule applied to ``outcomes`` (two budgets long): (passed, trials consumed)."""
    successes = 0
    for n, ok in enumerate(outcomes, start=1):
        successes += ok
        decision = _decide(options, successes, n)
        if decision is not None:
            return decision in PASSING, n
    raise AssertionError("the rule must decide by the end of the confirmation")


def _fixed(options: ProofOptions, outcomes: list[bool]) -> bool:
    """The two-stage fixed-size test, written out: the rate over the budget n₀ against
    min_success and, when those n₀ trials had a failure, the rate over 2n₀ as well."""
    n0 = options.trials

    def meets(trials: list[bool]) -> bool:
        return sum(trials) >= options.min_success * len(trials) - 1e-9

    first = outcomes[:n0]
    if not meets(first):
        return False
    return all(first) or meets(outcomes[: 2 * n0])


@pytest.mark.parametrize("budget, rate", [(5, 0.8), (6, 0.75), (7, 0.7), (7, 0.99)])
def test_sequential_test_agrees_with_the_fixed_size_test_on_every_pattern(budget, rate) -> None:
    # Two budgets below MIN_TRIALS_FOR_BOUND: only curtailment and the Wilson lower bound can
    # stop early; both must give the verdict of the two-stage test, on every one of 2^(2·budget)
    # patterns (at 0.99 over 7 no failure is allowed, so no confirmation ever runs).
    options = ProofOptions(trials=budget, min_success=rate)
    assert 2 * budget < MIN_TRIALS_FOR_BOUND
    for pattern in itertools.product((True, False), repeat=2 * budget):
        outcomes = list(pattern)
        passed, consumed = _sequential(options, outcomes)
        if passed and consumed not in (budget, 2 * budget):  # early: the bound cleared the rate
            lo, _ = wilson_interval(sum(outcomes[:consumed]), consumed, Z_95)
            assert lo >= rate
        else:
            assert passed == _fixed(options, outcomes), (outcomes, consumed)
        if passed and consumed == 2 * budget:  # a confirmation ran: the budget had a failure
            assert not all(outcomes[:budget])


def test_sequential_test_never_passes_what_the_full_budget_fails() -> None:
    # The Wilson upper rule may fail a program early, never pass it; curtailment is exact.
    rng = np.random.default_rng(3)
    options = ProofOptions(trials=300, min_success=0.99)
    for p in (0.95, 0.98, 0.99, 0.995, 1.0):
        for _ in range(200):
            outcomes = list(rng.random(600) < p)
            passed, consumed = _sequential(options, outcomes)
            if passed and consumed in (300, 600):
                assert _fixed(options, outcomes)
            if not _fixed(options, outcomes):
                assert not passed or consumed not in (300, 600)  # only a Wilson-lower pass


def test_a_confirmation_rejects_more_often_than_the_one_stage_test() -> None:
    # A program failing 3.5% of trials passes one budget of 100 at 0.99 with probability
    # 0.965^100 + 100·0.035·0.965^99 = 0.131 (binomial, ≤ 1 failure); confirmed, it must also
    # keep ≤ 2 failures over 200, which (≤ 1 in the second 100 after exactly 1 in the first)
    # gives 0.965^100 + 100·0.035·0.965^99·0.131 = 0.042. Monte Carlo over 20 000 programs'
    # proofs must find that, not the one-stage rate.
    q = 0.965
    one_failure = 100 * 0.035 * q**99
    expected = q**100 + one_failure * (q**100 + one_failure)
    assert expected == pytest.approx(0.0419, abs=5e-4)
    options = ProofOptions()
    rng = np.random.default_rng(11)
    runs = 20_000
    passes = 0
    for _ in range(runs):
        passes += _sequential(options, list(rng.random(200) >= 0.035))[0]
    sigma = math.sqrt(expected * (1 - expected) / runs)
    assert abs(passes / runs - expected) < 4 * sigma


def test_wilson_lower_bound_of_a_clean_run_and_the_early_pass() -> None:
    # k = n: lower = n/(n + z²) (the Wilson centre minus half-width collapses to this). It
    # clears 0.99 once n ≥ 0.99·z²/0.01 = 380.3, i.e. from the 381st clean trial on.
    z2 = Z_95**2
    for n in (10, 100, 380, 381):
        assert wilson_interval(n, n, Z_95)[0] == pytest.approx(n / (n + z2), rel=1e-12)
    options = ProofOptions(trials=1000, min_success=0.99)
    assert _decide(options, 380, 380) is None
    assert _decide(options, 381, 381) == "wilson-lower"
    # Curtailment at the default: 100 trials at 0.99 allow one failure; the second ends it.
    default = ProofOptions()
    assert (default.trials, default.min_success, default.allowed_failures) == (100, 0.99, 1)
    assert _decide(default, 49, 50) is None and _decide(default, 49, 51) == "curtailed"
    # A clean budget passes at once; one failure in it sends the proof to 2n = 200 trials,
    # which allow two: a third failure ends the confirmation, two pass it.
    assert _decide(default, 100, 100) == "budget" and _decide(default, 99, 100) is None
    assert _decide(default, 148, 150) is None and _decide(default, 147, 150) == "curtailed"
    assert _decide(default, 198, 200) == "confirmed" and _decide(default, 199, 200) == "confirmed"


def test_cli_defaults_match_the_proof_module() -> None:
    assert (CLI_PROOF_TRIALS, CLI_MIN_SUCCESS) == (DEFAULT_PROOF_TRIALS, DEFAULT_MIN_SUCCESS)


def test_options_come_from_the_task_unless_given() -> None:
    text = SEED_TASK.read_text()
    spec = parse_task(text + "proof: {min_success: 0.9, trials: 40}\n")
    assert (ProofOptions.for_task(spec).trials, ProofOptions.for_task(spec).min_success) == (
        40,
        0.9,
    )
    given = ProofOptions.for_task(spec, trials=7, min_success=0.5)
    assert (given.trials, given.min_success) == (7, 0.5)
    assert ProofOptions.for_task(load_task(SEED_TASK)).trials == DEFAULT_PROOF_TRIALS


@pytest.fixture(scope="module")
def first_cut_proof():
    spec = load_task(SEED_TASK)
    text = SEED_FIRST_CUT.read_text()
    return spec, text, prove(text, spec, ProofOptions(trials=100, seed=0), base_dir=TASKS)


def test_a_failing_program_is_rejected_early_with_the_replays_reason(first_cut_proof) -> None:
    # The first cut captures the pin in ~32% of worlds (test_replay_montecarlo.py): at 0.99 the
    # second failure ends the proof, long before 100 trials.
    spec, text, proof = first_cut_proof
    assert proof.nominal.success and not proof.passed
    assert proof.decided_by == "curtailed" and proof.trials <= 10
    failure = proof.first_failure
    assert failure is not None and failure.line is not None
    reason = proof.reason()
    assert f"AL line {failure.line}" in reason and failure.outcome in reason
    # The errors reported are the trial's own draw: the same generator as run_trial's.
    context = replay_context(text, spec, base_dir=TASKS)
    world_seed, _ = trial_seed(0, failure.index).spawn(2)
    world = sample_world(context.graph, np.random.default_rng(world_seed))
    assert failure.errors == world.parameters
    box = failure.errors["box"]
    assert set(box) == {"x", "y", "rz"}
    assert abs(box["x"]) <= 0.3 * 0.0254 and abs(box["rz"]) <= math.radians(5)
    assert run_trial(context, 0, failure.index).outcome == failure.outcome


def test_the_proof_is_the_same_on_one_and_two_workers(first_cut_proof) -> None:
    spec, text, one = first_cut_proof
    with TrialPool(2) as pool:
        two = prove(text, spec, ProofOptions(trials=100, seed=0), base_dir=TASKS, pool=pool)
    assert (two.trials, two.successes, two.decided_by, dict(two.outcomes)) == (
        one.trials,
        one.successes,
        one.decided_by,
        dict(one.outcomes),
    )
    assert two.first_failure == one.first_failure


def test_a_refused_candidate_sends_the_planner_to_the_next_best() -> None:
    # accept() stands for a failed proof: the plan must fall back to the best of the others,
    # which is exhaustive selection's best once the refused candidate is left out.
    spec = load_task(SEED_TASK)
    first = plan_task(spec).strategy
    refused: list[str] = []

    def refuse_first(strategy):
        if strategy.name == first.name:
            refused.append(strategy.name)
            return Rejection(strategy.name, "replay proof failed: test", cause="proof")
        return None

    second = plan_task(spec, accept=refuse_first)
    assert refused == [first.name] and second.strategy.name != first.name
    everything = plan_task(spec, options=PlanOptions(exhaustive=True))
    ranked = sorted(
        (c for c in everything.candidates if c.refined and c.name != first.name),
        key=lambda c: c.expected_time,
    )
    assert second.strategy.name == ranked[0].name
    proof_rejections = [r for r in second.rejected if r.stage == "proof"]
    assert [r.candidate for r in proof_rejections] == [first.name]


def test_no_proven_candidate_names_the_proof_as_root_cause() -> None:
    spec = load_task(SEED_TASK)
    with pytest.raises(NoStrategyError) as info:
        plan_task(
            spec,
            accept=lambda s: Rejection(s.name, "replay proof failed: 0 of 5", cause="proof"),
        )
    first_line = str(info.value).splitlines()[0]
    assert info.value.root.cause == "proof" and "replay proof" in first_line


def test_synthesize_proves_the_seed_program_and_reports_it() -> None:
    synthesis = synthesized(SEED_TASK, trials=20)
    proof = synthesis.proof
    assert proof.passed and proof.trials == 20 and proof.outcomes == {"success": 20}
    assert [a.candidate for a in synthesis.attempts] == [synthesis.strategy.name]
    document = synthesis.to_json()
    assert document["proof"]["wilson_95"] == pytest.approx(list(wilson_interval(20, 20)))
    assert document["program"] == synthesis.program


def test_cli_reports_the_proof_and_checks_its_options(tmp_path, capsys) -> None:
    out = tmp_path / "p.al"
    assert main(["plan", str(SEED_TASK), "--proof-trials", "0", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Proof: nominal replay passed" in text and out.read_text().startswith("{")
    assert main(["plan", str(SEED_TASK), "--proof-trials", "0", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["proof"]["passed"] and doc["proof"]["decided_by"] == "nominal-only"
    for bad in (["--min-success", "1.5"], ["--proof-trials", "-1"]):
        with pytest.raises(SystemExit) as refused:  # argparse's usage error, before planning
            main(["plan", str(SEED_TASK), *bad])
        assert refused.value.code == 2
        assert f"argument {bad[0]}: " in capsys.readouterr().err
    assert main(["plan", str(SEED_TASK), "--workers", "0"]) == 2
    assert "--workers must be 1 or more" in capsys.readouterr().err


def test_a_pin_from_an_uncertain_rack_is_relocated_after_center_and_proven() -> None:
    # The rack slides ±0.75 in along x: CENTER moves the arm onto the true pin, so the program
    # must believe the pin where the hand now is (PIN1 ← BMANIP*TRANS(grasp⁻¹)); with AFFIX
    # alone the believed grip kept the rack's error and 2 of the first 19 trials missed BH1
    # (the proof rejected all three candidates). The seed's exact rack emits no such line.
    rail = DATA_TASKS / "uncertain_rack_rail.yaml"
    proven = synthesized(rail, trials=20)
    assert "PIN1 ← BMANIP*TRANS(" in proven.program
    assert proven.proof.passed and proven.proof.outcomes == {"success": 20}
    assert "PIN1 ← BMANIP" not in SEED_PROGRAM.read_text()


def _seed_overstating_dr_ok() -> TaskSpec:
    """The seed task with Δr_ok = 1.2 cm: wider than all its parts' geometry captures."""
    text = SEED_TASK.read_text(encoding="utf-8")
    assert text.count("dr_ok: 0.762 cm") == 1
    return parse_task(text.replace("dr_ok: 0.762 cm", "dr_ok: 1.2 cm"))


def test_a_proof_that_misses_replans_the_search_at_the_parts_lead() -> None:
    # Searched at 0.75 · 1.2 = 0.9 cm, the spiral leaves parts of the footprint farther than the
    # lead (chamfer .25 + hole radius .32 − tip radius .13 = .44 cm) from every point it tries,
    # and there the tip lands on the box's face: a trial misses. The planner then takes the lead
    # for Δr_ok and searches at 0.75 · 0.44 = 0.33 cm.
    synthesis = synthesized(_seed_overstating_dr_ok(), trials=100)
    first, *_, last = synthesis.attempts
    assert not first.proof.passed and "PIN1 MISSED BH1" in first.proof.reason()
    assert last.candidate == synthesis.strategy.name == f"{first.candidate} {AT_THE_LEAD}"
    assert last.proof.passed and last.proof.outcomes == {"success": last.proof.trials}
    search = synthesis.strategy.search
    assert search is not None and search.step == pytest.approx(0.75 * 0.0044)
    assert any("refuting the task's Δr_ok = 1.2 cm" in d for d in synthesis.strategy.decisions)


@pytest.mark.slow
def test_the_search_at_the_lead_is_proven() -> None:
    # 1 000 trials through the exact chain: none misses (the first plan missed 2 of 49)
    synthesis = synthesized(_seed_overstating_dr_ok(), trials=100)
    context = replay_context(synthesis.program, synthesis.task)
    outcomes = [run_trial(context, 0, i).outcome for i in range(1000)]
    assert outcomes.count("success") == 1000


def test_a_passed_proof_with_a_miss_replans_the_seed_at_the_lead() -> None:
    # The seed's Δr_ok = 0.3 in = 0.762 cm (L1963) was measured on its real arm, whose
    # compliance the replay does not model: the replay captures within the parts' lead,
    # chamfer .25 + hole radius .32 − tip radius .13 = .44 cm. The search spaced by 0.75·Δr_ok
    # = 0.5715 cm leaves gaps, and trial 52 of seed 0 lands in one (the slow suite replays the
    # golden program at 199 of 200 for seed 0: that miss is its only failure). The proof passes
    # (one failure of 100, confirmed at 199 of 200), but a miss is the planner's own error
    # model refuted, so the search is planned again at the lead: 0.75 · 0.44 = 0.33 cm apart.
    synthesis = synthesized(SEED_TASK, trials=100)
    first, *_, last = synthesis.attempts
    assert first.candidate == "ω=180° γ=135° d=3.54 cm φ=90°"
    assert first.proof.passed and first.proof.decided_by == "confirmed"
    assert (first.proof.trials, first.proof.successes) == (200, 199)
    failure = first.proof.first_failure
    assert failure is not None and failure.index == 52
    assert failure.outcome == "abort" and failure.message.startswith("PIN1 MISSED BH1")
    assert first.refuted == "dr_ok" and last.refuted is None
    assert last.candidate == synthesis.strategy.name == f"{first.candidate} {AT_THE_LEAD}"
    assert last.proof.passed and last.proof.outcomes == {"success": last.proof.trials}
    search = synthesis.strategy.search
    assert search is not None and search.step == pytest.approx(0.75 * 0.0044)
    assert synthesis.strategy.dr_ok == pytest.approx(0.0044)  # the header's DROK says so too
    assert "DROK = 0.44*CM" in synthesis.program
    assert synthesis.fallback is None  # the program at the lead is the plan's first choice
    assert SEED_PROGRAM.read_text().count("DROK = 0.762*CM") == 1  # golden: the nominal proof


def test_a_proven_program_is_kept_when_nothing_at_the_lead_is_accepted() -> None:
    # accept() stands for the proofs: the first choice passes with a miss (proven, refuting
    # Δr_ok), and every candidate planned at the lead fails. The plan falls back on the first
    # choice, whose proof passed, rather than refusing a task it has a proven program for.
    spec = load_task(SEED_TASK)
    first = plan_task(spec).strategy
    asked: list[str] = []

    def verdict(strategy):
        asked.append(strategy.name)
        if strategy.name == first.name:
            return Rejection(
                strategy.name, "proven, but missed", "proof", refuted="dr_ok", proven=True
            )
        return Rejection(strategy.name, "replay proof failed: test", cause="proof")

    plan = plan_task(spec, accept=verdict)
    assert plan.strategy is first or plan.strategy.name == first.name
    assert asked[0] == first.name and len(asked) > 1
    assert all(name.endswith(AT_THE_LEAD) for name in asked[1:])
    assert plan.strategy.name in [c.name for c in plan.candidates]

    # With no belief left to re-plan (already at the lead), a proven verdict is acceptance.
    def missed(strategy):
        return Rejection(strategy.name, "proven, but missed", "proof", refuted="dr_ok", proven=True)

    at_lead = plan_task(spec, options=PlanOptions(at_lead=True), accept=missed)
    assert at_lead.strategy.name == f"{first.name} {AT_THE_LEAD}"


def test_a_sequence_proven_with_a_miss_is_kept_when_nothing_at_the_lead_is_planned(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The two-pin sequence's first proof passes, 199 of 200 (198 before its second pickup was
    # lifted over the box: another grasp), but a trial misses BH1 under the seed's Δr_ok: the
    # pipeline plans the sequence again at the lead. When that
    # plan is refused (here: the planner's second call raises as a refusal would), the first
    # sequence, whose proof passed, is written, and its proof is the synthesis's.
    import synth.pipeline as pipeline

    planned = pipeline.plan_sequence
    calls: list[bool] = []

    def refuse_at_the_lead(*args, **kwargs):
        calls.append(kwargs["options"].at_lead)
        if kwargs["options"].at_lead:
            refused = [Rejection("any", "no arm solution", "reach")]
            raise NoStrategyError("seed_box_two_pins", tuple(refused), root_cause(refused))
        return planned(*args, **kwargs)

    monkeypatch.setattr(pipeline, "plan_sequence", refuse_at_the_lead)
    task = TASKS / "seed_box_two_pins.yaml"
    options = pipeline.SynthesisOptions(proof=ProofOptions(trials=100, workers=1))
    synthesis = pipeline.synthesize(task, options)
    assert calls == [False, True]
    (only,) = synthesis.attempts
    assert only.refuted == "dr_ok" and synthesis.proof is only.proof
    assert only.proof.passed and (only.proof.trials, only.proof.successes) == (200, 199)
    failure = only.proof.first_failure
    assert failure is not None and failure.message.startswith("PIN1 MISSED BH1")
    assert all(AT_THE_LEAD not in s.strategy.name for s in synthesis.sequence.steps)
    # the one line that tells the engineer the written program is a fallback, and why
    assert synthesis.fallback is not None
    assert synthesis.fallback.startswith(f"{only.candidate} is written as the fallback")
    assert f"trial {failure.index} missed the hole" in synthesis.fallback
    assert synthesis.to_json()["fallback"] == synthesis.fallback
