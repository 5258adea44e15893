"""Human-readable renderings of synth's records (tables with units); no logic beyond layout."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from synth.errors.bounds import Interval
from synth.errors.contacts import ContactProblem
from synth.errors.estimate import ErrorReport
from synth.errors.locate import LocationResult
from synth.models.graph import AttributeGraph

_ROWS = (
    ("dx", "Δx", "length"),
    ("dy", "Δy", "length"),
    ("dz", "Δz", "length"),
    ("dtheta_x", "Δθx", "angle"),
    ("dtheta_y", "Δθy", "angle"),
    ("dtheta_z", "Δθz", "angle"),
)


def _fmt(value: float, kind: str) -> str:
    if kind == "length":
        return f"{value * 100:+.3f}"
    return f"{math.degrees(value):+.3f}"


def _interval(iv: Interval, kind: str) -> str:
    unit = "cm" if kind == "length" else "deg"
    return f"{_fmt(iv.lo, kind)} .. {_fmt(iv.hi, kind)} {unit}"


def errors_table(report: ErrorReport, graph: AttributeGraph) -> str:
    """The ``synth errors`` table: first-order (seed) and certified bounds side by side."""
    a, b = graph.node(report.start), graph.node(report.end)
    lines = [
        f"Errors of {a.al_name}⁻¹ ∘ {b.al_name} ({report.start} → {report.end}), "
        f"in the frame of {report.start}",
        f"{len(report.parameters)} error parameters: {', '.join(report.parameters) or 'none'}",
        "",
        f"{'':6}{'first order (seed Eqn 3.5.1)':>32}{'certified (exact chain)':>32}",
    ]
    for key, label, kind in _ROWS:
        lines.append(
            f"{label:6}{_interval(getattr(report.first_order, key), kind):>32}"
            f"{_interval(getattr(report.certified, key), kind):>32}"
        )
    lines.append(
        f"{'tilt':6}{math.degrees(report.first_order.tilt):>28.3f} deg"
        f"{math.degrees(report.certified.tilt):>28.3f} deg"
    )
    return "\n".join(lines)


_AXIS_LABELS = ("x̂", "ŷ", "ẑ")


def _direction_label(v: np.ndarray) -> str:
    """``x̂``, ``−ŷ`` … for a coordinate axis, else the vector to three decimals."""
    for i, name in enumerate(_AXIS_LABELS):
        if abs(abs(v[i]) - 1.0) < 1e-12 and np.sum(np.abs(v)) - abs(v[i]) < 1e-12:
            return ("−" if v[i] < 0 else "") + name
    return "(" + ", ".join(f"{x:.3f}" for x in v) + ")"


def _vector_label(c: np.ndarray, is_length: bool) -> str:
    """The seed's ``5.85·VECTOR(−.760, −.649, .000)`` [cm], or a unit vector as it is."""
    norm = float(np.linalg.norm(c))
    if norm < 1e-15:
        return "0"
    u = c / norm
    inner = "(" + ", ".join(f"{x:.3f}" for x in u) + ")"
    return f"{norm * 100:.2f}·{inner}" if is_length else inner


def constraint_listing(problem: ContactProblem) -> list[str]:
    """The rows of a contact problem in the seed's layout (L3007–3023), lengths in cm.

    E.g. ``x̂·R·5.85·(−0.760, −0.649, 0.000) ≤ 4.000 − x̂·P``.
    """
    out = []
    for row in problem.constraints:
        is_length = bool(np.any(row.position))
        op = "=" if row.equality else "≤"
        rhs = row.rhs * 100 if is_length else row.rhs
        text = f"{_direction_label(row.direction)}·R·{_vector_label(row.vector, is_length)} "
        text += f"{op} {rhs:.3f}"
        if is_length:
            text += f" − {_direction_label(row.position)}·P"
        out.append(f"{text}    [contacts[{problem.indices[row.contact]}] {row.role}]")
    return out


def _range(iv: Interval, kind: str) -> str:
    if kind == "length":
        return f"{iv.lo * 100:+9.3f} .. {iv.hi * 100:+9.3f} cm"
    return f"{math.degrees(iv.lo):+9.3f} .. {math.degrees(iv.hi):+9.3f} deg"


def locate_report(
    results: Sequence[LocationResult], graph: AttributeGraph, *, constraints: bool = False
) -> str:
    """The ``synth locate`` text: per object its estimates in the seed's terms (L2979–2985)."""
    if not results:
        return "no object is located by contacts in this task"
    lines: list[str] = []
    for res in results:
        p = res.problem
        obj, ref = graph.node(p.obj), graph.node(p.reference)
        used = ", ".join(f"contacts[{i}]" for i in p.indices)
        lines += [
            f"{p.obj} ({obj.al_name}) in {p.reference} ({ref.al_name}), by {used}: "
            f"{len(p.constraints)} constraints",
            f"  P = (X, Y, Z): origin of {p.obj} in {p.reference}; W: rotation about "
            f"{_direction_label(p.axis)} of {p.obj} (outward normal of {p.rest_face}), "
            "R = R_align·rot(n̂, W)",
        ]
        if constraints:
            lines += ["  " + row for row in constraint_listing(p)]
        if not res.estimates:
            lines += ["  no pose satisfies these contacts", ""]
            continue
        n = len(res.estimates)
        lines.append(
            f"  {n} estimate{'s' if n > 1 else ''}"
            + (" (separate gross orientations)" if n > 1 else "")
        )
        for k, e in enumerate(res.estimates, 1):
            lines += [
                f"  estimate {k}:",
                f"    X {_range(e.x, 'length')}",
                f"    Y {_range(e.y, 'length')}",
                f"    Z {_range(e.z, 'length')}",
                f"    W {_range(e.w, 'angle')}",
                f"    cos W0 = {math.cos(e.w0):.3f}  sin W0 = {math.sin(e.w0):.3f}  "
                f"cos DW = {math.cos(e.dw):.3f}  R = {math.sin(e.dw):.3f}",
            ]
        if res.link is not None:
            unc = res.link.uncertainty
            t = res.link.nominal.translation * 100
            parts = [
                f"{name} ±{b.hi * 100:.3f} cm"
                if name in ("x", "y", "z")
                else f"{name} ±{math.degrees(b.hi):.3f} deg"
                for name, b in unc.bounds().items()
            ]
            lines += [
                f"  derived link {p.reference} → {p.obj}: translation "
                f"({t[0]:.3f}, {t[1]:.3f}, {t[2]:.3f}) cm, "
                f"W0 = {math.degrees(res.estimates[0].w0):.3f} deg",
                f"    uncertainty: {', '.join(parts) or 'none (exact)'}; "
                f"{len(unc.constraints)} coupled constraints",
            ]
        lines.append("")
    return "\n".join(lines).rstrip()
