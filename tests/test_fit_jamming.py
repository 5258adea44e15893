"""Fit check and wedging limits: the planner's c/μ and the replay's exact two-point test.

Hand figures for the seed's parts (fixtures/tasks/seed_4_8.yaml): hole D = 0.64 cm, pin
d = 0.635 cm, μ = 0.3 (the default), so c = (D − d)/D = 0.005/0.64 = 0.0078125.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_PROGRAM, SEED_TASK

from synth.exceptions import SpecError
from synth.models.graph import AttributeGraph
from synth.models.insertion import derive
from synth.models.jamming import clearance_ratio, fit_problem, wedging_tilt
from synth.models.loader import load_task, parse_task
from synth.models.workcell import NominalPoses, WorkcellModel
from synth.replay.contact import first_contact
from synth.replay.run import replay_context, run_world
from synth.replay.truth import HandErrors, TrueWorld, nominal_world
from synth.replay.wedging import two_point_depth, wedges, wedging_onset

D, d, MU = 0.0064, 0.00635, 0.3
C = 0.005 / 0.64  # clearance ratio, by hand


def _seed_text() -> str:
    return SEED_TASK.read_text(encoding="utf-8")


def _with_diameters(pin: str, bh1: str) -> str:
    """seed_4_8 with PIN1's and BH1's diameters changed (the rack hole RH1 stays 0.64 cm)."""
    text = _seed_text().replace("diameter: 0.635 cm", f"diameter: {pin}")
    at_bh1 = "pose: {translation: [3.85 cm, 3.20 cm, 4.90 cm]}"
    head, tail = text.split(at_bh1, 1)
    return head + at_bh1 + tail.replace("diameter: 0.64 cm", f"diameter: {bh1}", 1)


def test_a_pin_wider_than_its_hole_is_refused_at_load_naming_the_fit() -> None:
    text = _with_diameters("0.70 cm", "0.62 cm")
    with pytest.raises(SpecError) as info:
        parse_task(text)
    assert info.value.path == "insertion.hole"
    assert "pin PIN1 (0.70 cm) does not fit hole BH1 (0.62 cm)" in str(info.value)


def test_an_equal_diameter_does_not_fit_and_a_thinner_pin_does() -> None:
    # zero clearance: c = 0, no tilt at all is admissible, so the pin cannot go in
    assert fit_problem("P", 0.0064, "H", 0.0064) == (
        "pin P (0.64 cm) does not fit hole H (0.64 cm): a pin must be thinner than its hole"
    )
    assert fit_problem("P", 0.00635, "H", 0.0064) is None
    text = _seed_text().replace("diameter: 0.635 cm", "diameter: 0.64 cm")
    with pytest.raises(SpecError, match=r"pin PIN1 \(0.64 cm\) does not fit hole BH1"):
        parse_task(text)


def test_a_pin_wider_than_its_start_hole_is_refused_naming_the_start_hole() -> None:
    # BH1 widened to 0.70 cm takes a 0.66 cm pin, but the rack hole RH1 (0.64 cm) it starts in
    # cannot hold it
    text = _with_diameters("0.66 cm", "0.70 cm")
    with pytest.raises(SpecError) as info:
        parse_task(text)
    assert info.value.path == "insertion.start_hole"
    assert "pin PIN1 (0.66 cm) does not fit hole RH1 (0.64 cm)" in str(info.value)


def test_planner_limit_is_whitneys_c_over_mu() -> None:
    assert clearance_ratio(D, d) == pytest.approx(0.0078125)
    # θ_wedge = c/μ = 0.0078125/0.3 = 0.0260417 rad = 1.4921°
    assert wedging_tilt(D, d, MU) == pytest.approx(0.0260417, rel=1e-5)
    assert math.degrees(wedging_tilt(D, d, MU)) == pytest.approx(1.4921, abs=1e-4)
    assert wedging_tilt(D, d, 0.0) == pytest.approx(math.pi / 2)  # no friction, no wedging
    assert wedging_tilt(D, 0.0070, MU) == 0.0


def test_replay_onset_solves_the_exact_two_point_balance() -> None:
    # By hand at θ = 0.027512 rad: sin θ = 0.027509, cos θ = 0.999622;
    # ℓ = (0.64 − 0.635·0.999622)/0.027509 = 0.19050 cm, h = ℓ cos θ − d sin θ = 0.17296 cm,
    # θ + atan(h/D) = 0.027512 + atan(0.27025) = 0.027512 + 0.263945 = 0.291457 = atan(0.3).
    onset = wedging_onset(D, d, MU)
    assert onset == pytest.approx(0.027512, abs=2e-6)
    assert two_point_depth(onset, D, d) == pytest.approx(0.0017296, abs=1e-7)
    # the two models agree to first order: the exact onset is c/μ + 5.6 % (the θ² terms the
    # small-angle limit drops), and the planner's c/μ is the lower, i.e. conservative, one
    planner = wedging_tilt(D, d, MU)
    assert planner < onset  # conservative
    assert onset / planner == pytest.approx(0.027512 / math.radians(1.4921), abs=1e-4)  # 1.0564
    # wedging needs the two-point contact before the seat: h(2°) = 0.12 cm
    assert wedges(math.radians(2.0), D, d, MU, seat=0.0171)
    assert not wedges(math.radians(2.0), D, d, MU, seat=0.001)
    assert not wedges(math.radians(1.5), D, d, MU, seat=0.0171)


def test_derived_dtheta_never_exceeds_the_wedging_limit() -> None:
    spec = load_task(SEED_TASK)
    assert spec.insertion is not None
    graph = AttributeGraph(spec)
    given = derive(graph, spec.insertion)
    assert given.dtheta_ok == pytest.approx(C / MU) and given.wedge_tilt == pytest.approx(C / MU)
    assert "exceeds the wedging limit c/μ = 1.492°" in given.notes[0]
    # a given value below the limit is kept as given
    kept = derive(graph, spec.insertion.model_copy(update={"dtheta_ok": math.radians(1.0)}))
    assert kept.dtheta_ok == pytest.approx(math.radians(1.0))
    assert kept.source["dtheta_ok"] == "given" and kept.notes == ()
    # an ordinary loose pin, μ = 0.1: c/μ = 0.078125 rad = 4.476°, still far below the 36.7°
    # lead tilt atan(0.44/0.59) the old rule gave
    loose = spec.insertion.model_copy(update={"dtheta_ok": None, "friction": 0.1})
    assert derive(graph, loose).dtheta_ok == pytest.approx(0.078125)


@pytest.fixture(scope="module")
def seed_cell():  # type: ignore[no-untyped-def]
    graph = AttributeGraph(load_task(SEED_TASK))
    cell = WorkcellModel(graph).place(NominalPoses(graph))
    return cell, cell.hole("bh1"), cell.pins["pin1"]


@pytest.mark.parametrize(
    ("tilt_deg", "kind"),
    [
        (1.0, "capture"),  # below both limits
        (1.53, "capture"),  # above the planner's 1.492°, below the replay's 1.576°
        (2.0, "wedge"),  # above both
    ],
)
def test_replay_wedges_a_pin_entering_beyond_the_onset(seed_cell, tilt_deg, kind) -> None:  # type: ignore[no-untyped-def]
    cell, hole, model = seed_cell
    tilt = pin.SE3(pin.utils.rotate("x", math.radians(tilt_deg)), np.zeros(3))

    def pose_at(s: float) -> pin.SE3:
        # the tip centre moves down the hole axis from 1 cm above the mouth to 0.5 cm below
        return hole.world_from_hole * pin.SE3(np.eye(3), np.array([0, 0, 0.01 - 0.015 * s])) * tilt

    found = first_contact(model, pose_at, 0.015, cell.obstacles, cell.holes, friction=cell.friction)
    assert found is not None and found.kind == kind and found.hole is hole
    assert cell.friction == MU


def _box_tilted(graph: AttributeGraph, degrees: float) -> TrueWorld:
    """The believed world with the box (and its top and holes) turned about its x axis."""
    poses = dict(nominal_world(graph).world_from)
    box = poses["box"]
    tilted = box * pin.SE3(pin.utils.rotate("x", math.radians(degrees)), np.zeros(3))
    for name in ("box", "box_top", "bh1", "bh2", "bh3", "bh4"):
        poses[name] = tilted * box.actInv(poses[name])
    return TrueWorld(poses, {}, nominal=False)


@pytest.mark.parametrize(("degrees", "outcome"), [(1.0, "success"), (2.5, "violation")])
def test_the_seed_program_wedges_in_a_box_tilted_past_the_onset(degrees, outcome) -> None:  # type: ignore[no-untyped-def]
    # the held pin stays vertical, so its tilt at entry is the box's: 1.0° is below the replay's
    # onset 1.576°, 2.5° above it
    program = SEED_PROGRAM.read_text(encoding="utf-8")
    context = replay_context(program, SEED_TASK)
    report = run_world(context, _box_tilted(context.graph, degrees), HandErrors.none())
    assert report.outcome == outcome
    if outcome == "violation":
        assert report.message.startswith("wedged: PIN1 wedged in BH1: it entered tilted 2.50°")
        assert report.violations[0].kind == "wedged"


@pytest.mark.parametrize(
    ("pose", "field", "fault"),
    [
        # 0.5 cm up a 4.9 cm box, axis exactly along z: the mouth alone is named (the axis's
        # floating-point angle, 1e-6°, was printed as a second fault)
        ("{translation: [3.85 cm, 3.20 cm, 0.5 cm]}", "pose.translation", "its mouth is 0.5 cm up"),
        (
            "{translation: [3.85 cm, 3.20 cm, 4.90 cm], rotation: [{x: 5 deg}]}",
            "pose.rotation",
            "its axis 5° off z",
        ),
    ],
)
def test_a_hole_off_its_box_top_names_only_what_is_off(pose: str, field: str, fault: str) -> None:
    text = SEED_TASK.read_text(encoding="utf-8")
    seated = "pose: {translation: [3.85 cm, 3.20 cm, 4.90 cm]}      # T_bh, L2576"
    assert seated in text
    graph = AttributeGraph(parse_task(text.replace(seated, f"pose: {pose}")))
    with pytest.raises(SpecError) as info:
        WorkcellModel(graph).place(NominalPoses(graph))
    assert info.value.path.endswith(field)
    assert info.value.detail.endswith(f"along the box's z); {fault}")
