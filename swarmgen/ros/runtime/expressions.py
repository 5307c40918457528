"""The safe expressions of simulation scripts: `${...}` in a script value, checked when the
script is read and computed by a small interpreter (no `eval`) over a subset of Python."""

from __future__ import annotations

import ast
import operator
import re
from collections.abc import Callable, Mapping
from typing import Any


class ScriptError(ValueError):
    """A simulation script that cannot be used."""


MAX_POWER = 1024  # |exponent| of `**` on integers; `2 ** 10 ** 9` would block the executor
MAX_REPEAT = 100_000  # items a repeated string or list may have (`"x" * 10 ** 12`)


def _pow(base: Any, exponent: Any) -> Any:
    if isinstance(exponent, int) and isinstance(base, int) and abs(exponent) > MAX_POWER:
        raise ValueError(f"integer exponent {exponent} is above {MAX_POWER}")
    return operator.pow(base, exponent)


def _mul(left: Any, right: Any) -> Any:
    for sequence, count in ((left, right), (right, left)):
        repeated = isinstance(sequence, str | list | tuple) and isinstance(count, int)
        if repeated and len(sequence) * count > MAX_REPEAT:
            raise ValueError(f"a repetition of more than {MAX_REPEAT} items")
    return operator.mul(left, right)


# Scripts come from files a user edits: their expressions are bounded, so that a typo cannot
# keep the executor (every member of the process) busy or exhaust its memory.
_BINARY: dict[type[ast.operator], Callable[[Any, Any], Any]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: _mul,
    ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv,
    ast.Mod: operator.mod,
    ast.Pow: _pow,
}
_COMPARE: dict[type[ast.cmpop], Callable[[Any, Any], Any]] = {
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
    ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b,
}
_FUNCTIONS: dict[str, Callable[..., Any]] = {
    "min": min,
    "max": max,
    "abs": abs,
    "round": round,
    "int": int,
    "float": float,
    "str": str,
    "len": len,
}
_TEMPLATE = re.compile(r"\$\{(.*?)\}")


def compile_expression(text: str) -> ast.Expression:
    """Parse an expression and check that it only uses the allowed subset."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as err:
        raise ScriptError(f"bad expression {text!r}: {err.msg}") from None
    for node in ast.walk(tree):
        allowed = (
            ast.Expression,
            ast.Constant,
            ast.Name,
            ast.Load,
            ast.Attribute,
            ast.BinOp,
            ast.UnaryOp,
            ast.BoolOp,
            ast.Compare,
            ast.IfExp,
            ast.Call,
            ast.List,
            ast.Tuple,
            ast.Dict,
            ast.And,
            ast.Or,
            ast.Not,
            ast.USub,
            ast.UAdd,
            *_BINARY,
            *_COMPARE,
        )
        if not isinstance(node, allowed):
            raise ScriptError(f"{type(node).__name__} is not allowed in expression {text!r}")
        if isinstance(node, ast.Attribute) and node.attr.startswith("_"):
            raise ScriptError(f"private attribute {node.attr!r} in expression {text!r}")
        if isinstance(node, ast.Call) and (
            not isinstance(node.func, ast.Name) or node.func.id not in _FUNCTIONS or node.keywords
        ):
            raise ScriptError(f"only {sorted(_FUNCTIONS)} may be called in {text!r}")
    return tree


def evaluate(tree: ast.AST, names: Mapping[str, Any]) -> Any:
    """Evaluate a checked expression tree (no `eval`: an interpreter over the allowed nodes)."""
    rule = _EVALUATE.get(type(tree))
    if rule is None:
        raise ScriptError(f"cannot evaluate {type(tree).__name__}")
    return rule(tree, names)


def _name(tree: ast.Name, names: Mapping[str, Any]) -> Any:
    if tree.id in _FUNCTIONS:
        return _FUNCTIONS[tree.id]
    if tree.id not in names:
        raise NameError(f"unknown name {tree.id!r}")
    return names[tree.id]


def _attribute(tree: ast.Attribute, names: Mapping[str, Any]) -> Any:
    value = evaluate(tree.value, names)
    if isinstance(value, Mapping):
        return value.get(tree.attr)
    raise TypeError(f"{tree.attr!r}: only the fields of records can be read")


def _unary(tree: ast.UnaryOp, names: Mapping[str, Any]) -> Any:
    operand = evaluate(tree.operand, names)
    if isinstance(tree.op, ast.Not):
        return not operand
    return -operand if isinstance(tree.op, ast.USub) else +operand


def _boolean(tree: ast.BoolOp, names: Mapping[str, Any]) -> Any:
    result: Any = isinstance(tree.op, ast.And)
    for value_node in tree.values:
        result = evaluate(value_node, names)
        if isinstance(tree.op, ast.And) and not result:
            return result
        if isinstance(tree.op, ast.Or) and result:
            return result
    return result


def _compare(tree: ast.Compare, names: Mapping[str, Any]) -> Any:
    left = evaluate(tree.left, names)
    for op, right_node in zip(tree.ops, tree.comparators, strict=True):
        right = evaluate(right_node, names)
        if not _COMPARE[type(op)](left, right):
            return False
        left = right
    return True


def _if(tree: ast.IfExp, names: Mapping[str, Any]) -> Any:
    test = evaluate(tree.test, names)
    return evaluate(tree.body if test else tree.orelse, names)


def _call(tree: ast.Call, names: Mapping[str, Any]) -> Any:
    function = _FUNCTIONS[tree.func.id]  # type: ignore[attr-defined]
    return function(*(evaluate(a, names) for a in tree.args))


def _dict(tree: ast.Dict, names: Mapping[str, Any]) -> Any:
    return {
        evaluate(k, names): evaluate(v, names)
        for k, v in zip(tree.keys, tree.values, strict=True)
        if k is not None
    }


def _sequence(tree: ast.List | ast.Tuple, names: Mapping[str, Any]) -> Any:
    return [evaluate(e, names) for e in tree.elts]


def _binary(tree: ast.BinOp, names: Mapping[str, Any]) -> Any:
    return _BINARY[type(tree.op)](evaluate(tree.left, names), evaluate(tree.right, names))


# The interpreter: one rule per node type that `compile_expression` allows.
_EVALUATE: dict[type[ast.AST], Callable[[Any, Mapping[str, Any]], Any]] = {
    ast.Expression: lambda tree, names: evaluate(tree.body, names),
    ast.Constant: lambda tree, _names: tree.value,
    ast.Name: _name,
    ast.Attribute: _attribute,
    ast.BinOp: _binary,
    ast.UnaryOp: _unary,
    ast.BoolOp: _boolean,
    ast.Compare: _compare,
    ast.IfExp: _if,
    ast.Call: _call,
    ast.List: _sequence,
    ast.Tuple: _sequence,
    ast.Dict: _dict,
}


def check_template(value: Any) -> None:
    """Check every `${...}` expression in a script value (ScriptError for a bad one)."""
    if isinstance(value, str):
        for match in _TEMPLATE.finditer(value):
            compile_expression(match.group(1))
    elif isinstance(value, Mapping):
        for item in value.values():
            check_template(item)
    elif isinstance(value, list):
        for item in value:
            check_template(item)


def render(value: Any, names: Mapping[str, Any]) -> Any:
    """A script value with its `${...}` expressions computed."""
    if isinstance(value, str):
        whole = _TEMPLATE.fullmatch(value)
        if whole is not None:
            return evaluate(compile_expression(whole.group(1)), names)
        return _TEMPLATE.sub(lambda m: str(evaluate(compile_expression(m.group(1)), names)), value)
    if isinstance(value, Mapping):
        return {str(k): render(v, names) for k, v in value.items()}
    if isinstance(value, list):
        return [render(v, names) for v in value]
    return value


def compile_condition(when: str) -> ast.Expression:
    """A condition of a script, written `${expression}` or as the bare expression."""
    whole = _TEMPLATE.fullmatch(when.strip())
    return compile_expression(whole.group(1) if whole else when)
