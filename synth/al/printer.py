"""AL AST → canonical AL text, such that ``parse(format_program(p)) == p`` up to positions.

Canonical form: keywords and names upper case; ``←`` for assignment; ``WITH`` for WHERE;
``SCALAR`` for REAL; relations ``< > = ≤ ≥ ≠``; ``.`` for the dot product; the fewest
parentheses the precedence of ``al.lark`` allows; comments are not kept by the AST and so not
printed; numbers in plain decimal notation (AL has no exponent form); strings in double quotes
with ``""`` for a quote. Every statement of a sequence ends with ``;``; motion clauses go one per
line under their statement; nested statements are indented by two spaces.

Two AST shapes have no text of their own, because the grammar resolves them the other way
(``al.lark`` header): an IF-with-ELSE whose THEN branch ends in an IF without ELSE, and an ON
clause followed by more clauses whose body ends in a motion statement. The printer wraps such a
branch in ``BEGIN ... END``, which means the same; the parser never produces those shapes, so
the round trip is exact for every parsed program.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from decimal import Decimal

from synth.al import ast
from synth.al.parser import grammar_keywords

__all__ = ["format_expression", "format_program", "format_statement"]

INDENT = "  "
_IDENTIFIER = re.compile(r"[A-Z][A-Z0-9_]*", re.ASCII)
_CONSTRUCTORS = frozenset({"FRAME", "VECTOR", "ROT", "TRANS"})

# Binding strength; a child printed where a stronger one is required gets parentheses.
_ASSIGN, _OR, _AND, _NOT, _RELATION, _SUM, _DOT, _PRODUCT, _UNARY, _PRIMARY = range(10)
_BINARY_PRECEDENCE = {"OR": _OR, "AND": _AND, "+": _SUM, "-": _SUM, ".": _DOT}
_BINARY_PRECEDENCE |= {"*": _PRODUCT, "/": _PRODUCT}


def format_program(program: ast.Program) -> str:
    """Print a whole program: each statement ends in ``;``, the text in a newline."""
    return "".join(line + "\n" for line in _sequence(program.body))


def format_statement(statement: ast.Stmt) -> str:
    """Print one statement (no trailing ``;``), possibly on several lines."""
    return "\n".join(_statement(statement))


def format_expression(expression: ast.Expr) -> str:
    """Print one expression on one line."""
    return _expression(expression, _ASSIGN)


# --------------------------------------------------------------------------------------------
# Lexical pieces


def _name(name: ast.Name, *, callee: bool = False) -> str:
    text = name.name
    if _IDENTIFIER.fullmatch(text) is None:
        raise ValueError(f"{name.spelling!r} is not an AL identifier")
    if text in grammar_keywords() and not (callee and text in _CONSTRUCTORS):
        raise ValueError(f"{text!r} is an AL keyword and cannot be printed as a name")
    return text


def _string(value: str) -> str:
    if "\n" in value or "\r" in value:
        raise ValueError(f"an AL string cannot contain a line break: {value!r}")
    return '"' + value.replace('"', '""') + '"'


def _number(value: float) -> str:
    """Shortest round-tripping decimal, never with an exponent (``1e-05`` → ``0.00001``)."""
    if value.is_integer() and abs(value) < 1e16:
        return str(int(value))
    text = format(Decimal(repr(value)), "f")
    return text.rstrip("0").rstrip(".") if "." in text else text


# --------------------------------------------------------------------------------------------
# Expressions


def _precedence(expression: ast.Expr) -> int:
    if isinstance(expression, ast.AssignExpr):
        return _ASSIGN
    if isinstance(expression, ast.BinOp):
        return _BINARY_PRECEDENCE[expression.op]
    if isinstance(expression, ast.UnaryOp):
        return _NOT if expression.op == "NOT" else _UNARY
    if isinstance(expression, ast.Compare):
        return _RELATION
    return _PRIMARY


def _expression(expression: ast.Expr, required: int) -> str:
    text = _bare(expression)
    return f"({text})" if _precedence(expression) < required else text


def _bare(e: ast.Expr) -> str:
    if isinstance(e, ast.Number):
        return _number(e.value)
    if isinstance(e, ast.String):
        return _string(e.value)
    if isinstance(e, ast.Name):
        return _name(e)
    if isinstance(e, ast.Call):
        args = ",".join(_expression(a, _ASSIGN) for a in e.args)
        return f"{_name(e.func, callee=True)}({args})"
    if isinstance(e, ast.BinOp):
        level = _BINARY_PRECEDENCE.get(e.op)
        if level is None:
            raise ValueError(f"unknown binary operator {e.op!r}")
        left = _expression(e.left, level)
        right = _expression(e.right, level + 1)
        return f"{left}{e.op}{right}" if level == _PRODUCT else f"{left} {e.op} {right}"
    if isinstance(e, ast.UnaryOp):
        if e.op == "NOT":
            return "NOT " + _expression(e.operand, _NOT)
        if e.op not in ("+", "-"):
            raise ValueError(f"unknown unary operator {e.op!r}")
        operand = _expression(e.operand, _UNARY)
        return e.op + (" " if operand[0] in "+-" else "") + operand
    if isinstance(e, ast.Compare):
        parts = [_expression(e.operands[0], _SUM)]
        for op, item in zip(e.ops, e.operands[1:], strict=True):
            parts += [op, _expression(item, _SUM)]
        return " ".join(parts)
    if isinstance(e, ast.Magnitude):
        return "|" + _expression(e.operand, _ASSIGN) + "|"
    if isinstance(e, ast.AssignExpr):
        return f"{_name(e.target)} ← {_expression(e.value, _ASSIGN)}"
    raise TypeError(f"not an AL expression node: {type(e).__name__}")


# --------------------------------------------------------------------------------------------
# Statements

_MOTIONS = (ast.Move, ast.Open, ast.Close, ast.Center)


def _tail(statement: ast.Stmt) -> ast.Stmt | None:
    """Return the nested statement whose text ends ``statement``'s text, if any."""
    if isinstance(statement, ast.If):
        return statement.orelse if statement.orelse is not None else statement.then
    if isinstance(statement, ast.While | ast.For):
        return statement.body
    if isinstance(statement, _MOTIONS) and statement.clauses:
        last = statement.clauses[-1]
        return last.body if isinstance(last, ast.OnClause) else None
    return None


def _ends_with(statement: ast.Stmt, test: Callable[[ast.Stmt], bool]) -> bool:
    current: ast.Stmt | None = statement
    while current is not None:
        if test(current):
            return True
        current = _tail(current)
    return False


def _open_if(statement: ast.Stmt) -> bool:
    return isinstance(statement, ast.If) and statement.orelse is None


def _is_motion(statement: ast.Stmt) -> bool:
    return isinstance(statement, _MOTIONS)


def _wrapped(statement: ast.Stmt) -> ast.Stmt:
    return ast.Block(None, (statement,))


def _indent(lines: list[str]) -> list[str]:
    return [INDENT + line for line in lines]


def _attach(header: str, body: list[str]) -> list[str]:
    """``header body`` on one line when the body is one line, else the body indented below."""
    if len(body) == 1:
        return [f"{header} {body[0]}"]
    return [header, *_indent(body)]


def _sequence(statements: tuple[ast.Stmt, ...]) -> list[str]:
    lines: list[str] = []
    for statement in statements:
        rendered = _statement(statement)
        rendered[-1] += ";"
        lines += rendered
    return lines


def _clause_lines(statement: ast.Move | ast.Open | ast.Close | ast.Center) -> list[str]:
    lines: list[str] = []
    count = len(statement.clauses)
    for index, clause in enumerate(statement.clauses):
        if isinstance(clause, ast.ViaClause):
            lines.append("VIA " + ", ".join(_expression(p, _ASSIGN) for p in clause.points))
        elif isinstance(clause, ast.WithClause):
            lines.append("WITH " + ", ".join(_expression(c, _ASSIGN) for c in clause.conditions))
        elif isinstance(clause, ast.OnClause):
            body = clause.body
            if index < count - 1 and _ends_with(body, _is_motion):
                body = _wrapped(body)
            lines += _attach(f"ON {_expression(clause.condition, _ASSIGN)} DO", _statement(body))
        else:
            raise TypeError(f"not an AL clause node: {type(clause).__name__}")
    return lines


def _statement(s: ast.Stmt) -> list[str]:
    if isinstance(s, ast.Block):
        head = "BEGIN" if s.name is None else f"BEGIN {_string(s.name)}"
        tail = "END" if s.end_name is None else f"END {_string(s.end_name)}"
        return [head, *_indent(_sequence(s.body)), tail]
    if isinstance(s, ast.Cobegin):
        return ["COBEGIN", *_indent(_sequence(s.body)), "COEND"]
    if isinstance(s, ast.Declaration):
        if s.type not in ast.DECLARABLE_TYPES or not s.names:
            raise ValueError(f"cannot declare {s.type!r} {s.names!r}")
        return [f"{s.type} " + ", ".join(_name(n) for n in s.names)]
    if isinstance(s, ast.Assign):
        return [f"{_name(s.target)} ← {_expression(s.value, _ASSIGN)}"]
    if isinstance(s, _MOTIONS):
        return [_motion_head(s), *_indent(_clause_lines(s))]
    if isinstance(s, ast.Affix):
        text = f"AFFIX {_name(s.frame)} TO {_name(s.parent)}"
        if s.rigid:
            text += " RIGIDLY"
        if s.at is not None:
            text += f" AT {_expression(s.at, _ASSIGN)}"
        return [text]
    if isinstance(s, ast.Unfix):
        return [f"UNFIX {_name(s.frame)} FROM {_name(s.parent)}"]
    if isinstance(s, ast.If):
        then = s.then
        if s.orelse is not None and _ends_with(then, _open_if):
            then = _wrapped(then)
        lines = _attach(f"IF {_expression(s.condition, _ASSIGN)} THEN", _statement(then))
        if s.orelse is not None:
            orelse = _statement(s.orelse)
            if isinstance(s.orelse, ast.If):
                lines += ["ELSE " + orelse[0], *orelse[1:]]
            else:
                lines += _attach("ELSE", orelse)
        return lines
    if isinstance(s, ast.While):
        return _attach(f"WHILE {_expression(s.condition, _ASSIGN)} DO", _statement(s.body))
    if isinstance(s, ast.For):
        head = (
            f"FOR {_name(s.variable)} ← {_expression(s.start, _ASSIGN)}"
            f" STEP {_expression(s.step, _ASSIGN)} UNTIL {_expression(s.limit, _ASSIGN)} DO"
        )
        return _attach(head, _statement(s.body))
    if isinstance(s, ast.Signal):
        return [f"SIGNAL {_name(s.event)}"]
    if isinstance(s, ast.Wait):
        return [f"WAIT {_name(s.event)}"]
    if isinstance(s, ast.Abort):
        return ["ABORT(" + ",".join(_expression(a, _ASSIGN) for a in s.args) + ")"]
    if isinstance(s, ast.Stop):
        return ["STOP"]
    raise TypeError(f"not an AL statement node: {type(s).__name__}")


def _motion_head(s: ast.Move | ast.Open | ast.Close | ast.Center) -> str:
    if isinstance(s, ast.Move):
        return f"MOVE {_name(s.frame)} TO {_expression(s.destination, _ASSIGN)}"
    if isinstance(s, ast.Open):
        return f"OPEN {_name(s.device)} TO {_expression(s.width, _ASSIGN)}"
    if isinstance(s, ast.Close):
        width = "" if s.width is None else f" TO {_expression(s.width, _ASSIGN)}"
        return f"CLOSE {_name(s.device)}{width}"
    return f"CENTER {_name(s.device)}"
