"""Rejection sampling of an error space is bounded: a block whose coupled constraints reject
(nearly) every draw is refused with a message naming them, after a fixed budget of draws,
instead of being sampled for ever; a feasible narrow block still samples, and a feasible space
gives the same draws as the unbounded sampler did."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from _paths import SEED_PROGRAM, SEED_TASK

from synth.cli import main
from synth.errors.parameters import (
    MIN_ACCEPTANCE,
    SAMPLE_BUDGET,
    ParameterBlock,
    ParameterSpace,
    SamplingError,
)
from synth.exceptions import SpecError
from synth.models.graph import AttributeGraph
from synth.models.loader import parse_task

MM = 1e-3


def _thin_text() -> str:
    """The seed task with the box's x and y errors tied within 1e-11 m of each other.

    (``min == max``, an exact equality, is refused by the loader at the constraint: test_spec.)
    """
    return SEED_TASK.read_text(encoding="utf-8").replace(
        "      rz: 5 deg\n",
        "      rz: 5 deg\n      constraints:\n"
        "        - {terms: {x: 1, y: -1}, min: 0 cm, max: 1e-9 cm}\n",
        1,
    )


def _square(owner: str = "box", half: float = 1 * MM) -> ParameterSpace:
    """x, y uniform on [−half, half]², no coupled rows."""
    lo, hi = np.full(2, -half), np.full(2, half)
    block = ParameterBlock(owner, ("x", "y"), lo, hi, np.zeros((0, 2)), np.zeros(0))
    return ParameterSpace((block,))


def test_an_infeasible_coupled_row_is_refused_after_the_budget_naming_it() -> None:
    # x ≥ 2 mm on a block bounded by |x| ≤ 1 mm: no draw can pass (a tap's row added with
    # constrain() is not checked by the loader's LP).
    space = _square().constrain(np.array([[-1.0, 0.0]]), np.array([-2 * MM]))
    rng = np.random.default_rng(0)
    with pytest.raises(SamplingError) as caught:
        space.sample(rng, 1)
    error = caught.value
    assert isinstance(error, ValueError) and isinstance(error, SpecError)
    assert error.path == "uncertainty of box"
    assert "−box.x ≤ -0.002" in error.detail  # the row, in SI, as written above
    assert "acceptance 0.0e+00" in error.detail and error.accepted == 0
    # Rounds of max(2·(n − kept), 64) = 64 draws for n = 1: the first total at or above the
    # budget is 64·⌈10⁵/64⌉ = 64·1563 = 100 032 draws, and not one more round is drawn.
    assert SAMPLE_BUDGET == 100_000
    assert error.drawn == 64 * math.ceil(100_000 / 64) == 100_032
    expected = np.random.default_rng(0)
    for _ in range(1563):
        expected.uniform(space.lo, space.hi, size=(64, 2))
    assert rng.bit_generator.state == expected.bit_generator.state


def test_a_band_the_loader_accepts_is_refused_by_the_sampler() -> None:
    # 0 ≤ x − y ≤ 1e-11 m: the LP finds the band feasible, but its area in the 0.6 × 0.4 in
    # rectangle is ~1e-11 × 0.01 m², so a uniform draw lands in it with probability ~1e-9.
    graph = AttributeGraph(parse_task(_thin_text()))
    unc = graph.links["box"].uncertainty
    assert unc is not None and len(unc.constraints) == 1
    space = ParameterSpace((ParameterBlock.from_uncertainty("box", unc),))
    with pytest.raises(SamplingError, match=r"uncertainty of box: 0 of 100032 draws") as caught:
        space.sample(np.random.default_rng(1), 1)
    assert "box.x − box.y ≤ 1e-11" in caught.value.detail
    assert "−box.x + box.y ≤ 0" in caught.value.detail


def test_a_narrow_feasible_corner_still_samples_inside_its_constraint() -> None:
    # x + y ≤ −1.9 mm on the 2 mm square keeps the corner triangle with legs 0.1 mm: area
    # 0.5·0.1² = 0.005 mm² of 4 mm², an acceptance of 1.25e-3, ten times the refusal rate.
    space = _square().constrain(np.array([[1.0, 1.0]]), np.array([-1.9 * MM]))
    assert 10 * MIN_ACCEPTANCE < 1.25e-3
    v = space.sample(np.random.default_rng(2), 200)
    assert v.shape == (200, 2)
    assert np.all(v[:, 0] + v[:, 1] <= -1.9 * MM + 1e-12)
    assert np.all((v >= -1 * MM) & (v <= 1 * MM))
    # Uniform in the triangle (−1, −1), (−0.9, −1), (−1, −0.9) mm: mean x is its centroid,
    # −2.9/3 mm, and σx = 0.1/√18 mm, so the mean of 200 is within 4σ/√200 = 0.0067 mm.
    assert abs(v[:, 0].mean() - (-2.9 / 3 * MM)) < 4 * 0.1 * MM / math.sqrt(18 * 200)


def test_a_box_space_draws_exactly_what_the_unbounded_sampler_drew() -> None:
    # Every draw of a box is feasible, so one round of max(2n, 64) uniforms gives the n samples:
    # the budget check adds no draw and changes no seeded replay.
    space = _square(half=3 * MM)
    got = space.sample(np.random.default_rng(3), 40)
    want = np.random.default_rng(3).uniform(space.lo, space.hi, size=(80, 2))[:40]
    assert np.array_equal(got, want)


def test_synth_replay_of_a_block_too_thin_to_sample_exits_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # The nominal run draws nothing; the first trial draws the box's error and is refused.
    task = tmp_path / "thin.yaml"
    task.write_text(_thin_text(), encoding="utf-8")
    argv = ["replay", str(SEED_PROGRAM), "--task", str(task), "--trials", "1"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("synth replay: error: uncertainty of box: 0 of 100032 draws")
    assert err.count("\n") == 1 and "Traceback" not in err
