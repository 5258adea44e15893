"""Human-readable renderings of synth's records (tables with units); no logic beyond layout."""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from synth.models.spec import WORLD

if TYPE_CHECKING:
    # Annotations only: ``synth replay`` imports this module for its summary, and the
    # referee's start-up must not pay for the estimator's and the planner's modules
    # (tests/test_layers.py checks that importing it loads neither).
    from synth.errors.bounds import Interval
    from synth.errors.contacts import ContactProblem
    from synth.errors.estimate import ErrorReport
    from synth.errors.locate import LocationResult
    from synth.models.graph import AttributeGraph
    from synth.replay.proof import Proof
    from synth.replay.report import ReplayReport
    from synth.replay.run import TrialRecord
    from synth.strategies.records import Destination, PinInHoleStrategy, PlanResult
    from synth.strategies.sequence import SequencePlan

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


def _al_label(graph: AttributeGraph, name: str) -> str:
    """AL name of a frame; the world frame has none and is shown as ``world``."""
    return name if name == WORLD else graph.node(name).al_name


def errors_table(report: ErrorReport, graph: AttributeGraph) -> str:
    """The ``synth errors`` table: first-order (seed) and certified bounds side by side."""
    a, b = _al_label(graph, report.start), _al_label(graph, report.end)
    lines = [
        f"Errors of {a}⁻¹ ∘ {b} ({report.start} → {report.end}), in the frame of {report.start}",
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


def _num(x: float) -> str:
    """A number the way the seed's printouts show it: three significant digits, 0 for ~0."""
    return "0" if abs(x) < 5e-4 else f"{x:.3g}"


def _rotn(rotation: np.ndarray) -> str:
    """``NILROTN``, ``ROTN(ZHAT,90*DEG)`` or ``ROTN(VECTOR(.679,.679,.281),149*DEG)``."""
    import pinocchio as pin

    w = pin.log3(rotation)
    angle = float(np.linalg.norm(w))
    if angle < 1e-9:
        return "NILROTN"
    axis = w / angle
    if abs(axis[2]) > 1 - 1e-9:
        return f"ROTN(ZHAT,{_num(math.degrees(angle) * np.sign(axis[2]))}*DEG)"
    inner = ",".join(_num(float(a)) for a in axis)
    return f"ROTN(VECTOR({inner}),{_num(math.degrees(angle))}*DEG)"


def al_trans(pose: object) -> str:
    """An ``SE3`` as the seed prints it: ``TRANS(ROTN(…),VECTOR(x,y,z))``, lengths in cm."""
    rotation = np.asarray(pose.rotation)  # type: ignore[attr-defined]
    t = np.asarray(pose.translation) * 100  # type: ignore[attr-defined]
    vector = ",".join(_num(float(v)) for v in t)
    return f"TRANS({_rotn(rotation)},VECTOR({vector}))"


def _destination(d: Destination) -> str:
    return f"{d.what}={d.base}*{al_trans(d.xf)}"


def strategy_spec(s: PinInHoleStrategy) -> list[str]:
    """A strategy in the layout of the seed's "PHL SPEC" printouts (L2600–2710).

    Lengths in cm, angles in degrees (the seed's ``PH FP ROT`` was in radians), times in s.
    Each time carries its plain name in brackets (``docs/glossary.md``), since the seed calls
    two different sums GOODNESS.
    """
    g = s.pickup
    lines = [
        f"PHL SPEC {s.name}",
        "PRELIMS: " + (", ".join(s.preliminaries) or "NULL_RECORD"),
        f"PICKUP: PICKUP SPEC {g.object} {g.remarks}",
        "  PRELIMINARIES: " + (", ".join(g.preliminaries) or "NULL_RECORD"),
        f"  APPROACH OPENING: {_num(100 * g.approach_opening)}",
        f"  APPROACH: {_destination(g.approach_point)}",
        f"  GRASP OPENING: {_num(100 * g.grasp_opening)}",
        f"  GRASP: {_destination(g.grasp_point)}",
        "  GRASP DETERM: " + ("NILTRANS" if g.grasp_determination is None else "see record"),
        f"  DEPARTURE POINT: {_destination(g.departure_point)}",
        f"  GOODNESS: {g.pickup_time:.3g}  [pickup_time]",
        f"  REMARKS: {g.remarks}",
        f"APPROACH: {_destination(s.approach)}",
        f"DESTINATION: {_destination(s.destination)}",
        f"TARGET: {_destination(s.target)}",
        f"XPORT TIME: {s.transport_time:.3g}  [transport_time]",
        f"GOODNESS: {s.gross_time:.3g}  [gross_time = pickup_time + transport_time]",
    ]
    if s.tap is None:
        lines.append("TAP: NULL_RECORD")
    else:
        lines.append(
            f"TAP: {_destination(s.tap.place)} ON {s.tap.surface}, clearance "
            f"{_num(100 * s.tap.clearance)}, DZ after tap {_num(100 * s.tap.dz_after)}, "
            f"{s.tap.time:.3g} s"
        )
    if s.search is None:
        lines.append("SEARCH: NULL_RECORD")
    else:
        lines.append(
            f"SEARCH: {s.search.rings} rings of {_num(100 * s.search.step)}, "
            f"{s.search.expected_points} points expected, {s.search.time:.3g} s"
        )
    if s.errors is None:
        lines.append("FINE TIME: (not refined)")
        return lines
    e = s.errors
    lines += [
        f"FINE TIME: {s.fine_time:.3g}  [fine_time]",
        f"TOTAL: {s.expected_time:.3g}  [expected_time]",
        f"PH DZ: {_num(100 * e.dz)}",
        f"PH FP DX: {_num(100 * e.dx)}",
        f"PH FP DY: {_num(100 * e.dy)}",
        f"PH FP ROT: {_num(math.degrees(e.zeta))} deg",
        f"PH DTHETA: {_num(math.degrees(e.dtheta))} deg",
        f"SUCCESS TEST: |DISTANCE_OFF| > {_num(100 * s.success_threshold)}",
    ]
    return lines


_REF = (
    r"(?:seed\s+(?:L\d+(?:[–-]\d+)?|Eqn\.?\s*\d+(?:\.\d+)*|§\s*\d+(?:\.\d+)*"
    r"|ch\.\s*[IVX]+(?:\s*§\s*\d+(?:\.\d+)*)?|App\.\s*\d+|A\.\d+)|\bL\d{4}(?:[–-]\d+)?)"
)
_REF_ALONE = re.compile(rf"\s*\(\s*{_REF}\s*\)")
_REF_FIRST = re.compile(rf"\(\s*{_REF}\s*[,;:]\s*")
_REF_AFTER = re.compile(rf"\s*[,;]\s*{_REF}(?=\s*[),;]|\s*$)", re.MULTILINE)
_REF_ANY = re.compile(rf"\s*{_REF}")


def strip_seed_references(text: str) -> str:
    """``text`` without the seed's line references (``seed L1963``, ``seed Eqn 3.5.1``, ``L2122``).

    The default output of ``synth plan`` is read without the thesis at hand; ``--verbose``
    keeps the references, and ``docs/glossary.md`` lists them. A parenthesis left empty goes,
    and so does a separator left dangling: ``(measured, seed L1963)`` → ``(measured)``,
    ``(seed L2122; --try-harder keeps all)`` → ``(--try-harder keeps all)``,
    ``(seed §4.5.1: grounds for rejection)`` → ``(grounds for rejection)``.
    """
    text = _REF_ALONE.sub("", text)
    text = _REF_FIRST.sub("(", text)
    text = _REF_AFTER.sub("", text)
    return _REF_ANY.sub("", text)


def grasp_words(s: PinInHoleStrategy) -> list[str]:
    """The grasp (ω, γ, d) and the approach (φ), each named once with what it means."""
    g = s.pickup.grasp
    return [
        f"Grasp of {s.pickup.object}: ω = {math.degrees(g.omega):.0f}° (grasp orientation: the "
        "hand's turn about the pin's axis), "
        f"γ = {math.degrees(g.gamma):.0f}° (grasp angle: between the hand's approach axis and "
        f"the pin's axis), d = {100 * g.distance:.2f} cm (grasp distance: from the pin's tip "
        "along its axis to the fingers' centre)",
        f"Approach to {s.hole}: φ = {math.degrees(s.phi):.0f}° (the pin's turn about the "
        f"hole's axis as it goes in), standoff {100 * s.standoff:.2f} cm above the hole, "
        f"aiming {100 * s.dtry:.2f} cm deep (dtry)",
    ]


def _fine_motion(s: PinInHoleStrategy) -> str:
    """The fine motion in words: tap and search with their times, or neither."""
    parts = []
    if s.tap is not None:
        parts.append(f"tap on {s.tap.surface}, {s.tap.time:.2f} s")
    if s.search is not None:
        parts.append(
            f"search {s.search.rings} rings {100 * s.search.step:.3g} cm apart, "
            f"{s.search.expected_points} points expected, {s.search.time:.2f} s"
        )
    return "; then ".join(parts) or "no tap, no search"


def plan_summary(
    result: PlanResult,
    proof: Proof | None = None,
    *,
    records: bool = False,
    verbose: bool = False,
) -> str:
    """The ``synth plan`` text.

    First the decisions, the expected time and the proof in plain words; then the grasp and
    the approach, the errors at the hole, the candidates and the rejections. ``records`` adds
    the chosen strategy's record in the seed's PHL SPEC layout (:func:`strategy_spec`);
    without ``verbose`` the seed's line references are left out
    (:func:`strip_seed_references`).
    """
    s = result.strategy
    lines = [
        f"Plan: {s.name} ({_fine_motion(s)}); lengths in cm, angles in degrees, times in s",
        "",
        "Decisions:",
        *(f"  - {d}" for d in s.decisions),
        "",
        f"Expected time {s.expected_time:.2f} s = pickup {s.pickup_time:.2f} + transport "
        f"{s.transport_time:.2f} + fine {s.fine_time:.2f} + release {s.release_time:.2f}",
    ]
    if proof is not None:
        lines.append(f"Proof: {proof.summary()}")
    lines += ["", *grasp_words(s)]
    if s.errors is not None:
        e = s.errors
        fo = e.first_order
        lines += [
            f"Errors at the hole (certified): footprint ±{_num(100 * e.dx)} × "
            f"±{_num(100 * e.dy)} cm turned ζ = {_num(math.degrees(e.zeta))}° about the hole's "
            f"axis, depth Δz ±{_num(100 * e.dz)} cm, tilt Δθ {_num(math.degrees(e.dtheta))}°; "
            f"a miss is told by |DISTANCE_OFF| > {_num(100 * s.success_threshold)} cm",
            "Errors at the hole (first order, seed Eqn 3.5.1): "
            f"Δx {_num(100 * fo.get('dx', math.nan))}, Δy {_num(100 * fo.get('dy', math.nan))}, "
            f"Δz {_num(100 * fo.get('dz', math.nan))} cm, "
            f"Δθ {_num(math.degrees(fo.get('dtheta', math.nan)))}°",
        ]
    if records:
        lines += ["", "Record (the seed's PHL SPEC layout, L2600–2710):", *strategy_spec(s)]
    width = max([36, *(len(c.name) + 2 for c in result.candidates)])
    lines += [
        "",
        f"Candidates ({len(result.candidates)}; {result.mode} refined {result.refined}, "
        f"minimum refinement cost {result.minimum_refinement_cost:.2f} s):",
        f"  {'candidate':{width}}{'gross':>10}{'fine':>8}{'total':>8}  refinement",
    ]
    for c in result.candidates:
        if c.refined:
            what = ", ".join(
                x for x, on in (("tap", c.tap is not None), ("search", c.search is not None)) if on
            )
            fine, total = f"{c.fine_time:8.2f}", f"{c.expected_time:8.2f}"
        else:
            least = c.gross_time + c.release_time  # and the minimum refinement cost
            what, fine, total = "not refined (cutoff)", f"{'—':>8}", f"{'≥':>4}{least:4.2f}"
        mark = "*" if c is s else " "
        lines.append(f"{mark} {c.name:{width}}{c.gross_time:10.2f}{fine}{total}  {what or 'none'}")
    lines.append(
        "  (gross = pickup + transport; total = gross + fine + release (let go, get clear): "
        "the expected time)"
    )
    lines += ["", f"Rejected ({len(result.rejected)}):"]
    lines += [
        f"  - {r.candidate} [{r.stage or '?'}, {r.kind}]: {r.reason}" for r in result.rejected
    ] or ["  none"]
    counts = ", ".join(f"{k} {v}" for k, v in result.counters.items())
    lines += ["", f"Planning time {result.planning_time:.3f} s ({counts})"]
    text = "\n".join(lines)
    return text if verbose else strip_seed_references(text)


def _fine_words(s: PinInHoleStrategy) -> str:
    """``search 3 rings`` / ``tap`` / ``no tap, no search``: a step's fine motion in words."""
    parts = []
    if s.tap is not None:
        parts.append("tap")
    if s.search is not None:
        parts.append(f"search {s.search.rings} rings, {s.search.expected_points} points expected")
    return ", ".join(parts) or "no tap, no search"


def sequence_summary(
    sequence: SequencePlan, proof: Proof | None = None, *, verbose: bool = False
) -> str:
    """The ``synth plan`` text of an assembly sequence: each step, what reuse saved, the proof.

    The same words as :func:`plan_summary` (expected time, errors at the hole); without
    ``verbose`` the seed's line references are left out.
    """
    lines = [
        f"Assembly sequence of {len(sequence.steps)} steps (order {sequence.order}; "
        f"{sequence.planned} step plans, {sequence.expanded} prefixes expanded); "
        f"expected time {sequence.expected_time:.2f} s",
        "",
    ]
    for k, step in enumerate(sequence.steps, start=1):
        s = step.strategy
        lines.append(
            f"Step {k}: {step.insertion.pin} into {step.insertion.hole} — {s.name}, "
            f"expected time {step.time:.2f} s ({_fine_words(s)})"
        )
        if s.errors is not None:
            lines.append(
                f"  errors at the hole: footprint ±{_num(100 * s.errors.dx)} × "
                f"±{_num(100 * s.errors.dy)} cm,"
                f" Δz ±{_num(100 * s.errors.dz)} cm"
            )
        if isinstance(step.alone, str):
            lines.append(f"  without what the earlier seats taught: refused ({step.alone})")
        elif step.alone is not None:
            a = step.alone.strategy
            before = (
                ""
                if a.errors is None
                else (f"±{_num(100 * a.errors.dx)} × ±{_num(100 * a.errors.dy)} cm, ")
            )
            lines.append(
                f"  without what the earlier seats taught: {before}expected time "
                f"{a.expected_time:.2f} s "
                f"({_fine_words(a)}); saved {step.saved:.2f} s"
            )
        if step.declined is not None:
            kn, faster = step.declined, step.declined_saving
            gain = (
                "has a plan only" if faster == float("inf") else f"is planned {faster:.2f} s faster"
            )
            lines.append(
                f"  {kn.part_al} is not corrected from the seated {kn.pin_al}: the next step "
                f"{gain} on what was known before the reading"
            )
        if step.knowledge is not None and k < len(sequence.steps):
            kn = step.knowledge
            if kn.corrected:
                lines.append(
                    f"  then {kn.part_al} is corrected from the seated {kn.pin_al} along "
                    f"{', '.join(kn.corrected)} (reading error ≤ {_num(100 * kn.epsilon)} cm)"
                )
            else:
                lines.append(
                    f"  {kn.part_al} is not corrected from the seated {kn.pin_al}: it is known "
                    f"better than the reading (error ≤ {_num(100 * kn.epsilon)} cm) on every axis"
                )
    if proof is not None:
        lines += ["", f"Proof: {proof.summary()}"]
    text = "\n".join(lines)
    return text if verbose else strip_seed_references(text)


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f} s"


def replay_summary(report: ReplayReport) -> str:
    """The report as text: the nominal run, its violations, and the Monte Carlo summary."""
    n = report.nominal
    lines = [f"replay {report.program} on task {report.task}"]
    where = f" (line {n.line})" if n.line is not None else ""
    lines.append(
        f"nominal: {n.outcome}{where}: {n.message}; {_seconds(n.time)}, {n.statements} statements"
    )
    for v in n.violations:
        lines.append(f"  violation: {v.kind} at line {v.line}: {v.detail}")
    mc = report.monte_carlo
    if mc.trials:
        lo, hi = mc.interval()
        rate = mc.success_rate or 0.0
        counts = ", ".join(f"{k} {v}" for k, v in mc.outcomes.items())
        lines.append(
            f"Monte Carlo: {mc.trials} trials (seed {mc.seed}): success {100 * rate:.1f}% "
            f"(95% Wilson interval {100 * lo:.1f}–{100 * hi:.1f}%)"
        )
        lines.append(f"  outcomes: {counts}")
        lines.append(f"  time: mean {_seconds(mc.time_mean)}, p95 {_seconds(mc.time_p95)}")
    else:
        lines.append("Monte Carlo: no trials")
    if report.interrupted:
        lines.append(
            f"  interrupted: {mc.trials} of {report.planned} trials done (Ctrl-C); "
            "the figures above are over those"
        )
    return "\n".join(lines)


def trial_text(record: TrialRecord, *, every_hand_error: bool = True) -> str:
    """A trial as text: outcome, AL line, message, time, and the errors it sampled.

    The hand's errors, one per motion target, are all listed, or with ``every_hand_error``
    False (a list of failures) only those of the run's last motion, with a count of the rest.
    A draw prints as ``hand (line 57, target 2)``: the second target (the destination after a
    VIA) of the motion at line 57; ``hand (line 57, visit 3, target 1)`` where the run came to
    that motion more than once (a search loop), at its third.
    """
    run = record.run
    where = f" at line {run.line}" if run.line is not None else ""
    lines = [f"trial {record.index}: {run.outcome}{where}: {run.message}; {run.time:.2f} s"]
    for v in run.violations:
        lines.append(f"  violation: {v.kind} at line {v.line}: {v.detail}")
    for frame, values in record.errors.items():
        lines.append(f"  {frame}: {_error_parts(values.items())}")
    draws = run.hand_errors
    repeated = {d.line for d in draws if d.visit > 1}
    if not every_hand_error and draws:
        first = max(k for k, d in enumerate(draws) if d.target == 1)
        earlier, draws = first, draws[first:]
        if earlier:
            lines.append(
                f"  hand: {earlier} earlier target(s) not shown (--trial {record.index} lists them)"
            )
    for draw in draws:
        where = "" if draw.line is None else f"line {draw.line}, "
        if draw.line in repeated:
            where += f"visit {draw.visit}, "
        lines.append(f"  hand ({where}target {draw.target}): {_error_parts(draw.values)}")
    return "\n".join(lines)


def _error_parts(values: Iterable[tuple[str, float]]) -> str:
    """``x +0.0120 cm, rz -0.2000°``: error parameters [m, rad] in cm and degrees."""
    return ", ".join(
        f"{name} {value * 100:+.4f} cm"
        if name in ("x", "y", "z")
        else f"{name} {math.degrees(value):+.4f}°"
        for name, value in values
    )
