"""Checked AL text: the only values a template may print (:class:`Fragment`).

Every number, name, string and comment in a generated program is made here, from SI values and
task names, and each maker checks its input (seed-al-subset.md §1, al-language.md §1):

- **numbers** carry an explicit unit — ``3.54*CM``, ``90*DEG``, ``8*OZ``, ``6.14*SEC`` — and a
  translation is one vector scaled by its unit, ``VECTOR(0,0,3.54)*CM`` (the form of
  :func:`synth.codegen.binding.preamble`), so no AL runtime has to guess that bare numbers are cm,
  rad or oz. They are printed with :data:`SIGNIFICANT_DIGITS` significant digits (at least
  the seed's three, L2789 footnote 21), never with an exponent, and values
  below :data:`RESOLUTION` in the printed unit print as ``0``. Non-finite numbers are refused;
- **names** pass :func:`synth.al.names.al_name_problem` and are printed upper-case;
- **strings** are double-quoted with ``""`` for a quote; line breaks and control characters
  are refused (an AL string is one line);
- **comments** are the text inside ``{ ... }``: braces become parentheses and control
  characters spaces, so no text can close a comment early or open one.

Units are AL's (the interpreter's table, :data:`synth.al.builtins.UNITS`): ``CM`` = 0.01 m,
``DEG`` = π/180 rad, ``OZ`` = ounce-force, ``SEC`` = 1 s. Rotations are ``NILROTN``,
``ROT(ZHAT,θ*DEG)`` about a principal axis, or ``ROT(VECTOR(a,b,c),θ*DEG)`` with a unit axis
(dimensionless, normalised by AL, S:2723).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from synth.al.names import NameRole, al_name_problem
from synth.exceptions import CodegenError
from synth.units import CM, DEG, OZ

__all__ = [
    "RESOLUTION",
    "SIGNIFICANT_DIGITS",
    "Fragment",
    "angle",
    "comment",
    "decimal",
    "dimensionless",
    "duration",
    "force",
    "join",
    "length",
    "name",
    "pose",
    "rotation",
    "string",
    "trans",
    "translation",
]

SIGNIFICANT_DIGITS = 4
"""Significant digits a printed number keeps: the seed's listings keep three (footnote 21,
L2789), which leaves angles of 100° or more only whole degrees (±0.5°, twice the hand's
±0.25°); four keeps them to ±0.05° and lengths under 10 cm to ±0.5 µm."""

RESOLUTION = 1e-6
"""Magnitudes below this, in the printed unit (cm, deg, oz, s, or a unit axis), print as 0."""

"""One degree [rad]."""

_PRINCIPAL_AXES = ("XHAT", "YHAT", "ZHAT")
_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f\u0080-\u009f\u2028\u2029]")
_PI_TOLERANCE = 1e-6
"""Rotations within this of π [rad] are half turns (below print resolution), axis sign canonical."""


@dataclass(frozen=True)
class Fragment:
    """A piece of AL text that has been checked; the only kind of value templates print.

    Make fragments with the functions of this module, never from unchecked text. The Jinja
    environment (:mod:`synth.codegen.environment`) refuses to print anything else, and
    ``__html__`` lets it insert the text verbatim.
    """

    text: str

    def __html__(self) -> str:
        """The text, for Jinja's output (it is already AL, nothing to escape)."""
        return self.text

    def __str__(self) -> str:
        return self.text

    def __bool__(self) -> bool:
        return bool(self.text)


def _finite(value: float, field: str) -> float:
    x = float(value)
    if not math.isfinite(x):
        raise CodegenError(field, f"cannot print the non-finite number {value!r}")
    return x


def decimal(value: float, *, field: str = "number") -> str:
    """Plain decimal text of ``value`` with :data:`SIGNIFICANT_DIGITS` significant digits.

    ``decimals = max(0, SIGNIFICANT_DIGITS − 1 − ⌊log10 |x|⌋)``: ``0.169``, ``-1.21``,
    ``0.00106``, ``60.16``, ``180``, ``12346`` (large numbers keep their integer digits);
    trailing zeros are dropped (``90``), ``|x| <`` :data:`RESOLUTION` is ``0``, there is no
    exponent (AL has none) and no ``-0``.
    """
    x = _finite(value, field)
    if abs(x) < RESOLUTION:
        return "0"
    places = max(0, SIGNIFICANT_DIGITS - 1 - math.floor(math.log10(abs(x))))
    text = f"{x:.{places}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "0", "") else text


def _quantity(value: float, unit_value: float, unit: str, field: str) -> Fragment:
    return Fragment(f"{decimal(_finite(value, field) / unit_value, field=field)}*{unit}")


def length(value: float, *, field: str = "length") -> Fragment:
    """``value`` [m] as ``n*CM`` (``0.0354`` → ``3.54*CM``)."""
    return _quantity(value, CM, "CM", field)


def angle(value: float, *, field: str = "angle") -> Fragment:
    """``value`` [rad] as ``n*DEG`` (``π/2`` → ``90*DEG``)."""
    return _quantity(value, DEG, "DEG", field)


def force(value: float, *, field: str = "force") -> Fragment:
    """``value`` [N] as ``n*OZ`` (ounce-force, the unit of the seed's thresholds, L2735)."""
    return _quantity(value, OZ, "OZ", field)


def duration(value: float, *, field: str = "time") -> Fragment:
    """``value`` [s] as ``n*SEC``."""
    return _quantity(value, 1.0, "SEC", field)


def dimensionless(value: float, *, field: str = "number") -> Fragment:
    """A pure number (a count, a component of a unit axis)."""
    return Fragment(decimal(value, field=field))


def name(value: str, *, field: str, role: NameRole = "frame") -> Fragment:
    """A validated AL identifier, upper-case (AL folds case); CodegenError names ``field``.

    ``role="arm"`` admits the blue arm's predeclared names (``BMANIP``, ``BHAND``).
    """
    problem = al_name_problem(value, role=role)
    if problem is not None:
        raise CodegenError(field, f"{value!r} cannot be written in AL: {problem}")
    return Fragment(value.upper())


def string(value: str, *, field: str = "string") -> Fragment:
    """An AL string literal: double quotes, ``"`` doubled; one line, no control characters."""
    if not isinstance(value, str):
        raise CodegenError(field, f"expected text, got {type(value).__name__}")
    if "\n" in value or "\r" in value or _CONTROL.search(value):
        raise CodegenError(field, f"an AL string is one line of printable text: {value!r}")
    return Fragment('"' + value.replace('"', '""') + '"')


def comment(value: str) -> Fragment:
    """Text safe inside ``{ ... }``: braces → parentheses, control characters → spaces.

    Line breaks are kept (a brace comment may span lines, S:1240).
    """
    cleaned = value.replace("\r\n", "\n").replace("{", "(").replace("}", ")")
    return Fragment(_CONTROL.sub(" ", cleaned.replace("\r", "\n")))


def join(fragments: Iterable[Fragment], separator: str = ",") -> Fragment:
    """Fragments joined by a fixed ``separator`` (punctuation or white space only)."""
    if separator.strip(" \n,;"):
        raise ValueError(f"a separator is punctuation or white space, not {separator!r}")
    parts = list(fragments)
    bad = [p for p in parts if not isinstance(p, Fragment)]
    if bad:
        raise TypeError(f"join takes checked fragments, got {bad[0]!r}")
    return Fragment(separator.join(p.text for p in parts))


def translation(vector: ArrayLike, *, field: str = "translation") -> Fragment:
    """A displacement [m] as ``VECTOR(x,y,z)*CM``."""
    v = np.asarray(vector, dtype=float).reshape(3)
    parts = ",".join(decimal(float(c) / CM, field=field) for c in v)
    return Fragment(f"VECTOR({parts})*CM")


def _axis_angle(matrix: np.ndarray) -> tuple[np.ndarray, float]:
    """Unit axis and angle θ ∈ [0, π] of a rotation.

    A half turn's axis has its largest component positive, so equal rotations print alike.
    """
    w = np.asarray(pin.log3(matrix), dtype=float)
    theta = float(np.linalg.norm(w))
    if theta == 0.0:
        return np.array([0.0, 0.0, 1.0]), 0.0
    if math.pi - theta > _PI_TOLERANCE:
        return w / theta, theta
    # Half turn: R = 2uuᵀ − I, so uuᵀ = (R + I)/2; read u off its strongest column.
    m = (np.asarray(matrix, dtype=float) + np.eye(3)) / 2.0
    k = int(np.argmax(np.diag(m)))
    u = m[:, k] / math.sqrt(max(m[k, k], 1e-300))
    u /= np.linalg.norm(u)
    if u[int(np.argmax(np.abs(u)))] < 0:
        u = -u
    return u, math.pi


def rotation(matrix: ArrayLike, *, field: str = "rotation") -> Fragment:
    """A rotation as ``NILROTN``, ``ROT(ZHAT,θ*DEG)`` or ``ROT(VECTOR(a,b,c),θ*DEG)``.

    θ ∈ (0°, 180°] about a unit axis (``pin.log3``); an axis along ±x̂, ±ŷ, ±ẑ (other components
    below :data:`RESOLUTION`) is written ``XHAT``/``YHAT``/``ZHAT`` with the sign on the angle.
    """
    m = np.asarray(matrix, dtype=float).reshape(3, 3)
    if not np.all(np.isfinite(m)):
        raise CodegenError(field, "cannot print a rotation with non-finite entries")
    axis, theta = _axis_angle(m)
    if abs(theta) / DEG < RESOLUTION:
        return Fragment("NILROTN")
    for k, hat in enumerate(_PRINCIPAL_AXES):
        others = np.delete(axis, k)
        if np.all(np.abs(others) < RESOLUTION):
            signed = theta if axis[k] > 0 else -theta
            return Fragment(f"ROT({hat},{angle(signed, field=field).text})")
    parts = ",".join(decimal(float(c), field=field) for c in axis)
    return Fragment(f"ROT(VECTOR({parts}),{angle(theta, field=field).text})")


def trans(xf: pin.SE3, *, field: str = "xf") -> Fragment:
    """A relation as ``TRANS(rotation, VECTOR(x,y,z)*CM)`` (S:2723)."""
    rot = rotation(xf.rotation, field=field)
    return Fragment(f"TRANS({rot.text},{translation(xf.translation, field=field).text})")


def pose(base: Fragment, xf: pin.SE3, *, field: str = "xf") -> Fragment:
    """The location ``base*TRANS(...)`` (the seed's ``base[d]*xf[d]``, L2549)."""
    if not isinstance(base, Fragment):
        raise TypeError(f"pose takes a checked base name, got {base!r}")
    return Fragment(f"{base.text}*{trans(xf, field=field).text}")
