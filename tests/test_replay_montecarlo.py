"""Monte Carlo replays of the seed's programs on seed_4_8.

**Search listing (L2715–2781).** Measured with this replay, the arm at (20, 70) cm and the
box 8.90 × 7.60 cm (seed L2340–2350): 1948 successes in 2000 trials (seed 0), rate 0.974, 95%
Wilson interval [0.966, 0.980]. (Earlier fixtures: 1957 with an 8.98 cm box, the OCR reading of
L3007; 1936 with the arm at (20, 80) cm.) Every failure is the listing's own
``ON ARRIVAL DO ABORT("EXPECTED A FORCE HERE")``: BH1 lies 0.60 cm from the box's +x edge and
0.60 cm from its +y edge (BH1 at (3.85, 3.20) cm), less than the box's own position error
(±0.76 cm in x, ±0.51 cm in y, ±5° ≈ ±0.44 cm at BH1), and the search's first ring (0.572 cm,
turned by FPW = 60°) starts towards that corner; a search point off the box lets the pin and
the fingers pass beside it, nothing is felt, and the program gives up. The issue asks for
≥ 99%; with *uniform* errors the seed's geometry does not allow it with a box edge that close.
Read as the seed's chapter IX reads a tolerance (normal, σ = tolerance/3, truncated;
L7240–7242; ``--distribution normal``), the same listing succeeds in 2000 of 2000 trials:
beside-the-box aborts need a box error near its bound. Both are asserted below; which
distribution a real workcell has is the production engineer's call (L7240).

The default test replays 300 trials and asserts k ≥ 279 successes (93%). Binomial argument:
for a true rate p = 0.966 (the lower end of the interval above), P(K ≤ 278 | n = 300) = 7e-4
(scipy.stats.binom.cdf): the bound is not picked for this seed. Each abort is then checked by
hand geometry: the pin ended beside the true box, below its top face. The 2000-trial run is
marked ``slow`` (``make test-slow``) and asserts k ≥ 1880:
P(K ≤ 1879 | n = 2000, p = 0.960) = 8e-6.

**synth's own search program** (fixtures/golden/seed_4_8.al) differs from the listing in one
documented way: a point where nothing is felt is backed out of and the search goes on
(records.OffSurface). Under the same uniform errors it succeeded in 1000 of 1000 trials.

**First cut (§2.3.4 style).** An independent model of its only chance: the pin goes straight to
the believed hole and is captured when the true mouth is within the lead of the parts,
lateral offset ≤ r_mouth − r_tip = 0.57 − 0.13 = 0.44 cm, with the offset sampled from the
task's box block (uniform) and hand block (uniform x, y), in plain numpy (below). The replay's
rate must agree within 0.08 (joint-interpolated paths sag by up to ~1.7 mm, which the model
ignores), with its 99% Wilson interval.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from _paths import SEED_FIRST_CUT, SEED_PROGRAM, SEED_SEARCH, SEED_TASK

from synth.models.graph import AttributeGraph
from synth.models.loader import load_task
from synth.replay import (
    HandErrors,
    machine_for,
    replay_context,
    replay_program,
    run_machine,
    run_trial,
    sample_world,
    trial_seed,
    wilson_interval,
)
from synth.units import CM, INCH

BOX_HALF = (4.45 * CM, 3.80 * CM)  # fixture: 8.90 × 7.60 cm
WORKERS = max(2, min(4, os.cpu_count() or 2))
"""Processes for the 2 000-trial runs: each holds the arm and workcell (~0.2 GB), so a CI
machine with many cores must not start one per core."""
BOX_TOP = 4.90 * CM


@pytest.fixture(scope="module")
def search_text() -> str:
    return SEED_SEARCH.read_text(encoding="utf-8")


def abort_line(text: str) -> int:
    """The line of the search move's ON ARRIVAL abort (the second such clause)."""
    lines = [
        i
        for i, t in enumerate(text.splitlines(), 1)
        if 'ON ARRIVAL DO ABORT("EXPECTED A FORCE HERE")' in t
    ]
    return lines[1]


def check_search_failures(text: str, report_trials: list, seed: int) -> None:  # type: ignore[type-arg]
    """Every failed trial aborted because the pin passed beside the box (hand geometry)."""
    context = replay_context(text, SEED_TASK)
    first_attempt = abort_line(text) - 19  # the first attempt's own ON ARRIVAL, L2736
    for index, run in enumerate(report_trials):
        if run.outcome == "success":
            continue
        assert run.outcome == "abort" and run.message == "EXPECTED A FORCE HERE"
        assert run.line in (abort_line(text), first_attempt)
        world_seed, hand_seed = trial_seed(seed, index).spawn(2)
        world = sample_world(context.graph, np.random.default_rng(world_seed))
        manipulator = context.spec.manipulator
        assert manipulator is not None
        hand = HandErrors(manipulator.hand_error, np.random.default_rng(hand_seed))
        machine = machine_for(context, world, hand)
        again, _ = run_machine(context, machine)
        assert (again.outcome, again.line, again.time) == (run.outcome, run.line, run.time)
        # by hand: the tip in the true box's frame lies outside its top face and below it
        box = world.pose("box")
        tip = machine.pins["pin1"].pose.translation
        local = box.rotation.T @ (tip - box.translation)
        assert abs(local[0]) > BOX_HALF[0] or abs(local[1]) > BOX_HALF[1]
        assert local[2] < BOX_TOP


@pytest.mark.slow
def test_search_listing_monte_carlo_300(search_text: str) -> None:
    report = replay_program(search_text, SEED_TASK, trials=300, seed=0, workers=2)
    mc = report.monte_carlo
    assert report.ok and mc.trials == 300
    assert mc.successes >= 279, mc.outcomes
    # no violation, and never a false success (the program's test fooled, pin not seated)
    assert set(mc.outcomes) <= {"success", "abort"}
    check_search_failures(search_text, list(report.trials), seed=0)
    # the timing statistics are those of the runs
    times = np.array([r.time for r in report.trials])
    assert mc.time_mean == pytest.approx(times.mean())
    assert mc.time_p95 == pytest.approx(np.percentile(times, 95))
    # trials do not depend on the worker count: a few re-run in this process
    context = replay_context(search_text, SEED_TASK)
    for index in (0, 7, 123):
        again = run_trial(context, 0, index)
        assert again == report.trials[index]


@pytest.mark.slow
def test_search_listing_monte_carlo_2000(search_text: str) -> None:
    report = replay_program(search_text, SEED_TASK, trials=2000, seed=0, workers=WORKERS)
    mc = report.monte_carlo
    # measured 1948/2000 (module docstring)
    assert mc.successes >= 1880, mc.outcomes
    assert set(mc.outcomes) <= {"success", "abort"}
    check_search_failures(search_text, list(report.trials), seed=0)


@pytest.mark.slow
def test_search_listing_monte_carlo_2000_normal(search_text: str) -> None:
    # The issue's ≥ 99% of 2 000, with the box and hand errors read as the seed's chapter IX
    # reads a tolerance: normal, σ = tolerance/3, truncated at it (L7240–7242). Measured
    # 2000/2000 (seed 0; 1999/2000 with the arm at (20, 80) cm): the beside-the-box aborts
    # need a box error near its bound, which a 3σ tolerance makes rare.
    # Binomial: for a true rate of 0.995, P(K < 1980) = 2e-4.
    report = replay_program(
        search_text, SEED_TASK, trials=2000, seed=0, workers=WORKERS, distribution="normal"
    )
    mc = report.monte_carlo
    assert report.ok and mc.trials == 2000
    assert mc.successes >= 1980, mc.outcomes
    assert set(mc.outcomes) <= {"success", "abort"}
    lo, _ = wilson_interval(mc.successes, mc.trials)
    assert lo > 0.99 - 0.005


def test_a_distribution_override_samples_every_block_from_it() -> None:
    # σ of the box's x error: uniform on ±0.3 in has 0.3 in/√3; a normal with σ = 0.1 in
    # truncated at 3σ has 0.1 in·√(1 − 6φ(3)/(2Φ(3) − 1)) = 0.0986 in.
    from scipy.stats import truncnorm

    spec = load_task(SEED_TASK)
    for name, expected in (
        ("uniform", 0.3 * INCH / math.sqrt(3)),
        ("normal", 0.1 * INCH * float(truncnorm(-3, 3).std())),
    ):
        graph = AttributeGraph(spec.with_distribution(name))
        rng = np.random.default_rng(5)
        xs = [sample_world(graph, rng).link_errors["box"].translation[0] for _ in range(4000)]
        assert float(np.std(xs)) == pytest.approx(expected, rel=0.05)
        manipulator = graph.spec.manipulator
        assert manipulator is not None and manipulator.hand_error is not None
        assert manipulator.hand_error.distribution == name
    assert spec.with_distribution("normal").frames[0].uncertainty.bounds() == (
        spec.frames[0].uncertainty.bounds()
    )


@pytest.mark.slow
def test_synths_search_program_does_not_give_up_beside_the_box() -> None:
    # synth's golden program for seed_4_8 backs out of a point where nothing is felt instead of
    # aborting (records.OffSurface); under the uniform errors with which the seed's listing
    # aborts beside the box, it succeeded in every one of 1000 trials (seed 0). Asserted:
    # ≥ 397 of 400 (scipy.stats.binom): a program as good as the listing (0.974) passes with
    # P = 0.007, one at 0.998 fails with P = 0.009.
    text = SEED_PROGRAM.read_text(encoding="utf-8")
    report = replay_program(text, SEED_TASK, trials=400, seed=0, workers=2)
    mc = report.monte_carlo
    assert report.ok and mc.successes >= 397, mc.outcomes


def first_cut_model(samples: int = 200_000) -> float:
    """P(capture) of a pin sent straight to the believed BH1, in plain numpy (docstring)."""
    rng = np.random.default_rng(2024)
    ex = rng.uniform(-0.3 * INCH, 0.3 * INCH, samples)  # box block, seed L2566
    ey = rng.uniform(-0.2 * INCH, 0.2 * INCH, samples)
    rz = rng.uniform(-math.radians(5), math.radians(5), samples)
    hx, hy = 3.85 * CM, 3.20 * CM  # BH1 in the box
    dx = ex + np.cos(rz) * hx - np.sin(rz) * hy - hx
    dy = ey + np.sin(rz) * hx + np.cos(rz) * hy - hy
    gx = rng.uniform(-0.05 * INCH, 0.05 * INCH, samples)  # hand block, A.2
    gy = rng.uniform(-0.05 * INCH, 0.05 * INCH, samples)
    return float(np.mean(np.hypot(dx - gx, dy - gy) <= (0.57 - 0.13) * CM))


def test_first_cut_program_fails_in_a_measurable_fraction() -> None:
    text = SEED_FIRST_CUT.read_text(encoding="utf-8")
    report = replay_program(text, SEED_TASK, trials=120, seed=0, workers=1)
    mc = report.monte_carlo
    assert report.ok  # the believed world is fine
    failures = mc.trials - mc.successes
    lo, hi = wilson_interval(mc.successes, mc.trials, z=2.5758293035489)  # 99%
    predicted = first_cut_model()
    assert failures >= 30  # measurable: about two in three
    assert lo - 0.08 <= predicted <= hi + 0.08, (mc.successes, predicted)
    # the misses push the pin into the box's top face: a collision at the transport's line
    line = next(
        i for i, t in enumerate(text.splitlines(), 1) if "move PIN1 to in_hole_position" in t
    )
    for run in report.trials:
        if run.outcome != "success":
            assert run.outcome in ("violation", "failure"), run.message
        if run.outcome == "violation":
            (violation,) = run.violations
            assert violation.kind == "collision" and violation.line == line
            assert "BOX" in violation.detail
