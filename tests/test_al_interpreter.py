"""AL values, interpreter, machine protocol and world binding.

Oracles are independent of the code under test: frames composed by hand (rotation matrices
written out, translations added in centimetres), the seed's numbers (design.md: T_wp, T_wb,
T_bh, BPARK), the force of 8 oz from the pound-force (1 lbf = 4.4482216152605 N exactly), and
the seed's search loop re-enumerated in plain Python from its listing (L2752–2770).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import pinocchio as pin
import pytest
from _paths import DATA_AL, SEED_SEARCH, SEED_TAP_TASK, SEED_TASK, TASKS

from synth.al import ast
from synth.al import values as V
from synth.al.interpreter import Interpreter, RunResult
from synth.al.machine import (
    DurationConstraint,
    DurationMonitor,
    ForceConstraint,
    ForceMonitor,
    IdealMachine,
    Machine,
    MachineCommand,
    OpeningMonitor,
)
from synth.al.parser import parse_program
from synth.codegen.binding import bind_world, preamble
from synth.exceptions import ALRuntimeError, SynthError
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task
from synth.units import CM, INCH

OZ_N = 4.4482216152605 / 16  # 1 oz-force = 1/16 lbf [N]


def Rz(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def Rx(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def Ry(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def axis_angle(axis: tuple[float, float, float], rad: float) -> np.ndarray:
    """Rodrigues' formula, written out."""
    k = np.array(axis, dtype=float)
    k /= np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(rad) * K + (1 - math.cos(rad)) * K @ K


def H(R: np.ndarray, p_cm: Sequence[float]) -> np.ndarray:
    """4×4 homogeneous transform, translation given in cm, returned in m."""
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.array(p_cm) * CM
    return T


def as_h(se3: pin.SE3) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = se3.rotation
    T[:3, 3] = se3.translation
    return T


def close(se3: pin.SE3, T: np.ndarray, atol: float = 1e-9) -> bool:
    return bool(np.allclose(as_h(se3), T, atol=atol))


def run(
    text: str, machine: Machine | None = None, *, max_statements: int = 1_000_000
) -> tuple[RunResult, Interpreter]:
    machine = machine if machine is not None else IdealMachine()
    interpreter = Interpreter(machine, max_statements=max_statements)
    return interpreter.run(parse_program(text, filename="t.al")), interpreter


def ev(text: str, machine: Machine | None = None) -> V.Value:
    """Value of the AL expression ``text``."""
    _, interpreter = run(f"RESULT ← {text};", machine)
    value = interpreter.value("RESULT")
    assert value is not None
    return value


def sv(value: V.Value | None) -> tuple[float, V.Exponents]:
    """A scalar as (SI value, dimension), for comparisons with pytest.approx."""
    assert isinstance(value, V.Scalar), value
    return value.value, value.dim


def al_error(text: str, machine: Machine | None = None) -> ALRuntimeError:
    with pytest.raises(ALRuntimeError) as info:
        run(text, machine)
    return info.value


# --------------------------------------------------------------------------------------------
# Values: dimensions


def test_units_are_si_and_bare_numbers_are_al_base_units() -> None:
    two_in = ev("2*INCHES")
    assert isinstance(two_in, V.Scalar)
    assert two_in.value == pytest.approx(0.0508) and two_in.dim == V.LENGTH
    # bare number next to a length is cm: 2 in + 1 = 6.08 cm
    mixed = ev("2*INCHES + 1")
    assert isinstance(mixed, V.Scalar) and mixed.value == pytest.approx(0.0608)
    # 8 oz is half a pound-force
    eight = ev("8*OZ")
    assert isinstance(eight, V.Scalar) and eight.dim == V.FORCE
    assert eight.value == pytest.approx(4.4482216152605 / 2, rel=1e-12)
    torque = ev("10*OZ*INCHES")
    assert isinstance(torque, V.Scalar) and torque.dim == V.TORQUE
    assert torque.value == pytest.approx(10 * OZ_N * INCH)
    angle = ev("(.572/.286)*RAD + 90*DEG")
    assert isinstance(angle, V.Scalar) and angle.dim == V.ANGLE
    assert angle.value == pytest.approx(2 + math.pi / 2)
    # a bare angle is radians
    assert ev("1.05 < 61*DEG") is True and ev("1.05 > 60*DEG") is True


def test_bare_vector_in_trans_is_cm() -> None:
    t = ev("TRANS(NILROTN, VECTOR(0,0,3.54))")
    assert isinstance(t, V.Pose) and t.kind == "trans"
    assert np.allclose(t.se3.translation, [0, 0, 0.0354])
    mixed = ev("VECTOR(15*INCHES, 10*INCHES, 0)")
    assert isinstance(mixed, V.Vector) and mixed.dim == V.LENGTH
    assert np.allclose(mixed.value, [15 * INCH, 10 * INCH, 0])


def test_chained_relation_with_bare_threshold() -> None:
    _, it = run(
        "D ← 1.7*CM; A ← ABS(D) > .169; B ← 0.2*INCHES > D > -0.2*INCHES;"
        "C ← 0.2*INCHES > 0.6*CM > -0.2*INCHES;"
    )
    assert it.value("A") is True  # 1.7 cm > 0.169 cm
    assert it.value("B") is False  # 1.7 cm is not within ±0.508 cm
    assert it.value("C") is False and ev("0.2*INCHES > 0.5*CM > -0.2*INCHES") is True


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("1*CM + 1*DEG", "length and a angle"),
        ("1*CM < 2*SEC", "cannot apply '<'"),
        ("SIN(1*CM)", "must be a angle"),
        ("TRANS(NILROTN, VECTOR(1,1,1)*DEG)", "length vector"),
        ("VECTOR(1*CM, 1*DEG, 0)", "share one dimension"),
    ],
)
def test_dimension_errors(text: str, fragment: str) -> None:
    error = al_error(f"X ← {text};")
    assert fragment in error.problem


# --------------------------------------------------------------------------------------------
# Values: the operator type table

E200 = "1" + "0" * 200
"""10²⁰⁰: AL numbers have no exponent."""
A_TEXT = "FRAME(ROT(ZHAT,90*DEG),VECTOR(1,2,3))"  # R_z(90°), (1, 2, 3) cm
B_TEXT = "FRAME(NILROTN,VECTOR(2,2,3))"


def test_frame_times_trans_is_frame() -> None:
    f = ev(f"{A_TEXT}*TRANS(ROT(XHAT,90*DEG),VECTOR(1,0,0))")
    assert isinstance(f, V.Pose) and f.kind == "frame"
    # p = (1,2,3) + Rz90·(1,0,0) = (1,3,3) cm; R = Rz90·Rx90
    assert close(f.se3, H(Rz(90) @ Rx(90), (1, 3, 3)))


def test_trans_times_trans_is_trans() -> None:
    t = ev("TRANS(ROT(ZHAT,90*DEG),VECTOR(1,0,0))*TRANS(NILROTN,VECTOR(0,1,0))")
    assert isinstance(t, V.Pose) and t.kind == "trans"
    # p = (1,0,0) + Rz90·(0,1,0) = (1,0,0) + (-1,0,0) = 0
    assert close(t.se3, H(Rz(90), (0, 0, 0)))


def test_inverse_frame_times_frame_is_trans() -> None:
    t = ev(f"INV({A_TEXT})*{B_TEXT}")
    assert isinstance(t, V.Pose) and t.kind == "trans"
    # A⁻¹B: R = Rz(-90); p = Rz(-90)·((2,2,3)-(1,2,3)) = Rz(-90)·(1,0,0) = (0,-1,0) cm
    assert close(t.se3, H(Rz(-90), (0, -1, 0)))


def test_rotations_and_vectors() -> None:
    v = ev("ROT(ZHAT,90*DEG)*XHAT")
    assert isinstance(v, V.Vector) and np.allclose(v.value, [0, 1, 0])
    r = ev("ROT(ZHAT,90*DEG)*ROT(XHAT,90*DEG)")
    assert isinstance(r, V.Rotation) and np.allclose(r.matrix, Rz(90) @ Rx(90))
    # any axis, normalised (S:2723)
    r2 = ev("ROTN(VECTOR(.924,.383,.001),180.*DEG)")
    assert isinstance(r2, V.Rotation)
    assert np.allclose(r2.matrix, axis_angle((0.924, 0.383, 0.001), math.pi))
    angle = ev("|ROT(ZHAT,30*DEG)|")
    assert isinstance(angle, V.Scalar) and angle.dim == V.ANGLE
    assert angle.value == pytest.approx(math.pi / 6)


def test_frame_times_vector_maps_a_point() -> None:
    p = ev(f"{A_TEXT}*VECTOR(1,0,0)")
    assert isinstance(p, V.Vector) and p.dim == V.LENGTH
    assert np.allclose(p.value, np.array([1, 3, 3]) * CM)
    origin = ev(f"{A_TEXT}*VECTOR(0,0,0)")
    assert isinstance(origin, V.Vector) and np.allclose(origin.value, np.array([1, 2, 3]) * CM)


def test_frame_plus_vector_translates_in_world() -> None:
    f = ev(f"{A_TEXT}+VECTOR(0,0,-3*INCHES)")
    assert isinstance(f, V.Pose) and f.kind == "frame"
    assert close(f.se3, H(Rz(90), (1, 2, 3 - 3 * 2.54)))
    g = ev(f"VECTOR(1,0,0)+{A_TEXT}-VECTOR(0,1,0)")
    assert isinstance(g, V.Pose) and close(g.se3, H(Rz(90), (2, 1, 3)))
    t = ev("TRANS(NILROTN,VECTOR(1,0,0))+VECTOR(1,0,0)")
    assert isinstance(t, V.Pose) and t.kind == "trans"


def test_frame_plus_rot_turns_about_own_origin() -> None:
    # §7 decision: F + R = F*TRANS(R, 0) (S:1390 pin+rot(xhat,10*deg))
    f = ev(f"{A_TEXT}+ROT(XHAT,10*DEG)")
    assert isinstance(f, V.Pose) and close(f.se3, H(Rz(90) @ Rx(10), (1, 2, 3)))
    g = ev(f"{A_TEXT}+ROT(XHAT,10*DEG)-ROT(XHAT,10*DEG)")
    assert isinstance(g, V.Pose) and close(g.se3, H(Rz(90), (1, 2, 3)))


def test_vector_arithmetic_and_dot_precedence() -> None:
    s = ev("VECTOR(1,2,3) . VECTOR(4,5,6)")
    assert isinstance(s, V.Scalar) and s.value == 32 and s.dim == V.DIMENSIONLESS
    d = ev("VECTOR(1,2,3)*CM . ZHAT")
    assert isinstance(d, V.Scalar) and d.value == pytest.approx(0.03) and d.dim == V.LENGTH
    # '.' binds looser than '*' and tighter than '-': ZHAT . (INV(F)*DISPL(P)) - C
    x = ev(f"ZHAT . INV({B_TEXT})*DISPL({A_TEXT}) - 1*CM")
    assert isinstance(x, V.Scalar) and x.value == pytest.approx(-0.01)  # 3 - 3 - 1 cm
    n = ev("|VECTOR(3,4,0)*CM - VECTOR(0,0,0)*CM|")
    assert isinstance(n, V.Scalar) and n.value == pytest.approx(0.05) and n.dim == V.LENGTH


def test_orient_displ_and_functions() -> None:
    r = ev(f"ORIENT({A_TEXT})")
    assert isinstance(r, V.Rotation) and np.allclose(r.matrix, Rz(90))
    p = ev(f"DISPL({A_TEXT})")
    assert isinstance(p, V.Vector) and np.allclose(p.value, [0.01, 0.02, 0.03])
    assert sv(ev("SQRT(4*CM*CM)")) == (pytest.approx(0.02), V.LENGTH)
    a = ev("ATAN2(1*CM, 1*CM)")
    assert isinstance(a, V.Scalar) and a.value == pytest.approx(math.pi / 4) and a.dim == V.ANGLE
    c = ev("COS(60*DEG) + SIN(0)")
    assert isinstance(c, V.Scalar) and c.value == pytest.approx(0.5)


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        (f"{A_TEXT} + 1", "cannot add a scalar to a frame"),
        (f"{A_TEXT} * {B_TEXT}", "frame * frame is not defined"),
        (f"ROT(ZHAT,1)*{A_TEXT}", "cannot multiply a rot by a frame"),
        ("XHAT*YHAT", "cannot multiply a vector by a vector"),
        ("1 + XHAT", "cannot add a vector to a scalar"),
        (f"ZHAT . {A_TEXT}", "DISPL"),
        ("NOT 1", "NOT needs a boolean"),
        ("TRUE AND 1", "AND needs two booleans"),
        ("1/0", "division by zero"),
        # overflow is an error at its line as 1/0 is (the fourth hunt: 1e200*1e200 was inf,
        # A − A NaN, and a NaN pose crashed the inverse kinematics with exit 70)
        (f"{E200}*{E200}", "not a finite number"),
        (f"({E200}*{E200}*CM) - ({E200}*{E200}*CM)", "not a finite number"),
        (f"VECTOR({E200}, 0, 0)*{E200}", "not a finite number"),
        (f"ROT(ZHAT, {E200}*{E200})", "not a finite number"),
        ("ROT(NILVECT, 1)", "non-zero"),
        ("INV(1)", "INV needs"),
        ("VECTOR(1,2)", "takes 3 arguments"),
    ],
)
def test_operator_errors(text: str, fragment: str) -> None:
    error = al_error(f"\n  X ← {text};")
    assert fragment in error.problem
    assert error.line == 2 and error.column >= 3
    assert isinstance(error, SynthError)
    assert str(error).startswith("t.al:2:")


def test_assignment_type_checks() -> None:
    assert "cannot assign scalar to frame F" in al_error("FRAME F; F ← 1;").problem
    assert "cannot assign vector to scalar X" in al_error("X ← 1; X ← XHAT;").problem
    assert "predeclared" in al_error("XHAT ← YHAT;").problem
    assert "sensed hand frame" in al_error("BMANIP ← NILTRANS;").problem
    assert "no value yet" in al_error("FRAME F; G ← F;").problem
    assert "unknown name Q" in al_error("X ← Q + 1;").problem
    error = al_error("BEGIN SCALAR X; X ← 1; END; Y ← X;")
    assert error.problem == "unknown name X"  # released with its block
    # MOVE of a name nobody declared says so, as any other use of it does
    assert al_error("MOVE PIN9 TO NILTRANS;").problem == "unknown name PIN9: MOVE needs a frame"
    assert al_error("SCALAR S; S ← 1; MOVE S TO NILTRANS;").problem == (
        "MOVE needs a frame, and S is a SCALAR"
    )


# --------------------------------------------------------------------------------------------
# Affixment


def test_nonrigid_affixment_follows_parent_and_chains() -> None:
    _, it = run(
        f"""FRAME A, B, C;
        A ← {A_TEXT};
        AFFIX B TO A AT TRANS(NILROTN, VECTOR(1,0,0));
        AFFIX C TO B AT TRANS(ROT(XHAT,90*DEG), VECTOR(0,0,2));
        A ← FRAME(NILROTN, VECTOR(10,0,0));"""
    )
    assert close(it.frame("B"), H(np.eye(3), (11, 0, 0)))
    assert close(it.frame("C"), H(Rx(90), (11, 0, 2)))


def test_affix_without_at_keeps_current_relation() -> None:
    _, it = run(
        f"""FRAME A, B; A ← {A_TEXT}; B ← {B_TEXT};
        AFFIX B TO A;
        A ← A + VECTOR(0,0,5);"""
    )
    assert close(it.frame("B"), H(np.eye(3), (2, 2, 8)))
    link = it.affixment("B")
    assert link is not None and link.parent == "A" and not link.rigid
    assert close(link.parent_from_child, H(Rz(-90), (0, -1, 0)))


def test_rigid_affixment_works_both_ways() -> None:
    # seed L1466–1477: spot_on_surface ← pin moves the box and everything affixed to it
    _, it = run(
        """FRAME BOX, SPOT, HOLE, PIN;
        BOX ← FRAME(NILROTN, VECTOR(40,100,0));
        AFFIX SPOT TO BOX RIGIDLY AT TRANS(NILROTN, VECTOR(1,2,4.9));
        AFFIX HOLE TO BOX AT TRANS(NILROTN, VECTOR(3.85,3.2,4.9));
        PIN ← FRAME(NILROTN, VECTOR(41,102,4.6));
        SPOT ← PIN;"""
    )
    # the box drops by 0.3 cm: (41,102,4.6) - (1,2,4.9)
    assert close(it.frame("BOX"), H(np.eye(3), (40, 100, -0.3)))
    assert close(it.frame("HOLE"), H(np.eye(3), (43.85, 103.2, 4.6)))
    # and the other way: moving the box moves the spot
    _, it2 = run(
        """FRAME BOX, SPOT;
        BOX ← FRAME(NILROTN, VECTOR(0,0,0));
        AFFIX SPOT TO BOX RIGIDLY AT TRANS(ROT(ZHAT,90*DEG), VECTOR(1,0,0));
        BOX ← FRAME(ROT(ZHAT,90*DEG), VECTOR(0,0,1));"""
    )
    assert close(it2.frame("SPOT"), H(Rz(180), (0, 1, 1)))


def test_rigid_chain_goes_up_but_nonrigid_parent_stays() -> None:
    # seed L1569 + L1625: in_hole_position rigid to hole, hole non-rigid to box
    _, it = run(
        """FRAME BOX, HOLE, IN_HOLE;
        AFFIX IN_HOLE TO HOLE RIGIDLY AT TRANS(NILROTN, VECTOR(0,0,-1));
        AFFIX HOLE TO BOX AT TRANS(NILROTN, VECTOR(5,4,3));
        BOX ← FRAME(NILROTN, VECTOR(10,10,0));
        IN_HOLE ← FRAME(NILROTN, VECTOR(15.5,14,1.5));"""
    )
    assert close(it.frame("HOLE"), H(np.eye(3), (15.5, 14, 2.5)))
    assert close(it.frame("BOX"), H(np.eye(3), (10, 10, 0)))
    # the hole's relation to the box was re-derived (§7): it now follows from the new place
    _, it2 = run(
        """FRAME BOX, HOLE, IN_HOLE;
        AFFIX IN_HOLE TO HOLE RIGIDLY AT TRANS(NILROTN, VECTOR(0,0,-1));
        AFFIX HOLE TO BOX AT TRANS(NILROTN, VECTOR(5,4,3));
        BOX ← FRAME(NILROTN, VECTOR(10,10,0));
        IN_HOLE ← FRAME(NILROTN, VECTOR(15.5,14,1.5));
        BOX ← BOX + VECTOR(1,0,0);"""
    )
    assert close(it2.frame("HOLE"), H(np.eye(3), (16.5, 14, 2.5)))
    assert close(it2.frame("IN_HOLE"), H(np.eye(3), (16.5, 14, 1.5)))


def test_assigning_nonrigid_child_rederives_relation() -> None:
    _, it = run(
        """FRAME A, B;
        A ← FRAME(NILROTN, VECTOR(0,0,0));
        AFFIX B TO A AT TRANS(NILROTN, VECTOR(1,0,0));
        B ← FRAME(NILROTN, VECTOR(0,5,0));
        A ← FRAME(NILROTN, VECTOR(0,0,2));"""
    )
    assert close(it.frame("B"), H(np.eye(3), (0, 5, 2)))


def test_unfix_keeps_value_either_direction() -> None:
    for unfix in ("UNFIX B FROM A", "UNFIX A FROM B"):
        _, it = run(
            f"""FRAME A, B;
            A ← FRAME(NILROTN, VECTOR(0,0,0));
            AFFIX B TO A AT TRANS(NILROTN, VECTOR(1,0,0));
            {unfix};
            A ← FRAME(NILROTN, VECTOR(0,0,9));"""
        )
        assert close(it.frame("B"), H(np.eye(3), (1, 0, 0)))
        assert it.affixment("B") is None
    assert "not affixed" in al_error("FRAME A, B; A ← NILTRANS; B ← A; UNFIX A FROM B;").problem


def test_affix_before_parent_has_a_value() -> None:
    # seed L1554–1556: pin_withdraw is affixed to pin_holder before pin_holder is assigned
    _, it = run(
        """FRAME PIN_HOLDER, PIN_WITHDRAW;
        AFFIX PIN_WITHDRAW TO PIN_HOLDER AT TRANS(ROT(ZHAT,30*DEG),VECTOR(0,0,4*CM));
        PIN_HOLDER ← FRAME(NILROTN,VECTOR(15*INCHES,10*INCHES,0));"""
    )
    assert close(it.frame("PIN_WITHDRAW"), H(Rz(30), (15 * 2.54, 10 * 2.54, 4)))


def test_affixment_errors() -> None:
    cycle = al_error("FRAME A, B; A ← NILTRANS; B ← A; AFFIX B TO A; AFFIX A TO B;")
    assert "cycle" in cycle.problem
    assert "cannot be affixed" in al_error("FRAME A; A ← NILTRANS; AFFIX BLUE TO A;").problem
    assert "needs both values" in al_error("FRAME A, B; A ← NILTRANS; AFFIX B TO A;").problem
    rigid_hand = al_error("FRAME P; P ← NILTRANS; AFFIX P TO BMANIP RIGIDLY; P ← NILTRANS;")
    assert "rigidly affixed to the hand" in rigid_hand.problem


def test_block_exit_releases_affixments() -> None:
    _, it = run(
        """FRAME A, B;
        A ← FRAME(NILROTN, VECTOR(0,0,0));
        B ← FRAME(NILROTN, VECTOR(1,0,0));
        BEGIN FRAME C; AFFIX C TO A AT NILTRANS; AFFIX B TO C; END;
        A ← FRAME(NILROTN, VECTOR(0,0,7));"""
    )
    assert close(it.frame("B"), H(np.eye(3), (1, 0, 0)))
    assert it.affixment("B") is None


# --------------------------------------------------------------------------------------------
# Motion

START = H(Ry(180), (43.5, 56.9, 10.7))  # BPARK, S:2573


def machine_at(T: np.ndarray = START, **kwargs: float) -> IdealMachine:
    return IdealMachine(pin.SE3(T[:3, :3], T[:3, 3]), **kwargs)


def test_destinations_and_vias_are_evaluated_before_the_motion() -> None:
    m = machine_at()
    result, it = run(
        """MOVE BMANIP TO BMANIP*TRANS(NILROTN,VECTOR(0,0,-5.08))
             VIA BMANIP*TRANS(NILROTN,VECTOR(0,0,-1)), BMANIP+VECTOR(1,0,0);""",
        m,
    )
    assert result.completed
    (command,) = m.commands
    # all three relative to the start; the hand's z axis points down (rot(y,180°))
    shifted = START.copy()
    shifted[0, 3] += 0.01
    expected = [START @ H(np.eye(3), (0, 0, -1)), shifted, START @ H(np.eye(3), (0, 0, -5.08))]
    for target, T in zip(command.targets, expected, strict=True):
        assert close(target, T)
    assert close(it.frame("BLUE"), START @ H(np.eye(3), (0, 0, -5.08)))
    assert close(it.frame("BLUE"), H(Ry(180), (43.5, 56.9, 15.78)))


def test_moving_a_frame_affixed_to_the_hand() -> None:
    m = machine_at()
    _, it = run(
        """FRAME P, Q;
        P ← BMANIP*TRANS(ROT(XHAT,180*DEG),VECTOR(0,0,3));
        AFFIX P TO BMANIP;
        AFFIX Q TO P AT TRANS(NILROTN,VECTOR(0,0,1));
        MOVE Q TO FRAME(NILROTN,VECTOR(10,20,30));""",
        m,
    )
    # Q = hand·T_hp·T_pq, so hand = D·(T_hp·T_pq)⁻¹
    T_hq = H(Rx(180), (0, 0, 3)) @ H(np.eye(3), (0, 0, 1))
    hand = H(np.eye(3), (10, 20, 30)) @ np.linalg.inv(T_hq)
    assert close(m.commands[0].targets[-1], hand)
    assert close(it.frame("Q"), H(np.eye(3), (10, 20, 30)))
    assert close(it.frame("P"), H(np.eye(3), (10, 20, 30)) @ H(np.eye(3), (0, 0, -1)))


def test_moving_a_frame_not_affixed_to_the_hand_is_an_error() -> None:
    error = al_error("FRAME P;\nP ← NILTRANS;\nMOVE P TO NILTRANS;")
    assert error.line == 3 and "not affixed to the hand" in error.problem


def test_open_close_center_take_any_hand_name() -> None:
    m = IdealMachine(grasp_width=0.635 * CM)
    _, it = run(
        "OPEN BHAND TO 2.98; W1 ← OPENING; CLOSE BFINGERS; W2 ← OPENING;"
        "OPEN BLUE TO 1*INCHES; CENTER BMANIP; W3 ← OPENING;",
        m,
    )
    assert sv(it.value("W1")) == (pytest.approx(0.0298), V.LENGTH)
    assert sv(it.value("W2")) == (pytest.approx(0.00635), V.LENGTH)
    assert sv(it.value("W3")) == (pytest.approx(0.00635), V.LENGTH)
    assert [c.kind for c in m.commands] == ["open", "close", "open", "center"]
    assert "not a hand" in al_error("FRAME F; F ← NILTRANS; OPEN F TO 1;").problem


def test_with_clauses_become_constraints() -> None:
    m = IdealMachine()
    run(
        """MOVE BLUE TO NILTRANS
             VIA NILTRANS WITH FORCE(XHAT)=0, DURATION > 2*SEC
             VIA NILTRANS WITH DURATION = 5;""",
        m,
    )
    (command,) = m.commands
    compliance, slow, exact = command.constraints
    assert isinstance(slow, DurationConstraint) and (slow.relation, slow.seconds) == (">", 2.0)
    assert isinstance(compliance, ForceConstraint)
    assert compliance.direction == (1.0, 0.0, 0.0) and compliance.value == 0.0
    assert isinstance(exact, DurationConstraint) and (exact.relation, exact.seconds) == ("=", 5.0)
    assert compliance.segment == 0 and slow.segment == 0 and exact.segment == 1
    assert m.time() == pytest.approx(2 + 5 + 1)  # min 2 s, exactly 5 s, default 1 s


# --------------------------------------------------------------------------------------------
# Monitors on a scripted machine


class ScriptedMachine(IdealMachine):
    """Stops chosen ``move`` calls part-way along their last segment, sensing a given force.

    ``script(n, command)`` for the n-th move (1-based) returns None (the ideal motion) or
    ``(s, force)``: stop at the fraction ``s`` of the last segment, sensing the world force
    vector ``force`` [N] from then on.
    """

    def __init__(
        self,
        script: Callable[[int, MachineCommand], tuple[float, np.ndarray] | None],
        hand: np.ndarray = START,
        **kwargs: float,
    ) -> None:
        super().__init__(pin.SE3(hand[:3, :3], hand[:3, 3]), **kwargs)
        self.script = script
        self.moves = 0
        self.stops = 0

    def contact(
        self, command: MachineCommand, path: Sequence[pin.SE3], knots: Sequence[float]
    ) -> tuple[float, np.ndarray] | None:
        self.moves += 1
        stop = self.script(self.moves, command)
        if stop is None:
            return None
        s, force = stop
        return knots[-2] + s * (knots[-1] - knots[-2]), force

    def stop(self) -> None:
        self.stops += 1
        super().stop()


UP_10_OZ = np.array([0.0, 0.0, 10 * OZ_N])


def test_force_monitor_stop_runs_rest_of_handler_and_continues() -> None:
    m = ScriptedMachine(lambda n, c: (0.25, UP_10_OZ), hand=H(Rx(180), (0, 0, 10)))
    result, it = run(
        """FRAME PIN; PIN ← BMANIP*TRANS(ROT(XHAT,180*DEG),VECTOR(0,0,2));
        AFFIX PIN TO BMANIP;
        HIT ← FALSE; ARRIVED ← FALSE;
        MOVE PIN TO PIN+VECTOR(0,0,-4)
          ON FORCE(ORIENT(PIN)*ZHAT) > 8*OZ DO BEGIN STOP; HIT ← TRUE; END
          ON ARRIVAL DO ARRIVED ← TRUE;
        AFTER ← TRUE;""",
        m,
    )
    assert result.completed and m.stops == 1
    assert it.value("HIT") is True and it.value("ARRIVED") is False and it.value("AFTER") is True
    # the pin (z up, at 8 cm) stopped a quarter of the way down 4 cm: at 7 cm
    assert close(it.frame("PIN"), H(np.eye(3), (0, 0, 7)))
    assert close(it.frame("BMANIP"), H(Rx(180), (0, 0, 9)))
    (monitor,) = m.commands[0].monitors
    assert isinstance(monitor, ForceMonitor)
    assert monitor.threshold == pytest.approx(0.5 * 4.4482216152605)
    assert monitor.direction == pytest.approx((0.0, 0.0, 1.0))


def test_loose_force_direction_uses_rotation_only() -> None:
    # S:1376 force(pin*zhat) means force(orient(pin)*zhat)
    m = ScriptedMachine(lambda n, c: (0.5, UP_10_OZ), hand=H(Rx(180), (0, 0, 10)))
    run(
        """FRAME PIN; PIN ← BMANIP*TRANS(ROT(XHAT,180*DEG),VECTOR(5,5,2));
        AFFIX PIN TO BMANIP;
        MOVE PIN TO PIN+VECTOR(0,0,-4) ON FORCE(PIN*ZHAT) > 8*OZ DO STOP;""",
        m,
    )
    (monitor,) = m.commands[0].monitors
    assert isinstance(monitor, ForceMonitor) and monitor.direction == pytest.approx((0, 0, 1))


def test_arrival_fires_only_when_unstopped() -> None:
    result, _ = run(
        'MOVE BLUE TO NILTRANS ON ARRIVAL DO ABORT("EXPECTED A FORCE HERE");', IdealMachine()
    )
    assert result.abort is not None and result.abort.message == "EXPECTED A FORCE HERE"
    assert result.abort.line == 1
    m = ScriptedMachine(lambda n, c: (0.5, UP_10_OZ))
    result2, _ = run(
        "MOVE BLUE TO NILTRANS ON FORCE(ZHAT) > 8*OZ DO STOP "
        'ON ARRIVAL DO ABORT("EXPECTED A FORCE HERE");',
        m,
    )
    assert result2.completed


def test_unwatched_contact_ends_motion_without_arrival() -> None:
    m = ScriptedMachine(lambda n, c: (0.5, UP_10_OZ), hand=H(np.eye(3), (0, 0, 0)))
    result, it = run("A ← FALSE; MOVE BLUE TO BLUE+VECTOR(0,0,-2) ON ARRIVAL DO A ← TRUE;", m)
    assert result.completed and it.value("A") is False
    assert close(it.frame("BLUE"), H(np.eye(3), (0, 0, -1)))
    assert it.machine.force(np.array([0.0, 0.0, 1.0])) == pytest.approx(10 * OZ_N)


def test_a_monitor_fires_once_and_motion_resumes_without_stop() -> None:
    # FORCE(ZHAT) < 1*OZ holds all along (nothing touched): it fires once, at the start
    result, it = run(
        """N ← 0; T ← 0; A ← FALSE;
        MOVE BLUE TO BLUE+VECTOR(0,0,1) VIA BLUE+VECTOR(0,0,2)
          ON FORCE(ZHAT) < 1*OZ DO N ← N + 1
          ON DURATION > 1.5*SEC DO T ← OPENING
          ON ARRIVAL DO A ← TRUE;""",
        IdealMachine(opening=0.02),
    )
    assert result.completed
    assert it.value("N") == V.Scalar(1.0) and it.value("A") is True
    assert sv(it.value("T")) == (pytest.approx(0.02), V.LENGTH)
    assert result.time == pytest.approx(2.0)


def test_handler_sees_hand_where_monitor_fired() -> None:
    m = IdealMachine(pin.SE3.Identity(), segment_time=2.0)
    _, it = run(
        """FRAME SEEN;
        MOVE BLUE TO BLUE+VECTOR(0,0,10) ON DURATION ≥ 0.5*SEC DO SEEN ← BLUE;""",
        m,
    )
    assert close(it.frame("SEEN"), H(np.eye(3), (0, 0, 2.5)))
    assert close(it.frame("BLUE"), H(np.eye(3), (0, 0, 10)))


def test_abort_in_handler_stops_motion_and_ends_program() -> None:
    m = ScriptedMachine(lambda n, c: (0.5, UP_10_OZ))
    result, it = run(
        """X ← 1;
        MOVE BLUE TO BLUE+VECTOR(0,0,-4)
          ON FORCE(ZHAT) > 8*OZ DO
            ABORT("HIT ", X+1, " AT ", 2*CM);
        X ← 2;""",
        m,
    )
    assert result.abort is not None
    assert result.abort.message == "HIT 2 AT 2 cm" and result.abort.line == 4
    assert it.value("X") == V.Scalar(1.0) and m.stops == 1


def test_center_grasp_check() -> None:
    text = 'OPEN BHAND TO 2.98; CENTER BMANIP ON OPENING < .185 DO BEGIN ABORT("GRASP FAILED"); END'
    failed, _ = run(text, IdealMachine(grasp_width=0.0))
    assert failed.abort is not None and failed.abort.message == "GRASP FAILED"
    m = IdealMachine(grasp_width=0.635 * CM)
    held, _ = run(text, m)
    assert held.completed
    (monitor,) = m.commands[1].monitors
    assert isinstance(monitor, OpeningMonitor)
    assert (monitor.relation, monitor.threshold) == ("<", pytest.approx(0.00185))


def test_monitor_with_sensor_on_the_right_is_flipped() -> None:
    m = IdealMachine()
    run("MOVE BLUE TO NILTRANS ON 2*SEC < DURATION DO STOP;", m)
    (monitor,) = m.commands[0].monitors
    assert isinstance(monitor, DurationMonitor)
    assert (monitor.relation, monitor.threshold) == (">", 2.0)


def test_stop_and_motion_rules() -> None:
    assert "STOP outside" in al_error("STOP;").problem
    nested = al_error(
        "MOVE BLUE TO NILTRANS ON DURATION > 0.1 DO BEGIN MOVE BLUE TO NILTRANS; END;"
    )
    assert "needs STOP first" in nested.problem
    m = IdealMachine()
    result, _ = run(
        """MOVE BLUE TO BLUE+VECTOR(0,0,4) ON DURATION > 0.5 DO
             BEGIN STOP; MOVE BLUE TO NILTRANS; END;""",
        m,
    )
    assert result.completed and [c.kind for c in m.commands] == ["move", "move"]
    bad = al_error("MOVE BLUE TO NILTRANS ON FORCE(ZHAT) + 1 DO STOP;")
    assert "a monitor watches" in bad.problem


# --------------------------------------------------------------------------------------------
# Control


def test_for_loop_algol_semantics() -> None:
    _, it = run("S ← 0; FOR N ← 1 STEP 1 UNTIL 6 DO S ← S + N;")
    assert it.value("S") == V.Scalar(21.0) and it.value("N") == V.Scalar(7.0)
    _, it2 = run("S ← 0; FOR N ← 10 STEP -3 UNTIL 1 DO S ← S + N;")
    assert it2.value("S") == V.Scalar(10 + 7 + 4 + 1)
    # seed L1532: assigning the control variable ends the loop
    _, it3 = run("C ← 0; FOR N ← 1 STEP 1 UNTIL 6 DO BEGIN C ← C + 1; IF N = 3 THEN N ← 7; END;")
    assert it3.value("C") == V.Scalar(3.0)
    _, it4 = run("C ← 0; FOR N ← 1 STEP 1 UNTIL 0 DO C ← C + 1;")
    assert it4.value("C") == V.Scalar(0.0)


def test_while_with_assignment_expression() -> None:
    # S:1600: while (n←n+1) ≤ 6 and not in_hole_flag do ...
    _, it2 = run(
        """N ← 0; C ← 0; FLAG ← FALSE;
        WHILE (N←N+1) ≤ 6 AND NOT FLAG DO BEGIN C ← C + 1; IF N = 4 THEN FLAG ← TRUE; END;"""
    )
    assert it2.value("C") == V.Scalar(4.0) and it2.value("N") == V.Scalar(5.0)
    _, it3 = run("N ← 0; C ← 0; WHILE (N←N+1) ≤ 6 DO C ← C + 1;")
    assert it3.value("C") == V.Scalar(6.0) and it3.value("N") == V.Scalar(7.0)


def test_and_or_evaluate_both_operands() -> None:
    _, it = run("X ← 0; Y ← 0; B ← (X ← 5) < 1 AND (Y ← 6) < 1; C ← TRUE OR FALSE;")
    assert it.value("Y") == V.Scalar(6.0) and it.value("B") is False and it.value("C") is True


def test_conditions_must_be_boolean_and_loops_are_bounded() -> None:
    assert "must be a boolean" in al_error("IF 1 THEN X ← 1;").problem
    with pytest.raises(ALRuntimeError, match="more than 50 statements executed"):
        run("WHILE TRUE DO X ← 1;", max_statements=50)


def test_cobegin_signal_wait() -> None:
    _, it = run(
        """EVENT E; X ← 0;
        COBEGIN
          BEGIN WAIT E; X ← X * 10; END;
          BEGIN X ← X + 1; SIGNAL E; END;
        COEND;"""
    )
    assert it.value("X") == V.Scalar(10.0)
    deadlock = al_error("EVENT E;\nWAIT E;")
    assert deadlock.line == 2 and "deadlock" in deadlock.problem
    _, it2 = run("SIGNAL READY; WAIT READY; X ← 1;")  # implicit global event
    assert it2.value("X") == V.Scalar(1.0)


# --------------------------------------------------------------------------------------------
# World binding (seed_4_8)


@pytest.fixture(scope="module")
def seed_graph() -> AttributeGraph:
    return AttributeGraph(load_task(SEED_TASK))


T_WP = H(Rz(90), (24.1, 117, 0.537))  # pin in the rack, design.md / S:2577
T_BH1 = H(np.eye(3), (45.2 + 3.85, 102 + 3.20, 4.90))  # T_wb ∘ T_bh, S:2575–2576
T_PARK = H(Ry(180), (43.5, 56.9, 10.7))


def test_binding_puts_task_names_at_nominal_poses(seed_graph: AttributeGraph) -> None:
    binding = bind_world(seed_graph)
    it = binding.interpreter(machine_at(T_PARK))
    assert close(it.frame("PIN1"), T_WP)
    assert close(it.frame("BH1"), T_BH1)
    assert close(it.frame("BPARK"), T_PARK)
    assert close(it.frame("BMANIP"), T_PARK) and close(it.frame("BARM"), T_PARK)
    assert set(binding.hand_names) == {"BMANIP", "BLUE", "BARM", "BHAND", "BFINGERS"}
    link = it.affixment("PIN1")
    assert link is not None and link.parent == "RH1" and not link.rigid
    assert close(link.parent_from_child, as_h(seed_graph.links["pin1"].parent_from_child))
    # features follow their object: move the box 1 cm along x
    it.run(parse_program("BOX ← BOX + VECTOR(1,0,0);"))
    assert close(it.frame("BH1"), H(np.eye(3), (50.05, 105.2, 4.9)))


def test_preamble_parses_and_binds_the_same_world(seed_graph: AttributeGraph) -> None:
    text = preamble(seed_graph)
    program = parse_program(text)
    assert "AFFIX PIN1 TO RH1 AT TRANS(NILROTN,VECTOR(0,0," in text
    assert "BPARK ← FRAME(ROT(VECTOR(0,1,0),180*DEG),VECTOR(43.5,56.9,10.7)*CM)" in text
    by_text = Interpreter(machine_at(T_PARK))
    assert by_text.run(program).completed
    for name in ("BOX", "BTOP", "BH1", "BH4", "RACK", "RH1", "PIN1", "BPARK"):
        assert close(
            by_text.frame(name),
            as_h(seed_graph.world_from(seed_graph.resolve(name))) if name != "BPARK" else T_PARK,
        )
    assert close(by_text.frame("PIN1"), T_WP)
    link = by_text.affixment("BH1")
    assert link is not None and link.parent == "BOX"


def test_binding_rigid_and_independent_kinds() -> None:
    graph = AttributeGraph(load_task(TASKS / "screw_on_driver.yaml"))
    binding = bind_world(graph)
    kinds = {a.child: a.rigid for a in binding.affixments}
    assert kinds == {"BTOP": False, "BH1": False, "DRIVER": True, "SCREW": False, "TIP": True}
    it = binding.interpreter(IdealMachine())
    # the tip is rigid to the screw: assigning it moves the screw (and not the driver)
    it.run(parse_program("TIP ← TIP + VECTOR(0,0,1);"))
    screw = as_h(graph.world_from("screw"))
    screw[2, 3] += 0.01
    assert close(it.frame("SCREW"), screw)
    assert close(it.frame("DRIVER"), as_h(graph.world_from("driver")))
    assert "AFFIX TIP TO SCREW RIGIDLY AT" in preamble(graph)


# --------------------------------------------------------------------------------------------
# The seed's generated search program (L2715–2781) on seed_4_8

PIN_DIAMETER = 0.635 * CM
APPROACH, DEPTH, AIM = 2.54, 1.71, 4.25  # cm above the hole / seated depth / aim below
SURFACE = APPROACH / (APPROACH + AIM)  # fraction of the last segment where the tip touches
SEATED = (APPROACH + DEPTH) / (APPROACH + AIM)


def search_program() -> ast.Program:
    return parse_program(SEED_SEARCH.read_text(encoding="utf-8"), filename=str(SEED_SEARCH))


def search_points() -> list[tuple[float, float]]:
    """The (X, Y) offsets [cm] the listing's loops visit, in order (L2752–2770)."""
    points = []
    r = 0.572
    while r <= 1.72:
        w, dw = 0.0, 0.572 / r
        while w < math.radians(359):
            x, y = r * math.cos(w), r * math.sin(w)
            if abs(x) < 1.58 and abs(y) < 1.15:
                points.append((x, y))
            w += dw
        r += 0.572
    return points


def line_of(text: str) -> int:
    lines = SEED_SEARCH.read_text(encoding="utf-8").splitlines()
    return next(i for i, line in enumerate(lines, 1) if text in line)


def attempts(m: IdealMachine) -> list[MachineCommand]:
    return [c for c in m.commands if c.kind == "move" and c.monitors]


def test_search_program_on_the_ideal_machine_aborts_on_arrival(seed_graph: AttributeGraph) -> None:
    # No contact in an ideal world: the first attempt goes all the way, which the generated
    # code treats as a failure (S:2736: aim past the contact, abort on arrival).
    m = machine_at(T_PARK, grasp_width=PIN_DIAMETER)
    result = bind_world(seed_graph).interpreter(m).run(search_program())
    assert result.abort is not None
    assert result.abort.message == "EXPECTED A FORCE HERE"
    assert result.abort.line == line_of('ON ARRIVAL DO ABORT("EXPECTED A FORCE HERE")')
    assert [c.kind for c in m.commands] == ["open", "move", "center", "move", "move"]


def grasp_relation() -> np.ndarray:
    """Hand in pin at the grasp (L2723): trans(rotn((.924,.383,.001),180°), (0,0,3.54) cm)."""
    return H(axis_angle((0.924, 0.383, 0.001), math.pi), (0, 0, 3.54))


def test_search_program_nominal_world_pin_seats_first_time(seed_graph: AttributeGraph) -> None:
    # The believed world: the pin bottoms out at d_f on the first attempt.
    def script(n: int, c: MachineCommand) -> tuple[float, np.ndarray] | None:
        return (SEATED, UP_10_OZ) if c.monitors else None

    m = ScriptedMachine(script, hand=T_PARK, grasp_width=PIN_DIAMETER)
    it = bind_world(seed_graph).interpreter(m)
    result = it.run(search_program())
    assert result.completed
    kinds = ["open", "move", "center", "move", "move", "open", "move"]
    assert [c.kind for c in m.commands] == kinds
    # grasp: hand = T_wp · T_grasp, via 5.08 cm further out along the pin's z
    grasp = T_WP @ grasp_relation()
    assert close(m.commands[1].targets[-1], grasp)
    assert close(m.commands[1].targets[0], T_WP @ H(grasp_relation()[:3, :3], (0, 0, 8.62)))
    # the pin is seated: tip 1.71 cm below the mouth of BH1, turned 90° about z
    seated = T_BH1 @ H(Rz(90), (0, 0, -DEPTH))
    value = it.value("DISTANCE_OFF")
    assert isinstance(value, V.Scalar) and abs(value.value) < 1e-9
    # released, then the hand withdraws 5.08 cm along its own -z (up)
    final = seated @ grasp_relation() @ H(np.eye(3), (0, 0, -5.08))
    assert close(it.frame("BMANIP"), final, atol=1e-9)
    assert it.affixment("PIN1") is None
    assert close(it.frame("PIN1"), seated)


def test_search_program_searches_after_a_miss(seed_graph: AttributeGraph) -> None:
    # First attempt and two search points stop on the surface; the third search point seats.
    lucky = 3

    def script(n: int, c: MachineCommand) -> tuple[float, np.ndarray] | None:
        if not c.monitors:
            return None
        return (SEATED if len(attempts(m)) == 1 + lucky else SURFACE), UP_10_OZ

    m = ScriptedMachine(script, hand=T_PARK, grasp_width=PIN_DIAMETER)
    it = bind_world(seed_graph).interpreter(m)
    result = it.run(search_program())
    assert result.completed
    tries = attempts(m)
    assert len(tries) == 1 + lucky
    # the pin's destination of each search attempt: SETPNT = BH1 ∘ (R_z(1.05 rad)·(X, Y, 0)),
    # then 4.25 cm below it, turned 90°
    hand_in_pin = grasp_relation()
    for (x, y), command in zip(search_points(), tries[1:], strict=False):
        offset = axis_angle((0, 0, 1), 1.05) @ np.array([x, y, 0.0])
        setpnt = T_BH1 @ H(np.eye(3), offset)
        pin_goal = setpnt @ H(Rz(90), (0, 0, -AIM))
        assert close(command.targets[-1], pin_goal @ hand_in_pin)
        assert close(command.targets[0], setpnt @ H(Rz(90), (0, 0, APPROACH)) @ hand_in_pin)
    # the program's own test saw the pin seated at the third search point
    x, y = search_points()[lucky - 1]
    offset = axis_angle((0, 0, 1), 1.05) @ np.array([x, y, 0.0])
    seated = T_BH1 @ H(Rz(90), offset + np.array([0.0, 0.0, -DEPTH]))
    assert close(it.frame("PIN1"), seated)
    assert [c.kind for c in m.commands][-2:] == ["open", "move"]


def test_search_program_gives_up_after_the_whole_pattern(seed_graph: AttributeGraph) -> None:
    def script(n: int, c: MachineCommand) -> tuple[float, np.ndarray] | None:
        return (SURFACE, UP_10_OZ) if c.monitors else None

    m = ScriptedMachine(script, hand=T_PARK, grasp_width=PIN_DIAMETER)
    result = bind_world(seed_graph).interpreter(m).run(search_program())
    assert result.abort is not None and result.abort.message == "PIN1 MISSED BH1"
    assert len(attempts(m)) == 1 + len(search_points())
    # 7 points at R = .572, 13 at 1.144, 4 at 1.716 fall inside the 1.58 × 1.15 cm footprint
    assert len(search_points()) == 24


def test_tap_program_corrects_for_a_box_higher_than_believed() -> None:
    # seed_4_8_tap (L2804–2844): the box is truly 0.5 in higher than believed. The tap stops
    # 1.27 cm early, CORR measures it, and the insertion test subtracts it.
    graph = AttributeGraph(load_task(SEED_TAP_TASK))
    high = 0.5 * 2.54
    tap = (5.08 - high) / (2 * 5.08)  # the tap runs from 5.08 cm above to 5.08 cm below
    seat = (APPROACH + DEPTH - high) / (APPROACH + AIM)

    def script(n: int, c: MachineCommand) -> tuple[float, np.ndarray] | None:
        if not c.monitors:
            return None
        return (tap if len(attempts(m)) == 1 else seat), UP_10_OZ

    m = ScriptedMachine(script, hand=T_PARK, grasp_width=PIN_DIAMETER)
    it = bind_world(graph).interpreter(m)
    path = DATA_AL / "seed_4_8_tap.al"
    result = it.run(parse_program(path.read_text(encoding="utf-8"), filename=str(path)))
    assert result.completed
    assert sv(it.value("CORR")) == (pytest.approx(high * CM), V.LENGTH)
    assert sv(it.value("DISTANCE_OFF")) == (pytest.approx(0.0, abs=1e-12), V.LENGTH)


def test_refined_hand_written_program() -> None:
    # Taylor's refined program (S:1549–1627) with its world: box at (40, 60, 0) cm, park at
    # BPARK. The insertion stops 0.1 cm short of in_hole_position: within ±0.2 in, no search.
    stop_z = 2.1  # cm; in_hole_position is at z = 3 - 1 = 2 cm, the pin descends from 4 cm

    def script(n: int, c: MachineCommand) -> tuple[float, np.ndarray] | None:
        if not any(isinstance(x, ForceMonitor) for x in c.monitors):
            return None
        return (4 - stop_z) / (4 - (2 - 3 * 2.54)), UP_10_OZ

    m = ScriptedMachine(script, hand=T_PARK, grasp_width=PIN_DIAMETER)
    it = Interpreter(m)
    it.define_frame("INITIAL_BOX_POSITION", pin.SE3(np.eye(3), np.array([0.40, 0.60, 0.0])))
    it.define_frame("BPARK", pin.SE3(T_PARK[:3, :3], T_PARK[:3, 3]))
    path = DATA_AL / "seed_2_3_8_refined.al"
    result = it.run(parse_program(path.read_text(encoding="utf-8"), filename=str(path)))
    assert result.completed
    assert [c.kind for c in m.commands] == ["open", "move", "center", "move", "open", "move"]
    T_g = H(Rx(180), (0, 0, 2))  # pin_grasp in pin
    T_a = H(np.eye(3), (0, 0, -3))  # pin_grasp_approach in pin_grasp
    holder = H(np.eye(3), (15 * 2.54, 10 * 2.54, 0))
    grasp, transport, park = m.commands[1], m.commands[3], m.commands[5]
    assert close(grasp.targets[0], holder @ T_g @ T_a) and close(grasp.targets[1], holder @ T_g)
    pin_targets = [
        holder @ H(Rz(30), (0, 0, 4)),  # pin_withdraw
        H(np.eye(3), (45, 64, 4)),  # hole_approach: box + (5,4,3) + (0,0,1)
        H(np.eye(3), (45, 64, 2 - 3 * 2.54)),  # in_hole_position + (0,0,-3 in)
    ]
    for target, expected in zip(transport.targets, pin_targets, strict=True):
        assert close(target, expected @ T_g)
    # after release the hand withdraws via pin_grasp_approach, which followed the pin
    stopped_pin = H(np.eye(3), (45, 64, stop_z))
    assert close(park.targets[0], stopped_pin @ T_g @ T_a)
    assert close(park.targets[1], T_PARK)


def test_a_huge_rotation_axis_keeps_its_direction() -> None:
    # |(1e200, 0, 0)|² overflows; the axis was refused as "a zero vector" (the fourth hunt)
    huge = ev(f"ROT(VECTOR({E200}, 0, 0), 30*DEG)")
    unit = ev("ROT(XHAT, 30*DEG)")
    assert isinstance(huge, V.Rotation) and isinstance(unit, V.Rotation)
    assert np.allclose(huge.matrix, unit.matrix, atol=1e-15)
    tiny = "0." + "0" * 12 + "1"  # 1e-13, below the 1e-12 a zero axis is told by
    assert "non-zero" in al_error(f"\n  X ← ROT(VECTOR({tiny}, 0, 0), 1);").problem
