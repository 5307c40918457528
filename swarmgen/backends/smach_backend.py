"""The smach backend: a Python package per swarm whose member modules build their behaviour with
SMACH's API (State, StateMachine, Concurrence, userdata, remapping) over the bundled runtime
`_runtime/smach.py`, which turns the containers into the same chart the asyncio backend builds and
runs it with the same engine. See docs/smach.md for the mapping."""

from __future__ import annotations

import ast
import keyword
from dataclasses import dataclass, field
from pathlib import PurePosixPath

from swarmgen import __version__
from swarmgen.backends import Files
from swarmgen.backends.asyncio_backend import (
    RUNTIME_MODULES,
    member_modules,
    package_name,
    support_files,
)
from swarmgen.backends.pyrender import (
    ChartRenderer,
    Function,
    event_fields_literal,
    format_python,
    py_literal,
)
from swarmgen.chart import model as c
from swarmgen.chart.model import Chart
from swarmgen.ir import expr
from swarmgen.ir.nodes import Model
from swarmgen.ir.query import composition as swarm_composition
from swarmgen.names import IdAllocator, doc_text, identifier, one_line, ros_name
from swarmgen.render import render

SMACH_RUNTIME = (*RUNTIME_MODULES, "smach")
COMPLETION = "done"  # the completion outcome of a Concurrence (`done` is never an event name)
TOP = "build_state_machine"
INDENT = "    "


@dataclass
class Factory:
    """One generated function that builds a container (the top one is `build_state_machine`)."""

    name: str
    returns: str  # "smach.StateMachine" or "smach.Concurrence"
    comment: str
    lines: list[str] = field(default_factory=list)


@dataclass
class SmachCode:
    functions: list[Function]
    factories: list[Factory]


class SmachRenderer(ChartRenderer):
    """A chart as SMACH containers. Guards, actions and goal callbacks are the same functions the
    asyncio backend renders; the structure becomes `add()` calls in document order."""

    def __init__(self, chart: Chart) -> None:
        super().__init__(chart)
        self.factories: list[Factory] = []
        self.behaviours = {b.name: b for b in chart.behaviours}
        self.parent: dict[str, str | None] = {}
        self.nodes: dict[str, c.Node] = {}
        self.function_names = IdAllocator({TOP})
        for node in chart.children:
            self._index(node, None)

    def _index(self, node: c.Node, parent: str | None) -> None:
        stack = [(node, parent)]
        while stack:
            current, owner = stack.pop()
            self.parent[current.id] = owner
            self.nodes[current.id] = current
            stack.extend((child, current.id) for child in current.children)

    def render_smach(self) -> SmachCode:
        top = Factory(TOP, "smach.StateMachine", one_line(f"member {self.chart.name}"))
        self.factories.append(top)
        finals = [n.id for n in self.chart.children if n.kind == "final"]
        top.lines.append(f"sm = smach.StateMachine(outcomes={finals!r})")
        for item in self.chart.data:
            value = py_literal(item.initial)
            if item.id.isidentifier() and not keyword.iskeyword(item.id) and item.id[0] != "_":
                top.lines.append(f"sm.userdata.{item.id} = {value}")
            else:
                top.lines.append(f"sm.userdata[{item.id!r}] = {value}")
        top.lines.append("with sm:")
        initial = [self._target(None, t) for t in self.chart.initial]
        top.lines.append(f"{INDENT}sm.set_initial_state({initial!r})")
        for node in self.chart.children:
            top.lines.append(INDENT + self._add("StateMachine", node))
        top.lines.append("return sm")
        return SmachCode(self.code.functions, self.factories)

    # --- containers

    def _factory(self, node: c.Node, remapping: dict[str, str]) -> str:
        name = self.function_names.claim(f"make_{ros_name(node.id)}")
        parallel = node.kind == "parallel"
        kind = "Concurrence" if parallel else "StateMachine"
        what = "parallel state" if parallel else "state"
        factory = Factory(name, f"smach.{kind}", one_line(f"{what} {node.name or node.id}"))
        self.factories.append(factory)
        options = self._state_options(node, remapping)
        if parallel:
            outcome_map = self._outcome_map(node)
            if outcome_map:
                options = [
                    f"outcomes={[COMPLETION]!r}",
                    f"default_outcome={COMPLETION!r}",
                    f"outcome_map={{{COMPLETION!r}: {outcome_map}}}",
                    *options,
                ]
            else:
                options = ["outcomes=[]", *options]
        else:
            finals = [child.id for child in node.children if child.kind == "final"]
            options = [f"outcomes={finals!r}", *options]
        factory.lines.append(f"sm = smach.{kind}({', '.join(options)})")
        body = []
        if node.initial is not None:
            action = self._action(node.initial.actions)
            extra = f", action={action}" if action else ""
            targets = [self._target(node.id, t) for t in node.initial.targets]
            body.append(f"sm.set_initial_state({targets!r}{extra})")
        for child in node.children:
            body.append(self._add(kind, child))
        factory.lines.append("with sm:")
        factory.lines.extend(INDENT + line for line in body or ["pass"])
        factory.lines.append("return sm")
        return f"{name}()"

    def _outcome_map(self, node: c.Node) -> str:
        """{region: final outcome(s)} when every region can reach a final state, else ''."""
        items = []
        for region in node.children:
            if region.kind == "history":
                continue
            finals = [child.id for child in region.children if child.kind == "final"]
            if region.kind != "state" or not finals:
                return ""
            value = repr(finals[0]) if len(finals) == 1 else repr(tuple(finals))
            items.append(f"{region.id!r}: {value}")
        return "{" + ", ".join(items) + "}" if items else ""

    # --- states

    def _add(self, kind: str, node: c.Node) -> str:
        """`smach.<kind>.add(label, state, transitions=..., remapping=..., name=...)`."""
        remapping: dict[str, str] = {}
        state = self._state(node, remapping)
        parts = [repr(node.id), state]
        transitions = self._transitions(node)
        if transitions:
            parts.append(f"transitions={transitions}")
        if remapping:
            parts.append(f"remapping={remapping!r}")
        if node.name and node.name != node.id:
            parts.append(f"name={node.name!r}")
        return f"smach.{kind}.add({', '.join(parts)})"

    def _state(self, node: c.Node, remapping: dict[str, str]) -> str:
        is_container = bool(node.children) and node.kind in {"state", "parallel"}
        if is_container:
            return self._factory(node, remapping)
        options = self._state_options(node, remapping)
        if node.kind == "final":
            return f"smach.FinalState({', '.join(options)})"
        if node.kind == "history":
            history = [f"deep={node.history == 'deep'}"]
            if node.initial is not None:
                scope = self.parent[node.id]
                targets = [self._target(scope, t) for t in node.initial.targets]
                history.append(f"default={targets!r}")
                action = self._action(node.initial.actions)
                if action:
                    history.append(f"action={action}")
            return f"smach.HistoryState({', '.join(history)})"
        if node.call is not None:
            return f"smach.BehaviourState({', '.join(options)})"
        if node.pseudostate:
            return f"smach.PseudoState({', '.join([repr(node.pseudostate), *options])})"
        return f"smach.EventState({', '.join(options)})"

    def _state_options(self, node: c.Node, remapping: dict[str, str]) -> list[str]:
        """Behaviour (leaf: positional, container: `behaviour=`), entry/exit actions, timers."""
        options: list[str] = []
        if node.call is not None:
            behaviour = self._behaviour(node.call, remapping)
            if node.children:
                options.append(f"behaviour=smach.Behaviour({', '.join(behaviour)})")
            else:
                options.extend(behaviour)
        entry = self._action(node.onentry)
        if entry:
            options.append(f"onentry={entry}")
        exit_ = self._action(node.onexit)
        if exit_:
            options.append(f"onexit={exit_}")
        if node.timers:
            options.append(f"timers={[(t.event, t.delay_ms) for t in node.timers]!r}")
        return options

    def _behaviour(self, call: c.Call, remapping: dict[str, str]) -> list[str]:
        """Behaviour name, kind and outcomes; inputs read from userdata (input_keys, remapped)
        or computed (goal_cb); outputs (output_keys, remapped)."""
        info = self.behaviours.get(call.behaviour)
        outcomes = list(info.outcomes) if info is not None else []
        output_keys = [name for name, _ in call.results]
        for name, data_id in call.results:
            if name != data_id:
                remapping[name] = data_id
        input_keys: list[str] = []
        computed: list[c.Arg] = []
        for arg in call.args:
            source = self._data_key(arg.value)
            bound = remapping.get(arg.name, arg.name) if arg.name in output_keys else None
            if source is None or (bound is not None and bound != source):
                computed.append(arg)
                continue
            if source != arg.name:
                remapping[arg.name] = source
            input_keys.append(arg.name)
        parts = [repr(call.behaviour), repr(call.kind), f"outcomes={outcomes!r}"]
        if input_keys:
            parts.append(f"input_keys={input_keys!r}")
        if output_keys:
            parts.append(f"output_keys={output_keys!r}")
        if computed:
            items = ", ".join(f"{a.name!r}: {self.py(a.value)}" for a in computed)
            parts.append(f"goal_cb={self._function('goal', [f'return {{{items}}}'])}")
        return parts

    def _data_key(self, value: expr.Expr) -> str | None:
        if isinstance(value, expr.Name):
            return self.data_ids.get(value.name) or identifier(value.name)
        return None

    # --- transitions

    def _cond(self, transition: c.Transition) -> str | None:
        """The guard function; `bool(a < b)`, not `bool((a < b))` (ruff UP034)."""
        parts = [f"ctx.is_active({s!r})" for s in transition.in_states]
        if transition.cond is not None:
            parts.append(self.py(transition.cond))
        if not parts:
            return None
        text = " and ".join(parts)
        return self._function("cond", [f"return bool({_unwrap(text)})"])

    def _transitions(self, node: c.Node) -> str:
        scope = self.parent[node.id]
        specs = []
        simple = True
        for transition in node.transitions:
            keys = self._keys(node, transition.events)
            targets = [self._target(scope, t) for t in transition.targets]
            guard = self._cond(transition)
            action = self._action(transition.actions)
            options = []
            if guard:
                options.append(f"guard={guard}")
            if action:
                options.append(f"action={action}")
            if transition.internal:
                options.append("internal=True")
            if transition.bounded:  # the step bound counts it (docs/semantics.md)
                options.append("bounded=True")
            plain = len(keys) == 1 and not keys[0].startswith("smach.")
            simple = simple and plain and len(targets) == 1 and not options
            specs.append((keys, targets, options))
        if not specs:
            return ""
        if simple and len({keys[0] for keys, _, _ in specs}) == len(specs):
            return "{" + ", ".join(f"{keys[0]}: {targets[0]!r}" for keys, targets, _ in specs) + "}"
        return "[" + ", ".join(self._transition_code(*spec) for spec in specs) + "]"

    @staticmethod
    def _transition_code(keys: list[str], targets: list[str], options: list[str]) -> str:
        parts = []
        if keys:
            parts.append(keys[0] if len(keys) == 1 else f"({', '.join(keys)})")
        if targets:
            to = repr(targets[0]) if len(targets) == 1 else repr(tuple(targets))
            parts.append(to if keys else f"to={to}")
        return f"smach.Transition({', '.join([*parts, *options])})"

    def _keys(self, node: c.Node, events: tuple[str, ...]) -> list[str]:
        """Transition keys as code: outcome names, container outcomes, event names, in the
        runtime's resolution order (behaviour outcome, container outcome, event)."""
        outcomes = self._behaviour_outcomes(node)
        completion = self._completion(node)
        keys: list[str] = []
        for event in events:
            outcome = event.removeprefix(f"outcome.{node.id}.")
            if event != outcome and outcome in outcomes:
                keys.append(repr(outcome))
            elif (
                event == f"done.state.{node.id}"
                and completion
                and not set(completion) & set(outcomes)
            ):
                keys.extend(repr(o) for o in completion)
            elif event in outcomes or event in completion:
                keys.append(f"smach.Event({event!r})")
            else:
                keys.append(repr(event))
        return keys

    def _behaviour_outcomes(self, node: c.Node) -> list[str]:
        if node.call is None:
            return []
        info = self.behaviours.get(node.call.behaviour)
        return list(info.outcomes) if info is not None else []

    def _completion(self, node: c.Node) -> list[str]:
        """The container outcomes that stand for `done.state.<id>`."""
        if not node.children:
            return []
        if node.kind == "parallel":
            return [COMPLETION] if self._outcome_map(node) else []
        return [child.id for child in node.children if child.kind == "final"]

    def _target(self, scope: str | None, target: str) -> str:
        """A label (sibling), a path below the scope ("A/B") or an absolute path ("/A/B")."""
        path = [target]
        owner = self.parent[target]
        while owner is not None and owner != scope:
            path.append(owner)
            owner = self.parent[owner]
        if owner == scope:
            return "/".join(reversed(path))
        return "/" + "/".join(reversed(path))


def _unwrap(text: str) -> str:
    """`(a < b)` -> `a < b`: the outer parentheses go when they enclose the whole expression
    (then the text without them is an expression too, token for token)."""
    if text.startswith("(") and text.endswith(")"):
        try:
            ast.parse(text[1:-1], mode="eval")
        except SyntaxError:
            return text
        return text[1:-1]
    return text


class SmachBackend:
    name = "smach"

    def render(self, model: Model, charts: tuple[Chart, ...]) -> Files:
        if not charts:
            return {}  # no state machine, nothing to run
        package = PurePosixPath(package_name(model))
        modules = member_modules(charts)
        source = charts[0].source
        common = {"version": __version__, "source": one_line(source), "runtime": "._runtime"}
        files: Files = {}
        for chart in charts:
            files[package / f"{modules[chart.name]}.py"] = render_member(chart, common)
        members = {c.member: modules[c.name] for c in charts if c.member}
        composition = swarm_composition(model)
        files[package / "__init__.py"] = format_python(
            render(
                "smach/package_init.py.j2",
                **common,
                model=doc_text(model.name),
                package=str(package),
                first_member=doc_text(next(iter(members), "")),
                modules=sorted(modules.values()),
                member_modules="{" + ", ".join(f"{k!r}: {v}" for k, v in members.items()) + "}",
                composition=repr(composition),
                exports=repr(["COMPOSITION", "MEMBER_TYPES", *sorted(modules.values())]),
            )
        )
        files.update(support_files("smach", package, common, charts, SMACH_RUNTIME))
        return files


def render_member(chart: Chart, common: dict[str, str]) -> str:
    code = SmachRenderer(chart).render_smach()
    scopes = {e.ident: e.scope or "swarm" for e in chart.events}
    what = f"member type {chart.member}" if chart.member else f"state machine {chart.machine}"
    text = render(
        "smach/member.py.j2",
        **common,
        what=one_line(what),
        what_doc=doc_text(what),
        doc=doc_text(f"Behaviour of {what} (state machine {chart.machine}), built with SMACH."),
        chart_name=repr(chart.name),
        member_type=repr(chart.member),
        machine=repr(chart.machine),
        event_scopes=repr(scopes),
        event_fields=event_fields_literal(chart),
        code=code,
    )
    return format_python(text)
