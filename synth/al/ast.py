"""AL abstract syntax tree: frozen dataclasses with source positions.

Built from the Lark grammar ``al.lark`` by :mod:`synth.al.parser` (in the style of lark's
``examples/advanced/create_ast.py``) and turned back into text by :mod:`synth.al.printer`.

Positions follow lark: ``line``/``column`` are 1-based and point at the first character of the
construct; ``end_line``/``end_column`` point just past its last character. Nodes built by code
(not by the parser) carry zeros. Positions take part in ``==`` and ``hash`` (so two identical
statements on different lines stay distinct as dictionary keys); compare shapes with
:func:`without_positions`.

AL folds case, so :attr:`Name.name` is upper-case; :attr:`Name.spelling` keeps the source text
and does not take part in ``==``. Likewise :attr:`Number.text` keeps the source lexeme.

Canonical forms the parser chooses (the printer emits them; seed-al-subset.md §1–3):

- ``←``, ``:=`` and statement-initial ``=`` are all :class:`Assign`;
- ``REAL`` declarations are ``SCALAR``; ``WHERE`` clauses are :class:`WithClause`;
- relations are ``< > = ≤ ≥ ≠`` (``<=``, ``>=``, ``<>`` are read as the last three);
- the dot product (``.`` or ``·``) is :class:`BinOp` with op ``"."``;
- ``AND``/``OR`` are :class:`BinOp`, ``NOT`` and the signs are :class:`UnaryOp`;
- a chain ``a > b > c`` is one :class:`Compare` (the conjunction of its adjacent pairs).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field, fields, replace
from typing import Any, TypeVar

POSITION_FIELDS: tuple[str, ...] = ("line", "column", "end_line", "end_column")

RELATIONS: frozenset[str] = frozenset({"<", ">", "=", "≤", "≥", "≠"})
BINARY_OPERATORS: frozenset[str] = frozenset({"+", "-", "*", "/", ".", "AND", "OR"})
UNARY_OPERATORS: frozenset[str] = frozenset({"+", "-", "NOT"})
DECLARABLE_TYPES: frozenset[str] = frozenset(
    {"FRAME", "VECTOR", "ROT", "TRANS", "SCALAR", "BOOLEAN", "EVENT"}
)


@dataclass(frozen=True)
class Node:
    """Base of every AST node: the source span (1-based; end is one past the last character)."""

    line: int = field(default=0, kw_only=True, repr=False)
    column: int = field(default=0, kw_only=True, repr=False)
    end_line: int = field(default=0, kw_only=True, repr=False)
    end_column: int = field(default=0, kw_only=True, repr=False)

    def __lark_meta__(self) -> Node:
        """Let lark's position propagation read a node's span like a token's."""
        return self


# --------------------------------------------------------------------------------------------
# Expressions


@dataclass(frozen=True)
class Expr(Node):
    """Base of expressions."""


@dataclass(frozen=True)
class Number(Expr):
    """A non-negative numeric literal (``15``, ``1.0``, ``.3``, ``102.``); signs are UnaryOp.

    ``value`` is dimensionless here: AL units are names multiplied in (``2*INCHES``).
    """

    value: float
    text: str = field(default="", compare=False, repr=False)

    def __post_init__(self) -> None:
        if not (0.0 <= self.value < float("inf")):
            raise ValueError(f"an AL number literal is finite and non-negative, not {self.value}")
        if type(self.value) is not float:
            object.__setattr__(self, "value", float(self.value))


@dataclass(frozen=True)
class String(Expr):
    """A string literal, unescaped (the source's doubled quote ``""`` is one ``"`` here)."""

    value: str


@dataclass(frozen=True)
class Name(Expr):
    """An identifier, upper-cased (AL folds case); ``spelling`` is the source text."""

    name: str
    spelling: str = field(default="", compare=False, repr=False)

    def __post_init__(self) -> None:
        if not self.spelling:
            object.__setattr__(self, "spelling", self.name)
        upper = self.name.upper()
        if upper != self.name:
            object.__setattr__(self, "name", upper)


@dataclass(frozen=True)
class Call(Expr):
    """A function or constructor call: ``VECTOR(0,0,1)``, ``ROT(ZHAT,90*DEG)``, ``FORCE(V)``."""

    func: Name
    args: tuple[Expr, ...]


@dataclass(frozen=True)
class UnaryOp(Expr):
    """``op`` is ``"+"``, ``"-"`` or ``"NOT"``."""

    op: str
    operand: Expr


@dataclass(frozen=True)
class BinOp(Expr):
    """``op`` is ``+ - * /``, ``.`` (dot product), ``AND`` or ``OR``; all left-associative."""

    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True)
class Compare(Expr):
    """A relation or a chain of them: ``operands[0] ops[0] operands[1] ops[1] ...``.

    A chain means the conjunction of its adjacent pairs, each operand evaluated once, left to
    right (``0.2*INCHES > DISTANCE_OFF > -0.2*INCHES``, S:1594). ``ops`` are ``< > = ≤ ≥ ≠``.
    """

    operands: tuple[Expr, ...]
    ops: tuple[str, ...]

    def __post_init__(self) -> None:
        if len(self.operands) != len(self.ops) + 1 or not self.ops:
            raise ValueError("a Compare has n+1 operands for n >= 1 relations")
        bad = [op for op in self.ops if op not in RELATIONS]
        if bad:
            raise ValueError(f"unknown relation(s) {bad}")

    def conjuncts(self) -> tuple[Compare, ...]:
        """Split the chain into binary relations (they share the middle operand nodes)."""
        return tuple(
            Compare(
                (left, right),
                (op,),
                line=left.line,
                column=left.column,
                end_line=right.end_line,
                end_column=right.end_column,
            )
            for left, op, right in zip(self.operands, self.ops, self.operands[1:], strict=False)
        )


@dataclass(frozen=True)
class Magnitude(Expr):
    """``|x|``: the magnitude of a scalar, vector or rotation (PNT77)."""

    operand: Expr


@dataclass(frozen=True)
class AssignExpr(Expr):
    """Assignment used as a value, e.g. ``(N ← N+1) ≤ 6`` (S:1600); yields the new value."""

    target: Name
    value: Expr


# --------------------------------------------------------------------------------------------
# Motion clauses


@dataclass(frozen=True)
class Clause(Node):
    """Base of the clauses of MOVE / OPEN / CLOSE / CENTER."""


@dataclass(frozen=True)
class ViaClause(Clause):
    """``VIA p1, p2, ...``: intermediate points, visited in order before the destination."""

    points: tuple[Expr, ...]


@dataclass(frozen=True)
class WithClause(Clause):
    """``WITH c1, c2`` (or ``WHERE``): constraints, e.g. ``FORCE(XHAT) = 0``, ``DURATION > 2*SEC``.

    Written right after a VIA list it qualifies that segment (S:1202–1215); the clause order of
    the statement is kept so the interpreter can tell.
    """

    conditions: tuple[Expr, ...]


@dataclass(frozen=True)
class OnClause(Clause):
    """``ON condition DO statement``: a monitor (force, torque, opening, ARRIVAL, an event)."""

    condition: Expr
    body: Stmt


# --------------------------------------------------------------------------------------------
# Statements


@dataclass(frozen=True)
class Stmt(Node):
    """Base of statements."""


class _HasClauses:
    """Views over the ``clauses`` of a motion-like statement, in source order."""

    clauses: tuple[Clause, ...]

    @property
    def via_points(self) -> tuple[Expr, ...]:
        """All VIA points, in order."""
        return tuple(p for c in self.clauses if isinstance(c, ViaClause) for p in c.points)

    @property
    def constraints(self) -> tuple[Expr, ...]:
        """All WITH/WHERE conditions, in order."""
        return tuple(x for c in self.clauses if isinstance(c, WithClause) for x in c.conditions)

    @property
    def monitors(self) -> tuple[OnClause, ...]:
        """The ON clauses, in order."""
        return tuple(c for c in self.clauses if isinstance(c, OnClause))


@dataclass(frozen=True)
class Program(Node):
    """A whole AL text: a statement sequence (usually one named block, or bare statements)."""

    body: tuple[Stmt, ...]
    filename: str = field(default="<al>", compare=False)


@dataclass(frozen=True)
class Block(Stmt):
    """``BEGIN ["name"] ... END ["name"]``; declarations may appear anywhere in ``body``."""

    name: str | None
    body: tuple[Stmt, ...]
    end_name: str | None = None


@dataclass(frozen=True)
class Cobegin(Stmt):
    """``COBEGIN s1; s2; ... COEND``: run the statements concurrently."""

    body: tuple[Stmt, ...]


@dataclass(frozen=True)
class Declaration(Stmt):
    """``FRAME A, B`` etc.; ``type`` is one of :data:`DECLARABLE_TYPES` (``REAL`` → ``SCALAR``)."""

    type: str
    names: tuple[Name, ...]


@dataclass(frozen=True)
class Assign(Stmt):
    """``target ← value`` (also written ``:=`` or, at statement start, ``=``)."""

    target: Name
    value: Expr


@dataclass(frozen=True)
class Move(_HasClauses, Stmt):
    """``MOVE frame TO destination {VIA ... | WITH ... | ON ... DO ...}``."""

    frame: Name
    destination: Expr
    clauses: tuple[Clause, ...] = ()


@dataclass(frozen=True)
class Open(_HasClauses, Stmt):
    """``OPEN device TO width {clauses}``."""

    device: Name
    width: Expr
    clauses: tuple[Clause, ...] = ()


@dataclass(frozen=True)
class Close(_HasClauses, Stmt):
    """``CLOSE device [TO width] {clauses}`` (e.g. ``WITH FORCE(XHAT)=0``, S:1303)."""

    device: Name
    width: Expr | None = None
    clauses: tuple[Clause, ...] = ()


@dataclass(frozen=True)
class Center(_HasClauses, Stmt):
    """``CENTER device {clauses}`` (e.g. ``ON OPENING < .185 DO ...``, S:2725)."""

    device: Name
    clauses: tuple[Clause, ...] = ()


@dataclass(frozen=True)
class Affix(Stmt):
    """``AFFIX frame TO parent [RIGIDLY | NONRIGIDLY] [AT relation]`` (options in any order).

    Without AT the current relation ``INV(parent)*frame`` is kept (seed-al-subset.md §4).
    """

    frame: Name
    parent: Name
    at: Expr | None = None
    rigid: bool = False


@dataclass(frozen=True)
class Unfix(Stmt):
    """``UNFIX frame FROM parent`` (the seed writes both directions for one link)."""

    frame: Name
    parent: Name


@dataclass(frozen=True)
class If(Stmt):
    """``IF condition THEN then [ELSE orelse]``."""

    condition: Expr
    then: Stmt
    orelse: Stmt | None = None


@dataclass(frozen=True)
class While(Stmt):
    """``WHILE condition DO body``."""

    condition: Expr
    body: Stmt


@dataclass(frozen=True)
class For(Stmt):
    """``FOR variable ← start STEP step UNTIL limit DO body`` (ALGOL semantics, S:1517)."""

    variable: Name
    start: Expr
    step: Expr
    limit: Expr
    body: Stmt


@dataclass(frozen=True)
class Signal(Stmt):
    """``SIGNAL event``."""

    event: Name


@dataclass(frozen=True)
class Wait(Stmt):
    """``WAIT event``."""

    event: Name


@dataclass(frozen=True)
class Abort(Stmt):
    """``ABORT("message", ...)``: end the program with a message."""

    args: tuple[Expr, ...]


@dataclass(frozen=True)
class Stop(Stmt):
    """``STOP``: end the motion whose monitor is running."""


# --------------------------------------------------------------------------------------------
# Generic helpers

N = TypeVar("N", bound=Node)


def children(node: Node) -> Iterator[Node]:
    """Yield the direct child nodes of ``node``, in field order."""
    for f in fields(node):
        value: Any = getattr(node, f.name)
        if isinstance(value, Node):
            yield value
        elif isinstance(value, tuple):
            for item in value:
                if isinstance(item, Node):
                    yield item


def walk(node: Node) -> Iterator[Node]:
    """Yield ``node`` and all its descendants, depth first, in source order."""
    stack = [node]
    while stack:
        current = stack.pop()
        yield current
        stack.extend(reversed(list(children(current))))


MAX_NESTING = 100
"""Deepest nesting of AST nodes below the program: statements inside blocks, IF, WHILE and FOR
bodies, and expressions inside expressions, all counted alike. The parser refuses deeper
programs with a syntax error and the interpreter with a runtime error, both naming the line:
evaluation recurses (two or three Python frames a level), so without the bound ~1 000 nested
NOTs, IFs, BEGINs or ABS calls ran into Python's recursion limit. The generated programs nest
fewer than 10 levels."""


def too_deep(node: Node, limit: int = MAX_NESTING) -> Node | None:
    """The first node (depth first, in source order) more than ``limit`` levels below ``node``.

    None when the tree is at most ``limit`` deep. Iterative, so any depth can be checked.
    """
    stack = [(node, 0)]
    while stack:
        current, depth = stack.pop()
        if depth > limit:
            return current
        stack.extend((child, depth + 1) for child in reversed(list(children(current))))
    return None


def without_positions(node: N) -> N:
    """Copy ``node`` with every position zeroed, to compare shapes (round trips)."""
    changes: dict[str, Any] = {}
    for f in fields(node):
        value: Any = getattr(node, f.name)
        if f.name in POSITION_FIELDS:
            if value:
                changes[f.name] = 0
        elif isinstance(value, Node):
            changes[f.name] = without_positions(value)
        elif isinstance(value, tuple) and any(isinstance(v, Node) for v in value):
            changes[f.name] = tuple(
                without_positions(v) if isinstance(v, Node) else v for v in value
            )
    return replace(node, **changes) if changes else node
