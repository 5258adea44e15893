"""AL identifiers: what a task may name a frame, the arm or its park, and the words AL keeps.

An identifier is an ASCII letter followed by ASCII letters, digits and ``_`` (al-language.md §1,
PNT77), at most :data:`MAX_LENGTH` characters. The whole string must match
(:func:`re.fullmatch`): a name with a trailing newline is not that name, and no control or
non-ASCII character gets through. AL folds case, so names are compared upper-cased.

A task may not take a name AL already gives a meaning (:data:`RESERVED`), or a generated
program would silently mean something else (``FLAG ← TRUE`` assigning the hand when the arm is
called ``TRUE``, ``ROT(ZHAT, …)`` turning about the hand):

- :data:`KEYWORDS`: statement keywords, type names, clause words (``ARRIVAL``, ``DURATION``),
  the sensed quantities (``FORCE``, ``TORQUE``, ``OPENING``);
- :data:`FUNCTIONS`: the interpreter's builtins (:data:`synth.al.builtins.BUILTINS`);
- :data:`UNITS`: the unit constants (:data:`synth.al.builtins.UNITS`: ``CM``, ``INCHES``, ``DEG``…);
- :data:`CONSTANTS`: the other predeclared constants (``TRUE``, ``FALSE``, ``XHAT``, ``ZHAT``,
  ``NILROTN``, ``NILTRANS``…, :data:`synth.al.builtins.CONSTANTS`) and AL's ``PI``, ``STATION``,
  ``NILDEPROACH`` (al-language.md §4: EX74, MOT74);
- :data:`ARM_NAMES`, :data:`OTHER_ARM_NAMES`, :data:`PARK_NAMES`: the arms' hand frames and
  parks.

Only one exception is made, and only for a name's own predeclared meaning (:data:`NameRole`):
the manipulator may be called by one of the blue arm's names (:data:`ARM_NAMES`: it *is* that
arm), and its park ``BPARK`` (the blue arm's park). A frame may take no predeclared name, the
arm no park or constant name, the park no hand name. The emitter's own variables
(``DISTANCE_OFF``, ``FLAG``, ``R``…) are not reserved: :mod:`synth.codegen.views` renames them
(``FLAG1``) when a task uses the name.
"""

from __future__ import annotations

import re
from typing import Literal

from synth.al.builtins import BUILTINS
from synth.al.builtins import CONSTANTS as _CONSTANT_VALUES
from synth.al.builtins import UNITS as _UNIT_VALUES

__all__ = [
    "ARM_NAMES",
    "CONSTANTS",
    "FUNCTIONS",
    "IDENTIFIER",
    "KEYWORDS",
    "MAX_LENGTH",
    "OTHER_ARM_NAMES",
    "PARK_NAMES",
    "PREDECLARED",
    "RESERVED",
    "UNITS",
    "NameRole",
    "al_name_problem",
]

IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_]*", re.ASCII)
"""An AL identifier; use it with ``fullmatch`` only (``match`` would accept a prefix)."""
MAX_LENGTH = 40

KEYWORDS: frozenset[str] = frozenset(
    """
    BEGIN END IF THEN ELSE WHILE DO FOR STEP UNTIL COBEGIN COEND MOVE TO VIA WHERE WITH ON
    ARRIVAL STOP ABORT OPEN CLOSE CENTER AFFIX UNFIX FROM AT RIGIDLY NONRIGIDLY INDEPENDENTLY
    SIGNAL WAIT AND OR NOT COMMENT DURATION FORCE TORQUE OPENING
    FRAME VECTOR SCALAR REAL BOOLEAN TRANS EVENT ROT ROTN ROTATION
    INV ORIENT DISPL ABS SIN COS SQRT ATAN2
    """.split()
)
"""Words of the grammar and the interpreter's clause and sensor names."""

FUNCTIONS: frozenset[str] = frozenset(BUILTINS)
"""The interpreter's builtin functions (``POS``, ``TAN``, ``INV``…)."""

UNITS: frozenset[str] = frozenset(_UNIT_VALUES)
"""AL's unit constants (``CM``, ``MM``, ``INCHES``, ``IN``, ``DEG``, ``RAD``, ``SEC``, ``OZ``…)."""

CONSTANTS: frozenset[str] = frozenset(set(_CONSTANT_VALUES) - UNITS) | {
    "PI",
    "STATION",
    "NILDEPROACH",
}
"""Predeclared constants: the interpreter's (``TRUE``, ``XHAT``, ``NILROTN``…) and AL's ``PI``,
``STATION`` (the root frame, EX74) and ``NILDEPROACH`` (MOT74's deproaches), which synth's
interpreter does not define but a real AL system would."""

ARM_NAMES: tuple[str, ...] = ("BMANIP", "BLUE", "BARM", "BHAND", "BFINGERS")
"""The blue arm's names: one hand frame, the sensed hand (seed-al-subset.md §1)."""
OTHER_ARM_NAMES: frozenset[str] = frozenset({"YELLOW", "YARM", "YMANIP", "YHAND", "YFINGERS"})
"""The yellow arm's names (al-language.md §6); synth drives one arm, so no task takes them."""
PARK_NAMES: frozenset[str] = frozenset({"BPARK", "YPARK"})
"""The arms' park frames."""

PREDECLARED: frozenset[str] = CONSTANTS | frozenset(ARM_NAMES) | OTHER_ARM_NAMES | PARK_NAMES
"""Every predeclared name that is not a keyword, function or unit."""

RESERVED: frozenset[str] = KEYWORDS | FUNCTIONS | UNITS | PREDECLARED
"""Every name a program's own variables must avoid."""

NameRole = Literal["frame", "arm", "park"]
"""What an AL name names: a task frame, the manipulator, or its park frame."""

_OWN_MEANING: dict[NameRole, frozenset[str]] = {
    "frame": frozenset(),
    "arm": frozenset(ARM_NAMES),
    "park": frozenset({"BPARK"}),
}


def al_name_problem(name: object, *, role: NameRole = "frame") -> str | None:
    """Say why ``name`` cannot be an AL name for a ``role``, or return None when it can.

    The rule: a string of 1–:data:`MAX_LENGTH` characters that :data:`IDENTIFIER` matches in
    full, not in :data:`RESERVED`, except the predeclared names of the role's own meaning
    (``role="arm"``: :data:`ARM_NAMES`; ``role="park"``: ``BPARK``).
    """
    if not isinstance(name, str) or not name:
        return "an AL name must be a non-empty string"
    if len(name) > MAX_LENGTH:
        return f"an AL name has at most {MAX_LENGTH} characters"
    if IDENTIFIER.fullmatch(name) is None:
        return (
            f"{name!r} is not an AL identifier: an ASCII letter followed by letters, digits "
            "and '_', with no space or control character"
        )
    upper = name.upper()
    if upper in _OWN_MEANING[role]:
        return None
    if upper in KEYWORDS or upper in FUNCTIONS:
        return f"{name!r} is an AL keyword or function"
    if upper in UNITS:
        return f"{name!r} is an AL unit"
    if upper in CONSTANTS:
        return f"{name!r} is a predeclared AL constant"
    if upper in PREDECLARED:
        hints: dict[NameRole, str] = {
            "frame": "",
            "arm": f" (the arm may be called {', '.join(ARM_NAMES)})",
            "park": " (the park may be called BPARK)",
        }
        return f"{name!r} is a predeclared AL arm or park name{hints[role]}"
    return None
