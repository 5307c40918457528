"""The smach backend: a Python package per swarm whose member modules build their behaviour with
SMACH's API (State, StateMachine, Concurrence, userdata, remapping) over the bundled runtime
`_runtime/smach.py`, which turns the containers into the same chart the asyncio backend builds and
runs it with the same engine. See docs/smach.md for the mapping."""

from __future__ import annotations

import keyword
from dataclasses import field

from swarmgen import expr
from swarmgen.backends import pylayout
from swarmgen.backends.asyncio_backend import RUNTIME_MODULES
from swarmgen.backends.pycommon import PackageBackend, member_view
from swarmgen.backends.pyrender import (
    ChartRenderer,
    Function,
    format_python,
    py_literal,
    zeros_literal,
)
from swarmgen.chart import model as c
from swarmgen.chart.model import Chart
from swarmgen.names import IdAllocator, identifier, one_line, ros_name
from swarmgen.records import dataclass
from swarmgen.render import render

SMACH_RUNTIME = (*RUNTIME_MODULES, "smach_states", "smach_containers", "smach_chart", "smach")
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
    """A chart rendered for SMACH: the shared helper functions and the container factories."""

    functions: list[Function]
    factories: list[Factory]
    sessions: int = 0  # invoked charts: the module imports `ChartBuilder` and `Invoke`


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
        """The helper functions and the container factories, `build_state_machine` first."""
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
        zeros = zeros_literal(self.chart)
        if zeros is not None:
            top.lines.append(f"sm.zeros = {zeros}")
        top.lines.append("with sm:")
        initial = [self._target(None, t) for t in self.chart.initial]
        top.lines.append(f"{INDENT}sm.set_initial_state({initial!r})")
        for node in self.chart.children:
            top.lines.append(INDENT + self._add("StateMachine", node))
        top.lines.append("return sm")
        return SmachCode(self.code.functions, self.factories, self.code.sessions)

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
        parts: list[pylayout.Arg] = [repr(node.id), state]
        transitions = self._transitions(node)
        if transitions is not None:
            parts.append(pylayout.Kw("transitions=", transitions))
        if remapping:
            parts.append(f"remapping={remapping!r}")
        if node.name and node.name != node.id:
            parts.append(f"name={node.name!r}")
        # in a factory's `with sm:` block, two levels deep
        return pylayout.statement(2, f"smach.{kind}.add", parts)

    def _state(self, node: c.Node, remapping: dict[str, str]) -> pylayout.Node:
        is_container = bool(node.children) and node.kind in {"state", "parallel"}
        if is_container:
            return self._factory(node, remapping)
        options = self._state_options(node, remapping)
        if node.kind == "final":
            return pylayout.Call("smach.FinalState", tuple(options))
        if node.kind == "history":
            history = [f"deep={node.history == 'deep'}"]
            if node.initial is not None:
                scope = self.parent[node.id]
                targets = [self._target(scope, t) for t in node.initial.targets]
                history.append(f"default={targets!r}")
                action = self._action(node.initial.actions)
                if action:
                    history.append(f"action={action}")
            return pylayout.Call("smach.HistoryState", tuple(history))
        if node.call is not None:
            return pylayout.Call("smach.BehaviourState", tuple(options))
        if node.pseudostate:
            return pylayout.Call("smach.PseudoState", (repr(node.pseudostate), *options))
        return pylayout.Call("smach.EventState", tuple(options))

    def _state_options(self, node: c.Node, remapping: dict[str, str]) -> list[str]:
        """Behaviour (leaf: positional, container: `behaviour=`), entry/exit actions, timers."""
        options: list[str] = []
        if node.call is not None:
            behaviour = self._behaviour(node.call, remapping)
            if node.children:
                options.append(f"behaviour=smach.Behaviour({', '.join(behaviour)})")
            else:
                options.extend(behaviour)
        options.extend(self._hooks(node))
        if node.timers:
            options.append(f"timers={[(t.event, t.delay_ms) for t in node.timers]!r}")
        if node.invokes:
            invokes = ", ".join(pylayout.flat(self._invoke(i)) for i in node.invokes)
            options.append(f"invokes=[{invokes}]")  # formatted by `format_python`
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

    def _transitions(self, node: c.Node) -> pylayout.Seq | None:
        """The `transitions=` value: a dict {key: target} when every transition is a plain
        one, else a list of `smach.Transition(...)`; None when the state has none."""
        scope = self.parent[node.id]
        specs = []
        simple = True
        for transition in node.transitions:
            keys = self._keys(node, transition.events)
            targets = [self._target(scope, t) for t in transition.targets]
            options = self._transition_options(transition, "guard")
            plain = len(keys) == 1 and not keys[0].startswith("smach.")
            simple = simple and plain and len(targets) == 1 and not options
            specs.append((keys, targets, options))
        if not specs:
            return None
        if simple and len({keys[0] for keys, _, _ in specs}) == len(specs):
            items = (pylayout.Kw(f"{keys[0]}: ", repr(targets[0])) for keys, targets, _ in specs)
            return pylayout.Seq("{", tuple(items))
        return pylayout.Seq("[", tuple(self._transition_code(*spec) for spec in specs))

    @staticmethod
    def _transition_code(keys: list[str], targets: list[str], options: list[str]) -> pylayout.Call:
        parts = []
        if keys:
            parts.append(keys[0] if len(keys) == 1 else f"({', '.join(keys)})")
        if targets:
            to = repr(targets[0]) if len(targets) == 1 else repr(tuple(targets))
            parts.append(to if keys else f"to={to}")
        return pylayout.Call("smach.Transition", (*parts, *options))

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


def render_member(chart: Chart, common: dict[str, str]) -> str:
    """A member module: its SMACH container factories over the shared helper functions."""
    code = SmachRenderer(chart).render_smach()
    view = member_view(chart, common, code, ", built with SMACH", header_text=one_line)
    return format_python(render("smach/member.py.j2", **view))


class SmachBackend(PackageBackend):
    """The SMACH package: member modules building SMACH containers over the vendored runtime."""

    name = "smach"
    runtime_modules = SMACH_RUNTIME
    member = staticmethod(render_member)
