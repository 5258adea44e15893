"""The seed's error calculations reproduced, and the certified bounds proved by Monte Carlo.

Sources: appendix A.2 (L3160–3290), §4.5.1 (L2230–2290), §4.5.3 (L2380–2440).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from _paths import DATA, SEED_TASK, TASKS

from synth.errors.bounds import build_error_lp, closed_form_bound, solve_error_lp
from synth.errors.chain import ErrorChain, Fixed, chain_between
from synth.errors.estimate import RelationModel, estimate_errors
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task
from synth.units import CM


@pytest.fixture(scope="module")
def screw() -> tuple[AttributeGraph, ErrorChain]:
    graph = AttributeGraph(load_task(TASKS / "screw_on_driver.yaml"))
    return graph, chain_between(graph, "hole", "tip")


@pytest.fixture(scope="module")
def approach() -> tuple[AttributeGraph, ErrorChain]:
    graph = AttributeGraph(load_task(DATA / "seed_4_5.yaml"))
    return graph, chain_between(graph, "hole", "pin")


def test_a2_first_order_matches_the_seed(screw: tuple[AttributeGraph, ErrorChain]) -> None:
    graph, chain = screw
    report = estimate_errors(chain, "hole", "tip")
    fo = report.first_order
    # Seed L3279–3283: −1.57 ≤ Δx ≤ 1.57, −1.37 ≤ Δy ≤ 1.37, −.127 ≤ Δz ≤ .127 cm.
    # Δy: the seed's objective row (L3266) uses the hole's lever arm 3.85 cm for the box rotation
    # γ; the exact Jacobian at the nominal tip (box⁻¹∘tip = (3.90, 3.20, 1.72) cm) gives 3.90, so
    # we reproduce 0.3903·… = 1.378 cm, 0.55% above the printed 1.37 — within the 1% asked.
    # (L3265 prints Δx's γ coefficient as "3.28": an OCR slip for 3.20, which the sum 1.57 needs.)
    assert fo.dx.hi == pytest.approx(1.57 * CM, rel=0.01)
    assert fo.dx.lo == pytest.approx(-1.57 * CM, rel=0.01)
    assert fo.dy.hi == pytest.approx(1.37 * CM, rel=0.01)
    assert fo.dz.hi == pytest.approx(0.127 * CM, rel=0.01)
    # Seed L3289–3290: −.0916 ≤ Δθx, Δθy ≤ .0916 rad (5° wobble + 0.25° hand).
    assert fo.dtheta_x.hi == pytest.approx(0.0916, rel=0.01)
    assert fo.dtheta_y.hi == pytest.approx(0.0916, rel=0.01)
    # The lever arm itself: coefficient of the box rotation in Δy is −(tip x in box) = −3.90 cm.
    rel = RelationModel.of(chain)
    gamma = chain.space.labels.index("box.rz")
    tip_in_box = graph.relative("box", "tip").translation
    assert rel.displacement.linear[gamma, 1] == pytest.approx(-tip_in_box[0], abs=1e-12)
    assert tip_in_box[0] == pytest.approx(3.90 * CM, abs=1e-9)


def test_first_order_model_is_the_jacobian(screw: tuple[AttributeGraph, ErrorChain]) -> None:
    """Taylor-model linear terms against central finite differences of the exact chain."""
    _, chain = screw
    rel = RelationModel.of(chain)
    n = chain.space.dim
    h = 1e-6
    eye = np.eye(n) * h
    r_plus, p_plus = chain.evaluate(eye)
    r_minus, p_minus = chain.evaluate(-eye)
    r0 = chain.nominal.rotation
    dp = (p_plus - p_minus) / (2 * h)
    np.testing.assert_allclose(dp, rel.displacement.linear, atol=1e-7)
    dr = (r_plus - r_minus) / (2 * h) @ r0.T
    np.testing.assert_allclose(dr, rel.rotation_error.linear, atol=1e-7)


def test_exact_chain_matches_pinocchio_composition(
    screw: tuple[AttributeGraph, ErrorChain],
) -> None:
    """The vectorised exact chain against SE3 products built one link at a time with pinocchio."""
    graph, chain = screw
    rng = np.random.default_rng(7)
    v = chain.space.sample(rng, 20)
    rot, pos = chain.evaluate(v)
    labels = chain.space.labels
    axes = {"x": 0, "y": 1, "z": 2}

    def perturbed(frame: str, row: np.ndarray) -> pin.SE3:
        link = graph.links[frame]
        t = np.zeros(3)
        r = np.eye(3)
        for param in ("x", "y", "z", "rx", "ry", "rz"):
            key = f"{frame}.{param}"
            if key in labels:
                value = row[labels.index(key)]
                if param.startswith("r"):
                    r = r @ pin.exp3(np.eye(3)[axes[param[1]]] * value)
                else:
                    t[axes[param]] += value
        return link.parent_from_child * pin.SE3(r, t)

    for i, row in enumerate(v):
        world_hole = perturbed("box", row) * graph.links["hole"].parent_from_child
        world_tip = (
            perturbed("hand", row)
            * graph.links["driver"].parent_from_child
            * perturbed("screw", row)
            * graph.links["tip"].parent_from_child
        )
        rel = world_hole.inverse() * world_tip
        np.testing.assert_allclose(rot[i], rel.rotation, atol=1e-12)
        np.testing.assert_allclose(pos[i], rel.translation, atol=1e-12)


def test_lp_and_closed_form_agree(screw: tuple[AttributeGraph, ErrorChain]) -> None:
    _, chain = screw
    rel = RelationModel.of(chain)
    rng = np.random.default_rng(3)
    objectives = [*rel.displacement.linear.T, *rng.normal(size=(5, chain.space.dim))]
    for c in objectives:
        lp = solve_error_lp(build_error_lp(c, chain.space))
        closed = closed_form_bound(c, chain.space)
        assert lp.lo == pytest.approx(closed.lo, abs=1e-12)
        assert lp.hi == pytest.approx(closed.hi, abs=1e-12)


def test_certified_bounds_hold_where_first_order_fails(
    screw: tuple[AttributeGraph, ErrorChain],
) -> None:
    """≥ 100 000 samples plus all 2¹¹ box corners through the exact nonlinear chain (A.2)."""
    _, chain = screw
    report = estimate_errors(chain, "hole", "tip")
    rng = np.random.default_rng(2026)
    v = np.vstack([chain.space.sample(rng, 100_000), chain.space.corners()])
    assert len(chain.space.corners()) == 2**11
    rot, pos = chain.evaluate(v)
    dp = pos - chain.nominal.translation
    dtheta = np.array([pin.log3(r @ chain.nominal.rotation.T) for r in rot[-2048:]])
    a0 = chain.nominal.rotation[:, 2]  # the screw points down into the hole: a₀ = −ẑ
    tilt = np.arccos(np.clip(rot[:, :, 2] @ a0, -1, 1))
    cert, first = report.certified, report.first_order
    for k, key in enumerate(("dx", "dy", "dz")):
        iv = getattr(cert, key)
        assert dp[:, k].max() <= iv.hi and dp[:, k].min() >= iv.lo
    for k, key in enumerate(("dtheta_x", "dtheta_y", "dtheta_z")):
        iv = getattr(cert, key)
        assert dtheta[:, k].max() <= iv.hi and dtheta[:, k].min() >= iv.lo
    assert tilt.max() <= cert.tilt
    # The first-order bound is exceeded: rotations bend the 3.18 cm screw and 28.6 cm driver.
    # About 3.18·(1 − cos 5° cos 5°) ≈ .024 cm extra along z, so |Δz| ≈ .15 cm (seed A.2).
    assert np.abs(dp[:, 2]).max() > first.dz.hi * 1.15
    assert np.abs(dp[:, 2]).max() == pytest.approx(0.15 * CM, rel=0.05)
    assert np.abs(dp[:, 0]).max() > first.dx.hi
    # …and the certified bound is not vacuous: within 10% of the worst sampled error.
    assert cert.dz.hi <= 1.10 * np.abs(dp[:, 2]).max()


def test_theta_table_of_4_5_1(approach: tuple[AttributeGraph, ErrorChain]) -> None:
    _, chain = approach
    first, certified = RelationModel.of(chain).tilt_table()
    # Seed L2287: ζ = 0°, 30°, …, 150° → .354°, .306°, .306°, .354°, .306°, .306°.
    # Closed form: 0.25°·(|cos(ζ−225°)| + |sin(ζ−225°)|) from the hand's η_x, η_y alone.
    seed = np.array([0.354, 0.306, 0.306, 0.354, 0.306, 0.306])
    np.testing.assert_allclose(np.degrees(first), seed, atol=0.0006)
    assert np.all(certified >= first)


def test_footprint_table_of_4_5_3(approach: tuple[AttributeGraph, ErrorChain]) -> None:
    _, chain = approach
    first, _ = RelationModel.of(chain).footprint_table()
    # Seed L2425–2432: ξ = 1.05, 1.43, 1.50, 1.24, 1.16, 1.15 cm for ζ = 0°, 30°, …, 150°.
    # Frame convention: the seed measures ζ from the hole's ŷ axis, i.e. in the hole frame
    # turned by the strategy's pin-hole angle φ = 90° (L2245): its ζ is our ζ + 90°, so its
    # table is ours shifted by three entries. (Its ν coefficient "(−3.20, −3.85, 0)" at L2395
    # has lost a sign in the OCR; the chain gives (3.20, −3.85, 0) in the hole frame.)
    seed = np.array([1.05, 1.43, 1.50, 1.24, 1.16, 1.15]) * CM
    np.testing.assert_allclose(np.roll(first, -3), seed, rtol=0.03)
    # Δx = max ξ_k = 1.50 cm at ζ = 60° (seed frame), Δy = ξ_(k+3) = 1.15 cm (L2434).
    k = int(np.argmax(np.roll(first, -3)))
    assert k == 2
    assert np.roll(first, -3)[(k + 3) % 6] == pytest.approx(1.15 * CM, rel=0.03)


def test_certified_footprint_holds_by_monte_carlo(
    approach: tuple[AttributeGraph, ErrorChain],
) -> None:
    _, chain = approach
    _, certified = RelationModel.of(chain).footprint_table()
    rng = np.random.default_rng(11)
    v = np.vstack([chain.space.sample(rng, 50_000), chain.space.corners()])
    _, pos = chain.evaluate(v)
    dp = pos - chain.nominal.translation
    zeta = np.arange(6) * math.pi / 6
    directions = np.stack([np.cos(zeta), np.sin(zeta), np.zeros(6)], axis=1)
    worst = np.abs(dp @ directions.T).max(axis=0)
    assert np.all(worst <= certified)


def test_fixed_chain_has_no_error() -> None:
    chain = ErrorChain(
        space=chain_between(AttributeGraph(load_task(SEED_TASK)), "rack", "pin1").space,
        terms=(Fixed(pin.SE3.Identity()),),
    )
    report = estimate_errors(chain)
    assert report.certified.dx.hi == 0.0 and report.certified.tilt == 0.0
