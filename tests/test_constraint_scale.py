"""A coupled constraint means the same set of errors whatever the size of its coefficients.

HiGHS refuses a matrix entry of 10¹⁵ or more (its ``large_matrix_value``) and drops one below
10⁻⁹ (``small_matrix_value``). Each constraint is divided by its largest coefficient before it
reaches the LPs and the sampler (:meth:`Uncertainty.constraint_rows`), which leaves its set of
values unchanged; the figures below are closed forms of that set on the seed's box (x ±0.3 in,
y ±0.2 in).
"""

from __future__ import annotations

import numpy as np
from _paths import SEED_TASK

from synth.errors.chain import chain_between
from synth.errors.estimate import estimate_errors
from synth.errors.parameters import ParameterBlock, ParameterSpace
from synth.models.graph import AttributeGraph
from synth.models.loader import parse_task

IN = 0.0254


def _box_with(constraint: str) -> AttributeGraph:
    text = SEED_TASK.read_text(encoding="utf-8").replace(
        "      rz: 5 deg\n", f"      rz: 5 deg\n      constraints:\n        - {constraint}\n", 1
    )
    return AttributeGraph(parse_task(text))


def _box_x(graph: AttributeGraph) -> tuple[float, float]:
    """The certified range of the box's x error in the world [m]."""
    dx = estimate_errors(chain_between(graph, "world", "box")).certified.dx
    return dx.lo, dx.hi


def test_a_huge_coefficient_is_a_feasible_constraint_not_an_infeasible_one() -> None:
    # x·10¹⁵ + y ≤ 0.4 in holds at x = y = 0; before the rows were scaled the loader's LP got
    # HiGHS's "model error" for the 10¹⁵ entry and refused the task as "admitting no error
    # values". Closed form: x ≤ (0.4 in − y)/10¹⁵ ≤ 0.6 in/10¹⁵ ≈ 1.5e-17 m, x ≥ −0.3 in.
    lo, hi = _box_x(_box_with("{terms: {x: 1e15, y: 1}, max: 0.4 in}"))
    assert abs(hi) < 1e-9
    assert abs(lo - (-0.3 * IN)) < 1e-9


def test_tiny_coefficients_still_constrain_the_errors() -> None:
    # 10⁻¹²·x + 10⁻¹²·y ≤ 10⁻¹⁴ in is x + y ≤ 0.01 in: x ≤ 0.01 in + 0.2 in = 0.21 in
    # (0.533 cm). HiGHS dropped the 10⁻¹² entries and gave the whole box, x ≤ 0.3 in.
    graph = _box_with("{terms: {x: 1e-12, y: 1e-12}, max: 1e-14 in}")
    lo, hi = _box_x(graph)
    assert abs(hi - 0.21 * IN) < 1e-9
    assert abs(lo - (-0.3 * IN)) < 1e-9
    # The Monte Carlo draws honour it too: with the unscaled rows the sampler's tolerance
    # (1e-12 on c·v ≤ b, against c·v ~ 1e-14) let every draw of the box through.
    unc = graph.links["box"].uncertainty
    assert unc is not None
    space = ParameterSpace((ParameterBlock.from_uncertainty("box", unc),))
    v = space.sample(np.random.default_rng(4), 2_000)
    x, y = v[:, 0], v[:, 1]
    assert np.all(x + y <= 0.01 * IN + 1e-12)
    # and they fill it up to the line: the strip 0 ≤ x + y ≤ 0.01 in has area 0.01·0.4 in² of
    # the feasible 0.24 − 0.29·0.4 = 0.124 in², 3.2 %: about 65 of 2 000 draws fall in it
    strip = np.count_nonzero(x + y >= 0.0)
    assert 30 < strip < 110
