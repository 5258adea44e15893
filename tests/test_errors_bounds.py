"""Error machinery beyond the seed's examples: coupled constraints, random chains, monotonicity."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from synth.errors.bounds import bound_linear, closed_form_bound
from synth.errors.chain import ErrorChain, Fixed, Perturbation, chain_between
from synth.errors.estimate import estimate_errors
from synth.errors.parameters import ParameterBlock, ParameterSpace
from synth.errors.taylor import TaylorModel, rotation_remainder
from synth.models.graph import AttributeGraph
from synth.models.loader import parse_task
from synth.models.uncertainty import Uncertainty

COUPLED = """\
name: coupled
frames:
  - name: box
    al_name: BOX
    pose: {translation: [40 cm, 100 cm, 0 cm]}
    uncertainty:
      x: 0.3 in
      y: 0.3 in
      rz: 5 deg
      constraints:
        - {terms: {x: 1, y: 1}, max: 0.2 in, min: -0.2 in}
        - {terms: {x: 1, rz: 2 cm/deg}, max: 0.25 in}
  - name: hole
    al_name: BH1
    parent: box
    pose: {translation: [3.85 cm, 3.20 cm, 4.90 cm]}
"""


def test_coupled_constraints_use_the_lp_and_stay_certified() -> None:
    graph = AttributeGraph(parse_task(COUPLED))
    chain = chain_between(graph, "world", "hole")
    assert not chain.space.is_box
    report = estimate_errors(chain)
    # The box hull alone would allow |Δx + Δy| = .6 in; the constraint caps x + y at .2 in, so
    # the LP bound along (1, 1)/√2 is far below the closed-form box bound.
    from synth.errors.estimate import RelationModel

    rel = RelationModel.of(chain)
    c = rel.displacement.linear @ np.array([1.0, 1.0, 0.0])
    lp = bound_linear(c, chain.space)
    box = closed_form_bound(c, chain.space)
    assert lp.hi < 0.75 * box.hi
    # Monte Carlo through the exact chain (rejection sampling honours the constraints).
    rng = np.random.default_rng(5)
    v = np.vstack([chain.space.sample(rng, 40_000), chain.space.corners()])
    assert np.all(chain.space.feasible(v))
    _, pos = chain.evaluate(v)
    dp = pos - chain.nominal.translation
    assert (dp @ [1.0, 1.0, 0.0]).max() <= lp.hi + np.abs(
        [1.0, 1.0, 0.0]
    ) @ rel.displacement.remainder
    for k, key in enumerate(("dx", "dy", "dz")):
        iv = getattr(report.certified, key)
        assert iv.lo <= dp[:, k].min() and dp[:, k].max() <= iv.hi
    # LP extrema are attained: a sampled point comes within 5% of the first-order bound of Δx.
    assert dp[:, 0].max() >= 0.95 * report.first_order.dx.hi


def test_rotation_remainder_is_exact_at_the_tolerance() -> None:
    for axis in range(3):
        for a in (1e-3, 0.1, 1.0, 3.0):
            bound = rotation_remainder(axis, a)
            for theta in np.linspace(-a, a, 41):
                k = np.eye(3)[axis] * theta
                rest = pin.exp3(k) - np.eye(3) - pin.skew(k)
                assert np.all(np.abs(rest) <= bound + 1e-15)
            # Attained at |θ| = a: the bound is tight, not merely safe.
            k = np.eye(3)[axis] * a
            assert np.abs(pin.exp3(k) - np.eye(3) - pin.skew(k)).max() == pytest.approx(bound.max())


def _random_chain(seed: int, scale: float) -> ErrorChain:
    rng = np.random.default_rng(seed)
    blocks = []
    terms: list[Fixed | Perturbation] = []
    for i in range(4):
        tol_t = scale * rng.uniform(0.001, 0.02)
        tol_r = scale * rng.uniform(0.001, 0.2)
        unc = Uncertainty.model_validate(
            {
                "x": f"{tol_t} m",
                "y": f"{tol_t / 2} m",
                "z": f"{tol_t} m",
                "rx": f"{tol_r} rad",
                "ry": f"{tol_r / 3} rad",
                "rz": f"{tol_r} rad",
            }
        )
        blocks.append(ParameterBlock.from_uncertainty(f"b{i}", unc))
        terms.append(Fixed(pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(scale=0.3, size=3))))
        terms.append(Perturbation(i, inverse=bool(i % 2)))
    terms.append(Fixed(pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(scale=0.3, size=3))))
    return ErrorChain(ParameterSpace(tuple(blocks)), tuple(terms))


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), scale=st.floats(0.1, 0.5))
def test_certified_bounds_contain_random_chains(seed: int, scale: float) -> None:
    chain = _random_chain(seed, scale)
    report = estimate_errors(chain)
    rng = np.random.default_rng(seed)
    # 24 parameters: 2²⁴ vertices are too many to list, so take 4 096 random vertices of the box
    # (extremes of the exact chain sit at or near vertices) besides the interior samples.
    space = chain.space
    vertices = space.lo + rng.integers(0, 2, size=(4096, space.dim)) * (space.hi - space.lo)
    v = np.vstack([space.sample(rng, 3000), vertices])
    rot, pos = chain.evaluate(v)
    dp = pos - chain.nominal.translation
    w = np.array([pin.log3(r @ chain.nominal.rotation.T) for r in rot[:500]])
    for k, key in enumerate(("dx", "dy", "dz")):
        iv = getattr(report.certified, key)
        assert iv.lo - 1e-12 <= dp[:, k].min() and dp[:, k].max() <= iv.hi + 1e-12
    for k, key in enumerate(("dtheta_x", "dtheta_y", "dtheta_z")):
        iv = getattr(report.certified, key)
        assert iv.lo - 1e-12 <= w[:, k].min() and w[:, k].max() <= iv.hi + 1e-12


@settings(max_examples=20, deadline=None)
@given(t1=st.floats(0.01, 1.0), t2=st.floats(0.01, 1.0), r1=st.floats(0.1, 10.0))
def test_bounds_grow_with_tolerance(t1: float, t2: float, r1: float) -> None:
    small, large = sorted((t1, t2))

    def report(tol: float):
        text = COUPLED.replace("x: 0.3 in\n      y: 0.3 in", f"x: {tol} in\n      y: {tol} in")
        text = text.replace("rz: 5 deg", f"rz: {r1} deg").split("      constraints:")[0]
        text += (
            "  - {name: hole, al_name: BH1, parent: box, pose: {translation: [3 cm, 3 cm, 4 cm]}}\n"
        )
        graph = AttributeGraph(parse_task(text))
        return estimate_errors(chain_between(graph, "world", "hole"))

    a, b = report(small), report(large)
    for key in ("dx", "dy", "dz"):
        assert getattr(a.first_order, key).hi <= getattr(b.first_order, key).hi + 1e-15
        assert getattr(a.certified, key).hi <= getattr(b.certified, key).hi + 1e-15


def test_taylor_product_remainder_is_rigorous() -> None:
    """rot(x̂,a)·rot(ŷ,b)·rot(ẑ,c): exact product minus linear part stays inside the bound."""
    m = np.array([0.3, 0.2, 0.25])
    tm = (
        TaylorModel.rotation(0, 0, m)
        @ TaylorModel.rotation(1, 1, m)
        @ TaylorModel.rotation(2, 2, m)
    )
    rng = np.random.default_rng(0)
    for v in rng.uniform(-m, m, size=(2000, 3)):
        exact = (
            pin.exp3(np.array([v[0], 0, 0]))
            @ pin.exp3(np.array([0, v[1], 0]))
            @ pin.exp3(np.array([0, 0, v[2]]))
        )
        linear = tm.value + np.tensordot(v, tm.linear, axes=1)
        assert np.all(np.abs(exact - linear) <= tm.remainder + 1e-15)
    assert tm.remainder.max() < 0.5 * m.sum() ** 2  # second order, not a vacuous bound


def test_huge_rotations_are_refused() -> None:
    from synth.exceptions import EstimationError, SpecError

    def task(rz: str, hole_rx: str = "0 deg") -> str:
        text = COUPLED.replace("rz: 5 deg", f"rz: {rz}").split("      constraints:")[0]
        return text + (
            "  - {name: hole, al_name: BH1, parent: box, pose: {translation: [3 cm, 3 cm, 4 cm]},"
            f" uncertainty: {{rx: {hole_rx}}}}}\n"
        )

    # one rotation by θ has tr(ΔR − I) = 2(cos θ − 1): at 90° the certificate's trace test
    # (tr > −2) fails whatever else the chain holds, so the spec is refused at the field
    with pytest.raises(SpecError, match="reaches 90°") as refused:
        parse_task(task("90 deg"))
    assert refused.value.path.endswith("uncertainty.rz")
    # alone, 89.5° is still certified (the cap is where the trace test fails, not a margin
    # below it), by a bound that covers the true 89.5°
    chain = chain_between(AttributeGraph(parse_task(task("89.5 deg"))), "world", "hole")
    assert estimate_errors(chain).certified.dtheta_z.hi >= math.radians(89.5)
    # two rotations of 70° and 50° add 2(1 − cos 70°) + 2(1 − cos 50°) = 2.03 > 2 to the trace
    # bound: refused, naming both tolerances, the larger first
    graph = AttributeGraph(parse_task(task("70 deg", "50 deg")))
    with pytest.raises(EstimationError, match=r"too large .*rz ±70°, .*rx ±50°"):
        estimate_errors(chain_between(graph, "world", "hole"))
    assert math.isfinite(rotation_remainder(2, math.pi).max())


def test_the_remainder_covers_float64_rounding_of_the_stored_model() -> None:
    # Exact rational arithmetic (fractions) on the stored float inputs: the product's true value
    # X(v) = (A₀ + Σ v_i A_i)(B₀ + Σ v_i B_i) minus its stored first-order model must lie within
    # the stored remainder, rounding included. With constant factors the first-order part is
    # exact algebra, so all of the gap is rounding: an unpadded remainder (0) fails here.
    from fractions import Fraction

    rng = np.random.default_rng(11)
    magnitude = np.array([0.01, 0.02])

    def model(scale: float) -> TaylorModel:
        value = rng.uniform(-scale, scale, (3, 3)) / 3.0
        linear = rng.uniform(-1.0, 1.0, (2, 3, 3)) / 7.0
        return TaylorModel(value, linear, np.zeros((3, 3)), magnitude)

    def exact(m: np.ndarray) -> list[list[Fraction]]:
        return [[Fraction(float(x)) for x in row] for row in m]

    def matmul(a: list[list[Fraction]], b: list[list[Fraction]]) -> list[list[Fraction]]:
        return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]

    for scale in (1.0, 1e3):  # 1e3: a metre-scale lever arm in millimetre-scale errors
        a = TaylorModel(model(scale).value, np.zeros((2, 3, 3)), np.zeros((3, 3)), magnitude)
        b = TaylorModel(model(scale).value, np.zeros((2, 3, 3)), np.zeros((3, 3)), magnitude)
        c = a @ b
        truth = matmul(exact(a.value), exact(b.value))
        gap = np.array(
            [
                [abs(float(truth[i][j] - Fraction(float(c.value[i, j])))) for j in range(3)]
                for i in range(3)
            ]
        )
        assert np.all(gap <= c.remainder) and gap.max() > 0  # rounding happened, and is covered
        # with linear parts: sampled corners of the box, exactly
        a, b = model(scale), model(scale)
        c = a @ b
        for v in ([0.01, 0.02], [-0.01, 0.02], [0.01, -0.02], [0.0, 0.0]):
            fv = [Fraction(x) for x in v]
            xa = [
                [
                    exact(a.value)[i][j] + sum(fv[n] * exact(a.linear[n])[i][j] for n in range(2))
                    for j in range(3)
                ]
                for i in range(3)
            ]
            xb = [
                [
                    exact(b.value)[i][j] + sum(fv[n] * exact(b.linear[n])[i][j] for n in range(2))
                    for j in range(3)
                ]
                for i in range(3)
            ]
            truth = matmul(xa, xb)
            stored = [
                [
                    exact(c.value)[i][j] + sum(fv[n] * exact(c.linear[n])[i][j] for n in range(2))
                    for j in range(3)
                ]
                for i in range(3)
            ]
            gap = np.array(
                [[abs(float(truth[i][j] - stored[i][j])) for j in range(3)] for i in range(3)]
            )
            assert np.all(gap <= c.remainder)
