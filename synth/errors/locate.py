"""Location estimates from contacts: bounds of X, Y, Z, W by linear programming (seed A.1).

Seed ch. III (L1780–1800): "techniques were developed for expressing 'semantic' relations
between object features in terms of mathematical constraints on scalar 'degrees of freedom' and
for applying linear programming techniques to predict limits"; appendix A.1 (L2938–3156) shows
"the output estimates that result from application of the iterative method". This module is
that method, made sound.

**Arc relaxation.** The rows of :mod:`synth.errors.contacts` are linear in (P, cos w, sin w).
On an arc ``w = w₀ + δ``, ``|δ| ≤ D < 90°``, write ``u = cos δ``, ``v = sin δ``; then
``cos w = u cos w₀ − v sin w₀`` and ``sin w = u sin w₀ + v cos w₀`` and every row is linear in
(P, u, v). The arc's points satisfy (the seed prints ``COS(W0)``, ``SIN(W0)``, ``COS(DW)`` and
``R = sin D``, L2984–2985)::

    cos D ≤ u ≤ 1,   −sin D ≤ v ≤ sin D,   u cos tⱼ + v sin tⱼ ≤ 1  (tangents, tⱼ ∈ [−D, D])

so the LP over (P, u, v) contains every feasible pose with w on the arc: its optima are sound
bounds. The polygon lies within ``1/cos(Δt/2) − 1`` of the arc, so the bounds are exact to
O(D²) (e.g. the seed's X bound 4 − b·cos D instead of 4 − b, L2980).

**Iteration (contraction).** ``max v`` and ``min v`` bound sin δ, hence δ ∈ [asin v_min,
asin v_max]; re-centre the arc there and repeat until the interval stops shrinking (the seed's
iteration, which re-centres W0 each time, L3101). A fixed point D* satisfies the extreme-rotation
equation exactly (first problem: ``b cos D* + a sin D* = 4 cm``, so W = 90° ± 2.627°, L2983).

**Gross orientation.** The circle is cut into sectors; each is contracted, bisected while its
ends are not genuinely feasible (an exact LP in P at fixed w), and dropped when the relaxation
is infeasible. Contracted arcs that touch are merged; what remains are the separate estimates
(the seed's ITEM416 and ITEM417, L2979 and L3052).

**Bounds.** X, Y, Z (and any direction d·P) are bounded over each estimate by splitting its arc
into pieces no wider than ``piece_width`` and taking the hull of the per-piece LP optima; with
one piece per estimate this is the seed's single relaxation. Every reported bound is rounded
outwards by ``pad``.

:func:`derive_link` turns one estimate into a nominal pose and an
:class:`~synth.models.uncertainty.Uncertainty` (bounds plus coupled linear constraints) — the same
input the error chains take from a hand-typed block; :func:`resolve_contacts` does so for a
task, and :func:`located_graph` is the hook :func:`synth.errors.chain.chain_between` calls.
"""

from __future__ import annotations

import itertools
import math
import weakref
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.optimize import linprog

from synth.errors.bounds import Interval
from synth.errors.contacts import ContactProblem, TrigForm, build_contact_problem
from synth.exceptions import EstimationError
from synth.models.contacts import ContactSpec
from synth.models.features import contact_groups
from synth.models.graph import AttributeGraph
from synth.models.spec import TaskSpec
from synth.models.spec_fields import Pose
from synth.models.uncertainty import Uncertainty

_HIGHS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}
_ROT_PARAMS = ("rx", "ry", "rz")
_TRANS_PARAMS = ("x", "y", "z")


@dataclass(frozen=True)
class LocateOptions:
    """Options of :func:`locate`; angles [rad], lengths [m].

    ``piece_width = math.inf`` bounds each estimate with one relaxation, as the seed does.
    ``equality_tolerance`` turns each equality of positional rows into a pair of inequalities
    ± that much (the seed uses .001 cm, L3061); 0 keeps them exact.
    """

    sectors: int = 24
    piece_width: float = math.radians(0.5)
    max_pieces: int = 64
    tangents: int = 5
    tolerance: float = 1e-12
    max_iterations: int = 100
    max_depth: int = 12
    min_width: float = 1e-7
    merge_gap: float = 1e-9
    equality_tolerance: float = 0.0
    pad: float = 1e-9


SEED_OPTIONS = LocateOptions(piece_width=math.inf, equality_tolerance=0.0)
"""One relaxation per estimate, like the seed's printed figures (module docstring)."""


@dataclass(frozen=True)
class LocationEstimate:
    """One orientation branch (the seed's ``ITEM``, L2979): bounds in the reference frame.

    ``x``, ``y``, ``z`` [m] bound the object's origin P; ``w`` [rad] the rotation about the
    outward normal of its resting face (R = R_align · rot(n̂_a, w)).
    """

    x: Interval
    y: Interval
    z: Interval
    w: Interval
    iterations: int

    @property
    def w0(self) -> float:
        """Centre of the rotation interval [rad] (the seed's W0)."""
        return 0.5 * (self.w.lo + self.w.hi)

    @property
    def dw(self) -> float:
        """Half-width of the rotation interval [rad] (the seed's DW; R = sin DW)."""
        return 0.5 * (self.w.hi - self.w.lo)

    def to_json(self) -> dict[str, object]:
        """JSON shape (SI units) of one estimate in ``synth locate --json``."""
        return {
            "x": self.x.as_list(),
            "y": self.y.as_list(),
            "z": self.z.as_list(),
            "w": self.w.as_list(),
            "w0": self.w0,
            "dw": self.dw,
            "iterations": self.iterations,
        }


@dataclass(frozen=True, eq=False)
class LocationResult:
    """Every estimate of one object's location (one per gross orientation)."""

    problem: ContactProblem
    estimates: tuple[LocationEstimate, ...]
    options: LocateOptions = field(default_factory=LocateOptions)
    link: DerivedLink | None = None
    """The derived pose and block when there is exactly one, bounded, estimate."""

    def to_json(self) -> dict[str, object]:
        """JSON shape of one object in ``synth locate --json`` (SI units)."""
        p = self.problem
        out: dict[str, object] = {
            "object": p.obj,
            "reference": p.reference,
            "contacts": list(p.indices),
            "rest_face": p.rest_face,
            "axis": p.axis.tolist(),
            "align": p.align.tolist(),
            "constraints": len(p.constraints),
            "estimates": [e.to_json() for e in self.estimates],
        }
        if self.link is not None:
            out["link"] = {
                "parent": p.reference,
                "pose": self.link.pose_json(),
                "uncertainty": self.link.uncertainty_json(),
            }
        return out


@dataclass(frozen=True, eq=False)
class Relaxation:
    """The LP over z = (P/L, u, v) for the arc w = w₀ + δ, |δ| ≤ D (module docstring)."""

    a_ub: np.ndarray
    b_ub: np.ndarray
    a_eq: np.ndarray
    b_eq: np.ndarray
    bounds: tuple[tuple[float | None, float | None], ...]
    w0: float
    half_width: float
    scale: float


def build_relaxation(
    form: TrigForm, w0: float, half_width: float, scale: float, options: LocateOptions
) -> Relaxation:
    """The relaxation LP of ``form`` on the arc ``|w − w0| ≤ D``.

    D = ``half_width`` [rad], 0 ≤ D < π/2; P is scaled by ``scale`` [m]; every row is
    normalised to unit max coefficient.
    """
    d = float(half_width)
    if not 0.0 <= d < math.pi / 2:
        raise ValueError("arc half-width must be in [0, 90°)")
    c0, s0 = math.cos(w0), math.sin(w0)
    cu = form.kc * c0 + form.ks * s0  # coefficient of u
    cv = -form.kc * s0 + form.ks * c0  # coefficient of v
    rows = np.column_stack([form.position * scale, cu, cv])
    rhs = form.rhs - form.k0
    eq = form.equality
    a_ub = [rows[~eq]]
    b_ub = [rhs[~eq]]
    a_eq, b_eq = rows[eq], rhs[eq]
    if options.equality_tolerance > 0 and a_eq.shape[0]:
        tol = options.equality_tolerance * (np.abs(form.position[eq]).sum(axis=1) > 0)
        a_ub += [a_eq, -a_eq]
        b_ub += [b_eq + tol, -(b_eq - tol)]
        a_eq, b_eq = np.zeros((0, 5)), np.zeros(0)
    ts = np.linspace(-d, d, max(options.tangents, 1)) if d > 0 else np.zeros(0)
    arc = np.zeros((len(ts) + 1, 5))
    arc[:-1, 3], arc[:-1, 4] = np.cos(ts), np.sin(ts)
    arc[-1, 3] = -1.0
    a_ub.append(arc)
    b_ub.append(np.concatenate([np.ones(len(ts)), [-math.cos(d)]]))
    a, b = _normalised(np.vstack(a_ub), np.concatenate(b_ub))
    ae, be = _normalised(a_eq, b_eq)
    bounds = ((None, None),) * 3 + ((math.cos(d), 1.0), (-math.sin(d), math.sin(d)))
    return Relaxation(a, b, ae, be, bounds, float(w0), d, float(scale))


def _normalised(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    norm = np.abs(a).max(axis=1) if a.shape[0] else np.zeros(0)
    norm = np.where(norm > 0, norm, 1.0)
    return a / norm[:, None], b / norm


def solve_relaxation(lp: Relaxation, objective: np.ndarray) -> Interval | None:
    """``[min, max]`` of ``objective · z`` over the relaxation; None if it is infeasible.

    Unbounded directions give ±inf. Raises :class:`EstimationError` if HiGHS fails otherwise.
    """
    out = []
    for sense in (1.0, -1.0):
        res = linprog(
            sense * np.asarray(objective, dtype=float),
            A_ub=lp.a_ub if lp.a_ub.shape[0] else None,
            b_ub=lp.b_ub if lp.a_ub.shape[0] else None,
            A_eq=lp.a_eq if lp.a_eq.shape[0] else None,
            b_eq=lp.b_eq if lp.a_eq.shape[0] else None,
            bounds=lp.bounds,
            method="highs",
            options=_HIGHS,
        )
        if res.status == 2:
            return None
        if res.status == 3:
            out.append(-sense * math.inf)
            continue
        if res.status != 0:
            raise EstimationError(f"location LP failed: {res.message}")
        out.append(sense * float(res.fun))
    return Interval(out[0], out[1])


class _Locator:
    """The iterative method on one problem (module docstring); holds the scaled trig form."""

    def __init__(self, problem: ContactProblem, options: LocateOptions) -> None:
        self.problem = problem
        self.options = options
        self.form = problem.trig_form()
        self.scale = problem.length_scale
        self.iterations = 0
        self.guard = options.pad / 10  # [rad] outward rounding of each contraction step

    def relaxation(self, lo: float, hi: float) -> Relaxation:
        return build_relaxation(
            self.form, 0.5 * (lo + hi), 0.5 * (hi - lo), self.scale, self.options
        )

    def contract(self, lo: float, hi: float) -> tuple[float, float] | None:
        """Shrink [lo, hi] to the rotations the relaxation allows; None if it allows none."""
        e_v = np.array([0.0, 0.0, 0.0, 0.0, 1.0])
        for it in range(self.options.max_iterations):
            self.iterations += 1
            lp = self.relaxation(lo, hi)
            sv = solve_relaxation(lp, e_v)
            if sv is None:
                return None
            new_lo = max(lo, lp.w0 + math.asin(min(1.0, max(-1.0, sv.lo))) - self.guard)
            new_hi = min(hi, lp.w0 + math.asin(min(1.0, max(-1.0, sv.hi))) + self.guard)
            gain = (hi - lo) - (new_hi - new_lo)
            lo, hi = new_lo, min(max(new_hi, new_lo), hi)
            if gain <= self.options.tolerance or (it >= 3 and gain < 1e-4 * (hi - lo)):
                break
        return lo, hi

    def feasible_at(self, w: float) -> bool:
        """Whether some P satisfies every row at this exact w (an LP in P alone)."""
        lp = build_relaxation(self.form, w, 0.0, self.scale, self.options)
        return solve_relaxation(lp, np.zeros(5)) is not None

    def branch(self, lo: float, hi: float, depth: int = 0) -> list[tuple[float, float]]:
        """Contract [lo, hi]; bisect while its ends are not genuinely feasible."""
        got = self.contract(lo, hi)
        if got is None:
            return []
        lo, hi = got
        width = hi - lo
        if width <= self.options.min_width or depth >= self.options.max_depth:
            return [(lo, hi)]
        inset = min(10 * self.guard, width / 4)
        if self.feasible_at(lo + inset) and self.feasible_at(hi - inset):
            return [(lo, hi)]
        mid = 0.5 * (lo + hi)
        return self.branch(lo, mid, depth + 1) + self.branch(mid, hi, depth + 1)

    def orientations(self) -> list[tuple[float, float]]:
        """Disjoint rotation intervals (gross orientations) that may hold feasible poses."""
        edges = np.linspace(-math.pi, math.pi, self.options.sectors + 1)
        arcs: list[tuple[float, float]] = []
        for lo, hi in itertools.pairwise(edges):
            arcs += self.branch(float(lo), float(hi))
        merged = _merge(sorted(arcs), self.options.merge_gap)
        out = []
        for lo, hi in merged:
            if hi - lo < math.pi * 0.9:
                got = self.contract(lo, hi)
                if got is None:
                    continue
                lo, hi = got
            out.append((lo, hi))
        return out

    def pieces(self, lo: float, hi: float) -> list[tuple[float, float]]:
        width = hi - lo
        n = (
            1
            if not math.isfinite(self.options.piece_width)
            else math.ceil(width / self.options.piece_width)
        )
        n = max(1, min(n, self.options.max_pieces))
        if width / n >= math.pi * 0.9:
            n = math.ceil(width / (math.pi * 0.9))
        edges = np.linspace(lo, hi, n + 1)
        return [(float(a), float(b)) for a, b in itertools.pairwise(edges)]

    def bound_directions(
        self, lo: float, hi: float, directions: np.ndarray
    ) -> list[Interval] | None:
        """Bounds of ``d·P`` [m] over w ∈ [lo, hi], for each row d of ``directions``.

        The hull of the per-piece LP optima, padded; None if every piece is infeasible.
        """
        found: list[Interval] | None = None
        for a, b in self.pieces(lo, hi):
            lp = self.relaxation(a, b)
            ivs = []
            for d in directions:
                iv = solve_relaxation(lp, np.concatenate([np.asarray(d) * self.scale, [0.0, 0.0]]))
                if iv is None:
                    break
                ivs.append(iv)
            else:
                found = (
                    ivs
                    if found is None
                    else [
                        Interval(min(f.lo, g.lo), max(f.hi, g.hi))
                        for f, g in zip(found, ivs, strict=True)
                    ]
                )
        if found is None:
            return None
        pad = self.options.pad
        return [Interval(iv.lo - pad, iv.hi + pad) for iv in found]


def _merge(arcs: list[tuple[float, float]], gap: float) -> list[tuple[float, float]]:
    """Merge touching arcs; an arc ending at +π joins one starting at −π (wrap-around)."""
    out: list[list[float]] = []
    for lo, hi in arcs:
        if out and lo - out[-1][1] <= gap:
            out[-1][1] = max(out[-1][1], hi)
        else:
            out.append([lo, hi])
    if len(out) > 1 and out[0][0] <= -math.pi + gap and out[-1][1] >= math.pi - gap:
        first = out.pop(0)
        out[-1] = [out[-1][0], first[1] + 2 * math.pi]
    return [(a, b) for a, b in out]


def locate(problem: ContactProblem, options: LocateOptions | None = None) -> LocationResult:
    """Every estimate of the pose of ``problem.obj`` allowed by its contact rows.

    The estimates are sound (they contain every pose satisfying the rows exactly) and, with the
    default options, within about b·(1 − cos(piece_width/2)) of the exact extremes.
    """
    opts = options or LocateOptions()
    loc = _Locator(problem, opts)
    estimates = []
    eye = np.eye(3)
    for lo, hi in loc.orientations():
        ivs = loc.bound_directions(lo, hi, eye)
        if ivs is None:
            continue
        w = Interval(lo - opts.pad, hi + opts.pad)
        w = _normal_angles(w)
        estimates.append(LocationEstimate(ivs[0], ivs[1], ivs[2], w, loc.iterations))
    result = LocationResult(problem, tuple(estimates), opts)
    if len(estimates) == 1 and all(
        math.isfinite(b) for iv in (estimates[0].x, estimates[0].y) for b in (iv.lo, iv.hi)
    ):
        result = replace(result, link=derive_link(result))
    return result


def _normal_angles(w: Interval) -> Interval:
    """Shift an interval by 2πk so that its centre lies in (−π, π]."""
    c = 0.5 * (w.lo + w.hi)
    k = math.floor((math.pi - c) / (2 * math.pi))
    shift = 2 * math.pi * k
    if c + shift <= -math.pi:
        shift += 2 * math.pi
    return Interval(w.lo + shift, w.hi + shift)


def locate_objects(
    spec: TaskSpec,
    contacts: Sequence[ContactSpec] | None = None,
    options: LocateOptions | None = None,
    objects: Iterable[str] | None = None,
) -> tuple[LocationResult, ...]:
    """Estimates for every object located by ``contacts`` (default: the task's).

    Objects come in the order of their first contact; ``objects`` restricts to some of them
    (frame or AL names).
    """
    graph = AttributeGraph(spec)
    cs = tuple(spec.contacts if contacts is None else contacts)
    groups = contact_groups(graph, cs)
    wanted = None if objects is None else {graph.resolve(o) for o in objects}
    out = []
    for obj, idx in groups.items():
        if wanted is not None and obj not in wanted:
            continue
        problem = build_contact_problem(graph, obj, [cs[i] for i in idx], idx)
        out.append(locate(problem, options))
    return tuple(out)


@dataclass(frozen=True, eq=False)
class DerivedLink:
    """Nominal pose (in the reference object's frame) and uncertainty block of a located object.

    The true pose is ``nominal ∘ transl(x, y, z) ∘ rot(axis, r)`` — the perturbation of
    :mod:`synth.errors.chain`, with ``r`` the parameter of the object-frame axis along n̂_a.
    """

    obj: str
    parent: str
    nominal: pin.SE3
    uncertainty: Uncertainty
    pose: Pose

    def pose_json(self) -> dict[str, object]:
        """``{translation: [m]×3, rotation: 3×3}``."""
        return {
            "translation": self.nominal.translation.tolist(),
            "rotation": self.nominal.rotation.tolist(),
        }

    def uncertainty_json(self) -> dict[str, object]:
        """Bounds [m, rad] and coupled constraints ``Σ c_k v_k ≤ max`` of the derived block."""
        u = self.uncertainty
        return {
            "bounds": {k: [b.lo, b.hi] for k, b in u.bounds().items()},
            "constraints": [
                {"terms": dict(c.terms), "min": c.min, "max": c.max, "kind": c.kind}
                for c in u.constraints
            ],
        }


def derive_link(
    result: LocationResult, branch: int = 0, exact_width: float | None = None
) -> DerivedLink:
    """The estimate ``branch`` of ``result`` as a nominal pose and an uncertainty block.

    Nominal: w₀ the centre of the W interval, P₀ the centre of the bounds of the error
    translation e = R₀ᵀ(P − P₀) (object frame). Bounds of e by the piecewise LP; r = σ(w − w₀)
    for n̂_a = σ·(object axis k). Each contact row ``g·P + φ(w) ≤ rhs`` becomes
    ``(R₀ᵀg)·e + β r ≤ rhs − g·P₀ − α + s⁻`` with α + βr the chord of φ on [−r̄, r̄] and s⁻ its
    sag, ``max|φ''|·r̄²/2`` (φ'' = −φ, zero sag on the side where φ's sign makes it concave or
    convex); equalities give both sides. Parameters whose interval is narrower than
    ``exact_width`` (default 10 · pad) are treated as exact, their slack moved into the rows.
    """
    p, est, opts = result.problem, result.estimates[branch], result.options
    tiny = 10 * opts.pad if exact_width is None else exact_width
    loc = _Locator(p, opts)
    w_nom = est.w0
    r_nom = p.rotation(w_nom)
    p_ref = np.array([0.5 * (iv.lo + iv.hi) for iv in (est.x, est.y, est.z)])
    ivs = loc.bound_directions(est.w.lo, est.w.hi, r_nom.T)
    if ivs is None:
        raise EstimationError(f"{p.obj}: estimate {branch} has no feasible pose")
    e_mid = np.array([0.5 * (iv.lo + iv.hi) - r_nom[:, i] @ p_ref for i, iv in enumerate(ivs)])
    e_half = np.array([0.5 * (iv.hi - iv.lo) for iv in ivs])
    if not all(math.isfinite(h) for h in (*e_half, *p_ref)):
        raise EstimationError(
            f"{p.obj}: its position is unbounded by its contacts; add contacts (e.g. inside_of) "
            "that bound it"
        )
    p_nom = p_ref + r_nom @ e_mid
    k = int(np.argmax(np.abs(p.axis)))
    sigma = 1.0 if p.axis[k] > 0 else -1.0
    r_half = est.dw
    if r_half >= math.pi / 2:  # no error block certifies a turn of 90° or more
        where = ", ".join(f"contacts[{i}]" for i in p.indices)
        turn = "" if r_half >= math.pi - 1e-9 else f" ±{math.degrees(r_half):.3g}°"
        raise EstimationError(
            f"{where}: these contacts leave {p.obj!r} free to turn{turn} about the normal of "
            f"{p.rest_face}; add a contact that fixes its orientation (against a wall or an "
            "edge), or give its pose and uncertainty instead"
        )
    keep_e = [i for i in range(3) if 2 * e_half[i] > tiny]
    keep_r = 2 * r_half > tiny
    r_name = _ROT_PARAMS[k]

    bounds: dict[str, Any] = {}
    for i in keep_e:
        bounds[_TRANS_PARAMS[i]] = [_q(-e_half[i], "m"), _q(e_half[i], "m")]
    if keep_r:
        bounds[r_name] = [_q(-r_half, "rad"), _q(r_half, "rad")]

    constraints = []
    form = p.trig_form()
    hull = [(np.eye(3)[i], iv) for i, iv in enumerate((est.x, est.y, est.z))]
    for j in range(len(form.rhs)):
        g, k0, kc, ks = form.position[j], form.k0[j], form.kc[j], form.ks[j]
        eq = bool(form.equality[j])
        if not np.any(g):
            continue  # rotation-only rows (cones, alignment): already in the W bounds
        gp = r_nom.T @ g
        const = float(form.rhs[j] - g @ p_nom - k0)
        alpha, beta, s_lo, s_hi = _chord(kc, ks, w_nom, sigma, r_half if keep_r else 0.0)
        slack_e = sum(abs(gp[i]) * e_half[i] for i in range(3) if i not in keep_e)
        slack_r = 0.0 if keep_r else math.hypot(kc, ks) * r_half
        sides = [(1.0, const - alpha + s_lo + slack_e + slack_r)]
        if eq:
            sides.append((-1.0, -(const - alpha - s_hi) + slack_e + slack_r))
        for sign, rhs in sides:
            terms: dict[str, Any] = {
                _TRANS_PARAMS[i]: float(sign * gp[i]) for i in keep_e if abs(gp[i]) > 1e-15
            }
            if keep_r and abs(beta) > 1e-15:
                terms[r_name] = _q(sign * beta, "m/rad")
            if terms:
                constraints.append({"terms": terms, "max": _q(rhs + opts.pad, "m")})
    for d, iv in hull:  # the bounds of X, Y, Z in the reference frame, as rows on e
        gp = r_nom.T @ d
        base = float(d @ p_nom)
        terms_hi = {_TRANS_PARAMS[i]: float(gp[i]) for i in keep_e if abs(gp[i]) > 1e-15}
        if not terms_hi or not (math.isfinite(iv.lo) and math.isfinite(iv.hi)):
            continue
        slack = sum(abs(gp[i]) * e_half[i] for i in range(3) if i not in keep_e)
        constraints.append({"terms": terms_hi, "max": _q(iv.hi - base + slack, "m")})
        constraints.append(
            {"terms": {n: -c for n, c in terms_hi.items()}, "max": _q(base - iv.lo + slack, "m")}
        )

    unc = Uncertainty.model_validate({**bounds, "constraints": constraints if bounds else []})
    rpy = pin.rpy.matrixToRpy(r_nom)
    rotation = [
        {"axis": ax, "angle": _q(a, "rad")}
        for ax, a in zip("zyx", (rpy[2], rpy[1], rpy[0]), strict=True)
        if a != 0.0
    ]
    pose = Pose.model_validate({"translation": [_q(x, "m") for x in p_nom], "rotation": rotation})
    return DerivedLink(p.obj, p.reference, pin.SE3(r_nom, p_nom), unc, pose)


def _q(value: float, unit: str) -> str:
    """A quantity string the spec models parse back to the same float: ``'0.0123 m'``."""
    return f"{float(value)!r} {unit}"


def _chord(
    kc: float, ks: float, w_nom: float, sigma: float, half: float
) -> tuple[float, float, float, float]:
    """Chord α + βr of φ(r) = k_c cos(w₀ + σr) + k_s sin(w₀ + σr) on [−h, h] and its sags.

    Returns (α, β, s⁻, s⁺) with α + βr − s⁻ ≤ φ(r) ≤ α + βr + s⁺ on the interval: the linear
    interpolation error is at most max|φ''|·h²/2, and φ'' = −φ, so φ is concave where φ ≥ 0.
    """

    def phi(r: float) -> float:
        return kc * math.cos(w_nom + sigma * r) + ks * math.sin(w_nom + sigma * r)

    if half <= 0:
        return phi(0.0), 0.0, 0.0, 0.0
    f_lo, f_hi = phi(-half), phi(half)
    alpha, beta = 0.5 * (f_lo + f_hi), (f_hi - f_lo) / (2 * half)
    # Extremes of φ = ρ cos(w − θ) on the arc: ends, and w ≡ θ (mod π) inside it.
    rho, theta = math.hypot(kc, ks), math.atan2(ks, kc)
    lo_w, hi_w = sorted((w_nom - half, w_nom + half))
    values = [f_lo, f_hi]
    k = math.ceil((lo_w - theta) / math.pi)
    while theta + k * math.pi <= hi_w:
        values.append(rho if k % 2 == 0 else -rho)
        k += 1
    f_min, f_max = min(values), max(values)
    sag = 0.5 * half * half
    eps = 1e-15 * (rho + 1.0)
    if f_min >= 0:
        return alpha, beta, eps, f_max * sag + eps
    if f_max <= 0:
        return alpha, beta, -f_min * sag + eps, eps
    big = max(abs(f_min), abs(f_max)) * sag + eps
    return alpha, beta, big, big


def resolve_contacts(
    spec: TaskSpec,
    objects: Iterable[str] | None = None,
    options: LocateOptions | None = None,
) -> TaskSpec:
    """``spec`` with located objects given their derived pose and uncertainty.

    Every object located by contacts (or those in ``objects``) gets its nominal pose and block
    from :func:`derive_link`, and its contacts are removed — a task the error chains read as if
    the blocks had been typed by hand.

    Raises :class:`EstimationError` when an object's contacts admit no pose, or several gross
    orientations (the seed's ITEM416/ITEM417, L2979–3059): add a contact that decides.
    """
    results = locate_objects(spec, options=options, objects=objects)
    frames = list(spec.frames)
    index = {f.name: i for i, f in enumerate(frames)}
    used: set[int] = set()
    for res in results:
        p = res.problem
        where = ", ".join(f"contacts[{i}]" for i in p.indices)
        if not res.estimates:
            raise EstimationError(f"{where}: no pose of {p.obj!r} satisfies these contacts")
        if len(res.estimates) > 1:
            ws = ", ".join(f"{math.degrees(e.w0):.1f}°" for e in res.estimates)
            raise EstimationError(
                f"{where}: {p.obj!r} has {len(res.estimates)} possible orientations (w ≈ {ws} "
                f"about the normal of {p.rest_face}); add a contact that fixes which one"
            )
        link = res.link or derive_link(res)
        i = index[p.obj]
        frames[i] = frames[i].model_copy(
            update={"pose": link.pose, "uncertainty": link.uncertainty}
        )
        used.update(p.indices)
    remaining = tuple(c for i, c in enumerate(spec.contacts) if i not in used)
    return spec.model_copy(update={"frames": tuple(frames), "contacts": remaining})


_RESOLVED: weakref.WeakKeyDictionary[AttributeGraph, dict[frozenset[str], AttributeGraph]] = (
    weakref.WeakKeyDictionary()
)


def located_graph(graph: AttributeGraph, start: str, end: str) -> AttributeGraph:
    """The graph to build the chain ``start⁻¹ ∘ end`` on.

    That is ``graph`` itself, or — when objects on that path are located by contacts — a graph
    of :func:`resolve_contacts` for those objects.

    This is the extension point of :func:`synth.errors.chain.chain_between`. Results are cached
    per graph (weakly), so repeated chains do not repeat the LPs.
    """
    if not graph.spec.contacts:
        return graph
    path = graph.path(start, end)
    groups = contact_groups(graph, graph.spec.contacts)
    on_path = frozenset(link.child for link in (*path.up, *path.down) if link.child in groups)
    if not on_path:
        return graph
    cache = _RESOLVED.setdefault(graph, {})
    if on_path not in cache:
        cache[on_path] = AttributeGraph(resolve_contacts(graph.spec, objects=sorted(on_path)))
    return cache[on_path]


__all__ = [
    "SEED_OPTIONS",
    "DerivedLink",
    "LocateOptions",
    "LocationEstimate",
    "LocationResult",
    "Relaxation",
    "build_relaxation",
    "derive_link",
    "locate",
    "locate_objects",
    "located_graph",
    "resolve_contacts",
    "solve_relaxation",
]
