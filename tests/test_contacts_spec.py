"""Contact assertions in the task spec and the world base; named features; loader checks.

Seed A.1 (L2938–3156): ``(contacts, bxbtm, bfl.sb, inside_of)``,
``(contacts, be9, bfls2, extent_irrelevant)``.
"""

from __future__ import annotations

import textwrap

import numpy as np
import pytest
from _paths import BOX_FIXTURE_TASK

from synth.errors.locate import locate_objects
from synth.exceptions import SpecError
from synth.models.contacts import ContactSpec
from synth.models.features import box_features, fixture_features, object_vertices
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task, parse_task
from synth.units import CM

FIXTURE = BOX_FIXTURE_TASK

BASE = textwrap.dedent(
    """\
    name: t
    frames:
      - name: fix
        al_name: FIX
        shape: {type: fixture, inside: [8 cm, 10 cm, 3 cm], wall: 1 cm, floor: 1 cm}
      - name: box
        al_name: BOX
        parent: fix
        shape: {type: box, size: [8.9 cm, 7.6 cm, 4.9 cm]}
      - name: lid
        al_name: LID
        parent: box
        pose: {translation: [0 cm, 0 cm, 4.9 cm]}
        shape:
          type: surface
          outline: [[-1 cm, -1 cm], [1 cm, -1 cm], [1 cm, 1 cm], [-1 cm, 1 cm]]
    contacts:
    """
)


def _spec(contacts: str, frames_extra: str = "") -> str:
    return BASE.replace("contacts:\n", frames_extra + "contacts:\n") + textwrap.indent(
        textwrap.dedent(contacts), "  "
    )


def test_box_features_are_derived_from_the_size() -> None:
    f = box_features((8.9 * CM, 7.6 * CM, 4.9 * CM))
    # 6 faces, 12 edges, 8 corners.
    kinds = [x.kind for x in f.values()]
    assert (kinds.count("face"), kinds.count("edge"), kinds.count("corner")) == (6, 12, 8)
    bottom = f["bottom"]
    assert bottom.normal == pytest.approx([0, 0, -1])
    assert bottom.point == pytest.approx([0, 0, 0])
    # be9 of L3068: the vertical edge at (−a, −b), between faces with normals −x̂ and −ŷ.
    edge = f["xneg_yneg"]
    assert edge.start == pytest.approx([-4.45 * CM, -3.8 * CM, 0])
    assert edge.end == pytest.approx([-4.45 * CM, -3.8 * CM, 4.9 * CM])
    assert {tuple(n) for n in edge.normals} == {(-1.0, 0.0, 0.0), (0.0, -1.0, 0.0)}
    assert f["xpos_ypos_bottom"].point == pytest.approx([4.45 * CM, 3.8 * CM, 0])


def test_fixture_features_face_into_the_cavity() -> None:
    f = fixture_features((8 * CM, 10 * CM, 3 * CM), 1 * CM, 1 * CM)
    # Walls at x = ±4.000, y = ±5.000 (L3007–3022); each inner face's normal points inwards.
    assert f["xpos"].normal == pytest.approx([-1, 0, 0])
    assert f["xpos"].point[0] == pytest.approx(4 * CM)
    assert f["ypos"].normal == pytest.approx([0, -1, 0])
    assert f["ypos"].point[1] == pytest.approx(5 * CM)
    assert f["floor"].normal == pytest.approx([0, 0, 1])
    assert f["bottom"].normal == pytest.approx([0, 0, -1])
    assert f["bottom"].point[2] == pytest.approx(-1 * CM)
    assert not f["xpos_ypos"].convex
    # The floor outline is the cavity; inward edge normals point to its centre.
    for m, q in f["floor"].inward_edge_normals():
        assert m @ (np.zeros(3) - q) > 0


def test_fixture_vertices_are_its_outer_hull() -> None:
    spec = load_task(FIXTURE)
    fix = next(f for f in spec.frames if f.name == "fixture1")
    v = object_vertices(fix.shape)
    assert v.min(axis=0) == pytest.approx([-5 * CM, -6 * CM, -1 * CM])
    assert v.max(axis=0) == pytest.approx([5 * CM, 6 * CM, 3 * CM])


def test_fixture_file_loads_with_three_problems() -> None:
    spec = load_task(FIXTURE)
    assert len(spec.contacts) == 7
    # The seed's tuple form and the mapping form read the same.
    assert spec.contacts[3] == ContactSpec(a="box3.bottom", b="fixture3.floor", kind="inside_of")
    assert spec.contacts[0].kind == "inside_of"
    assert spec.contacts[2].kind == "extent_irrelevant"


def test_feature_names_accept_any_face_order() -> None:
    spec = parse_task(
        _spec("""\
        - {a: box.bottom, b: fix.floor, kind: inside_of}
        - {a: box.yneg_xneg, b: fix.xpos, kind: extent_irrelevant}
        """)
    )
    assert spec.contacts[1].a == "box.yneg_xneg"


def test_surface_frame_is_a_face() -> None:
    # A box upside down on its lid face (a surface frame) — the lid is a feature by itself.
    spec = parse_task(
        _spec("""\
        - {a: lid, b: fix.floor, kind: inside_of}
        """)
    )
    (res,) = locate_objects(spec)
    assert res.problem.axis == pytest.approx([0, 0, 1])
    # Upside down, the box's origin (bottom centre) is 4.9 cm above the floor.
    assert res.estimates[0].z.lo == pytest.approx(4.9 * CM, abs=1e-8)


@pytest.mark.parametrize(
    ("contacts", "frames_extra", "path", "message"),
    [
        ("- {a: box.bottom, b: fix.floor, kind: on_top_of}\n", "", "contacts[0].kind", "inside_of"),
        (
            "- {a: box.bottm, b: fix.floor, kind: inside_of}\n",
            "",
            "contacts[0].a",
            "no feature 'bottm'",
        ),
        (
            "- {a: crate.bottom, b: fix.floor, kind: inside_of}\n",
            "",
            "contacts[0].a",
            "unknown frame 'crate'",
        ),
        (
            "- {a: box.bottom, b: fix.xpos_ypos, kind: inside_of}\n",
            "",
            "contacts[0].b",
            "must be a face",
        ),
        (
            "- {a: box.bottom, b: fix.floor, kind: inside_of}\n"
            "- {a: box.xneg_yneg, b: fix.xpos, kind: inside_of}\n",
            "",
            "contacts[1].kind",
            "inside_of joins two faces",
        ),
        (
            "- {a: box.xneg_yneg, b: fix.xpos, kind: extent_irrelevant}\n",
            "",
            "contacts[0].a",
            "none of them is face on face",
        ),
        (
            "- {a: box.bottom, b: box.top, kind: extent_irrelevant}\n",
            "",
            "contacts[0].b",
            "same object",
        ),
        (
            "- {a: fix.xpos_ypos, b: box.top, kind: extent_irrelevant}\n",
            "",
            "contacts[0].a",
            "concave",
        ),
        (
            "- {a: box.bottom, b: 'fix floor', kind: inside_of}\n",
            "",
            "contacts[0].b",
            "not a feature",
        ),
        ("- [box.bottom, fix.floor]\n", "", "contacts[0]", "[a, b, kind]"),
        (
            "- {a: lid.top, b: fix.floor, kind: inside_of}\n",
            "",
            "contacts[0].a",
            "named features exist on box and fixture",
        ),
    ],
)
def test_bad_contacts_name_the_field(
    contacts: str, frames_extra: str, path: str, message: str
) -> None:
    text = _spec(contacts, frames_extra)
    with pytest.raises(SpecError) as info:
        parse_task(text)
    assert info.value.path == path
    assert message in info.value.detail
    # Each contact is one flow line below ``contacts:``, so contacts[k] (and its a, b, kind)
    # starts k + 1 lines after it.
    k = int(path.split("[", 1)[1].split("]", 1)[0])
    assert info.value.line == text.splitlines().index("contacts:") + 1 + k + 1


def test_located_frame_must_not_carry_a_pose_or_be_elsewhere() -> None:
    text = _spec("- {a: box.bottom, b: fix.floor, kind: inside_of}\n").replace(
        "    parent: fix\n", "    parent: fix\n    pose: {translation: [1 cm, 0 cm, 0 cm]}\n"
    )
    with pytest.raises(SpecError) as info:
        parse_task(text)
    assert info.value.path == "frames[1].pose"
    assert "derived from its contacts" in info.value.detail
    assert info.value.line == 9  # the pose line of frame box

    text = _spec("- {a: box.bottom, b: fix.floor, kind: inside_of}\n").replace(
        "    parent: fix\n", "    parent: world\n"
    )
    with pytest.raises(SpecError) as info:
        parse_task(text)
    assert info.value.path == "frames[1].parent"
    assert "its parent must be 'fix'" in info.value.detail


def test_fixture_shape_errors_name_the_field() -> None:
    text = BASE.replace("wall: 1 cm, ", "") + "  []\n"
    text = text.replace("contacts:\n  []\n", "")
    with pytest.raises(SpecError) as info:
        parse_task(text)
    assert info.value.path == "frames[0].shape.wall"


def test_without_the_edge_contact_the_second_box_is_ambiguous() -> None:
    # Seed A.1 (L3029, L3104): the floor contact alone leaves box2 two ways round in fixture2;
    # the edge contact against the side wall picks one.
    spec = load_task(FIXTURE)
    (full,) = locate_objects(spec, objects=["box2"])
    edge = ("box2.xneg_yneg", "fixture2.xpos")
    fewer = tuple(c for c in spec.contacts if (c.a, c.b) != edge)
    assert len(fewer) == len(spec.contacts) - 1
    (res,) = locate_objects(spec, contacts=fewer, objects=["box2"])
    assert (len(full.estimates), len(res.estimates)) == (1, 2)


def test_graph_knows_fixture_shapes() -> None:
    graph = AttributeGraph(load_task(FIXTURE))
    assert graph.node("FIX2").kind == "fixture"
    assert graph.parent("box2") == "fixture2"
