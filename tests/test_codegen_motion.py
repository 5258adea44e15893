"""Motion sequences as write_motion_sequence (seed L2537–2560, output form L2723–2724)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from synth.al import ast
from synth.al.parser import parse_program
from synth.codegen import literals as L
from synth.codegen.environment import template_environment
from synth.codegen.motion import Guard, MoveView, Waypoint, motion_sequence
from synth.exceptions import CodegenError


def wp(what: str, base: str, z_cm: float) -> Waypoint:
    xf = pin.SE3(np.eye(3), np.array([0.0, 0.0, z_cm / 100.0]))
    return Waypoint(L.name(what, field="w", role="arm"), L.name(base, field="b"), xf, "t")


GUARD = Guard(L.name("PIN1", field="g"), L.force(2.224), L.string("EXPECTED A FORCE HERE"))


def render(move: MoveView) -> str:
    env = template_environment("al")
    template = env.from_string('{% from "motion.al.j2" import move %}{{ move(m) }}\n')
    return template.render(m=move)


def z_of(location: L.Fragment) -> str:
    return location.text.split("VECTOR(0,0,")[1].split(")")[0]


def test_last_destination_after_to_earlier_ones_after_via_in_order() -> None:
    # The seed's pickup approach (L2723–2724): TO the grasp point VIA the approach point.
    moves = motion_sequence([wp("BMANIP", "PIN1", 8.62), wp("BMANIP", "PIN1", 3.54)])
    assert len(moves) == 1
    (m,) = moves
    assert m.frame.text == "BMANIP"
    assert z_of(m.destination) == "3.54"
    assert [z_of(v) for v in m.via] == ["8.62"]


def test_runs_of_the_same_controllable_frame_make_one_move_each() -> None:
    points = [
        wp("BMANIP", "PIN1", 1),
        wp("BMANIP", "PIN1", 2),
        wp("PIN1", "BH1", 3),
        wp("PIN1", "BH1", 4),
        wp("PIN1", "BH1", 5),
    ]
    moves = motion_sequence(points)
    assert [m.frame.text for m in moves] == ["BMANIP", "PIN1"]
    assert z_of(moves[0].destination) == "2" and [z_of(v) for v in moves[0].via] == ["1"]
    assert z_of(moves[1].destination) == "5"
    assert [z_of(v) for v in moves[1].via] == ["3", "4"]  # traversal order
    assert all(m.guard is None for m in moves)


def test_only_consecutive_destinations_are_grouped() -> None:
    moves = motion_sequence([wp("BMANIP", "PIN1", 1), wp("PIN1", "BH1", 2), wp("BMANIP", "BH1", 3)])
    assert [m.frame.text for m in moves] == ["BMANIP", "PIN1", "BMANIP"]
    assert all(not m.via for m in moves)


def test_a_guarded_motion_is_never_split() -> None:
    points = [wp("BMANIP", "PIN1", 1), wp("PIN1", "BH1", 2)]
    with pytest.raises(CodegenError, match="would be split into 2 MOVE statements") as info:
        motion_sequence(points, guard=GUARD, field="target")
    assert info.value.field == "target"


def test_a_guarded_run_is_one_move_with_its_guard() -> None:
    moves = motion_sequence([wp("PIN1", "BH1", z) for z in (5, 2.54, -4.25)], guard=GUARD)
    assert len(moves) == 1 and moves[0].guard is GUARD
    assert [z_of(v) for v in moves[0].via] == ["5", "2.54"]


def test_no_destination_is_an_error() -> None:
    with pytest.raises(CodegenError, match="at least one destination"):
        motion_sequence([])


def test_rendered_move_parses_with_vias_in_order_and_the_guard() -> None:
    (m,) = motion_sequence([wp("PIN1", "BH1", z) for z in (7, 5, 2.54, -4.25)], guard=GUARD)
    text = render(m)
    assert text.splitlines()[1].startswith("  VIA ")
    program = parse_program(text)
    (move,) = program.body
    assert isinstance(move, ast.Move) and move.frame.name == "PIN1"
    zs = []
    for point in move.via_points:
        assert isinstance(point, ast.BinOp) and isinstance(point.right, ast.Call)
        vector = point.right.args[1]
        assert isinstance(vector, ast.BinOp) and isinstance(vector.left, ast.Call)
        zs.append(vector.left.args[2])
    assert [z.value if isinstance(z, ast.Number) else None for z in zs] == [7, 5, 2.54]
    conditions = [c.condition for c in move.monitors]
    assert isinstance(conditions[0], ast.Compare)
    assert isinstance(conditions[1], ast.Name) and conditions[1].name == "ARRIVAL"
    assert isinstance(move.monitors[0].body, ast.Stop)


def test_rendered_unguarded_move_without_via() -> None:
    (m,) = motion_sequence([wp("PIN1", "PIN1", 6.79)])
    assert render(m) == "MOVE PIN1 TO PIN1*TRANS(NILROTN,VECTOR(0,0,6.79)*CM);\n"
