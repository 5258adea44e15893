"""A link's bounded error parameters: tolerances, coupled constraints, their distribution.

The true link is ``nominal ∘ transl(x, y, z) ∘ rot(x̂, rx) ∘ rot(ŷ, ry) ∘ rot(ẑ, rz)`` (seed
Eqn 3.5.1, L2205); each parameter is bounded by a tolerance (``"0.3 in"``: ±0.3 in) or an
interval, and linear constraints may couple them.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, model_validator

from synth.models.spec_fields import SpecModel
from synth.units import parse_quantity, read_quantity, registry, si_magnitude

TRANSLATION_PARAMS: tuple[str, ...] = ("x", "y", "z")
ROTATION_PARAMS: tuple[str, ...] = ("rx", "ry", "rz")
PARAMS: tuple[str, ...] = TRANSLATION_PARAMS + ROTATION_PARAMS
"""Error parameters of a link, in the link's own frame: Δ = transl(x, y, z) ∘ rot(x̂, rx) ∘
rot(ŷ, ry) ∘ rot(ẑ, rz), applied on the right of the nominal pose (seed A.2, L3190–3200)."""


class Bound(SpecModel):
    """Closed interval [lo, hi] of one error parameter, SI units; lo ≤ 0 ≤ hi."""

    lo: float
    hi: float


def _check_rotation_error(given: Any, largest_rad: float) -> None:
    """Refuse a rotation error of 90° or more: no error chain through it can be certified.

    The certified bound needs tr(ΔR − I) > −2 (:func:`synth.errors.estimate.estimate_errors`);
    one rotation by θ alone has tr(ΔR − I) = 2(cos θ − 1), which reaches −2 at θ = 90°.
    """
    if largest_rad >= math.pi / 2:
        raise ValueError(
            f"rotation error {given!r} reaches 90°: the error model certifies rotations below "
            "90° (a part known only that loosely has to be located before it is planned for)"
        )


_FORMS = "a bound is one tolerance ('0.3 in' means ±0.3 in) or [min, max], each with its unit"


def _bound(kind: Literal["length", "angle"]) -> Any:
    def parse(v: Any) -> Any:
        if isinstance(v, Bound):
            return v  # built in code, already in SI
        if isinstance(v, dict):
            # the record's own {lo, hi} in SI would bypass the unit and bound checks below
            raise ValueError(_FORMS)
        if isinstance(v, list | tuple):
            if len(v) != 2:
                raise ValueError(_FORMS)
            lo, hi = (parse_quantity(x, kind) for x in v)
            if lo > hi:
                raise ValueError(f"min {v[0]!r} exceeds max {v[1]!r}")
            if lo > 0 or hi < 0:
                raise ValueError("the nominal value (0) must lie inside [min, max]")
            if kind == "angle":
                _check_rotation_error(v, max(-lo, hi))
            return {"lo": lo, "hi": hi}
        tol = parse_quantity(v, kind)
        if tol < 0:
            raise ValueError(f"tolerance {v!r} is negative; write the half-width, e.g. '0.3 in'")
        lo, hi = -tol, tol
        if kind == "angle":
            _check_rotation_error(v, tol)
        return {"lo": lo, "hi": hi}

    return BeforeValidator(parse)


LengthBound = Annotated[Bound, _bound("length")]
AngleBound = Annotated[Bound, _bound("angle")]


class LinearConstraint(SpecModel):
    """A coupled constraint ``min ≤ Σ c_k · v_k ≤ max`` between a link's error parameters.

    Coefficients are numbers, or quantities that convert between kinds (``"2 cm/deg"`` on a
    rotation parameter gives a length). Every term must have the dimension of the bound.
    """

    terms: dict[str, float]
    min: float | None = None
    max: float | None = None
    kind: Literal["length", "angle"]

    @model_validator(mode="before")
    @classmethod
    def _parse(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            raise ValueError("a constraint is a mapping with 'terms' and 'min' and/or 'max'")
        raw_terms = data.get("terms")
        if not isinstance(raw_terms, dict) or not raw_terms:
            raise ValueError(
                "'terms' must map error parameters (x, y, z, rx, ry, rz) to coefficients"
            )
        if data.get("min") is None and data.get("max") is None:
            raise ValueError("a constraint needs 'min', 'max' or both")
        kind = _constraint_kind(data)
        terms: dict[str, float] = {}
        for param, coefficient in raw_terms.items():
            if param not in PARAMS:
                raise ValueError(
                    f"unknown error parameter {param!r}; use one of {', '.join(PARAMS)}"
                )
            terms[param] = _coefficient_si(param, coefficient, kind)
        out: dict[str, Any] = {"terms": terms, "kind": kind}
        for key in ("min", "max"):
            if data.get(key) is not None:
                out[key] = parse_quantity(data[key], kind)
        extra = set(data) - {"terms", "min", "max"}
        if extra:
            raise ValueError(f"unknown constraint field(s): {', '.join(sorted(extra))}")
        return out

    @model_validator(mode="after")
    def _ordered(self) -> LinearConstraint:
        if self.min is not None and self.max is not None and self.min > self.max:
            raise ValueError("constraint min exceeds max")
        if self.min is not None and self.min == self.max:
            # an equality leaves errors of no volume: the Monte Carlo trials draw none of them
            # (the planner gave up after 100 000 draws, naming no field)
            raise ValueError(
                "min equals max: an equality between error parameters leaves no room to sample "
                "the errors from; give min < max (a tolerance on the relation)"
            )
        return self


def _constraint_kind(data: dict[str, Any]) -> Literal["length", "angle"]:
    bound = data.get("max") if data.get("max") is not None else data.get("min")
    ureg = registry()
    q = read_quantity(bound)
    if q.unitless:
        raise ValueError(f"constraint bound {bound!r} has no unit")
    if q.dimensionality == ureg.meter.dimensionality:
        return "length"
    if q.dimensionality == ureg.radian.dimensionality:
        return "angle"
    raise ValueError(f"constraint bound {bound!r} must be a length or an angle")


def _coefficient_si(param: str, coefficient: Any, kind: Literal["length", "angle"]) -> float:
    """SI value of a constraint coefficient, checking that c · param has the bound's kind."""
    ureg = registry()
    param_kind = "length" if param in TRANSLATION_PARAMS else "angle"
    if isinstance(coefficient, bool):
        raise ValueError(f"coefficient of {param} must be a number or a quantity")
    if isinstance(coefficient, int | float):
        value = float(coefficient)
        if not math.isfinite(value):
            raise ValueError(f"coefficient of {param} is not finite")
        if param_kind != kind:
            raise ValueError(
                f"term {param} is {_a(param_kind)} but the bound is {_a(kind)}; give its "
                f"coefficient a unit, e.g. '1 cm/deg'"
            )
        return value
    q = read_quantity(coefficient)
    length_dim = ureg.meter.dimensionality
    if param_kind == kind and q.dimensionality == ureg.dimensionless.dimensionality:
        return si_magnitude(q, "", coefficient)
    if param_kind == "angle" and kind == "length" and q.dimensionality == length_dim:
        return si_magnitude(q, "m/rad", coefficient)
    if param_kind == "length" and kind == "angle" and q.dimensionality == 1 / length_dim:
        return si_magnitude(q, "rad/m", coefficient)
    raise ValueError(
        f"coefficient {coefficient!r} of {param} does not turn {_a(param_kind)} into {_a(kind)}"
    )


def _a(kind: str) -> str:
    """``a length``, ``an angle``: a bound's kind with its article."""
    return f"an {kind}" if kind[0] in "aeiou" else f"a {kind}"


Distribution = Literal["uniform", "normal"]
"""How a bounded error is sampled in Monte Carlo (seed ch. IX, L7240–7242: uniform, or normal
with σ = tolerance/3 truncated at the tolerance); the choice is the production engineer's."""


class Uncertainty(SpecModel):
    """Bounded error parameters of one link, in the link's frame (seed Eqn 3.5.1, L2205).

    The true link is ``nominal ∘ transl(x, y, z) ∘ rot(x̂, rx) ∘ rot(ŷ, ry) ∘ rot(ẑ, rz)``.
    Unlisted parameters are exact. ``distribution`` is for Monte Carlo sampling: ``uniform`` on
    the feasible set, or ``normal`` with σ = tolerance/3 truncated at the tolerance (seed L7242).
    """

    x: LengthBound | None = None
    y: LengthBound | None = None
    z: LengthBound | None = None
    rx: AngleBound | None = None
    ry: AngleBound | None = None
    rz: AngleBound | None = None
    constraints: tuple[LinearConstraint, ...] = ()
    distribution: Distribution = "uniform"

    def bounds(self) -> dict[str, Bound]:
        """The bounded parameters in canonical order (x, y, z, rx, ry, rz)."""
        return {p: getattr(self, p) for p in PARAMS if getattr(self, p) is not None}

    def constraint_rows(self) -> tuple[list[list[float]], list[float]]:
        """``min ≤ c·v ≤ max`` as rows of ``A v ≤ b`` over :meth:`bounds`' order [SI].

        Each constraint is divided by its largest |c_k|, which leaves its set of values alone
        and its entries within [−1, 1]: HiGHS refuses a matrix entry of 10¹⁵ or more as a
        model error (``large_matrix_value``), which the feasibility check read as "no error
        values" for ``x·10¹⁵ + y ≤ 0.4 in`` (x = y = 0 satisfies it), and it drops entries
        below 10⁻⁹ (``small_matrix_value``), here a term worth less than 10⁻⁹ of the largest.
        """
        names = list(self.bounds())
        rows: list[list[float]] = []
        rhs: list[float] = []
        for c in self.constraints:
            scale = max(abs(x) for x in c.terms.values())
            scale = scale if scale > 0.0 else 1.0
            row = [c.terms.get(n, 0.0) / scale for n in names]
            if c.max is not None:
                rows.append(row)
                rhs.append(c.max / scale)
            if c.min is not None:
                rows.append([-x for x in row])
                rhs.append(-c.min / scale)
        return rows, rhs

    @model_validator(mode="after")
    def _constraints_use_bounded_params(self) -> Uncertainty:
        bounded = self.bounds()
        for i, c in enumerate(self.constraints):
            for p in c.terms:
                if p not in bounded:
                    raise ValueError(
                        f"constraints[{i}] uses {p}, which has no bound in this block; "
                        f"every error parameter must be bounded"
                    )
        return self
