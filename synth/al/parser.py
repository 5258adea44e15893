"""Parse AL text into the AST of :mod:`synth.al.ast`; syntax errors raise :class:`ALSyntaxError`.

The grammar is the package file ``al.lark`` (its header lists every decision about AL's
ambiguous surface syntax). One Lark parser is built on first use and cached:

- ``parser="lalr"``: the grammar is LALR(1) once two classic ambiguities are settled the way
  ALGOL settles them — ELSE binds to the nearest IF, and motion clauses after a motion that is
  the body of an ON clause bind to that inner motion (both by shift). LALR is linear-time and
  gives exact error states for ``match_examples``; Earley is not needed.
- ``lexer="contextual"``: after an operand only operators are looked for, so ``V.3*W`` is a dot
  product while ``.3`` elsewhere is a number. Keyword terminals are word-bounded regexes, and a
  lexer callback turns an identifier that spells a keyword into that keyword, so a keyword can
  never be taken for a variable (``X ← END`` fails at ``END``).
- The AST is built by an inline transformer during the parse (no intermediate tree); each
  callback computes its node's span from its first and last child, so all grammar tokens are
  named terminals that stay in the children.

Errors carry line, column, caret context, and what the grammar accepts at that point (lark's
``accepts``, computed by replaying the parser, grouped into "a statement", "an expression",
"an operator" where those sets appear whole). Common mistakes get a hint: ``;`` before ELSE
(recognised with lark's ``match_examples``), a missing ``;`` between statements, a number
followed by a unit without ``*``, a keyword used as a name, unterminated comments and strings.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import replace
from importlib import resources
from typing import Any, cast

from lark import Lark, Token, Transformer
from lark.exceptions import (
    UnexpectedCharacters,
    UnexpectedEOF,
    UnexpectedInput,
    UnexpectedToken,
)

from synth.al import ast
from synth.al.names import UNITS
from synth.exceptions import ALSyntaxError

__all__ = ["grammar_keywords", "parse_program"]

_LONE_CR = re.compile(r"\r(?!\n)")
_KEYWORD_LINE = re.compile(r"^([A-Z]+)\.2:\s*/([a-z]+)\\b/i\s*$", re.MULTILINE)

_BINARY = {
    "PLUS": "+",
    "MINUS": "-",
    "STAR": "*",
    "SLASH": "/",
    "DOT": ".",
    "AND": "AND",
    "OR": "OR",
}
_UNARY = {"PLUS": "+", "MINUS": "-", "NOT": "NOT"}
_RELATION = {"LT": "<", "GT": ">", "EQ": "=", "LE": "≤", "GE": "≥", "NE": "≠"}


def _grammar_text() -> str:
    return resources.files("synth.al").joinpath("al.lark").read_text(encoding="utf-8")


@functools.cache
def _keyword_types() -> dict[str, str]:
    """Upper-case keyword spelling → terminal name, read from the grammar's keyword section."""
    return {word.upper(): name for name, word in _KEYWORD_LINE.findall(_grammar_text())}


def grammar_keywords() -> frozenset[str]:
    """Return the words the grammar reserves (BEGIN, MOVE, FRAME, ...), upper-case."""
    return frozenset(_keyword_types())


def _retype_keyword(token: Token) -> Token:
    """Lexer callback for NAME: a name spelling a keyword becomes that keyword's token."""
    kind = _keyword_types().get(token.value.upper())
    if kind is not None:
        token.type = kind
    return token


# --------------------------------------------------------------------------------------------
# Tree → AST


class _TokenError(Exception):
    """A token the grammar accepts but AL does not; the caller makes it an ALSyntaxError.

    An AFFIX option repeated or contradicted, a number literal too large for a float.
    """

    def __init__(self, token: Token, problem: str) -> None:
        super().__init__(problem)
        self.token = token
        self.problem = problem


def _span(first: Any, last: Any) -> dict[str, int]:
    return {
        "line": first.line,
        "column": first.column,
        "end_line": last.end_line,
        "end_column": last.end_column,
    }


def _located(items: Sequence[Any]) -> list[Any]:
    """Keep the children that carry a position (tokens and nodes; not None or sequences)."""
    return [c for c in items if isinstance(c, Token | ast.Node)]


def _node_span(items: Sequence[Any]) -> dict[str, int]:
    located = _located(items)
    return _span(located[0], located[-1])


def _exprs(items: Iterable[Any]) -> tuple[ast.Expr, ...]:
    return tuple(c for c in items if isinstance(c, ast.Expr))


def _clauses(items: Iterable[Any]) -> tuple[ast.Clause, ...]:
    return tuple(c for c in items if isinstance(c, ast.Clause))


def _unquote(token: Token) -> str:
    return token.value[1:-1].replace('""', '"')


class _ToAST(Transformer[Token, Any]):
    """Inline LALR callbacks: each method gets its rule's children and returns an AST node."""

    # ---- program and blocks

    def start(self, c: list[Any]) -> ast.Program:
        body: tuple[ast.Stmt, ...] = c[0]
        if not body:
            return ast.Program(body)
        first, last = body[0], body[-1]
        return ast.Program(
            body,
            line=first.line,
            column=first.column,
            end_line=last.end_line,
            end_column=last.end_column,
        )

    def stmt_seq(self, c: list[Any]) -> tuple[ast.Stmt, ...]:
        return tuple(s for s in c if isinstance(s, ast.Stmt))

    def block(self, c: list[Any]) -> ast.Block:
        name = _unquote(c[1]) if c[1] is not None else None
        end_name = _unquote(c[4]) if c[4] is not None else None
        return ast.Block(name, c[2], end_name, **_node_span(c))

    def cobegin(self, c: list[Any]) -> ast.Cobegin:
        return ast.Cobegin(c[1], **_node_span(c))

    # ---- simple statements

    def type_kw(self, c: list[Token]) -> Token:
        return c[0]

    def decl(self, c: list[Any]) -> ast.Declaration:
        kind = c[0].type
        kind = "SCALAR" if kind == "REAL" else kind
        names = tuple(x for x in c if isinstance(x, ast.Name))
        return ast.Declaration(kind, names, **_node_span(c))

    def assign(self, c: list[Any]) -> ast.Assign:
        return ast.Assign(c[0], c[2], **_node_span(c))

    def signal_stmt(self, c: list[Any]) -> ast.Signal:
        return ast.Signal(c[1], **_node_span(c))

    def wait_stmt(self, c: list[Any]) -> ast.Wait:
        return ast.Wait(c[1], **_node_span(c))

    def abort_stmt(self, c: list[Any]) -> ast.Abort:
        return ast.Abort(_exprs(c), **_node_span(c))

    def stop_stmt(self, c: list[Any]) -> ast.Stop:
        return ast.Stop(**_node_span(c))

    # ---- motion and hand

    def move_stmt(self, c: list[Any]) -> ast.Move:
        return ast.Move(c[1], c[3], _clauses(c[4:]), **_node_span(c))

    def open_stmt(self, c: list[Any]) -> ast.Open:
        return ast.Open(c[1], c[3], _clauses(c[4:]), **_node_span(c))

    def close_stmt(self, c: list[Any]) -> ast.Close:
        width = c[3] if isinstance(c[2], Token) else None
        return ast.Close(c[1], width, _clauses(c[2:]), **_node_span(c))

    def center_stmt(self, c: list[Any]) -> ast.Center:
        return ast.Center(c[1], _clauses(c[2:]), **_node_span(c))

    def via_clause(self, c: list[Any]) -> ast.ViaClause:
        return ast.ViaClause(_exprs(c), **_node_span(c))

    def with_clause(self, c: list[Any]) -> ast.WithClause:
        return ast.WithClause(_exprs(c), **_node_span(c))

    def on_clause(self, c: list[Any]) -> ast.OnClause:
        return ast.OnClause(c[1], c[3], **_node_span(c))

    # ---- affixment

    def affix_option(self, c: list[Any]) -> tuple[Token, Any]:
        head: Token = c[0]
        if head.type == "AT":
            return head, c[1]
        return head, head.type == "RIGIDLY"

    def affix_stmt(self, c: list[Any]) -> ast.Affix:
        at: ast.Expr | None = None
        rigid: bool | None = None
        last: Any = c[3]
        for head, value in c[4:]:
            if head.type == "AT":
                if at is not None:
                    raise _TokenError(head, "AFFIX has more than one AT")
                at = value
                last = value
            else:
                if rigid is not None:
                    raise _TokenError(head, "AFFIX has more than one RIGIDLY / NONRIGIDLY option")
                rigid = value
                last = head
        return ast.Affix(c[1], c[3], at, bool(rigid), **_span(c[0], last))

    def unfix_stmt(self, c: list[Any]) -> ast.Unfix:
        return ast.Unfix(c[1], c[3], **_node_span(c))

    # ---- control

    def if_stmt(self, c: list[Any]) -> ast.If:
        return ast.If(c[1], c[3], c[5], **_node_span(c))

    def while_stmt(self, c: list[Any]) -> ast.While:
        return ast.While(c[1], c[3], **_node_span(c))

    def for_stmt(self, c: list[Any]) -> ast.For:
        return ast.For(c[1], c[3], c[5], c[7], c[9], **_node_span(c))

    # ---- expressions

    def assign_expr(self, c: list[Any]) -> ast.AssignExpr:
        return ast.AssignExpr(c[0], c[2], **_node_span(c))

    def binop(self, c: list[Any]) -> ast.BinOp:
        return ast.BinOp(_BINARY[c[1].type], c[0], c[2], **_node_span(c))

    def unop(self, c: list[Any]) -> ast.UnaryOp:
        return ast.UnaryOp(_UNARY[c[0].type], c[1], **_node_span(c))

    def relop(self, c: list[Token]) -> Token:
        return c[0]

    def compare(self, c: list[Any]) -> ast.Compare:
        operands = tuple(c[0::2])
        ops = tuple(_RELATION[t.type] for t in c[1::2])
        return ast.Compare(operands, ops, **_node_span(c))

    def number(self, c: list[Token]) -> ast.Number:
        value = float(c[0].value)  # digits only (the grammar's NUMBER): never a ValueError
        if math.isinf(value):
            digits = len(c[0].value.split(".")[0])
            raise _TokenError(
                c[0], f"the number literal ({digits} digits) is too large: at most ~1.8e308"
            )
        return ast.Number(value, c[0].value, **_node_span(c))

    def string(self, c: list[Token]) -> ast.String:
        return ast.String(_unquote(c[0]), **_node_span(c))

    def name(self, c: list[Token]) -> ast.Name:
        return ast.Name(c[0].value.upper(), c[0].value, **_node_span(c))

    def var(self, c: list[Any]) -> ast.Name:
        name: ast.Name = c[0]
        return name

    def callee(self, c: list[Any]) -> ast.Name:
        item = c[0]
        if isinstance(item, ast.Name):
            return item
        return ast.Name(item.value.upper(), item.value, **_node_span(c))

    def call(self, c: list[Any]) -> ast.Call:
        return ast.Call(c[0], _exprs(c[1:]), **_node_span(c))

    def paren(self, c: list[Any]) -> ast.Expr:
        inner: ast.Expr = c[1]
        return inner

    def magnitude(self, c: list[Any]) -> ast.Magnitude:
        return ast.Magnitude(c[1], **_node_span(c))


@functools.cache
def _lark() -> Lark:
    """Build the one AL parser (on first use, ~0.2 s; cached)."""
    return Lark(
        _grammar_text(),
        parser="lalr",
        lexer="contextual",
        transformer=_ToAST(),
        lexer_callbacks={"NAME": _retype_keyword},
        maybe_placeholders=True,
    )


def parse_program(text: str, *, filename: str = "<al>") -> ast.Program:
    """Parse AL source ``text`` into an :class:`~synth.al.ast.Program`.

    The last few programs parsed are kept (:func:`_parsed`): a program is parsed again by each
    stage that takes its text (the emitter's check, the nominal replay, the proof, the
    service), and the tree is immutable (frozen nodes, tuples), so a kept tree is a fresh one.

    Raises:
        ALSyntaxError: the text is not AL; the error names file, line, column, a caret
            context and what the grammar expected there. Also for a number literal too large
            for a float (309 digits) and for a program nested more than
            :data:`~synth.al.ast.MAX_NESTING` levels deep.
    """
    if len(text) > _KEPT_TEXT:
        return _parse(text, filename)
    return _parsed(text, filename)


_KEPT_TEXT = 1 << 16
"""[characters] The longest program whose tree is kept: synth's own programs are a few kB, and
a megabyte of hostile text must not leave its tree (tens of MB) behind in a server process."""


def _parse(text: str, filename: str) -> ast.Program:
    """:func:`parse_program` itself."""
    # A lone CR ends a line for editors but not for lark's line counter, whose columns would
    # then be offsets into the whole text; one character for one keeps every position.
    text = _LONE_CR.sub("\n", text)
    try:
        program = cast(ast.Program, _lark().parse(text))
    except UnexpectedInput as error:
        problem = _syntax_error(error, text, filename)
        problem.context = problem.context.replace("\r", "")
        raise problem from None
    except _TokenError as error:
        line, column = error.token.line or 1, error.token.column or 1
        raise ALSyntaxError(
            line,
            column,
            error.problem,
            context=_caret(text, line, column),
            filename=filename,
        ) from None
    deep = ast.too_deep(program)
    if deep is not None:
        raise ALSyntaxError(
            deep.line,
            deep.column,
            f"nested more than {ast.MAX_NESTING} levels deep (statements and expressions)",
            context=_caret(text, deep.line, deep.column),
            filename=filename,
        )
    return replace(program, filename=filename) if filename != program.filename else program


_parsed = functools.lru_cache(maxsize=32)(_parse)  # a syntax error is raised afresh, not kept


# --------------------------------------------------------------------------------------------
# Errors

_IGNORED = frozenset({"WS", "BRACE_COMMENT", "BANG_COMMENT"})
_STATEMENT_KEYWORDS = frozenset(
    {"BEGIN", "COBEGIN", "FRAME", "VECTOR", "ROT", "TRANS", "SCALAR", "REAL", "BOOLEAN", "EVENT"}
    | {"MOVE", "OPEN", "CLOSE", "CENTER", "AFFIX", "UNFIX", "IF", "WHILE", "FOR", "SIGNAL"}
    | {"WAIT", "ABORT", "STOP"}
)
_STATEMENT_START = _STATEMENT_KEYWORDS | {"NAME"}
_EXPRESSION_START = frozenset(
    {"NAME", "NUMBER", "STRING", "LPAR", "BAR", "PLUS", "MINUS", "NOT"}
    | {"FRAME", "VECTOR", "ROT", "TRANS"}
)
_OPERATORS = frozenset(
    {"PLUS", "MINUS", "STAR", "SLASH", "DOT", "LT", "GT", "LE", "GE", "EQ", "NE", "AND", "OR"}
)
_SHOWN = {
    "NAME": "a name",
    "NUMBER": "a number",
    "STRING": "a string",
    "$END": "end of input",
    "ARROW": "'←'",
    "EQ": "'='",
    "LE": "'≤'",
    "GE": "'≥'",
    "NE": "'≠'",
    "LT": "'<'",
    "GT": "'>'",
    "PLUS": "'+'",
    "MINUS": "'-'",
    "STAR": "'*'",
    "SLASH": "'/'",
    "DOT": "'.'",
    "BAR": "'|'",
    "LPAR": "'('",
    "RPAR": "')'",
    "COMMA": "','",
    "SEMI": "';'",
}
_CHARACTER_PROBLEMS = {
    "{": "unterminated '{' comment",
    "!": "unterminated '!' comment",
    '"': 'unterminated string (a string ends on its own line; write "" for a quote)',
    "}": "'}' without a matching '{'",
    "°": "'°' is not AL (write *DEG)",
}
# Wrong keywords recognised by parser state (lark's match_examples). A label is used only when
# the offending token is the one its examples are about, since other errors share the state.
_STATE_EXAMPLES: dict[str, list[str]] = {
    "AL's loop is FOR v ← a STEP s UNTIL b DO": ["FOR N ← 1 TO 6 DO STOP"],
    "WHILE takes DO, not THEN": ["WHILE A THEN STOP"],
    "IF takes THEN, not DO": ["IF A DO STOP"],
    "ON takes DO, not THEN": ["MOVE A TO B ON C THEN STOP"],
    "a motion's destination follows TO; VIA points come after it": ["MOVE A VIA B TO C"],
}
_STATE_EXAMPLE_TOKENS = {
    "AL's loop is FOR v ← a STEP s UNTIL b DO": "TO",
    "WHILE takes DO, not THEN": "THEN",
    "IF takes THEN, not DO": "DO",
    "ON takes DO, not THEN": "THEN",
    "a motion's destination follows TO; VIA points come after it": "VIA",
}


def describe_expected(terminals: Iterable[str]) -> tuple[str, ...]:
    """Readable names for a set of terminal names, whole families folded into one phrase."""
    names = set(terminals) - _IGNORED
    shown: list[str] = []
    if {"MOVE", "IF", "STOP", "BEGIN"} <= names:
        shown.append("a statement")
        names -= _STATEMENT_START
    if {"NUMBER", "STRING", "LPAR"} <= names:
        shown.append("an expression")
        names -= _EXPRESSION_START
    if {"STAR", "PLUS", "LT"} <= names:
        shown.append("an operator")
        names -= _OPERATORS
    words = sorted(n for n in names if n not in _SHOWN)
    symbols = sorted((n for n in names if n in _SHOWN), key=list(_SHOWN).index)
    return (*shown, *words, *(_SHOWN[n] for n in symbols))


def _describe_token(token: Token) -> str:
    if token.type == "$END":
        return "end of input"
    if token.type in _keyword_types().values():
        return token.value.upper()
    if token.type in {"NAME", "NUMBER", "STRING"}:
        return f"{_SHOWN[token.type][2:]} {token.value}"
    return repr(token.value)


def _caret(text: str, line: int, column: int) -> str:
    lines = text.split("\n")
    source = lines[line - 1] if 0 < line <= len(lines) else ""
    before = source[: column - 1]
    return source + "\n" + " " * len(before.expandtabs()) + "^\n"


def _end_of(text: str) -> tuple[int, int]:
    last = text.rsplit("\n", 1)[-1]
    return text.count("\n") + 1, len(last) + 1


def _accepts(error: UnexpectedToken) -> frozenset[str]:
    try:
        return frozenset(error.accepts)
    except Exception:  # replaying the parser must never hide the real error
        return frozenset(error.expected)


def _previous_token(text: str, token: Token) -> Token | None:
    """Find the token before ``token`` (lark keeps no history for parser-level errors)."""
    if token.type == "$END":
        end = len(text)
    elif token.start_pos is None:
        return None
    else:
        end = token.start_pos
    previous: Token | None = None
    try:
        for lexed in _lark().lex(text[:end]):
            previous = lexed
    except UnexpectedInput:
        return None
    return previous


def _unclosed(text: str, opening: str, closing: str) -> str:
    """``the BEGIN at line 25 has no matching END``: the innermost block left open at the end."""
    open_lines: list[int] = []
    try:
        for token in _lark().lex(text):
            if token.type == opening:
                open_lines.append(token.line or 0)
            elif token.type == closing and open_lines:
                open_lines.pop()
    except UnexpectedInput:
        open_lines = []
    if not open_lines:
        return f"a {opening} has no matching {closing}"
    return f"the {opening} at line {open_lines[-1]} has no matching {closing}"


def _token_hint(error: UnexpectedToken, text: str, accepts: frozenset[str]) -> str | None:
    token = error.token
    previous = _previous_token(text, token)
    kind = token.type
    if kind == "ELSE" and previous is not None and previous.type == "SEMI":
        return "AL has no ';' before ELSE"
    if kind in _STATE_EXAMPLE_TOKENS.values():
        label = error.match_examples(_lark().parse, _STATE_EXAMPLES, use_accepts=True)
        if label is not None and _STATE_EXAMPLE_TOKENS[label] == kind:
            return label
    if kind == "$END":
        if "END" in accepts:
            return _unclosed(text, "BEGIN", "END")
        if "COEND" in accepts:
            return _unclosed(text, "COBEGIN", "COEND")
        return None
    after_number = previous is not None and previous.type == "NUMBER" and kind == "NAME"
    if after_number and previous is not None and previous.end_pos == token.start_pos:
        return "AL numbers have no exponent, and a unit is multiplied in: 8*OZ"
    if after_number and token.value.upper() in UNITS and "STAR" in accepts:
        return "missing '*' between a number and its unit?"
    if kind in _STATEMENT_START and "SEMI" in accepts:
        return "missing ';' before this statement?"
    if kind in _keyword_types().values() and "NAME" in accepts and "MOVE" not in accepts:
        return f"{token.value.upper()} is a reserved word and cannot be a name"
    if "RPAR" in accepts and kind in {"SEMI", "$END", "THEN", "DO"}:
        return "missing ')'?"
    return None


def _accepts_before(text: str) -> frozenset[str]:
    """Replay the parse up to a lexical error; return what the parser accepts there."""
    interactive = _lark().parse_interactive(text)
    try:
        for _ in interactive.iter_parse():
            pass
    except UnexpectedInput:
        try:
            return frozenset(interactive.accepts())
        except Exception:  # replaying the parser must never hide the real error
            return frozenset()
    return frozenset()


def _syntax_error(error: UnexpectedInput, text: str, filename: str) -> ALSyntaxError:
    if isinstance(error, UnexpectedToken):
        token = error.token
        accepts = _accepts(error)
        expected = describe_expected(accepts)
        hint = _token_hint(error, text, accepts)
        if token.type == "$END":
            line, column = _end_of(text)
            context = _caret(text, line, column)
        else:
            line, column = token.line, token.column
            context = error.get_context(text)
        return ALSyntaxError(
            line,
            column,
            f"unexpected {_describe_token(token)}",
            context=context,
            expected=expected,
            filename=filename,
            hint=hint,
        )
    if isinstance(error, UnexpectedCharacters):
        char = error.char
        problem = _CHARACTER_PROBLEMS.get(char, f"unexpected character {char!r}")
        return ALSyntaxError(
            error.line,
            error.column,
            problem,
            context=error.get_context(text),
            expected=describe_expected(_accepts_before(text) or error.allowed or ()),
            filename=filename,
        )
    if isinstance(error, UnexpectedEOF):
        line, column = _end_of(text)
        return ALSyntaxError(
            line,
            column,
            "unexpected end of input",
            context=_caret(text, line, column),
            expected=describe_expected(error.expected),
            filename=filename,
        )
    line = getattr(error, "line", 1) or 1
    column = getattr(error, "column", 1) or 1
    return ALSyntaxError(line, column, str(error), filename=filename)
