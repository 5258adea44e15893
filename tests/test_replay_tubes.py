"""The sweeps' tubes (synth/replay/tubes.py): a free sweep's floors reused for nearby sweeps.

The truth is Coal's exact distances (meshes themselves) at dense points of each path; the
claims checked are the module docstring's: a tube's floors lie under its own path's gaps, a pair
it proves for a nearby path (other ends, the obstacles moved) stays beyond the clearance there,
and the replay's trials come out the same with and without tubes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_PROGRAM, SEED_SEARCH, SEED_TASK

from synth.models.arm import Obstacle, SweepOptions
from synth.replay import machine_for, replay_context, run_trial
from synth.replay.advance import fast_sweep
from synth.replay.bounds import ArmChain
from synth.replay.sweeps import pair_distances
from synth.replay.truth import HandErrors, nominal_world
from synth.replay.tubes import BUILDS, Tubes, certify

CLEARANCE = 1e-3
POINTS = 60


@pytest.fixture(scope="module")
def cell():  # type: ignore[no-untyped-def]
    context = replay_context(SEED_PROGRAM.read_text(encoding="utf-8"), SEED_TASK)
    machine = machine_for(context, nominal_world(context.graph), HandErrors.none())
    return context, machine


def true_gaps(scene, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Per pair the least exact distance over POINTS points of q0 → q1 [m]."""
    pairs = list(range(len(scene.pairs)))
    samples = [pair_distances(scene, q0 + x * (q1 - q0), pairs) for x in np.linspace(0, 1, POINTS)]
    return np.min(np.array(samples), axis=0)


def moved(obstacle: Obstacle, rng: np.random.Generator, size: float) -> Obstacle:
    """``obstacle`` displaced by a random rigid motion of about ``size`` [m] (and rad/10)."""
    step = pin.SE3(pin.exp3(rng.normal(scale=0.1 * size, size=3)), rng.normal(scale=size, size=3))
    return Obstacle(obstacle.name, obstacle.geometry, obstacle.pose * step)


def test_tubes_prove_only_what_the_truth_keeps_clear(cell) -> None:  # type: ignore[no-untyped-def]
    context, machine = cell
    scene = machine.scene()
    chain = ArmChain.of(context.arm)
    limits = context.arm.limits
    options = SweepOptions(clearance=CLEARANCE)
    environment = scene.environment
    rng = np.random.default_rng(11)
    built = proven = checked = partial_agree = 0
    for _ in range(8):
        q0 = rng.uniform(limits.lower, limits.upper)
        q1 = np.clip(q0 + rng.normal(scale=0.4, size=q0.size), limits.lower, limits.upper)
        scene.reposition(environment, scene.held)
        if not fast_sweep(scene, chain, q0, q1, options).free:
            continue
        tube = certify(scene, chain, q0, q1, options)
        built += 1
        # the floors are lower bounds on the tube's own path (margins are zero here)
        assert np.all(tube.floors <= true_gaps(scene, q0, q1) + 1e-9)
        for size in (1e-3, 5e-3, 2e-2):
            p0 = np.clip(q0 + rng.normal(scale=size, size=q0.size), limits.lower, limits.upper)
            p1 = np.clip(q1 + rng.normal(scale=size, size=q1.size), limits.lower, limits.upper)
            scene.reposition([moved(o, rng, size) for o in environment], scene.held)
            left = tube.unproven(scene, chain, p0, p1, CLEARANCE)
            claimed = np.setdiff1d(np.arange(len(scene.pairs)), left)
            truth = true_gaps(scene, p0, p1)
            # every pair the tube proves is beyond the clearance all along the new path
            assert np.all(truth[claimed] > CLEARANCE), (size, truth[claimed].min())
            proven += claimed.size
            checked += len(scene.pairs)
            # sweeping only the pairs left gives the whole scene's verdict
            whole = fast_sweep(scene, chain, p0, p1, options)
            part = fast_sweep(scene, chain, p0, p1, options, only=left)
            assert part.free == whole.free
            if not whole.free:
                assert part.pair == whole.pair and part.distance <= CLEARANCE
            partial_agree += 1
    scene.reposition(environment, scene.held)
    # not vacuous: tubes were built and proved most pairs of the nearby paths
    assert built >= 4 and partial_agree >= 12
    assert proven >= 0.5 * checked


def test_a_line_stops_building_tubes_after_its_budget(cell) -> None:  # type: ignore[no-untyped-def]
    context, machine = cell
    scene = machine.scene()
    chain = ArmChain.of(context.arm)
    options = SweepOptions(clearance=CLEARANCE)
    tubes = Tubes()
    q0 = context.arm.limits.lower * 0.5 + context.arm.limits.upper * 0.5
    for k in range(BUILDS + 3):
        tubes.build(7, scene, chain, q0, q0 + 0.01 * (k + 1), options)
    assert len(tubes.tubes) == BUILDS and tubes.built[7] == BUILDS


def _runs(program: Path, trials: int) -> list[tuple[object, ...]]:
    """Trials 0 … trials−1 of seed 0 in a new context (its own scenes, so no one's tubes)."""
    context = replay_context(program.read_text(encoding="utf-8"), SEED_TASK)
    runs = [run_trial(context, 0, i) for i in range(trials)]
    return [(r.outcome, r.line, r.message, r.statements, r.time) for r in runs]


@pytest.mark.parametrize(
    ("program", "trials"),
    [
        (SEED_SEARCH, 20),
        pytest.param(SEED_SEARCH, 100, marks=pytest.mark.slow),
        pytest.param(SEED_PROGRAM, 100, marks=pytest.mark.slow),
    ],
    ids=["search-20", "search-100", "golden-100"],
)
def test_trials_are_the_same_with_and_without_tubes(
    program: Path, trials: int, monkeypatch
) -> None:  # type: ignore[no-untyped-def]
    # 200 trials of both programs with seed 0 were compared when the tubes were written: all
    # identical in outcome, line, message, statements and simulated time
    with_tubes = _runs(program, trials)
    monkeypatch.setattr(Tubes, "unproven", lambda self, *a, **k: None)
    monkeypatch.setattr(Tubes, "build", lambda self, *a, **k: None)
    assert _runs(program, trials) == with_tubes
