"""Python rendering shared by the Python backends: a chart becomes `ChartBuilder` calls plus the
guard, action and argument functions rendered from the expression AST (never from model text).

Every string that comes from the model is printed with `repr()`, so it stays a string literal.
"""

from __future__ import annotations

import ast
import functools
from dataclasses import field
from typing import Any

from swarmgen import expr
from swarmgen.backends import pyformat, pyknown, pylayout
from swarmgen.chart import model as c
from swarmgen.names import identifier
from swarmgen.records import dataclass
from swarmgen.runtime.values import zero_like

LINE_LENGTH = pyformat.LINE_LENGTH


def black_mode(line_length: int = LINE_LENGTH) -> Any:
    """The project's black mode (black pinned: its output is in golden files and generated/).
    Imported here, not at module level: black is only the fallback of `format_python` and the
    reference of tests/test_black_stable.py, never on the compile path of the shipped forms."""
    import black
    from black.mode import TargetVersion

    return black.Mode(line_length=line_length, target_versions={TargetVersion.PY311})


def black_statement(statement: str, indent: int) -> str:
    """One statement formatted by black, as if it stood `indent` columns deep."""
    import black

    return str(black.format_str(statement, mode=black_mode(LINE_LENGTH - indent)))


@functools.lru_cache(maxsize=1024)
def format_python(source: str) -> str:
    """Generated Python exactly as black (pinned, `black_mode()`) prints it, made by
    `pyformat` without running black; a statement pyformat does not reproduce goes through
    black alone (`pyformat.STATS` counts them). Memoised in this process only: an on-disk
    cache under the user's cache directory would let whoever can write there choose the bytes
    swarmgen emits, and generated code must be a function of the model and swarmgen's version
    alone (docs/security.md)."""
    return pyformat.format_source(source, black_statement)


# What each kind of helper function returns: guards, actions, call arguments and goal callbacks.
RETURNS = {
    "cond": "bool",
    "action": "None",
    "args": "dict[str, Any]",
    "goal": "dict[str, Any]",
    "donedata": "Any",
    "value": "Any",
    "session": "Chart",
}


@dataclass(frozen=True)
class Function:
    """A helper function of a member module: `def <name>(ctx: Context) -> <returns>: <body>`."""

    name: str
    kind: str  # a key of RETURNS
    body: tuple[str, ...]
    reads_data: bool = False  # the body uses the datamodel `d` (then `d = ctx.data` first)

    @property
    def returns(self) -> str:
        """The function's return annotation."""
        return RETURNS[self.kind]


def laid_out_function(name: str, kind: str, body: list[str], reads_data: bool) -> Function:
    """The helper function with its body in black's layout (quotes normalised) when each line
    is one `pyformat.quick_line` copies, and its lines recorded (`pyknown`) as statements black
    prints so, one per line, for `pyformat` to copy in every module that prints the function
    (common/python.j2's `functions`). Else the body as given: pyformat formats it as before."""
    quick = [pyformat.quick_line("    " + line) for line in body]
    lines = [line for line in quick if line is not None]
    if len(lines) < len(body):
        return Function(name, kind, tuple(body), reads_data)
    # the header and `d = ctx.data` hold no string and fit: black prints them as they are
    pyknown.register_line(f"def {name}(ctx: Context) -> {RETURNS[kind]}:")
    if reads_data:
        pyknown.register_line("    d = ctx.data")
    for line in lines:
        pyknown.register_line(line)
    return Function(name, kind, tuple(line[4:] for line in lines), reads_data)


@dataclass
class ChartCode:
    """What a template prints for one chart: helper functions, then builder statements."""

    functions: list[Function] = field(default_factory=list)
    # each in black's layout (`pylayout`) for `build()`: further lines carry their indentation
    statements: list[str] = field(default_factory=list)
    data_literal: str = "{}"
    sessions: int = 0  # invoked sessions' builders (`_session_<n>`): the module imports `Invoke`


def py_literal(value: Any) -> str:
    """A JSON-like value (scalars, and dicts of them for data types) as Python source."""
    if isinstance(value, dict):
        return "{" + ", ".join(f"{str(k)!r}: {py_literal(v)}" for k, v in value.items()) + "}"
    if isinstance(value, float) and (value != value or value in {float("inf"), float("-inf")}):
        return "None"
    return repr(value)


def event_fields_literal(chart: c.Chart) -> str:
    """`EVENT_FIELDS` of a member module: each event's fields and their defaults."""
    items = (f"{e.ident!r}: {py_literal(dict(e.defaults))}" for e in chart.events if e.defaults)
    return "{" + ", ".join(items) + "}"


def zeros_literal(chart: c.Chart) -> str | None:
    """The data whose zero the runtime cannot tell from their initial value (`zero_like`: an
    enumeration's is its first literal, not ""), as a dict literal; None when there are none,
    so a model without them renders as before."""
    items = [
        f"{d.id!r}: {py_literal(d.zero)}"
        for d in chart.data
        if py_literal(d.zero) != py_literal(zero_like(d.initial))
    ]
    return "{" + ", ".join(items) + "}" if items else None


# The last charts' code by identity (the chart itself kept, so its id is not reused): the asyncio
# and rclpy members print the same chart's functions and statements, rendered once per compile.
_SHARED: dict[int, tuple[c.Chart, ChartCode]] = {}
_SHARED_LIMIT = 16


def chart_code(chart: c.Chart) -> ChartCode:
    """`ChartRenderer(chart).render()`, the same object for the same chart object (shared by the
    backends that print it as it is: read it, do not change it)."""
    held = _SHARED.get(id(chart))
    if held is not None and held[0] is chart:
        return held[1]
    if len(_SHARED) >= _SHARED_LIMIT:
        _SHARED.clear()
    code = ChartRenderer(chart).render()
    _SHARED[id(chart)] = (chart, code)
    return code


class ChartRenderer:
    """Turns one chart into `ChartCode`."""

    def __init__(self, chart: c.Chart) -> None:
        self.chart = chart
        self.code = ChartCode()
        self.data_ids = {d.name: d.id for d in chart.data}
        self._counter = 0
        # whether code rendered since the last helper function reads or writes `d`: every
        # expression is rendered right before the function that holds it
        self._reads_data = False
        # each expression's code, and whether it reads `d`, by the expression's identity (the
        # entry holds it): one parsed text is one object on every transition that has it
        self._python: dict[int, tuple[expr.Expr, str, bool]] = {}

    def render(self) -> ChartCode:
        """The chart's helper functions and `ChartBuilder` statements, in document order."""
        items = ", ".join(f"{d.id!r}: {py_literal(d.initial)}" for d in self.chart.data)
        self.code.data_literal = "{" + items + "}"
        zeros = zeros_literal(self.chart)
        if zeros is not None:
            self.code.statements.append(f"b.zeros({zeros})")
        for node in self.chart.children:
            self._node(node, None)
        self.code.statements.append(f"b.initial(None, {tuple(self.chart.initial)!r})")
        return self.code

    def _session(self, chart: c.Chart) -> str:
        """An invoked chart's builder: a helper function `_session_<n>(ctx) -> Chart` of its
        own `ChartBuilder` statements (the engine calls it once), its helper functions
        numbered on with this chart's."""
        child = ChartRenderer(chart)
        child.code = ChartCode(functions=self.code.functions)
        child._counter = self._counter
        child.render()
        self._counter = child._counter
        self.code.sessions += 1 + child.code.sessions
        head = f"b = ChartBuilder({chart.name!r}, data={child.code.data_literal}, "
        body = [head + f"events={event_fields_literal(chart)})", *child.code.statements]
        reads = self._reads_data
        self._reads_data = False
        name = self._function("session", [*body, "return b.build()"])
        self._reads_data = reads
        return name

    def _invoke(self, invoke: c.Invoke) -> pylayout.Call:
        """`Invoke(<chart>, ...)` of a state's `invokes=` option, its chart rendered first."""
        parts: list[pylayout.Arg] = [self._session(invoke.chart)]
        if invoke.invokeid is not None:
            parts.append(f"invokeid={invoke.invokeid!r}")
        if invoke.idlocation is not None:
            parts.append(f"idlocation={invoke.idlocation!r}")
        if invoke.kind_expr is not None:
            kind = self._function("value", [f"return {_unwrap(self.py(invoke.kind_expr))}"])
            parts.append(f"type={kind}")
        if invoke.params:
            items = ", ".join(f"{p.name!r}: {self.py(p.value)}" for p in invoke.params)
            parts.append(f"args={self._function('args', [f'return {{{items}}}'])}")
        finalize = self._action(invoke.finalize)
        if finalize is not None:
            parts.append(f"finalize={finalize}")
        if invoke.autoforward:
            parts.append("autoforward=True")
        return pylayout.Call("Invoke", tuple(parts))

    # --- expressions

    def py(self, e: expr.Expr | c.FieldDefault) -> str:
        """An expression (or an event field's default) as Python source over `d` and `ctx`."""
        if isinstance(e, c.FieldDefault):
            return py_literal(e.value)
        held = self._python.get(id(e))
        if held is None or held[0] is not e:
            reads, self._reads_data = self._reads_data, False
            code = expr.to_python(
                e,
                name=self._data,
                # a field the event does not carry is an error, as `$sg.field` in the SCXML
                event_field=lambda f: f"ctx.field({identifier(f)!r})",
            )
            held = self._python[id(e)] = (e, code, self._reads_data)
            self._reads_data = reads
        self._reads_data = self._reads_data or held[2]
        return held[1]

    def _data(self, name: str) -> str:
        """A datamodel item as code: `d['id']`."""
        self._reads_data = True
        return f"d[{(self.data_ids.get(name) or identifier(name))!r}]"

    def _function(self, kind: str, body: list[str]) -> str:
        self._counter += 1
        name = f"_{kind}_{self._counter}"
        self.code.functions.append(laid_out_function(name, kind, body, self._reads_data))
        self._reads_data = False
        return name

    def _cond(self, transition: c.Transition) -> str | None:
        """The guard function; `bool(a < b)`, not `bool((a < b))` (ruff UP034)."""
        parts = [f"ctx.is_active({s!r})" for s in transition.in_states]
        if transition.cond is not None:
            parts.append(self.py(transition.cond))
        if not parts:
            return None
        return self._function("cond", [f"return bool({_unwrap(' and '.join(parts))})"])

    def _action(self, actions: tuple[c.Action, ...]) -> str | None:
        lines = [line for action in actions for line in self._action_lines(action)]
        return self._function("action", lines) if lines else None

    def _action_lines(self, action: c.Action) -> list[str]:
        if isinstance(action, c.Assign) and action.invalid:
            return [f"ctx.invalid({action.location!r})"]  # raises: error.execution
        if isinstance(action, c.Assign) and action.location in expr.SYSTEM_VARIABLES:
            return [f"ctx.assign_system({action.location!r})"]  # raises: error.execution
        if isinstance(action, c.Assign):
            self._reads_data = True
            # black drops parentheses around a whole right-hand side: printed without them
            return [f"d[{action.location!r}] = {_unwrap(self.py(action.value))}"]
        if isinstance(action, c.Raise | c.Send):
            method = "raise_event" if isinstance(action, c.Raise) else "send"
            data = "{" + ", ".join(f"{p.name!r}: {self.py(p.value)}" for p in action.params) + "}"
            data = data if action.params else "None"
            if isinstance(action, c.Raise) and action.named is not None and not action.params:
                data = "{}"  # `<send eventexpr target="#_internal">`: the external queue
            if isinstance(action, c.Raise) and action.content is not None:
                data = _unwrap(self.py(action.content))  # the event's whole data
            if isinstance(action, c.Raise) and (action.via is not None or action.into is not None):
                return [self._through(action, data)]
            name = self._event_of(action)
            if isinstance(action, c.Raise) and action.target is not None:
                target = _unwrap(self.py(action.target))
                ms = self._delay_ms(action.delay) if action.delay is not None else "0"
                call = f"ctx.raise_to({name}, {data}, {target}, {ms}, {action.sendid!r})"
                return [call]
            if isinstance(action, c.Raise) and action.delay is not None:
                return [self._delayed(action, action.delay, data)]
            return [f"ctx.{method}({name}, {data})"]
        if isinstance(action, c.Cancel) and action.expr is not None:
            return [f"ctx.cancel({_unwrap(self.py(action.expr))})"]
        if isinstance(action, c.Cancel):
            return [f"ctx.cancel({action.sendid!r})"]
        if isinstance(action, c.Block):  # its own function: an error in it ends only it
            reads = self._reads_data
            inner = [line for each in action.actions for line in self._action_lines(each)]
            name = self._function("action", inner or ["pass"])
            self._reads_data = reads
            return [f"ctx.block({name})"]
        if isinstance(action, c.Log):
            return [f"ctx.log({action.label!r}, {_unwrap(self.py(action.value))})"]
        if isinstance(action, c.If):
            return self._if_lines(action)
        if isinstance(action, c.ForEach):
            self._reads_data = True
            index = f"d[{action.index!r}]" if action.index is not None else "_"
            head = f"for d[{action.item!r}], {index} in ctx.each({_unwrap(self.py(action.array))}):"
            inner = [line for each in action.actions for line in self._action_lines(each)]
            return [head, *("    " + line for line in inner or ["pass"])]
        return [f"ctx.opaque({action.language!r}, {action.text!r})"]

    def _if_lines(self, action: c.If) -> list[str]:
        """`if`/`elif`/`else`: each condition through `ctx.holds`, which makes one that fails
        false and raises error.execution, and the block goes on (W3C `<if>`)."""
        lines: list[str] = []
        for number, (cond, actions) in enumerate(action.branches):
            if cond is None:
                lines.append("else:")
            else:
                keyword = "if" if number == 0 else "elif"
                lines.append(f"{keyword} ctx.holds(lambda: {_unwrap(self.py(cond))}):")
            inner = [line for each in actions for line in self._action_lines(each)]
            lines += ["    " + line for line in inner or ["pass"]]
        return lines

    def _delayed(self, action: c.Raise, delay: c.Delay, data: str) -> str:
        """`raise e after ...` with its delay in milliseconds."""
        ms = self._delay_ms(delay)
        return f"ctx.raise_later({self._event_of(action)}, {data}, {ms}, {action.sendid!r})"

    def _event_of(self, action: c.Raise | c.Send) -> str:
        """The event's name as Python: its literal, or `ctx.event_name(...)` checking the
        computed one (`raise (expr)`, W3C's eventexpr) when the action runs."""
        if isinstance(action, c.Raise) and action.named is not None:
            return f"ctx.event_name({_unwrap(self.py(action.named))})"
        return repr(action.event)

    def _through(self, action: c.Raise, data: str) -> str:
        """`raise e ... via p` / `into v`: ctx.raise_via (the engine writes the send id to
        `v`, also when the send fails)."""
        target = _unwrap(self.py(action.target)) if action.target is not None else "None"
        ms = self._delay_ms(action.delay) if action.delay is not None else "None"
        via = _unwrap(self.py(action.via)) if action.via is not None else "None"
        options = f"({target}, {ms}, {action.sendid!r}, {via})"
        return f"ctx.raise_via({self._event_of(action)}, {data}, {options}, {action.into!r})"

    def _delay_ms(self, delay: c.Delay) -> str:
        """A delay as Python computing milliseconds."""
        amount = _unwrap(self.py(delay.amount))
        if delay.unit == "s" and isinstance(delay.amount, expr.Const):
            return f"{amount} * 1000"
        return {"ms": amount, "s": f"({amount}) * 1000", "": f"ctx.duration({amount})"}[delay.unit]

    def _hooks(self, node: c.Node) -> list[str]:
        """The `onentry=` and `onexit=` options of a state (its action functions, if any), and
        a final state's `donedata=` (the fields of its done.state event)."""
        hooks = [("onentry", self._action(node.onentry)), ("onexit", self._action(node.onexit))]
        if node.donedata or node.donecontent is not None:
            items = ", ".join(f"{p.name!r}: {self.py(p.value)}" for p in node.donedata)
            value = self.py(node.donecontent) if node.donecontent is not None else f"{{{items}}}"
            hooks.append(("donedata", self._function("donedata", [f"return {_unwrap(value)}"])))
        return [f"{key}={function}" for key, function in hooks if function]

    def _transition_options(self, transition: c.Transition, guard: str) -> list[str]:
        """The guard (option `guard`), action, `internal` and `bounded` options of a transition."""
        options = []
        cond = self._cond(transition)
        if cond:
            options.append(f"{guard}={cond}")
        action = self._action(transition.actions)
        if action:
            options.append(f"action={action}")
        if transition.internal:
            options.append("internal=True")
        if transition.bounded:  # the step bound counts it (docs/semantics.md)
            options.append("bounded=True")
        return options

    def _args(self, call: c.Call) -> str:
        items = ", ".join(f"{a.name!r}: {self.py(a.value)}" for a in call.args)
        return self._function("args", [f"return {{{items}}}"])

    # --- structure

    def _statement(self, callee: str, *args: pylayout.Arg) -> None:
        """A builder call in `build()` (one level deep), in black's layout when `pylayout`
        reproduces it."""
        self.code.statements.append(pylayout.statement(1, callee, args))

    def _node(self, node: c.Node, parent: str | None) -> None:
        options: list[pylayout.Arg] = [f"name={(node.name or node.id)!r}"]
        if node.history:
            options.append(f"history={node.history!r}")
        options.extend(self._hooks(node))
        if node.call is not None:
            call = node.call
            parts = [repr(call.behaviour), repr(call.kind), self._args(call)]
            parts += [repr(tuple(call.results)), repr(tuple(call.outcomes))]
            options.append(pylayout.Kw("call=", pylayout.Call("Call", tuple(parts))))
        if node.timers:
            options.append(f"timers={tuple((t.event, t.delay_ms) for t in node.timers)!r}")
        if node.invokes:
            invokes = ", ".join(pylayout.flat(self._invoke(i)) for i in node.invokes)
            options.append(f"invokes=({invokes},)")  # an atom: formatted by `format_python`
        self._statement("b.node", repr(node.id), repr(node.kind), repr(parent), *options)
        if node.initial is not None:
            action = self._action(node.initial.actions)
            extra = [f"action={action}"] if action else []
            self._statement("b.initial", repr(node.id), repr(tuple(node.initial.targets)), *extra)
        for child in node.children:
            self._node(child, node.id)
        for transition in node.transitions:
            self._transition(node.id, transition)

    def _transition(self, source: str, transition: c.Transition) -> None:
        options = self._transition_options(transition, "cond")
        events, targets = repr(tuple(transition.events)), repr(tuple(transition.targets))
        self._statement("b.transition", repr(source), events, targets, *options)


@functools.lru_cache(maxsize=8192)
def _unwrap(text: str) -> str:
    """`(a < b)` -> `a < b`: the outer parentheses go when they enclose the whole expression
    (then the text without them is an expression too, token for token; counting parentheses
    would be fooled by those inside string literals). Memoised: the smach and the asyncio
    members print the same guards and assignments, and `ast.parse` is the costly part."""
    if text.startswith("(") and text.endswith(")"):
        try:
            inner = ast.parse(text[1:-1], mode="eval")
        except SyntaxError:
            return text
        # a tuple keeps its parentheses (black keeps them too)
        return text if isinstance(inner.body, ast.Tuple) else text[1:-1]
    return text
