"""Grasp generation and approach (seed §4.3–4.4) against the seed's figures and closed forms.

Seed: seeds/000_1457622cbb9a2614.txt. Lengths in the seed are cm, printed to three digits, so
seed comparisons allow half a unit in the last printed digit unless noted.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_TASK

from synth.errors.estimate import RelationModel
from synth.models.loader import load_task
from synth.models.manipulator import HandSpec
from synth.models.spec import PinShape
from synth.report import al_trans
from synth.strategies import PlanOptions
from synth.strategies.approach import plan_approach
from synth.strategies.context import plan_context
from synth.strategies.grasp import (
    finger_span,
    generate_pickups,
    geometry_problem,
    grasp_distance_limits,
    grasp_distances,
    palm_clearance,
    pin_from_approach,
)
from synth.strategies.hypotheses import Affixed, Holding
from synth.strategies.options import hand_openings
from synth.strategies.records import Grasp
from synth.strategies.relations import approach_relation
from synth.units import CM, DEG, INCH

OPTS = PlanOptions()


@pytest.fixture(scope="module")
def ctx():
    return plan_context(load_task(SEED_TASK))


@pytest.fixture(scope="module")
def pickups(ctx):
    return generate_pickups(ctx, try_harder=True)


def test_grasp_distance_is_the_seeds_3_54_cm(ctx) -> None:
    # L2032: d_min = max(d_i, d_f) + r_fp + κ = 1.71 + 0.635 + 0.254 = 2.599 cm;
    # L2042: d_max = l_pin − (l_taper + κ) = 5.08 − (0.34 + 0.254) = 4.486 cm;
    # 1.887 cm < 2.5 in, so the midpoint only (L2050): 3.5425 cm, printed 3.54 (L2595).
    pin_shape = ctx.pin_shape
    d_min, d_max = grasp_distance_limits(
        pin_shape.length,
        pin_shape.tip_taper_length,
        ctx.d_i,
        1.71 * CM,
        0.25 * INCH,
        0.1 * INCH,
        same_end=True,
    )
    assert d_min == pytest.approx(2.599 * CM, abs=1e-9)
    assert d_max == pytest.approx(4.486 * CM, abs=1e-9)
    (d,) = grasp_distances(d_min, d_max, OPTS)
    assert d == pytest.approx(3.54 * CM, abs=0.005 * CM)


def test_long_interval_gives_three_distances_and_turn_over_limits() -> None:
    # L2056–2060: d_max − 0.6 in, d_min + 0.6 in, midpoint, when the interval ≥ 2.5 in.
    d = grasp_distances(1 * INCH, 4 * INCH, OPTS)
    assert d == pytest.approx((3.4 * INCH, 1.6 * INCH, 2.5 * INCH))
    # L2076: l − (d_f + r_fp + κ) ≥ d ≥ d_i + r_fp + κ, turned over.
    lo, hi = grasp_distance_limits(
        5 * INCH, 0.1 * INCH, 1 * INCH, 1.5 * INCH, 0.25 * INCH, 0.1 * INCH, same_end=False
    )
    assert (lo, hi) == pytest.approx((1.35 * INCH, 3.15 * INCH))
    assert grasp_distances(3 * INCH, 2 * INCH, OPTS) == ()


def test_hand_openings_follow_l2139() -> None:
    # L2139: approach = diameter + 1 in, closure threshold = diameter − 0.1 in. The seed prints
    # 2.98 and .185 cm (L2606, L2610): its pin was 2.98 − 2.54 = 0.44 cm thick at the grasp
    # point (.44 − .254 = .186, printed .185: the diameter was 0.439–0.440 cm).
    approach, grasp = hand_openings(0.4395 * CM, OPTS)
    assert approach == pytest.approx(2.98 * CM, abs=0.005 * CM)
    assert grasp == pytest.approx(0.185 * CM, abs=0.001 * CM)
    # The fixture's pin is 0.635 cm (1/4 in) thick: 3.175 and 0.381 cm.
    assert hand_openings(0.635 * CM, OPTS) == pytest.approx((3.175 * CM, 0.381 * CM))
    # A 2 mm dowel: the seed's threshold would be 2 − 2.54 < 0 mm, which no closing ever
    # reads; a quarter of its diameter (0.5 mm) stays between "closed on the pin" (2 mm) and
    # "closed on nothing" (0). The two rules meet at 4/3 · 0.1 in, where d − 0.1 in = d/4.
    assert hand_openings(0.2 * CM, OPTS)[1] == pytest.approx(0.05 * CM)
    meet = 0.4 * INCH / 3
    assert hand_openings(meet, OPTS)[1] == pytest.approx(meet - 0.1 * INCH)
    assert hand_openings(meet, OPTS)[1] == pytest.approx(meet / 4)


def test_approach_points_match_the_phl_spec_printouts() -> None:
    # L2609: ω = 90°, γ = 135°: TRANS(ROTN(VECTOR(.679,.679,.281),149*DEG),VECTOR(-3.59,0,7.13)).
    xf = pin_from_approach(Grasp(90 * DEG, 135 * DEG, 3.54 * CM), 2 * INCH)
    assert al_trans(xf) == "TRANS(ROTN(VECTOR(0.679,0.679,0.281),149*DEG),VECTOR(-3.59,0,7.13))"
    # L2661: ω = 90°, γ = 100°: ROTN(VECTOR(.608,.608,.510),126.*DEG), VECTOR(-5.,0,4.42).
    xf = pin_from_approach(Grasp(90 * DEG, 100 * DEG, 3.54 * CM), 2 * INCH)
    assert al_trans(xf) == "TRANS(ROTN(VECTOR(0.608,0.608,0.51),126*DEG),VECTOR(-5,0,4.42))"
    # L2690: γ = 180°: VECTOR(0,0,8.62) = 3.54 + 5.08. The printout's axis (.924,.383,.001) is
    # rot(ẑ,45°)·rot(x̂,180°); the remark says ω = 315° (L2696, also L2244 and ROT(z,225°) =
    # ω − φ at L2248), whose axis is (.924,−.383,0): the printed rotation and the remark disagree
    # (a lost minus sign, repeated at L2692, L2723–2724?). We follow the remark.
    xf = pin_from_approach(Grasp(315 * DEG, 180 * DEG, 3.54 * CM), 2 * INCH)
    np.testing.assert_allclose(xf.translation, [0, 0, 8.62 * CM], atol=0.005 * CM)
    axis = pin.log3(xf.rotation) / math.pi
    np.testing.assert_allclose(np.abs(axis), [0.924, 0.383, 0.0], atol=0.001)
    assert axis[0] * axis[1] < 0


def test_finger_and_palm_checks_closed_forms() -> None:
    hand = HandSpec()
    shape = PinShape(
        type="pin",
        length="2 in",
        diameter="0.635 cm",
        tip_taper_length="0.34 cm",
        tip_radius="0.13 cm",
    )
    # γ = 135°: the pads reach r_fp·(sin γ + |cos γ|) = 0.635·√2 = 0.898 cm below d.
    lo, _ = finger_span(Grasp(0.0, 135 * DEG, 3.54 * CM), hand)
    assert lo == pytest.approx(3.54 * CM - 0.635 * CM * math.sqrt(2), abs=1e-12)
    # At d_min = 2.599 cm the seed's rule leaves a tilted grasp 0.0098 cm below the plane: the
    # L2032 limit is for γ = 180° and condition (a) catches the rest.
    problem = geometry_problem(
        Grasp(0.0, 135 * DEG, 2.599 * CM), shape, hand, 1.71 * CM, 1.71 * CM, "tip"
    )
    assert problem is not None and "below the start hole" in problem
    assert (
        geometry_problem(Grasp(0.0, 135 * DEG, 3.54 * CM), shape, hand, 1.71 * CM, 1.71 * CM, "tip")
        is None
    )
    # γ = 180°: palm face at z = −L_f = −5.08 cm, pin top at d − l = −1.54 cm: clearance
    # 5.08 − 1.54 − r_pin = 3.2225 cm (L2070's check l_pin − d < L_f, with the radius).
    assert palm_clearance(Grasp(0.0, math.pi, 3.54 * CM), shape, hand) == pytest.approx(
        3.2225 * CM, abs=1e-9
    )
    short = HandSpec(finger_length="1 cm")
    problem = geometry_problem(
        Grasp(0.0, math.pi, 3.54 * CM), shape, short, 1.71 * CM, 1.71 * CM, "tip"
    )
    assert problem is not None and "palm" in problem
    # Condition (b): an approach vector with a component along the outward normal.
    problem = geometry_problem(
        Grasp(0.0, 80 * DEG, 3.54 * CM), shape, hand, 1.71 * CM, 1.71 * CM, "tip"
    )
    assert problem is not None and "90°" in problem


def test_omega_pruning_keeps_the_best_three_by_theta5(ctx) -> None:
    pickups, rejected = generate_pickups(ctx)
    by_gamma: dict[int, list[Grasp]] = {}
    for p in pickups:
        by_gamma.setdefault(round(p.strategy.grasp.gamma / DEG), []).append(p.strategy.grasp)
    # Three ω kept per γ (L2122); a kept ω may still fall to the gross-motion sweep.
    for gamma, kept in by_gamma.items():
        swept = [r for r in rejected if " sweeps " in r.reason and f"γ={gamma}°" in r.candidate]
        assert len(kept) + len(swept) == 3
    for gamma in by_gamma:
        ratings = sorted(
            p.strategy.rating for p in pickups if round(p.strategy.grasp.gamma / DEG) == gamma
        )
        pruned = [
            r for r in rejected if r.reason.startswith("pruned") and f"γ={gamma}°" in r.candidate
        ]
        for r in pruned:  # every pruned ω rates no better than the kept ones
            rating = float(r.reason.split("= ")[1].split("°")[0]) * DEG
            assert rating >= ratings[-1] - 0.05 * DEG
    # γ = 180°: |θ5| does not depend on ω, so the ratings tie and the first three ω survive,
    # except ω = 0 with the arm at (20, 70) cm: there the wrist with θ5 = +76.4° needs
    # θ6 = −165.9°, past the −165° stop, so only the flipped wrist (θ5 = −76.4°, rated 121.4°)
    # is attainable and ω = 0 is pruned (at the old base, (20, 80) cm, θ6 = −161.9°: all tied).
    assert [round(g.omega / DEG) for g in by_gamma[180]] == [45, 90, 135]
    assert all("--try-harder" in r.reason for r in rejected if r.reason.startswith("pruned"))


def test_pickup_records_departure_and_worlds(ctx, pickups) -> None:
    found, rejected = pickups
    # --try-harder keeps every reachable ω (more than the 3 per γ of L2122) unless its move from
    # the park is obstructed (synth/strategies/clearance.py).
    swept = [r for r in rejected if " sweeps " in r.reason]
    assert len(found) + len(swept) > 9 and found
    for p in found:
        g = p.strategy
        # L2630: DEPARTURE POINT: PIN1=PIN1*TRANS(NILROTN,VECTOR(0,0,6.79)) = 2 in + d_i.
        np.testing.assert_allclose(g.departure_point.xf.translation, [0, 0, 6.79 * CM], atol=1e-12)
        assert (g.departure_point.what, g.departure_point.base) == ("PIN1", "PIN1")
        assert (g.grasp_point.what, g.grasp_point.base) == ("BMANIP", "PIN1")
        assert g.grasp_determination is None  # NILTRANS (L2630)
        # Each pickup plans in its own child of the base world, with its own grasp affixed.
        assert p.world.parent is ctx.base_world
        assert p.world.get(Affixed, "PIN1", "BMANIP").grasp == g.grasp
        assert p.world.get(Holding, "BMANIP").what == "PIN1"
    assert not ctx.base_world.facts(Affixed)
    assert ctx.base_world.get(Holding, "BMANIP").what == "nothing"
    # Relations read the grasp from their world: same nominal pin at the approach point, but
    # the hand errors act through each world's own grasp.
    a, b = found[0], found[-1]
    chain_a, chain_b = approach_relation(ctx, a.world, 0.0), approach_relation(ctx, b.world, 0.0)
    np.testing.assert_allclose(chain_a.nominal.translation, [0, 0, 2.54 * CM], atol=1e-12)
    np.testing.assert_allclose(chain_b.nominal.translation, [0, 0, 2.54 * CM], atol=1e-12)
    lin_a = RelationModel.of(chain_a).displacement.linear
    lin_b = RelationModel.of(chain_b).displacement.linear
    assert not np.allclose(lin_a, lin_b)
    diff = a.world.diff(b.world)  # what a assumes beyond b
    assert Affixed("PIN1", "BMANIP", a.strategy.grasp) in diff.added
    assert Affixed("PIN1", "BMANIP", b.strategy.grasp) in diff.removed


def test_phi_is_the_fastest_and_dtry_standoff_follow_l2188(ctx, pickups) -> None:
    found, _ = pickups
    cand = plan_approach(ctx, found[0])
    assert not hasattr(cand, "reason")
    times = [t for _, t in cand.phi_times if t is not None]
    # φ by the table's time (departure → approach → destination, L2160); the transport then
    # runs through the vias that bound the path bow (synth.strategies.bow), no faster.
    assert dict(cand.phi_times)[cand.strategy.phi] == min(times)
    assert cand.strategy.approach_vias and cand.transport_time >= min(times)
    s = cand.strategy
    # L2188–2196: dtry = d_f + 1 in = 4.25 cm, standoff = 2.54 cm, and the destinations
    # pin = hole*trans(rot(zhat,φ),vector(0,0,2.54)) / (0,0,−1.71) / (0,0,−4.25).
    assert s.dtry == pytest.approx(4.25 * CM, abs=1e-12)
    assert s.standoff == pytest.approx(2.54 * CM, abs=1e-12)
    for dest, z in ((s.approach, 2.54), (s.destination, -1.71), (s.target, -4.25)):
        assert (dest.what, dest.base) == ("PIN1", "BH1")
        np.testing.assert_allclose(dest.xf.translation, [0, 0, z * CM], atol=1e-12)
        np.testing.assert_allclose(pin.log3(dest.xf.rotation), [0, 0, s.phi], atol=1e-12)
    assert s.gross_time == pytest.approx(cand.pickup.strategy.pickup_time + cand.transport_time)
    # Pickup time = open + park→approach→grasp + center + lift (50 jiffies each, L3854–3857).
    g = cand.pickup
    assert g.strategy.pickup_time == pytest.approx(100 / 60 + g.move_time + g.lift_time)
