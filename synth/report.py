"""Human-readable renderings of synth's records (tables with units); no logic beyond layout."""

from __future__ import annotations

import math

from synth.errors.bounds import Interval
from synth.errors.estimate import ErrorReport
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
