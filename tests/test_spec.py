"""Task spec validation: units, AL names, tree checks, and bad input through the CLI."""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from _paths import SEED_TASK, TASKS

from synth.cli import main
from synth.exceptions import SpecError, UnitError
from synth.models.graph import AttributeGraph
from synth.models.insertion import at_lead, derive, exceeds_lead
from synth.models.loader import load_task, parse_task
from synth.units import parse_quantity

GOOD = textwrap.dedent(
    """\
    name: t
    frames:
      - name: box
        al_name: BOX
        pose: {translation: [1 cm, 2 cm, 0 cm]}
        uncertainty:
          x: 0.3 in
          rz: 5 deg
      - name: hole
        al_name: BH1
        parent: box
        pose: {translation: [0 cm, 0 cm, 4 cm]}
    """
)


def test_units_convert_to_si() -> None:
    assert parse_quantity("3.85 cm", "length") == pytest.approx(0.0385)
    assert parse_quantity("0.3 in", "length") == pytest.approx(0.3 * 0.0254)
    assert parse_quantity("5 deg", "angle") == pytest.approx(math.radians(5))
    # 8 oz read as a force is the weight of 8 avoirdupois ounces: 8 × 28.349523125 g × g₀.
    assert parse_quantity("8 oz", "force") == pytest.approx(8 * 0.028349523125 * 9.80665)
    with pytest.raises(UnitError, match="no unit"):
        parse_quantity("3.85", "length")
    with pytest.raises(UnitError, match="not a length"):
        parse_quantity("5 deg", "length")


def test_good_spec_loads_and_composes() -> None:
    spec = parse_task(GOOD)
    graph = AttributeGraph(spec)
    assert graph.resolve("bh1") == "hole"
    assert graph.world_from("hole").translation == pytest.approx([0.01, 0.02, 0.04])
    box = spec.frames[0].uncertainty
    assert box is not None and box.x is not None
    assert (box.x.lo, box.x.hi) == pytest.approx((-0.00762, 0.00762))


def test_seed_fixture_composes_the_seed_frames() -> None:
    graph = AttributeGraph(load_task(SEED_TASK))
    # T_wp = trans(rot(ẑ, 90°), (24.1, 117, .537) cm), seed L2577.
    pin_pose = graph.world_from("PIN1")
    assert pin_pose.translation == pytest.approx([0.241, 1.17, 0.00537])
    assert pin_pose.rotation[:, 0] == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)
    assert graph.world_from("BH1").translation == pytest.approx([0.4905, 1.052, 0.049])
    assert [n.al_name for n in graph.holes_in("box_top")] == ["BH1", "BH2", "BH3", "BH4"]
    path = graph.path("BH1", "PIN1")
    assert path.ancestor == "world"
    assert [link.child for link in path.up] == ["bh1", "box"]
    assert [link.child for link in path.down] == ["rack", "rh1", "pin1"]


def test_insertion_parameters_given_and_derived() -> None:
    spec = load_task(SEED_TASK)
    graph = AttributeGraph(spec)
    assert spec.insertion is not None
    given = derive(graph, spec.insertion)
    assert given.d_f == pytest.approx(0.0171)
    # the seed's 10° is above Whitney's wedging limit c/μ = ((.64 − .635)/.64)/0.3 = .026042 rad
    # (1.492°) for these parts and μ = 0.3, so it is clipped to the limit and the plan says so
    assert given.dtheta_ok == pytest.approx(0.0078125 / 0.3)
    assert given.source["dtheta_ok"] == "given, clipped to the wedging limit"
    bare = spec.insertion.model_copy(update={"d_f": None, "dr_ok": None, "dtheta_ok": None})
    derived = derive(graph, bare)
    # Whitney's lead: chamfer .25 + (hole radius .32 − tip radius .13) = .44 cm.
    assert derived.dr_ok == pytest.approx(0.0044)
    assert derived.d_f == pytest.approx(0.0171)  # the hole depth: the pin bottoms out
    # the lead tilt atan(.44 / (.34 + .25)) = 36.7° is far above the wedging limit 1.492°
    assert math.atan2(0.44, 0.34 + 0.25) > derived.dtheta_ok == pytest.approx(0.0078125 / 0.3)
    assert derived.source["dr_ok"] == "derived" and given.source["dr_ok"] == "given"


def test_the_parameters_at_the_lead_take_its_width_and_tilt() -> None:
    spec = load_task(SEED_TASK)
    graph = AttributeGraph(spec)
    assert spec.insertion is not None
    # μ = 0: no wedging limit, so the given 10° stands until the lead's own tilt bounds it
    free = derive(graph, spec.insertion.model_copy(update={"friction": 0.0, "dtheta_ok": 1.0}))
    assert free.dr_ok == pytest.approx(0.00762) and exceeds_lead(free)
    lead = at_lead(free, "note: test")
    # width: chamfer .25 + (hole radius .32 − tip radius .13) = .44 cm; tilt: the tip still
    # lands on the chamfer up to atan(.44 / (taper .34 + chamfer .25)) = 36.7°
    assert lead.dr_ok == pytest.approx(0.0044) and not exceeds_lead(lead)
    assert lead.dtheta_ok == pytest.approx(math.atan2(0.44, 0.59))
    assert lead.source["dr_ok"] == "the geometric lead" and lead.notes[-1] == "note: test"
    # with the seed's μ = 0.3 the wedging limit 1.492° stays the tighter bound
    seed = at_lead(derive(graph, spec.insertion), "note: test")
    assert seed.dtheta_ok == pytest.approx(0.0078125 / 0.3)


BAD = [
    ("unknown parent", GOOD.replace("parent: box", "parent: bx"), "frames[1].parent", 11),
    ("missing unit", GOOD.replace("x: 0.3 in", "x: 0.3"), "frames[0].uncertainty.x", 7),
    ("wrong unit", GOOD.replace("rz: 5 deg", "rz: 5 cm"), "frames[0].uncertainty.rz", 8),
    ("negative tolerance", GOOD.replace("x: 0.3 in", "x: -0.3 in"), "frames[0].uncertainty.x", 7),
    ("NaN", GOOD.replace("2 cm", "nan cm"), "frames[0].pose.translation[1]", 5),
    ("AL keyword", GOOD.replace("al_name: BOX", "al_name: MOVE"), "frames[0].al_name", 4),
    ("bad AL name", GOOD.replace("al_name: BOX", "al_name: 2BOX"), "frames[0].al_name", 4),
    ("duplicate AL name", GOOD.replace("al_name: BH1", "al_name: box"), "frames[1].al_name", 10),
    ("unknown field", GOOD.replace("name: t", "name: t\nfoo: 1"), "foo", 2),
    # a mapping is no form of bound (the record's own {lo, hi} skipped every check of the two)
    ("mapping bound", GOOD.replace("x: 0.3 in", "x: {a: 1}"), "frames[0].uncertainty.x", 7),
    (
        "unknown rotation axis",
        GOOD.replace("[0 cm, 0 cm, 4 cm]}", "[0 cm, 0 cm, 4 cm], rotation: [{w: 225 deg}]}"),
        "frames[1].pose.rotation[0]",
        12,
    ),
    (
        "two axes in one rotation",
        GOOD.replace(
            "[0 cm, 0 cm, 4 cm]}", "[0 cm, 0 cm, 4 cm], rotation: [{z: 30 deg, x: 10 deg}]}"
        ),
        "frames[1].pose.rotation[0]",
        12,
    ),
    (
        "short translation",
        GOOD.replace("[1 cm, 2 cm, 0 cm]", "[1 cm, 2 cm]"),
        "frames[0].pose.translation[2]",
        5,
    ),
    (
        "cycle",
        GOOD.replace("    al_name: BOX\n", "    al_name: BOX\n    parent: hole\n"),
        "frames[0].parent",
        5,
    ),
    (
        "infeasible",
        GOOD.replace(
            "rz: 5 deg", "rz: 5 deg\n      constraints:\n        - {terms: {x: 1}, min: 1 in}"
        ),
        "frames[0].uncertainty.constraints",
        9,
    ),
    (
        "bad coefficient kind",
        GOOD.replace(
            "rz: 5 deg",
            "rz: 5 deg\n      constraints:\n        - {terms: {x: 1, rz: 1}, max: 1 in}",
        ),
        "frames[0].uncertainty.constraints[0]",
        10,
    ),
    (
        # x = y exactly: errors of no volume, which the trials' rejection sampler never drew
        # (synth plan gave up after 100 000 draws, naming no field)
        "equality constraint",
        GOOD.replace(
            "rz: 5 deg",
            "rz: 5 deg\n      constraints:\n        - {terms: {x: 1, y: -1}, min: 0 in, max: 0 in}",
        ),
        "frames[0].uncertainty.constraints[0]",
        10,
    ),
    # a name is how messages and the service's plan list tell tasks apart
    ("blank name", GOOD.replace("name: t\n", "name: '  '\n"), "name", 1),
    ("two-line name", GOOD.replace("name: t\n", 'name: "t\\nu"\n'), "name", 1),
]


@pytest.mark.parametrize(("label", "text", "path", "line"), BAD, ids=[b[0] for b in BAD])
def test_bad_spec_names_field_and_line(label: str, text: str, path: str, line: int) -> None:
    with pytest.raises(SpecError) as info:
        parse_task(text)
    assert info.value.path == path, str(info.value)
    assert info.value.line == line, str(info.value)
    if label == "short translation":  # not "this field is required" of a field never written
        assert info.value.detail == "the list has 2 values; value 3 is required too"
    if label == "mapping bound":
        assert info.value.detail.startswith("a bound is one tolerance ('0.3 in' means ±0.3 in)")
    if label == "unknown rotation axis":  # not "axis: this field is required"
        assert info.value.detail.startswith("'w' is not an axis")
    if label == "equality constraint":
        assert info.value.detail.startswith("min equals max")
    if label == "bad coefficient kind":
        assert info.value.detail.startswith("term rz is an angle but the bound is a length")
    if label == "blank name":
        assert info.value.detail == "a task needs a name (it was blank)"
    if label == "two-line name":
        assert info.value.detail == "a task's name is one printable line, got 't\\nu'"
    if label == "two axes in one rotation":  # not "z: unknown field", a valid key
        assert info.value.detail.startswith("one axis per rotation, not 'z', 'x'")


def test_a_refusal_made_after_loading_gets_its_fields_line() -> None:
    # The park's refusal and the service's model paths are found after loading, by code that
    # knows the field but not the file: its line is the field's in the task file (line 95 of
    # fixtures/tasks/seed_4_8.yaml is `  park:`), and a refusal with a line keeps its own
    spec = load_task(SEED_TASK)
    assert SEED_TASK.read_text(encoding="utf-8").splitlines()[94] == "  park:"
    with pytest.raises(SpecError) as refused, spec.lines_on_errors():
        raise SpecError("manipulator.park", "the fingers touch the arm")
    assert (refused.value.line, str(refused.value)) == (
        95,
        "manipulator.park (line 95): the fingers touch the arm",
    )
    with pytest.raises(SpecError) as kept, spec.lines_on_errors():
        raise SpecError("manipulator.park", "elsewhere", 7)
    assert kept.value.line == 7


def test_coupled_constraint_units() -> None:
    text = GOOD.replace(
        "rz: 5 deg",
        "rz: 5 deg\n      constraints:\n        - {terms: {x: 1, rz: 2 cm/deg}, max: 0.5 cm}",
    )
    unc = parse_task(text).frames[0].uncertainty
    assert unc is not None
    (c,) = unc.constraints
    # 2 cm per degree = 0.02 m / (π/180 rad) on the rotation parameter, in SI.
    assert c.terms["rz"] == pytest.approx(0.02 / math.radians(1))
    assert c.max == pytest.approx(0.005)


def test_cli_bad_input_exits_2_without_traceback(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    task = tmp_path / "t.yaml"
    task.write_text(GOOD.replace("x: 0.3 in", "x: 0.3"))
    assert main(["errors", str(task), "--from", "box", "--to", "hole"]) == 2
    err = capsys.readouterr().err
    assert "frames[0].uncertainty.x (line 7)" in err and "Traceback" not in err
    task.write_text(GOOD)
    assert main(["errors", str(task), "--from", "box", "--to", "nothing"]) == 2
    assert "unknown frame or feature 'nothing'" in capsys.readouterr().err
    assert main(["errors", str(tmp_path / "missing.yaml"), "--from", "a", "--to", "b"]) == 2
    task.write_text("name: [unclosed")
    assert main(["errors", str(task), "--from", "a", "--to", "b"]) == 2
    assert "YAML syntax error" in capsys.readouterr().err


def test_cli_json_shape() -> None:
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "synth.cli",
            "errors",
            str(TASKS / "screw_on_driver.yaml"),
            "--from",
            "hole",
            "--to",
            "tip",
            "--json",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    import json

    data = json.loads(out.stdout)
    for part in ("first_order", "certified"):
        assert set(data[part]) == {"dx", "dy", "dz", "dtheta_x", "dtheta_y", "dtheta_z", "tilt"}
    assert data["first_order"]["dz"][1] == pytest.approx(0.00127, rel=0.01)
    assert data["certified"]["dz"][1] > data["first_order"]["dz"][1]


def test_cli_errors_against_the_world_frame(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["errors", str(SEED_TASK), "--from", "world", "--to", "BH1"]) == 0
    out = capsys.readouterr().out
    # In the world frame BH1's x error is the box's ±0.3 in = ±0.762 cm plus the box rotation
    # ±5° acting on the hole's lever arm y = 3.20 cm: 3.20·0.0873 = 0.279 cm; 1.041 cm in all.
    assert "Errors of world⁻¹ ∘ BH1" in out
    assert "-1.041 .. +1.041 cm" in out


def test_a_hole_deeper_than_its_box_is_refused_at_its_depth() -> None:
    # BH1 of the seed task is 1.71 cm deep in a 4.90 cm box. At 5.00 cm the pin's seat d_f
    # would lie 0.10 cm below the box's floor, inside the table: the planner used to refuse it
    # only after planning ("the insertion into BH1 sweeps PIN1 into table").
    text = SEED_TASK.read_text(encoding="utf-8")
    bh1 = "    # rtd = hole radius + pin tip radius"
    assert text.count(bh1) == 1
    head, tail = text.split(bh1)
    deeper = head + bh1 + tail.replace("depth: 1.71 cm", "depth: 5.00 cm", 1)
    with pytest.raises(SpecError) as refused:
        parse_task(deeper)
    assert refused.value.path == "frames[2].shape.depth"
    assert refused.value.line == text[: text.index("depth: 1.71 cm")].count("\n") + 1
    assert "5 cm deep in box 'box', which is 4.9 cm tall" in refused.value.detail
    # A through hole (depth = the box's height) is a hole the meshes drill (test_meshes).
    through = head + bh1 + tail.replace("depth: 1.71 cm", "depth: 4.90 cm", 1)
    assert parse_task(through).frames[2].shape.depth == pytest.approx(0.049)


def _seed_with(old: str, new: str) -> tuple[str, int]:
    """The seed task with its one ``old`` replaced by ``new``, and the line of the change."""
    text = SEED_TASK.read_text(encoding="utf-8")
    assert text.count(old) == 1, old
    return text.replace(old, new), text[: text.index(old)].count("\n") + 1


@pytest.mark.parametrize(
    ("old", "new", "path", "fragment"),
    [
        # BH1 is 1.71 cm deep: a pin pushed 2.5 cm in would be below its bottom (the planner
        # refused it as "hand cannot grasp": d_min exceeded d_max)
        ("  d_f: 1.71 cm  ", "  d_f: 2.5 cm   ", "insertion.d_f", "2.5 cm is deeper than hole BH1"),
        # the success test tells seated from missed by d_f − d_s: negative limits otherwise
        ("  d_s: 0 cm", "  d_s: 1.8 cm", "insertion.d_s", "1.8 cm must be less than d_f = 1.71"),
        # with d_f left out, the derived one: min(1.71 cm deep, 5.08 − 0.34 cm of pin) (the
        # planner refused every candidate as "a tap would not narrow Δz")
        (
            "  d_f: 1.71 cm                                            # measured by the seed "
            "(L2582–2585)\n  d_s: 0 cm",
            "  d_s: 1.8 cm",
            "insertion.d_s",
            "1.8 cm must be less than d_f = 1.71 cm, derived (the task gives none)",
        ),
        # the pin stands in RH1; BH2 is a hole of the box, 21 cm away
        ("  start_hole: RH1", "  start_hole: BH2", "insertion.start_hole", "does not stand in BH2"),
        # and the message points at the pin's own frame (PIN1 is frames[9], placed against rh1)
        (
            "  start_hole: RH1",
            "  start_hole: BH2",
            "insertion.start_hole",
            "name the hole it stands in, or place it in this one (frames[9], its pose against rh1)",
        ),
        # RH1 (0.64 cm) leaves the 0.635 cm pin 0.0025 cm of radial play: an axis 0.1 cm off
        # puts the pin into the rack's wall, though its tip centre is inside the 0.32 cm mouth
        (
            "pose: {translation: [0 cm, 0 cm, -1.71 cm]}",
            "pose: {translation: [0.1 cm, 0 cm, -1.71 cm]}",
            "insertion.start_hole",
            "its axis 0.1 cm from the hole's, where the radial clearance allows 0.0025 cm",
        ),
        # a tip above the mouth stands on nothing: said as height, not as a negative depth
        (
            "pose: {translation: [0 cm, 0 cm, -1.71 cm]}",
            "pose: {translation: [0 cm, 0 cm, 0.5 cm]}",
            "insertion.start_hole",
            "tip 0.5 cm above its mouth",
        ),
        (
            "pose: {translation: [0 cm, 0 cm, -1.71 cm]}",
            "pose: {translation: [0 cm, 0 cm, -2 cm]}",
            "insertion.start_hole",
            "tip 2 cm deep in a hole 1.71 cm deep",
        ),
        # pulling PIN1 out of RH1 to put it back planned and proved a no-op
        ("  hole: BH1\n  start_hole", "  hole: RH1\n  start_hole", "insertion.hole", "already"),
        # BH1 is drilled into the box; the rack's top was taken for its face (tapping place
        # and search measured on the rack)
        (
            "depth: 1.71 cm, chamfer_width: 0.25 cm, surface: box_top}\n  - name: bh2",
            "depth: 1.71 cm, chamfer_width: 0.25 cm, surface: rack_top}\n  - name: bh2",
            "frames[2].shape.surface",
            "belongs to 'box' but surface 'rack_top' to 'rack'",
        ),
        # an outline 0.2 cm wider than the 8.90 cm box put tapping places in the air
        (
            "[[-4.45 cm, -3.80 cm], [4.45 cm, -3.80 cm]",
            "[[-4.65 cm, -3.80 cm], [4.45 cm, -3.80 cm]",
            "frames[1].shape.outline[0]",
            "outside face top of box 'box' (8.9 × 7.6 × 4.9 cm)",
        ),
        # a top declared 0.3 cm low lies inside the solid box the replay collides with: the
        # taps and the search were planned on a plane 0.3 cm under the real face
        (
            "pose: {translation: [0 cm, 0 cm, 4.90 cm]}",
            "pose: {translation: [0 cm, 0 cm, 4.60 cm]}",
            "frames[1].pose",
            "it is 0.3 cm inside the box's top face",
        ),
        (
            "pose: {translation: [0 cm, 0 cm, 4.90 cm]}",
            "pose: {translation: [0 cm, 0 cm, 4.90 cm], rotation: [{x: 2 deg}]}",
            "frames[1].pose",
            "it is turned 2° from the box's top face",
        ),
        # the rack moved onto the box's place: the two solids overlap from the start (a rack
        # inside a plate was planned and "proven"); both centred there, the least translation
        # that parts them is the rack's 2.247 cm height (Coal's penetration depth)
        (
            "pose: {translation: [24.1 cm, 117 cm, 0 cm]}",
            "pose: {translation: [45.2 cm, 102 cm, 0 cm]}",
            "frames[6].pose",
            "box 'rack' overlaps box 'box' (by 2.247 cm)",
        ),
        # the box 3 cm under the table top
        (
            "pose: {translation: [45.2 cm, 102 cm, 0 cm]}          # T_wb, L2575",
            "pose: {translation: [45.2 cm, 102 cm, -3 cm]}",
            "frames[0].pose",
            "box 'box' reaches 3 cm under the table top (z = 0)",
        ),
    ],
)
def test_an_insertion_or_face_the_parts_contradict_is_refused_at_its_field(
    old: str, new: str, path: str, fragment: str
) -> None:
    text, line = _seed_with(old, new)
    with pytest.raises(SpecError) as refused:
        parse_task(text)
    assert refused.value.path == path
    assert fragment in refused.value.detail
    if path == "insertion.start_hole":
        # the pin's pose and its start_hole disagree: the message points at the start_hole
        line = text[: text.index("  start_hole:")].count("\n") + 1
    if "\n" not in old:
        assert refused.value.line == line


@pytest.mark.parametrize(
    ("pose", "outline", "refusal"),
    [
        # 0.05 mm above the top (a size written in inches, a face in centimetres): on it
        (
            "{translation: [0 cm, 0 cm, 4.905 cm]}",
            "[[-4 cm, -3 cm], [4 cm, -3 cm], [4 cm, 3 cm]]",
            None,
        ),
        # the +x side face (x = 4.45 cm, 7.6 × 4.9 cm): the surface's z turned onto +x
        (
            "{translation: [4.45 cm, 0 cm, 2.45 cm], rotation: [{y: 90 deg}]}",
            "[[-2.4 cm, -3.7 cm], [2.4 cm, -3.7 cm], [2.4 cm, 3.7 cm]]",
            None,
        ),
        # on that side face, but 5 cm tall where the face is 4.9 cm: vertex 1 is 0.05 cm
        # below the box's bottom (the surface's x runs down the face)
        (
            "{translation: [4.45 cm, 0 cm, 2.45 cm], rotation: [{y: 90 deg}]}",
            "[[2.5 cm, -3.7 cm], [-2.4 cm, -3.7 cm], [-2.4 cm, 3.7 cm]]",
            "outline vertex 1 of 'side' lies outside face xpos",
        ),
        # beside the box, 1 cm out from its −y side
        (
            "{translation: [0 cm, -4.80 cm, 2.45 cm], rotation: [{x: 90 deg}]}",
            "[[-1 cm, -1 cm], [1 cm, -1 cm], [1 cm, 1 cm]]",
            "it is 1 cm outside the box's yneg face",
        ),
    ],
)
def test_a_surface_lies_on_a_face_of_its_box(pose: str, outline: str, refusal: str | None) -> None:
    old = "  - name: bh1\n"
    side = (
        f"  - name: side\n    al_name: SIDE\n    parent: box\n    pose: {pose}\n"
        f"    shape: {{type: surface, outline: {outline}}}\n"
    )
    text, _ = _seed_with(old, side + old)
    if refusal is None:
        parse_task(text)
        return
    with pytest.raises(SpecError) as refused:
        parse_task(text)
    assert refused.value.path.startswith("frames[2].")
    assert refusal in refused.value.detail, refused.value.detail
