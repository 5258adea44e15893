"""AL identifiers: what a task may name a frame, and the words AL keeps for itself.

An identifier is a letter followed by letters, digits and ``_`` (al-language.md §1, PNT77).
AL folds case, so names are compared upper-cased. Reserved words are the statement keywords,
type names, units and predeclared frames of the subset in ``seed-al-subset.md``; a task may not
rebind them, or generated programs would silently mean something else.
"""

from __future__ import annotations

import re

IDENTIFIER = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
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

UNITS: frozenset[str] = frozenset("INCHES INCH IN CM MM DEG DEGREES RAD SEC OZ LBS GM".split())

PREDECLARED: frozenset[str] = frozenset(
    """
    BLUE BMANIP BARM BHAND BFINGERS YELLOW YMANIP YHAND YFINGERS BPARK YPARK
    XHAT YHAT ZHAT NILROTN NILROT NILTRANS NILVECT TRUE FALSE
    """.split()
)

RESERVED: frozenset[str] = KEYWORDS | UNITS | PREDECLARED


def al_name_problem(name: str, *, allow_predeclared: bool = False) -> str | None:
    """Say why ``name`` cannot be an AL variable name, or return None when it can.

    ``allow_predeclared`` admits the predeclared frame names (``BPARK``) for the frames a task
    binds to them.
    """
    if not isinstance(name, str) or not name:
        return "an AL name must be a non-empty string"
    if len(name) > MAX_LENGTH:
        return f"an AL name has at most {MAX_LENGTH} characters"
    if not IDENTIFIER.match(name):
        return "an AL name is a letter followed by letters, digits and '_'"
    upper = name.upper()
    if upper in KEYWORDS or upper in UNITS:
        return f"{name!r} is an AL keyword or unit"
    if upper in PREDECLARED and not allow_predeclared:
        return f"{name!r} is a predeclared AL frame or constant"
    return None
