"""Seed A.1 reproduced: a box located in a fixture by its contacts alone (L2938–3156).

Oracles, all independent of ``synth.errors.contacts`` and ``synth.errors.locate``:

* the seed's listings and estimates (line numbers below; its OCR slips are noted where used);
* closed forms for a box of half-sizes a = 4.45, b = 3.80 cm between walls x = ±4, y = ±5 cm
  (dimensions inferred in fixtures/tasks/box_in_fixture.yaml): turned by 90° + δ, its x extent
  is b cos δ + a |sin δ|, so the rotation limit δ* solves b cos δ + a sin δ = 4 cm, i.e.
  δ* = asin(4/√(a² + b²)) − atan(b/a) = 2.6274°;
* the exact nonlinear geometry written out below (box corners rotated by W about −ẑ, the seed's
  R = ROTN(−ZHAT, W), L3024), sampled, and its extremes solved with SLSQP from several starts.

Comparison with the seed (cm, deg); "ours" with default options, "seed method" with one arc
relaxation per estimate (``SEED_OPTIONS``), "exact" from the closed forms / SLSQP:

=====================  ================  ===========  ===========  =======================
quantity               seed (line)       seed method  ours         exact
=====================  ================  ===========  ===========  =======================
1st  X                 ±.284 (L3035)     ±.2040       ±.2000       ±(4 − b) = ±.2000
1st  Y                 ±.555 (L3036)     ±.5547       ±.5500       ±(5 − a) = ±.5500
1st  Z                 ±.881 (L3037)     0            0            0
1st  W (ITEM416)       87.368–92.632     87.373–92.627  (same)     90 ± δ* = 87.373–92.627
2nd  X                 −.000–.288 (3097) 0–.2000      0–.2000      0 – (4 − b) = 0–.2000
2nd  Y                 ±.558 (L3098)     ±.5500       ±.5500       ±(5 − a) = ±.5500
2nd  W (ITEM426)       −92.632–−90.000   −92.627–−90  (same)       −90 − δ* … −90
final X                .000–.000 (3151)  0            0            0
final Y                .379–.381 (3152)  .3805        .3805        5 − a cos δ* − b sin δ*
final W (ITEM442)      −92.632–−92.603   −92.627      −92.627      −90 − δ* = −92.627
=====================  ================  ===========  ===========  =======================

Differences, one by one:

* X of the first problem: the seed prints .284, its own method gives 4 − b·cos DW = .204 (the
  relaxation's chord u ≥ cos DW lets the box reach X while pretending to be turned by DW); .284
  is .204 with the OCR's usual 0→8 slip (the same slip prints .768 for .760 at L3007, .881 for
  .001 at L3037, 1.88 for 1.00 at L3072). The exact extreme is .200 (box square to the walls);
  ours is .2000 because we bound over arcs ≤ 0.5° wide (error b(1 − cos .25°) < 4e-5 cm).
* Y of the first problem: .555 = 5 − a·cos DW, the same chord effect; exact .550.
* Z: the seed relaxes Z = 0 to ±.001 (L3061); ".881" at L3037 is "-.001 TO .001" misread. Ours
  keeps the equality exact.
* W of the first problem: the seed's 2.632° vs δ* = 2.627°: .005°, the seed's 3-digit box
  dimensions (5.85·(.760, .649) is 4.446 × 3.797, giving 2.68°; 4.45 × 3.80 gives 2.627°).
* Second problem X .288 and Y .558: the seed method gives exactly .200 and .550 here (the arc
  end W = −90° is itself feasible), so both are OCR slips of .200 and .550.
* Final problem: Y .379–.381 brackets the exact .3805; the seed's W interval is .029° wide where
  the exact answer is a point: it relaxes equalities to ±.001 cm (L3061), which alone leaves
  .013° (tested below), and the rest is where its iteration stopped.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from _paths import BOX_FIXTURE_TASK, DATA_TASKS, SEED_TASK, TASKS
from scipy.optimize import brentq, minimize

from synth.cli import main
from synth.errors.chain import chain_between
from synth.errors.contacts import ContactProblem, build_contact_problem
from synth.errors.estimate import estimate_errors
from synth.errors.locate import (
    SEED_OPTIONS,
    LocateOptions,
    LocationResult,
    locate,
    locate_objects,
    resolve_contacts,
)
from synth.exceptions import EstimationError
from synth.models.features import contact_groups
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task
from synth.units import CM

FIXTURE = str(BOX_FIXTURE_TASK)
A, B = 4.45 * CM, 3.80 * CM  # half-sizes of the box [m]
XW, YW = 4.0 * CM, 5.0 * CM  # walls at x = ±XW, y = ±YW [m]
DELTA = math.asin(XW / math.hypot(A, B)) - math.atan2(B, A)  # rotation limit [rad]
CORNERS = np.array([[-A, -B], [A, -B], [A, B], [-A, B]])  # box frame; (−a, −b) is be9's

# Exact extremes in closed form (module docstring), [m] and [rad].
EXACT = {
    1: {
        "x": (-(XW - B), XW - B),
        "y": (-(YW - A), YW - A),
        "w": (math.pi / 2 - DELTA, math.pi / 2 + DELTA),
    },
    2: {"x": (0.0, XW - B), "y": (-(YW - A), YW - A), "w": (-math.pi / 2 - DELTA, -math.pi / 2)},
    3: {
        "x": (0.0, 0.0),
        "y": (YW - A * math.cos(DELTA) - B * math.sin(DELTA),) * 2,
        "w": (-math.pi / 2 - DELTA,) * 2,
    },
}
BOX = {1: "box1", 2: "box2", 3: "box3"}


# ----- the exact geometry, written out independently ------------------------------------------


def world_corners(x: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray:
    """(N, 4, 2) corners of the box at P = (x, y), R = rot(−ẑ, w) = rot(ẑ, −w)."""
    c, s = np.cos(-w)[:, None], np.sin(-w)[:, None]
    cx = x[:, None] + c * CORNERS[:, 0] - s * CORNERS[:, 1]
    cy = y[:, None] + s * CORNERS[:, 0] + c * CORNERS[:, 1]
    return np.stack([cx, cy], axis=-1)


def inequalities(z: np.ndarray) -> np.ndarray:
    """Containment, ≤ 0 when every corner is inside the walls (z = (x, y, w), one pose)."""
    k = world_corners(np.array([z[0]]), np.array([z[1]]), np.array([z[2]]))[0]
    return np.concatenate([k[:, 0] - XW, -XW - k[:, 0], k[:, 1] - YW, -YW - k[:, 1]])


def equalities(problem: int, z: np.ndarray) -> np.ndarray:
    """Edge contacts: be9 on x = +4 (2nd, final); be10 on y = +5, be11 on x = −4 (final)."""
    k = world_corners(np.array([z[0]]), np.array([z[1]]), np.array([z[2]]))[0]
    eqs = []
    if problem >= 2:
        eqs.append(k[0, 0] - XW)
    if problem == 3:
        eqs += [k[1, 1] - YW, k[2, 0] + XW]
    return np.array(eqs)


def feasible(
    problem: int, x: np.ndarray, y: np.ndarray, w: np.ndarray, tol: float = 1e-12
) -> np.ndarray:
    k = world_corners(x, y, w)
    ok = np.all(np.abs(k[..., 0]) <= XW + tol, axis=1) & np.all(
        np.abs(k[..., 1]) <= YW + tol, axis=1
    )
    if problem >= 2:
        ok &= np.abs(k[:, 0, 0] - XW) <= tol
    if problem == 3:
        ok &= (np.abs(k[:, 1, 1] - YW) <= tol) & (np.abs(k[:, 2, 0] + XW) <= tol)
    return ok


def exact_poses(problem: int, rng: np.random.Generator, n: int) -> np.ndarray:
    """Feasible poses (x, y, w) of the exact geometry, including boundary-hugging ones."""
    if problem == 1:
        w = rng.choice([-1.0, 1.0], n) * math.pi / 2 + rng.uniform(-DELTA, DELTA, n)
        k = world_corners(np.zeros(n), np.zeros(n), w)
        x_hi = XW - k[..., 0].max(axis=1)
        y_hi = YW - k[..., 1].max(axis=1)
        # Interior points, and points on the boundary of the feasible (x, y) rectangle.
        x = rng.uniform(-1, 1, n) * x_hi
        y = rng.uniform(-1, 1, n) * y_hi
        edge = rng.random(n) < 0.5
        x[edge] = np.sign(x[edge]) * x_hi[edge]
        y[~edge] = np.sign(y[~edge]) * y_hi[~edge]
    elif problem == 2:
        w = -math.pi / 2 - rng.uniform(0, 1, n) ** 0.5 * DELTA
        w[:3] = [-math.pi / 2, -math.pi / 2 - DELTA, -math.pi / 2 - DELTA / 2]
        k = world_corners(np.zeros(n), np.zeros(n), w)
        x = XW - k[:, 0, 0]
        y_hi = YW - k[..., 1].max(axis=1)
        y = rng.uniform(-1, 1, n) * y_hi
        top = rng.random(n) < 0.3
        y[top] = y_hi[top]
    else:
        f = lambda d: B * math.cos(d) + A * math.sin(d) - XW  # noqa: E731
        d = brentq(f, 0.0, 0.1, xtol=1e-15)
        w = np.array([-math.pi / 2 - d])
        k = world_corners(np.zeros(1), np.zeros(1), w)
        x = XW - k[:, 0, 0]
        y = YW - k[:, 1, 1]
    ok = feasible(problem, x, y, w, tol=1e-12)
    assert ok.mean() > 0.99  # the sampler itself is right
    return np.column_stack([x, y, w])[ok]


def slsqp_extremes(problem: int, starts: np.ndarray) -> dict[str, tuple[float, float]]:
    """min/max of x, y, w over the exact geometry, best of several SLSQP starts."""
    out = {}
    cons = [{"type": "ineq", "fun": lambda z: -inequalities(z)}]
    if problem >= 2:
        cons.append({"type": "eq", "fun": lambda z: equalities(problem, z)})
    for i, name in enumerate("xyw"):
        ends = []
        for sense in (1.0, -1.0):
            best = None
            for z0 in starts:
                res = minimize(
                    lambda z, s=sense, i=i: s * z[i],
                    z0,
                    method="SLSQP",
                    constraints=cons,
                    options={"ftol": 1e-15, "maxiter": 500},
                )
                z = res.x
                ok = np.max(inequalities(z)) <= 1e-10 and (
                    problem == 1 or np.max(np.abs(equalities(problem, z))) <= 1e-10
                )
                if ok and (best is None or sense * z[i] < sense * best):
                    best = float(z[i])
            assert best is not None
            ends.append(best)
        out[name] = (ends[0], ends[1])
    return out


# ----- fixtures ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def spec():  # type: ignore[no-untyped-def]
    return load_task(FIXTURE)


@pytest.fixture(scope="module")
def results(spec) -> dict[int, LocationResult]:  # type: ignore[no-untyped-def]
    return {k: r for k, r in zip((1, 2, 3), locate_objects(spec), strict=True)}


@pytest.fixture(scope="module")
def seed_results(spec) -> dict[int, LocationResult]:  # type: ignore[no-untyped-def]
    return {
        k: r for k, r in zip((1, 2, 3), locate_objects(spec, options=SEED_OPTIONS), strict=True)
    }


@pytest.fixture(scope="module")
def problems(spec) -> dict[int, ContactProblem]:  # type: ignore[no-untyped-def]
    graph = AttributeGraph(spec)
    groups = contact_groups(graph, spec.contacts)
    return {
        k: build_contact_problem(
            graph, BOX[k], [spec.contacts[i] for i in groups[BOX[k]]], groups[BOX[k]]
        )
        for k in (1, 2, 3)
    }


# ----- constraint generation against the seed's listings ----------------------------------------


def test_box_dimensions_match_the_printed_corner() -> None:
    # L3123: 5.85·VECTOR(−.760, −.649, 0) cm — three printed digits.
    r = math.hypot(A, B)
    assert r / CM == pytest.approx(5.85, abs=0.005)
    assert (A / r, B / r) == pytest.approx((0.760, 0.649), abs=0.0006)


def test_first_listing_rows(problems: dict[int, ContactProblem]) -> None:
    rows = problems[1].constraints
    # L3007–3023: 16 containment rows h·R·c ≤ wall − h·PV and the floor equality.
    inside = [r for r in rows if r.role == "inside"]
    assert len(inside) == 16 and len(rows) == 17
    for r in inside:
        assert r.position == pytest.approx(r.direction)
        axis = int(np.argmax(np.abs(r.direction)))
        assert r.rhs / CM == pytest.approx([4.000, 5.000][axis])  # x̂ rows 4.000, ŷ rows 5.000
        assert np.linalg.norm(r.vector) / CM == pytest.approx(5.85, abs=0.005)
        # L3007 prints .768 — an OCR slip for .760 (L3123, and Y = .555 needs a = 4.45 cm).
        assert np.abs(r.vector[:2]) / np.linalg.norm(r.vector) == pytest.approx(
            (0.760, 0.649), abs=0.0006
        )
    corners = {tuple(np.sign(r.vector[:2])) for r in inside}
    assert len(corners) == 4
    (rest,) = [r for r in rows if r.role == "rest"]
    assert rest.equality and rest.direction == pytest.approx([0, 0, 1]) and rest.rhs == 0


def test_edge_contact_rows(problems: dict[int, ContactProblem]) -> None:
    # L3072: −XHAT·R·1.88·VECTOR(−.707, −.707, 0) ≤ −.787, OCR for 1.00·(…) ≤ −.707: the fixture
    # side's normal (−x̂) must lie within 45° of the edge's outward bisector.
    (cone,) = [r for r in problems[2].constraints if r.role == "cone"]
    assert cone.direction == pytest.approx([-1, 0, 0])
    assert cone.vector == pytest.approx([-math.sqrt(0.5), -math.sqrt(0.5), 0])
    assert cone.rhs == pytest.approx(-math.sqrt(0.5))
    # L3139–3141: the final problem's equalities. L3140 prints (.760, −.649) against x = −4,
    # a sign slip: that corner is at x ≈ +3.6 cm; be11 is the (+a, +b) corner.
    touch = {
        (tuple(np.sign(r.direction)), tuple(np.sign(r.vector[:2])))
        for r in problems[3].constraints
        if r.role == "touch"
    }
    assert touch == {
        ((-1.0, 0.0, 0.0), (-1.0, -1.0)),  # −x̂·R·(−.760, −.649) = −4 − −x̂·P
        ((0.0, -1.0, 0.0), (1.0, -1.0)),  # −ŷ·R·(.760, −.649) = −5 − −ŷ·P
        ((1.0, 0.0, 0.0), (1.0, 1.0)),
    }  # x̂·R·(.760, .649) = −4 − x̂·P


def test_rows_agree_with_the_exact_geometry(problems: dict[int, ContactProblem]) -> None:
    """Rodrigues' trig form (Eqn 2) against the corners rotated here, at random poses."""
    rng = np.random.default_rng(3)
    form = problems[3].trig_form()
    for _ in range(20):
        z = np.array([rng.uniform(-0.01, 0.01), rng.uniform(-0.01, 0.01), rng.uniform(-4, 4)])
        res = form.residual(np.array([z[0], z[1], 0.0]), z[2])
        k = world_corners(z[:1], z[1:2], z[2:])[0]
        rows = problems[3].constraints
        for r, value in zip(rows, res, strict=True):
            if r.role in ("inside", "touch"):
                # g·P + h·R·c − rhs is the signed distance of a corner past a wall.
                corner = int(np.argmin(np.linalg.norm(CORNERS - r.vector[:2], axis=1)))
                axis = int(np.argmax(np.abs(r.direction)))
                wall = r.rhs
                expect = np.sign(r.direction[axis]) * k[corner, axis] - wall
                assert value == pytest.approx(expect, abs=1e-15)


# ----- the estimates ------------------------------------------------------------------------------


def test_first_problem_has_two_orientations_as_printed(results: dict[int, LocationResult]) -> None:
    ests = results[1].estimates
    assert len(ests) == 2  # ITEM416 and ITEM417, L3034 and L3052
    w = sorted((math.degrees(e.w.lo), math.degrees(e.w.hi)) for e in ests)
    # L3038: W 87.368°–92.632°; L3057: −92.632° to −87.368°.
    assert w[1] == pytest.approx((87.368, 92.632), abs=0.1)
    assert w[0] == pytest.approx((-92.632, -87.368), abs=0.1)
    # And the closed form to solver precision (δ* = 2.6274°).
    assert w[1] == pytest.approx((90 - math.degrees(DELTA), 90 + math.degrees(DELTA)), abs=1e-6)
    # L3039–3040: COS(W0) = .000, SIN(W0) = ±1.000, COS(DW) = .999, R = .046.
    for e in ests:
        assert abs(math.cos(e.w0)) < 5e-4 and abs(math.sin(e.w0)) == pytest.approx(1.0)
        assert round(math.cos(e.dw), 3) == 0.999 and round(math.sin(e.dw), 3) == 0.046


@pytest.mark.parametrize("problem", [1, 2, 3])
def test_estimates_are_sound_on_sampled_exact_poses(
    results: dict[int, LocationResult], problem: int
) -> None:
    poses = exact_poses(problem, np.random.default_rng(problem), 20_000)
    ests = results[problem].estimates
    inside = np.zeros(len(poses), dtype=bool)
    for e in ests:
        w = np.angle(np.exp(1j * (poses[:, 2] - e.w0))) + e.w0  # same turn as the estimate
        inside |= (
            (poses[:, 0] >= e.x.lo)
            & (poses[:, 0] <= e.x.hi)
            & (poses[:, 1] >= e.y.lo)
            & (poses[:, 1] <= e.y.hi)
            & (w >= e.w.lo)
            & (w <= e.w.hi)
            & (e.z.lo <= 0)
            & (e.z.hi >= 0)
        )
    assert inside.all(), poses[~inside][:5]


@pytest.mark.parametrize("problem", [1, 2, 3])
def test_estimates_contain_and_hug_the_exact_extremes(
    results: dict[int, LocationResult], problem: int
) -> None:
    """Sound: contain the SLSQP extremes. Tight: within 5% of the exact range (1e-7 m if 0)."""
    rng = np.random.default_rng(10 + problem)
    ests = results[problem].estimates
    e = max(ests, key=lambda e: e.w0)  # the branch near +90° in the first problem
    starts = exact_poses(problem, rng, 400)
    starts = starts[np.abs(starts[:, 2] - e.w0) < 0.1][:6]
    found = slsqp_extremes(problem, starts)
    for name, iv in (("x", e.x), ("y", e.y), ("w", e.w)):
        lo, hi = found[name]
        closed = EXACT[problem][name]
        # SLSQP agrees with the closed form …
        assert (lo, hi) == pytest.approx(closed, abs=1e-9)
        # … the estimate contains it …
        assert iv.lo <= lo + 1e-12 and iv.hi >= hi - 1e-12
        # … and is tight.
        margin = max(0.05 * (hi - lo), 1e-7)
        assert lo - iv.lo <= margin and iv.hi - hi <= margin
    assert e.z.lo <= 0 <= e.z.hi and e.z.hi - e.z.lo < 1e-8


def test_seed_method_reproduces_the_printed_figures(
    seed_results: dict[int, LocationResult],
) -> None:
    """One relaxation per estimate, as the seed: its numbers, OCR slips corrected."""
    cos_d = math.cos(DELTA)
    first = seed_results[1].estimates[0]
    # L3035 prints X ±.284: OCR for ±.204 = 4 − b·cos DW (0 → 8, as .768/.760 at L3007).
    assert first.x.hi == pytest.approx(XW - B * cos_d, abs=1e-8)
    assert round(first.x.hi / CM, 3) == 0.204
    # L3036: Y ±.555 = 5 − a·cos DW, printed correctly.
    assert round(first.y.hi / CM, 3) == 0.555
    assert first.y.hi == pytest.approx(YW - A * cos_d, abs=1e-8)
    second = seed_results[2].estimates[0]
    # L3097: X −.000 to .288 — OCR for .200: the arc end W = −90° is feasible, so even one
    # relaxation gives the exact 4 − b. L3098: Y ±.558 — OCR for ±.550.
    assert round(second.x.lo / CM, 3) == 0.0 and round(second.x.hi / CM, 3) == 0.200
    assert round(second.y.hi / CM, 3) == 0.550
    # L3100: W −92.632° to −90.000°.
    assert (math.degrees(second.w.lo), math.degrees(second.w.hi)) == pytest.approx(
        (-92.632, -90.0), abs=0.01
    )
    final = seed_results[3].estimates[0]
    # L3151–3152: X .000 to .000, Y .379 to .381.
    assert abs(final.x.lo) < 1e-7 and abs(final.x.hi) < 1e-7
    assert final.y.lo / CM >= 0.379 and final.y.hi / CM <= 0.381


def test_equality_tolerance_leaves_the_seeds_sliver(problems: dict[int, ContactProblem]) -> None:
    """With Z and the contacts relaxed to ±.001 cm (L3061) the final W is an interval again.

    Containment caps X + f(δ) ≤ 4 while the contact allows ≥ 4 − t, with f = b cos δ + a sin δ
    for both x-contacts, so 2f ∈ [8 − 2t, 8] and δ ∈ [δ* − t/f′(δ*), δ*]: W runs from
    −90° − δ* up by .0134°. The seed's interval also runs up from its −92.632°, by .029°
    (L3154); the rest is where its iteration stopped (the stopping rule is not in the text).
    """
    t = 0.001 * CM
    res = locate(problems[3], LocateOptions(equality_tolerance=t))
    (e,) = res.estimates
    f_prime = A * math.cos(DELTA) - B * math.sin(DELTA)
    assert math.degrees(e.w.hi - e.w.lo) == pytest.approx(math.degrees(t / f_prime), rel=0.02)
    assert math.degrees(e.w.lo) == pytest.approx(-90 - math.degrees(DELTA), abs=1e-6)


def test_unbounded_contacts_give_infinite_bounds(spec) -> None:  # type: ignore[no-untyped-def]
    """A box on a floor with no walls (extent_irrelevant): X, Y unbounded, any rotation."""
    from synth.models.contacts import ContactSpec

    free = (ContactSpec(a="box1.bottom", b="fixture1.floor", kind="extent_irrelevant"),)
    (res,) = locate_objects(spec, contacts=free)
    (e,) = res.estimates
    assert math.isinf(e.x.hi) and math.isinf(e.y.lo)
    assert e.w.hi - e.w.lo >= 2 * math.pi - 1e-6
    assert res.link is None


# ----- the derived uncertainty block feeds the error machinery ----------------------------------


def test_derived_block_contains_every_exact_pose(spec) -> None:  # type: ignore[no-untyped-def]
    graph = AttributeGraph(spec)
    chain = chain_between(graph, "fixture2", "box2")
    assert chain.space.labels == ("box2.x", "box2.y", "box2.rz")
    nominal = chain.nominal
    poses = exact_poses(2, np.random.default_rng(5), 5000)
    # Pose of the box in the fixture: trans(rot(ẑ, −w), (x, y, 0)); error e = N_Rᵀ(P − N_p),
    # rz = angle of N_Rᵀ R about ẑ (the box's z is the fixture's).
    p = np.column_stack([poses[:, :2], np.zeros(len(poses))])
    e = (p - nominal.translation) @ nominal.rotation
    w_nom = math.atan2(nominal.rotation[1, 0], nominal.rotation[0, 0])
    rz = np.angle(np.exp(1j * (-poses[:, 2] - w_nom)))
    v = np.column_stack([e[:, 0], e[:, 1], rz])
    assert chain.space.feasible(v, tol=1e-12).all()
    # The chain maps these parameters back onto the same poses.
    rot, pos = chain.evaluate(v)
    assert pos[:, :2] == pytest.approx(poses[:, :2], abs=1e-12)
    assert np.arctan2(rot[:, 1, 0], rot[:, 0, 0]) == pytest.approx(-poses[:, 2], abs=1e-12)
    assert np.abs(e[:, 2]).max() < 1e-15 and abs(nominal.translation[2]) < 1e-15


def test_errors_of_a_located_hole_are_certified_and_tight(spec) -> None:  # type: ignore[no-untyped-def]
    graph = AttributeGraph(spec)
    report = estimate_errors(chain_between(graph, "fixture2", "box2_bh1"), "fixture2", "box2_bh1")
    hole_in_box = np.array([3.85 * CM, 3.20 * CM, 4.90 * CM])
    poses = exact_poses(2, np.random.default_rng(9), 20_000)
    c, s = np.cos(-poses[:, 2]), np.sin(-poses[:, 2])
    hx = poses[:, 0] + c * hole_in_box[0] - s * hole_in_box[1]
    hy = poses[:, 1] + s * hole_in_box[0] + c * hole_in_box[1]
    chain = chain_between(graph, "fixture2", "box2_bh1")
    dx, dy = hx - chain.nominal.translation[0], hy - chain.nominal.translation[1]
    cert = report.certified
    assert (dx >= cert.dx.lo).all() and (dx <= cert.dx.hi).all()
    assert (dy >= cert.dy.lo).all() and (dy <= cert.dy.hi).all()
    # Tight: the certified ranges exceed the sampled exact ones by < 5%.
    assert (cert.dx.hi - cert.dx.lo) <= 1.05 * (dx.max() - dx.min())
    assert (cert.dy.hi - cert.dy.lo) <= 1.05 * (dy.max() - dy.min())
    # Rotation: the W interval's half-width, δ*/2.
    assert cert.dtheta_z.hi == pytest.approx(DELTA / 2, rel=1e-3)


def test_resolved_spec_is_a_hand_typed_equivalent(spec) -> None:  # type: ignore[no-untyped-def]
    resolved = resolve_contacts(spec, objects=["box2", "box3"])
    frames = {f.name: f for f in resolved.frames}
    assert frames["box2"].uncertainty is not None and frames["box2"].uncertainty.rz is not None
    # The final problem pins the box: no error parameters at all (the seed's R = .000, L3156).
    assert frames["box3"].uncertainty is not None and not frames["box3"].uncertainty.bounds()
    graph = AttributeGraph(resolved)
    t = graph.relative("fixture3", "box3")
    assert t.translation[:2] == pytest.approx([0.0, EXACT[3]["y"][0]], abs=1e-9)
    assert math.atan2(t.rotation[1, 0], t.rotation[0, 0]) == pytest.approx(
        math.pi / 2 + DELTA, abs=1e-9
    )  # rot(ẑ, −W) with W = −90° − δ*
    # Box 1 is still located by contacts[0] only.
    assert [c.a for c in resolved.contacts] == ["box1.bottom"]


def test_ambiguous_orientation_is_an_error_for_chains(spec) -> None:  # type: ignore[no-untyped-def]
    graph = AttributeGraph(spec)
    with pytest.raises(EstimationError, match="2 possible orientations"):
        chain_between(graph, "fixture1", "box1")
    # Chains that do not pass box1 are unaffected.
    assert chain_between(graph, "world", "fixture1").space.dim == 0


# ----- command line -------------------------------------------------------------------------------


def test_cli_locate_prints_the_estimates(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["locate", FIXTURE, "--constraints"]) == 0
    out = capsys.readouterr().out
    assert "2 estimates (separate gross orientations)" in out
    assert "W   -92.627 ..   -90.000 deg" in out
    assert "x̂·R·5.85·(-0.760, -0.649, 0.000) ≤ 4.000 − x̂·P" in out


def test_cli_locate_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["locate", FIXTURE, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    objs = {o["object"]: o for o in data["objects"]}
    assert len(objs["box1"]["estimates"]) == 2 and "link" not in objs["box1"]
    (e,) = objs["box2"]["estimates"]
    assert e["x"] == pytest.approx([0.0, XW - B], abs=1e-6)
    assert set(objs["box2"]["link"]["uncertainty"]["bounds"]) == {"x", "y", "rz"}


def test_cli_errors_on_a_located_box(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["errors", FIXTURE, "--from", "FIX2", "--to", "B2H1"]) == 0
    assert main(["errors", FIXTURE, "--from", "FIX1", "--to", "BOX1"]) == 2
    err = capsys.readouterr().err
    assert "contacts[0]" in err and "2 possible orientations" in err


@pytest.mark.parametrize(
    "command",
    [["locate"], ["locate", "--json"], ["errors", "--from", "TB", "--to", "TRAY"]],
    ids=["locate", "locate-json", "errors"],
)
def test_a_part_free_to_turn_is_refused_at_its_contact(
    command: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    # A tray inside_of a block's top and touching nothing else turns freely about the top's
    # normal: W spans the circle, and no error block certifies a turn of 90° or more. The
    # block's validator raised from inside derive_link: an internal error, exit 70.
    task = str(DATA_TASKS / "located_free_to_turn.yaml")
    assert main([command[0], task, *command[1:]]) == 2
    err = capsys.readouterr().err
    assert "internal error" not in err
    assert "contacts[0]: these contacts leave 'tray' free to turn about the normal of " in err
    assert "add a contact that fixes its orientation" in err


def test_cli_locate_bad_input_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = Path(FIXTURE).read_text().replace("box2.xneg_yneg", "box2.edge9")
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    assert main(["locate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "contacts[2].a (line" in err and "no feature 'edge9'" in err


def test_cli_locate_contacts_that_admit_no_pose_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # box1 made 20 cm long, in a fixture 8 × 10 cm inside: the pose LP is
    # infeasible, the report says so, and the exit code was 0
    text = Path(FIXTURE).read_text()
    data = yaml.safe_load(text)
    box1 = next(f for f in data["frames"] if f["name"] == "box1")
    box1["shape"]["size"][0] = "20 cm"
    bad = tmp_path / "wide.yaml"
    bad.write_text(yaml.safe_dump(data, sort_keys=False))
    assert main(["locate", str(bad)]) == 2
    out, err = capsys.readouterr()
    assert "no pose satisfies these contacts" in out
    assert "no pose satisfies the contacts of box1" in err


def test_plan_uses_the_located_box(capsys: pytest.CaptureFixture[str]) -> None:
    """A task whose box is located only by contacts plans like its hand-typed equivalent."""
    from synth.strategies import plan_task

    spec = load_task(TASKS / "seed_4_8_fixture.yaml")
    located, by_hand = (plan_task(s).to_json() for s in (spec, resolve_contacts(spec)))
    for d in (located, by_hand):
        d.pop("planning_time")
        d.pop("counters")
    assert located == by_hand
    # The fixture holds the box to X ±.1, Y ±.55 cm, W ±1.3° about its nominal — tighter than
    # seed_4_8's ±0.3 in, ±0.2 in, ±5° (L2566) — so the search footprint is smaller.
    free = plan_task(load_task(SEED_TASK)).to_json()
    fixed_search, free_search = located["strategy"]["search"], free["strategy"]["search"]
    assert fixed_search["dx"] < free_search["dx"] and fixed_search["dy"] < free_search["dy"]
    # a short proof: the CLI path and its text are what is checked here (the proof: test_proof)
    argv = ["plan", str(TASKS / "seed_4_8_fixture.yaml"), "--proof-trials", "10", "--workers", "1"]
    assert main(argv) == 0
    assert "search" in capsys.readouterr().out
