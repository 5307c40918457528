"""Tests of swarmgen.expr: parsing, errors, limits, renderings and their safety."""

from __future__ import annotations

import ast
import contextlib
import json
import operator
import pickle
from collections.abc import Callable
from typing import Any

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from pydantic import TypeAdapter, ValidationError

from swarmgen.expr import (
    MAX_DEPTH,
    MAX_INT,
    MAX_TEXT,
    RESERVED,
    Action,
    Arg,
    Assign,
    Attr,
    Binary,
    Binding,
    Const,
    Else,
    EventField,
    Expr,
    ExprError,
    Name,
    Raise,
    Send,
    Unary,
    event_fields,
    free_names,
    parse_actions,
    parse_bindings,
    parse_expr,
    to_ecmascript,
    to_python,
    to_text,
    walk,
)

FAST = settings(max_examples=200, deadline=None)


def py(e: Expr) -> str:
    """Python rendering with readable callbacks: fully parenthesised, so it shows the tree."""
    return to_python(e, name=lambda n: n, event_field=lambda f: f"event.{f}")


# --- precedence and associativity -----------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "tree"),
    [
        ("a + b * c", "(a + (b * c))"),
        ("a * b + c", "((a * b) + c)"),
        ("a - b - c", "((a - b) - c)"),
        ("a / b / c", "((a / b) / c)"),
        ("a % b * c", "((a % b) * c)"),
        ("(a + b) * c", "((a + b) * c)"),
        ("a or b and c", "(a or (b and c))"),
        ("a and b or c", "((a and b) or c)"),
        ("a or b or c", "((a or b) or c)"),
        ("a and b and c", "((a and b) and c)"),
        ("not a and b", "((not a) and b)"),
        ("a and not b", "(a and (not b))"),
        ("not a == b", "(not (a == b))"),
        ("not not a", "(not (not a))"),
        ("a == b and c != d", "((a == b) and (c != d))"),
        ("a < b + c", "(a < (b + c))"),
        ("a + b >= c * d", "((a + b) >= (c * d))"),
        ("(a < b) < c", "((a < b) < c)"),
        ("a < (b < c)", "(a < (b < c))"),
        ("-a * b", "((-a) * b)"),
        ("-a.b", "(-a.b)"),
        ("a + -b", "(a + (-b))"),
        ("- -a", "(-(-a))"),
        ("+a", "(+a)"),
        ("-2 * 3", "((-2) * 3)"),
        ("2 - -1", "(2 - (-1))"),
        ("-(1)", "(-1)"),
        ("event.x.y > 2", "(event.x.y > 2)"),
        ("!a || b && c", "((not a) or (b and c))"),
        ("a\n and b", "(a and b)"),
    ],
)
def test_precedence(text: str, tree: str) -> None:
    assert py(parse_expr(text)) == tree


def test_negative_literal_is_folded_but_unary_minus_of_group_is_not() -> None:
    assert parse_expr("-1") == Const(value=-1)
    assert parse_expr("- 2.5") == Const(value=-2.5)
    assert parse_expr("-(1)") == Unary(op="-", operand=Const(value=1))
    assert parse_expr("- -1") == Unary(op="-", operand=Const(value=-1))


# --- node kinds -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("42", 42),
        ("007", 7),
        ("1.5", 1.5),
        (".5", 0.5),
        ("1.", 1.0),
        ("1e3", 1000.0),
        ("1.5e-3", 0.0015),
        ("2E+2", 200.0),
        ("'single'", "single"),
        ('"double"', "double"),
        (r'"a\\b\'c\"d\ne\tf\rg"', "a\\b'c\"d\ne\tf\rg"),
        (r"'\x41\u00e9\U0001F600'", "Aé😀"),
        ("'it\"s'", 'it"s'),
        ("''", ""),
        ("true", True),
        ("True", True),
        ("false", False),
        ("False", False),
        ("null", None),
        ("None", None),
    ],
)
def test_literals(text: str, value: object) -> None:
    e = parse_expr(text)
    assert isinstance(e, Const)
    assert e.value == value
    assert type(e.value) is type(value)


def test_every_node_kind() -> None:
    assert parse_expr("speed") == Name(name="speed")
    assert parse_expr("größe") == Name(name="größe")
    assert parse_expr("event.speed") == EventField(field="speed")
    assert parse_expr("pos.x") == Attr(obj=Name(name="pos"), name="x")
    assert parse_expr("event.pos.x") == Attr(obj=EventField(field="pos"), name="x")
    assert parse_expr("not a") == Unary(op="not", operand=Name(name="a"))
    assert parse_expr("a % 2") == Binary(op="%", left=Name(name="a"), right=Const(value=2))
    assert parse_expr("else") == Else()
    assert parse_expr("  else\n") == Else()
    # Words after a dot are field names even when they are keywords elsewhere.
    assert parse_expr("event.not") == EventField(field="not")


@pytest.mark.parametrize(
    ("alias", "canonical"),
    [("a && b", "a and b"), ("a || b", "a or b"), ("!a", "not a"), ("!!a", "not not a")],
)
def test_aliases(alias: str, canonical: str) -> None:
    assert parse_expr(alias) == parse_expr(canonical)
    assert to_text(parse_expr(alias)) == canonical


def test_actions() -> None:
    text = (
        "x = x + 1\nraise done(code = 2, why = 'ok');send ping\n\nsend pong()\nraise e(\n a = 1,\n)"
    )
    assert parse_actions(text) == (
        Assign(target="x", value=parse_expr("x + 1")),
        Raise(
            event="done",
            args=(Arg(name="code", value=Const(value=2)), Arg(name="why", value=Const(value="ok"))),
        ),
        Send(event="ping"),
        Send(event="pong"),
        Raise(event="e", args=(Arg(name="a", value=Const(value=1)),)),
    )


def test_action_edge_cases() -> None:
    assert parse_actions("") == ()
    assert parse_actions(" ;\n; x = 1;") == (Assign(target="x", value=Const(value=1)),)
    # `raise`/`send` followed by `=` assign member data of that name.
    assert parse_actions("send = 1") == (Assign(target="send", value=Const(value=1)),)
    assert parse_actions("raise e(x = event.x)")[0] == Raise(
        event="e", args=(Arg(name="x", value=EventField(field="x")),)
    )


def test_bindings() -> None:
    assert parse_bindings("speed = 2 * v\nheading = event.h; tol = 0.1") == (
        Binding(name="speed", value=parse_expr("2 * v")),
        Binding(name="heading", value=EventField(field="h")),
        Binding(name="tol", value=Const(value=0.1)),
    )
    assert parse_bindings("\n") == ()


def test_queries() -> None:
    e = parse_expr("a + pos.x > event.limit and not b or event.flag == a")
    assert free_names(e) == {"a", "pos", "b"}
    assert event_fields(e) == {"limit", "flag"}
    kinds = [n.kind for n in walk(e)]
    assert kinds[0] == "binary"
    assert kinds.count("name") == 4 and kinds.count("event_field") == 2
    assert [n.name for n in walk(parse_expr("a - b * c")) if isinstance(n, Name)] == ["a", "b", "c"]
    assert free_names(Else()) == frozenset()


# --- errors ---------------------------------------------------------------------------------------

ERRORS: list[tuple[Callable[[str], object], str, str, int, str | None]] = [
    # parse function, text, message, offset, part of the hint
    (parse_expr, "a and )", "expected an expression after 'and'", 6, None),
    (parse_expr, "a and", "expected an expression after 'and'", 5, None),
    (parse_expr, "a || ", "expected an expression after '||'", 5, None),
    (parse_expr, "", "expected an expression", 0, None),
    (parse_expr, ")", "unexpected token ')'", 0, None),
    (parse_expr, "a )", "unexpected token ')'", 2, "unbalanced"),
    (parse_expr, "a b", "unexpected token 'b'", 2, "operator missing"),
    (parse_expr, "x @ y", "unknown character '@'", 2, None),
    (parse_expr, "a & b", "unknown character '&'", 2, "`and`"),
    (parse_expr, "[x > 0]", "a guard is not a list", 0, "without `[ ]`"),
    (parse_expr, "xs[0] > 1", "indexing is not part of the expression language", 2, None),
    (parse_expr, "a = 1", "`==` expected, `=` is assignment", 2, "a == b"),
    (parse_expr, "(a = 1)", "`==` expected, `=` is assignment", 3, "a == b"),
    (parse_expr, "a < b < c", "chained comparison `a < b < c` is not supported", 6, None),
    (parse_expr, "a == b != c", "chained comparison `a == b != c` is not supported", 7, None),
    (parse_expr, "f(x)", "function calls are not part of the expression language", 1, None),
    (
        parse_expr,
        "bank.verifyPIN()",
        "function calls are not part of the expression language",
        14,
        None,
    ),
    (
        parse_expr,
        "numIncorrect++",
        "`++` is not supported; write `numIncorrect = numIncorrect + 1`",
        12,
        None,
    ),
    (parse_expr, "++x", "`++` is not supported; write `x = x + 1`", 0, None),
    (parse_expr, "x--", "`--` is not supported; write `x = x - 1`", 1, None),
    (parse_expr, "x += 2", "`+=` is not supported; write `x = x + ...`", 2, None),
    (parse_expr, "a === b", "`===` is not supported; write `==`", 2, None),
    (parse_expr, "a !== b", "`!==` is not supported; write `!=`", 2, None),
    (parse_expr, "a ** 2", "`**` is not supported", 2, None),
    (parse_expr, "a // 2", "`//` is not supported", 2, None),
    (parse_expr, "'abc", "unterminated string", 0, "close it with '"),
    (parse_expr, 'x == "abc\ny"', "unterminated string", 5, None),
    (parse_expr, r'"ab\q"', "unknown escape '\\q' in string", 3, None),
    (parse_expr, r'"\x4"', "invalid escape '\\x4\"'", 1, None),
    (parse_expr, r'"\ud800"', "strings must not contain lone surrogates", 1, None),
    (parse_expr, "event", "`event` needs a field: event.<field>", 0, None),
    (parse_expr, "event + 1", "`event` needs a field: event.<field>", 0, None),
    (parse_expr, "event.(x)", "expected a field name after 'event.'", 6, None),
    (parse_expr, "a.(b)", "expected a field name after '.'", 2, None),
    (parse_expr, "'s'.x", "attribute access needs a name on the left", 3, None),
    (parse_expr, "x else", "`else` is only allowed as a whole guard", 2, None),
    (parse_expr, "else or x", "`else` is only allowed as a whole guard", 0, None),
    (parse_expr, "(a", "missing ')'", 2, "line 1, column 1"),
    (parse_expr, "a == not b", "'not' needs parentheses here", 5, "a == (not b)"),
    (parse_expr, "a; b", "unexpected token ';'", 1, "single expression"),
    (parse_expr, "__import__", "names starting with `__` are reserved: '__import__'", 0, None),
    (parse_expr, "9007199254740992", "integer '9007199254740992' is too large", 0, None),
    (parse_expr, "1" * 5000, "is too large", 0, None),
    (parse_expr, "1e999", "number '1e999' is too large", 0, None),
    (parse_expr, "and", "unexpected token 'and'", 0, None),
    (parse_actions, "x = 1; atm.abort", "an action must be `name = expression`", 7, None),
    (parse_actions, "x == 1", "an action must be `name = expression`", 0, "did you mean `x = 1`?"),
    (
        parse_actions,
        "bank.verifyPIN()",
        "function calls are not part of the expression language",
        14,
        None,
    ),
    (
        parse_actions,
        "numIncorrect++",
        "`++` is not supported; write `numIncorrect = numIncorrect + 1`",
        12,
        None,
    ),
    (parse_actions, "a.b = 1", "can only assign to member data names, not `a.b`", 0, None),
    (parse_actions, "x = 1 = 2", "`==` expected, `=` is assignment", 6, None),
    (parse_actions, "raise", "expected an event name after 'raise'", 5, None),
    (parse_actions, "send (x)", "expected an event name after 'send'", 5, None),
    (parse_actions, "raise e .x", "unexpected token '.'", 8, None),
    (parse_actions, "raise e(a = 1, a = 2)", "duplicate argument 'a'", 15, None),
    # (`raise e(1)` is the event with the value 1 as its data: `raise e(value)`, W3C <content>)
    (
        parse_actions,
        "raise e(a = 1, 2)",
        "expected an argument `name = expression`, found '2'",
        15,
        None,
    ),
    (
        parse_actions,
        "raise e(a = 1, b)",
        "expected '=' after argument name 'b'",
        16,
        "field = expression",
    ),
    (parse_actions, "raise e(a = 1", "missing ')'", 13, None),
    (parse_actions, "else", "`else` is only allowed as a whole guard", 0, None),
    (parse_bindings, "x", "a binding must be `name = expression`", 0, None),
    (parse_bindings, "a = 1\na = 2", "duplicate binding 'a'", 6, None),
    (parse_bindings, "a = (1\n+ 2", "missing ')'", 10, None),
]


@pytest.mark.parametrize(("parse", "text", "message", "offset", "hint"), ERRORS)
def test_error_messages(
    parse: Callable[[str], object], text: str, message: str, offset: int, hint: str | None
) -> None:
    with pytest.raises(ExprError) as info:
        parse(text)
    err = info.value
    assert message in err.message
    assert err.offset == offset
    if hint is not None:
        assert err.hint is not None and hint in err.hint


@pytest.mark.parametrize(
    ("parse", "text", "offset", "line", "col"),
    [
        (parse_actions, "x = 1\natm.abort", 6, 1, 0),
        (parse_actions, "x = 1\n  numIncorrect++", 20, 1, 14),
        (parse_actions, "x = 1\ny = 2\nz = @", 16, 2, 4),
        (parse_bindings, "a = 1\n\n  a = 2", 9, 2, 2),
        (parse_expr, "a and\n  b <\n c < d", 15, 2, 3),
        (parse_expr, "abc @", 4, 0, 4),
    ],
)
def test_error_lines_and_columns(
    parse: Callable[[str], object], text: str, offset: int, line: int, col: int
) -> None:
    with pytest.raises(ExprError) as info:
        parse(text)
    assert (info.value.offset, info.value.line, info.value.col) == (offset, line, col)


def test_error_str_and_pickle() -> None:
    with pytest.raises(ExprError) as info:
        parse_expr("a < b < c")
    err = info.value
    assert str(err) == (
        "line 1, column 7: chained comparison `a < b < c` is not supported "
        "(hint: write `a < b and b < c`)"
    )
    again = pickle.loads(pickle.dumps(err))
    assert (again.message, again.offset, again.line, again.col, again.hint) == (
        err.message,
        err.offset,
        err.line,
        err.col,
        err.hint,
    )


def test_messages_do_not_echo_control_characters() -> None:
    with pytest.raises(ExprError) as info:
        parse_expr("\x1b[31m")
    assert "\x1b" not in info.value.message
    assert "\\x1b" in info.value.message


# --- limits ---------------------------------------------------------------------------------------


def test_text_length_limit() -> None:
    assert parse_expr("a" * MAX_TEXT) == Name(name="a" * MAX_TEXT)
    for parse in (parse_expr, parse_actions, parse_bindings):
        with pytest.raises(ExprError, match="too long"):
            parse("a" * (MAX_TEXT + 1))


@pytest.mark.parametrize(
    ("make", "limit"),
    [
        (lambda n: "(" * n + "a" + ")" * n, MAX_DEPTH),
        (lambda n: "- " * n + "a", MAX_DEPTH - 1),
        (lambda n: "not " * n + "a", MAX_DEPTH - 1),
        (lambda n: "!" * n + "a", MAX_DEPTH - 1),
        (lambda n: " + ".join(["a"] * (n + 1)), MAX_DEPTH - 1),
        (lambda n: "a" + ".b" * n, MAX_DEPTH - 1),
    ],
)
def test_nesting_limit(make: Callable[[int], str], limit: int) -> None:
    parse_expr(make(limit))
    with pytest.raises(ExprError, match="nested too deeply"):
        parse_expr(make(limit + 1))


@pytest.mark.parametrize(
    "text",
    [
        "(" * 5000,
        "(" * 4999 + "a" + ")" * 4999,
        "-" * 9999 + "a",
        "not " * 2400 + "a",
        " or ".join(["a"] * 2000),
        "x = " + "(" * 4000,
    ],
)
def test_huge_inputs_give_expr_error_not_recursion_error(text: str) -> None:
    with pytest.raises(ExprError):
        parse_actions(text) if text.startswith("x =") else parse_expr(text)


# --- renderings -----------------------------------------------------------------------------------


def py_fields(e: Expr) -> str:
    return to_python(e, name=lambda n: f"self.{n}", event_field=lambda f: f"event[{f!r}]")


@pytest.mark.parametrize(
    ("text", "js", "python"),
    [
        ("a and b or not c", "((a && b) || (!c))", "((self.a and self.b) or (not self.c))"),
        ("x == 1.0", "(x == 1.0)", "(self.x == 1.0)"),
        ("x != null", "(x != null)", "(self.x != None)"),
        ("true", "true", "True"),
        ("False", "false", "False"),
        ("event.speed > 2", '($sg.field(_event, "speed") > 2)', "(event['speed'] > 2)"),
        ("event.größe", '$sg.field(_event, "gr\\u00f6\\u00dfe")', "event['größe']"),
        ("a % b", "$sg.mod(a, b)", "(self.a % self.b)"),
        ("a / 2", "$sg.div(a, 2)", "(self.a / 2)"),
        ("-x", "(-x)", "(-self.x)"),
        ("-1", "(-1)", "(-1)"),
        ("-1.5", "(-1.5)", "(-1.5)"),
        ("- -1", "(-(-1))", "(-(-1))"),
        ("1e16", "1e+16", "1e+16"),
        ("1e3", "1000.0", "1000.0"),
        ('"a\\"b"', '"a\\"b"', "'a\"b'"),
        ("'<&>'", '"\\u003c\\u0026\\u003e"', "'<&>'"),
        ("'é'", '"\\u00e9"', "'é'"),
        ("pos.x", "pos.x", "self.pos.x"),
        ("pos.class", "pos.class", "getattr(self.pos, 'class')"),
        ("pos.größe", 'pos["gr\\u00f6\\u00dfe"]', "getattr(self.pos, 'größe')"),
        ("event.a.b", '$sg.field(_event, "a").b', "event['a'].b"),
        ("else", "true", "True"),
        ("(a < b) < c", "((a < b) < c)", "((self.a < self.b) < self.c)"),
    ],
)
def test_renderings(text: str, js: str, python: str) -> None:
    e = parse_expr(text)
    assert to_ecmascript(e) == js
    assert py_fields(e) == python
    if not isinstance(e, Else):
        ast.parse(python, mode="eval")


def test_name_callbacks() -> None:
    e = parse_expr("a + event.b")
    assert to_ecmascript(e, name=lambda n: f"m_{n}") == '(m_a + $sg.field(_event, "b"))'
    assert to_python(e, name=lambda n: f"m_{n}", event_field=lambda f: f"f_{f}") == "(m_a + f_b)"


@pytest.mark.parametrize(
    ("text", "canonical"),
    [
        ("a+b*c", "a + b * c"),
        ("(a + b) * c", "(a + b) * c"),
        ("a - (b - c)", "a - (b - c)"),
        ("(a < b) == c", "(a < b) == c"),
        ("not (a or b)", "not (a or b)"),
        ("a == (not b)", "a == (not b)"),
        ("-(a + b)", "-(a + b)"),
        ("-(1)", "-(1)"),
        ("- -a", "- -a"),
        ("'x'", '"x"'),
        ("None", "null"),
        ("True", "true"),
        ("'a\x00b\u200f'", '"a\\x00b\\u200f"'),
    ],
)
def test_to_text(text: str, canonical: str) -> None:
    e = parse_expr(text)
    assert to_text(e) == canonical
    assert parse_expr(canonical) == e


# --- hostile text ---------------------------------------------------------------------------------

HOSTILE = [
    '"); os.system("x',
    "'); os.system('x",
    "</cond><script>alert(1)</script>",
    "]]><x/>",
    "\\'; import os; '",
    "\n\r\t\x00\x1b[2J",
    "\u2028\u2029",
    "\u202e}; evil(); {",
    "${x}`\"'",
]


def _string_constants(tree: ast.AST) -> list[str]:
    return [
        n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)
    ]


@pytest.mark.parametrize("value", HOSTILE)
def test_hostile_strings_stay_string_literals(value: str) -> None:
    e = parse_expr("x == " + to_text(Const(value=value)))
    assert e == Binary(op="==", left=Name(name="x"), right=Const(value=value))

    python = to_python(e, name=lambda n: n, event_field=lambda f: f)
    tree = ast.parse(python, mode="eval")
    assert isinstance(tree.body, ast.Compare)
    assert _string_constants(tree) == [value]
    assert not any(isinstance(n, ast.Call | ast.Attribute) for n in ast.walk(tree))

    js = to_ecmascript(e)
    assert js.startswith("(x == ") and js.endswith(")")
    literal = js[len("(x == ") : -1]
    assert literal.startswith('"') and literal.endswith('"')
    assert json.loads(literal) == value
    assert literal.isascii() and not any(c in literal for c in "<>&\n\r\u2028")


def test_hostile_names_are_rejected_by_the_tree() -> None:
    for bad in ["a); os.system(1", "a b", "", "1a", "and", "event", "__class__"]:
        with pytest.raises(ValidationError):
            Name(name=bad)
    with pytest.raises(ValidationError):
        EventField(field="x; y")
    with pytest.raises(ValidationError):
        Attr(obj=Name(name="a"), name="__globals__")
    with pytest.raises(ValidationError):
        Attr(obj=Const(value=1), name="x")
    with pytest.raises(ValidationError):
        Raise(event="e(); evil")
    with pytest.raises(ValidationError):
        Send(event="e", args=(Arg(name="a", value=Const(value=1)),) * 2)
    with pytest.raises(ValidationError):
        Const(value=float("nan"))
    with pytest.raises(ValidationError):
        Const(value=MAX_INT + 1)
    with pytest.raises(ValidationError):
        Unary(op="not", operand=Else())


def test_json_schema_and_round_trip() -> None:
    expr_adapter: TypeAdapter[Expr] = TypeAdapter(Expr)
    schema = expr_adapter.json_schema()
    assert "discriminator" in json.dumps(schema)
    e = parse_expr("not (a.b + -1.5 * event.x) == 'sé' or null")
    assert expr_adapter.validate_json(expr_adapter.dump_json(e)) == e
    actions_adapter: TypeAdapter[tuple[Action, ...]] = TypeAdapter(tuple[Action, ...])
    actions = parse_actions("raise e(x = 1)\nsend f(y = event.z)\nq = true")
    assert actions_adapter.validate_json(actions_adapter.dump_json(actions)) == actions
    actions_adapter.json_schema()


# --- properties -----------------------------------------------------------------------------------

IDENTS = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,6}", fullmatch=True).filter(
    lambda s: s not in RESERVED and not s.startswith("__")
) | st.sampled_from(["größe", "π", "class", "raise", "send", "if", "x_1", "événement", "self"])
FIELDS = IDENTS | st.sampled_from(["and", "not", "event", "else"])
NUMBERS = st.integers(-MAX_INT, MAX_INT) | st.floats(allow_nan=False, allow_infinity=False)
BINOPS = ["or", "and", "==", "!=", "<", "<=", ">", ">=", "+", "-", "*", "/", "%"]


def expressions(strings: st.SearchStrategy[str], attrs: bool) -> st.SearchStrategy[Expr]:
    names = st.builds(Name, name=IDENTS)
    fields = st.builds(EventField, field=FIELDS)
    constants = st.builds(Const, value=st.none() | st.booleans() | NUMBERS | strings)
    leaves: st.SearchStrategy[Expr] = constants | names | fields
    if attrs:
        leaves |= st.builds(Attr, obj=names | fields, name=FIELDS)

    def extend(children: st.SearchStrategy[Expr]) -> st.SearchStrategy[Expr]:
        unary = st.builds(Unary, op=st.sampled_from(["not", "-", "+"]), operand=children)
        binary = st.builds(Binary, op=st.sampled_from(BINOPS), left=children, right=children)
        return unary | binary

    return st.recursive(leaves, extend, max_leaves=12)


def depth(e: Expr) -> int:
    kids = [depth(k) for k in (getattr(e, a, None) for a in ("obj", "operand", "left", "right"))
            if k is not None]  # fmt: skip
    return 1 + max(kids, default=0)


@FAST
@given(expressions(st.text(max_size=8), attrs=True))
def test_to_text_round_trips(e: Expr) -> None:
    assume(depth(e) <= MAX_DEPTH)
    again = parse_expr(to_text(e))
    assert again == e
    assert again.model_dump_json() == e.model_dump_json()  # also tells 1 from 1.0 and True


class _TooBig(Exception):
    pass


def _times(a: Any, b: Any) -> Any:
    # "ab" * 2**50 would exhaust memory: skip such examples rather than evaluate them.
    for s, n in ((a, b), (b, a)):
        if isinstance(s, str) and isinstance(n, int) and len(s) * n > 1000:
            raise _TooBig
    return a * b


_OPS: dict[str, Callable[[Any, Any], Any]] = {
    "==": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le,
    ">": operator.gt, ">=": operator.ge, "+": operator.add, "-": operator.sub,
    "*": _times, "/": operator.truediv, "%": operator.mod,
}  # fmt: skip


def reference(e: Expr) -> Any:
    """Python's semantics, evaluated directly over the tree: names are 1, event fields 2."""
    if isinstance(e, Const):
        return e.value
    if isinstance(e, Name):
        return 1
    if isinstance(e, EventField):
        return 2
    if isinstance(e, Unary):
        v = reference(e.operand)
        return not v if e.op == "not" else (-v if e.op == "-" else +v)
    assert isinstance(e, Binary)
    left = reference(e.left)
    if e.op == "and":
        return reference(e.right) if left else left
    if e.op == "or":
        return left if left else reference(e.right)
    return _OPS[e.op](left, reference(e.right))


class _Names(dict[str, int]):
    def __missing__(self, key: str) -> int:
        return 1


def _outcome(run: Callable[[], Any]) -> tuple[str, str]:
    try:
        value = run()
    except (ZeroDivisionError, TypeError, OverflowError) as exc:
        return "raised", type(exc).__name__
    return type(value).__name__, repr(value)


@FAST
@given(expressions(st.text(alphabet="ab'\"\\\n<>/ é", max_size=4), attrs=False))
def test_python_rendering_evaluates_like_the_tree(e: Expr) -> None:
    assume(depth(e) <= MAX_DEPTH)
    try:
        expected = _outcome(lambda: reference(e))
    except _TooBig:
        assume(False)
    source = to_python(e, name=lambda n: f"N[{n!r}]", event_field=lambda f: "E")
    code = compile(ast.parse(source, mode="eval"), "<guard>", "eval")
    env = {"N": _Names(), "E": 2}
    assert _outcome(lambda: eval(code, {"__builtins__": {}}, env)) == expected


@FAST
@given(st.text())
def test_arbitrary_text_parses_or_raises_expr_error(text: str) -> None:
    for parse in (parse_expr, parse_actions, parse_bindings):
        try:
            parse(text)
        except ExprError as err:
            assert 0 <= err.offset <= len(text)


TOKENS = [
    "a", "b", "event", ".", "x", "1", "2.5", "-", "+", "*", "/", "%", "==", "!=", "<", ">=", "=",
    "(", ")", ",", ";", "\n", "and", "or", "not", "!", "&&", "||", "true", "null", "'s'", '"\\n"',
    "raise", "send", "e", "else", "++", "+=", "===", "@", "'", "\\", " ",
]  # fmt: skip


@FAST
@given(st.lists(st.sampled_from(TOKENS), max_size=12), st.sampled_from(["", " "]))
def test_token_soup(tokens: list[str], sep: str) -> None:
    text = sep.join(tokens)
    try:
        e = parse_expr(text)
    except ExprError as err:
        assert 0 <= err.offset <= len(text)
        assert 0 <= err.col <= err.offset
    else:
        assert parse_expr(to_text(e)) == e
        if not isinstance(e, Else):
            ast.parse(to_python(e, name=lambda n: f"N[{n!r}]", event_field=repr), mode="eval")
    for parse in (parse_actions, parse_bindings):
        with contextlib.suppress(ExprError):
            parse(text)
