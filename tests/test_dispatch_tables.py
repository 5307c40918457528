"""The engine's dispatch tables (swarmgen/runtime/configuration.py over microstep.py: interned configurations,
selections and microstep plans; chart.py's compiled event fillers) against a brute-force
interpreter that computes everything again at every step, as the engine did before the tables:
on random charts (nesting, parallel regions, shallow and deep history, finals, internal
transitions, guards, raised events) and random event sequences, both give the same trace of
configurations, history and executed content, also with two engines sharing one chart's tables.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from swarmgen.runtime.chart import (
    Chart,
    ChartBuilder,
    Context,
    Node,
    Transition,
    fields_filler,
    fill_fields,
    record,
)
from swarmgen.runtime.configuration import Plan, Step, Tables, make_plan
from swarmgen.runtime.engine import Engine, NullHost
from swarmgen.runtime.microstep import (
    document_order,
    entry_set,
    exit_set,
    in_final,
    recorded_history,
    remove_conflicts,
)

EVENTS = ("a", "b", "c", "a.x", "b.y")
# `r` is what transitions raise; no transition on `r` raises again, and none matches the
# `done.state.*` events, so no macrostep cycles on events (eventless ones are bounded: EVENTLESS)
DESCRIPTORS = ("a", "b", "c", "a.*", "b", "r")
EVENTLESS = 300  # eventless transitions are guarded by `n < EVENTLESS`, and each raises `n`
Log = list[tuple[str, str]]


class BruteForce:
    """The W3C algorithm with nothing kept between steps: every selection walks the atomic
    states in document order, every microstep computes its exit and entry sets anew."""

    def __init__(self, chart: Chart) -> None:
        self.chart = chart
        self.data = chart.fresh_data()
        self.ctx = Context(self, self.data)
        self.config: set[Node] = set()
        self.history: dict[Node, tuple[Node, ...]] = {}
        self.internal: deque[str] = deque()
        self.running = True

    def is_active(self, node_id: str) -> bool:
        """`In(state)`."""
        return any(n.id == node_id for n in self.config)

    def raise_internal(self, name: str, data: Any) -> None:
        """`raise e`: the internal queue."""
        self.internal.append(name)

    def start(self) -> None:
        """The initial configuration, then the macrostep."""
        assert self.chart.root.initial is not None
        self._enter((self.chart.root.initial,))
        self._macrostep()

    def send(self, name: str) -> None:
        """One external event."""
        if self.running:
            self._step(name)
            self._macrostep()

    def _macrostep(self) -> None:
        while self.running:
            if self._step(None):
                continue
            if not self.internal:
                break
            self._step(self.internal.popleft())

    def _step(self, name: str | None) -> bool:
        enabled: list[Transition] = []
        for state in sorted((n for n in self.config if n.is_atomic), key=document_order):
            for owner in (state, *state.ancestors):
                chosen = next((t for t in owner.transitions if self._enabled(t, name)), None)
                if chosen is not None:
                    if chosen not in enabled:
                        enabled.append(chosen)
                    break
        if not enabled:
            return False
        taken = remove_conflicts(enabled, self.config, self.history)
        exits = sorted(exit_set(taken, self.config, self.history), key=document_order)
        for state in reversed(exits):
            for child in state.children:
                if child.kind == "history":
                    self.history[child] = recorded_history(child, state, self.config)
        for state in reversed(exits):
            if state.onexit is not None:
                state.onexit(self.ctx)
            self.config.discard(state)
        for transition in taken:
            if transition.action is not None:
                transition.action(self.ctx)
        self._enter(taken)
        return True

    def _enabled(self, transition: Transition, name: str | None) -> bool:
        if name is None:
            matches = not transition.events
        else:
            matches = bool(transition.events) and transition.matches(name)
        return matches and (transition.cond is None or transition.cond(self.ctx))

    def _enter(self, transitions: tuple[Transition, ...]) -> None:
        entry = entry_set(transitions, self.history)
        for state in sorted(entry.to_enter, key=document_order):
            self.config.add(state)
            if state.onentry is not None:
                state.onentry(self.ctx)
            initial = state.initial if state in entry.default_entry else None
            if initial is not None and initial.action is not None:
                initial.action(self.ctx)
            if state in entry.history_content:
                action = entry.history_content[state].action
                if action is not None:
                    action(self.ctx)
            if state.kind == "final":
                self._final(state)

    def _final(self, state: Node) -> None:
        parent = state.parent
        assert parent is not None
        if parent.kind == "scxml":
            self.running = False
            for active in sorted(self.config, key=document_order, reverse=True):
                if active.onexit is not None:
                    active.onexit(self.ctx)
            self.internal.clear()
            return
        self.internal.append(f"done.state.{parent.id}")
        grand = parent.parent
        regions = [] if grand is None or grand.kind != "parallel" else grand.children
        if regions and all(in_final(c, self.config) for c in regions if c.kind != "history"):
            self.internal.append(f"done.state.{grand.id}")  # type: ignore[union-attr]


# --- random charts ------------------------------------------------------------------------------

Spec = dict[str, Any]  # a node: kind, children, history kind, transitions


def _logger(log: Log, what: str, node_id: str) -> Callable[[Context], None]:
    def run(ctx: Context) -> None:
        log.append((what, node_id))
        ctx.data["n"] = ctx.data["n"] + 1

    return run


def _raiser(log: Log, node_id: str, name: str) -> Callable[[Context], None]:
    def run(ctx: Context) -> None:
        log.append(("raise", f"{node_id}:{name}"))
        ctx.raise_event(name)

    return run


def _guard(mod: int, rest: int, watched: str) -> Callable[[Context], bool]:
    def cond(ctx: Context) -> bool:
        return ctx.data["n"] % mod == rest or ctx.is_active(watched)

    return cond


def _bounded(ctx: Context) -> bool:
    return bool(ctx.data["n"] < EVENTLESS)


@st.composite
def charts(draw: st.DrawFn) -> Callable[[Log], Chart]:
    """A random chart's description, as a function building it with content logging into a
    list (each interpreter gets its own chart and log)."""
    nodes: list[tuple[str, str, str | None, str]] = []  # id, kind, parent, history kind
    counter = iter(range(10_000))

    def make(parent: str | None, depth: int) -> str:
        node_id = f"s{next(counter)}"
        kinds = ["state", "state", "final"] + (["parallel", "state"] if depth < 3 else [])
        kind = draw(st.sampled_from(kinds if depth > 0 else ["state", "parallel"]))
        nodes.append((node_id, kind, parent, ""))
        if kind in {"state", "parallel"} and depth < 3 and (depth == 0 or draw(st.booleans())):
            for _ in range(draw(st.integers(2, 3))):
                make(node_id, depth + 1)
            if kind == "state" and draw(st.booleans()):
                hid = f"h{next(counter)}"
                nodes.append((hid, "history", node_id, draw(st.sampled_from(["shallow", "deep"]))))
        return node_id

    make(None, 0)
    ids = [n[0] for n in nodes]
    proper = [n[0] for n in nodes if n[1] != "history"]
    transitions = []
    for _ in range(draw(st.integers(1, 4 * len(ids)))):
        source = draw(st.sampled_from(proper))
        events = draw(st.sampled_from([(), *((d,) for d in DESCRIPTORS), ("a",), ("b",)]))
        targets = draw(st.sampled_from([(), (draw(st.sampled_from(ids)),)]))
        if not events and not targets:
            targets = (draw(st.sampled_from(ids)),)
        guard = draw(st.sampled_from([None, (2, 0), (3, 1)]))
        raises = draw(st.booleans()) and bool(events) and events[0] != "r"
        internal = draw(st.booleans())
        transitions.append((source, events, targets, guard, raises, internal))
    watched = draw(st.sampled_from(ids))

    def build(log: Log) -> Chart:
        b = ChartBuilder("random", data={"n": 0})
        for node_id, kind, parent, history in nodes:
            if kind == "history":
                b.node(node_id, "history", parent, history=history)
                continue
            b.node(
                node_id,
                kind,
                parent,
                onentry=_logger(log, "entry", node_id),
                onexit=_logger(log, "exit", node_id),
            )
        for node_id, kind, parent, _ in nodes:
            proper_children = [n for n, k, p, _ in nodes if p == node_id and k != "history"]
            if kind == "state" and proper_children:
                b.initial(node_id, (proper_children[-1],), _logger(log, "initial", node_id))
            if kind == "history":
                siblings = [n for n, k, p, _ in nodes if p == parent and k != "history"]
                b.initial(node_id, (siblings[0],), _logger(log, "default", node_id))
        b.initial(None, (ids[0],))
        for number, (source, events, targets, guard, raises, internal) in enumerate(transitions):
            action = (
                _raiser(log, f"t{number}", "r")
                if raises
                else _logger(log, "transition", f"t{number}")
            )
            cond = _guard(guard[0], guard[1], watched) if guard else None
            b.transition(
                source,
                events,
                targets,
                cond=cond if events else _bounded,
                action=action,
                internal=internal,
            )
        return b.build()

    return build


def _observe(engine: Any) -> tuple[Any, ...]:
    history = sorted((h.id, tuple(n.id for n in v)) for h, v in engine.history.items())
    return (sorted(n.id for n in engine.config), history, engine.data["n"], engine.running)


@settings(max_examples=200, deadline=None)
@given(build=charts(), events=st.lists(st.sampled_from(EVENTS), max_size=40))
def test_tables_give_the_brute_force_trace(
    build: Callable[[Log], Chart], events: list[str]
) -> None:
    logs: tuple[Log, Log] = ([], [])
    reference = BruteForce(build(logs[0]))
    engine = Engine(build(logs[1]), NullHost())
    reference.start()
    engine.start()
    assert _observe(engine) == _observe(reference)
    for name in events:
        reference.send(name)
        engine.send(engine.make_event(name))
        assert _observe(engine) == _observe(reference)
        assert logs[1] == logs[0]


@settings(max_examples=60, deadline=None)
@given(build=charts(), events=st.lists(st.sampled_from(EVENTS), max_size=25), split=st.integers())
def test_engines_sharing_a_chart_share_its_tables_safely(
    build: Callable[[Log], Chart], events: list[str], split: int
) -> None:
    """Two engines of one chart (as simulate runs them): each gives the trace it gives alone,
    although their configurations and history differ while they share the plans."""
    log: Log = []
    shared = build(log)
    one, two = Engine(shared, NullHost()), Engine(shared, NullHost())
    alone = [Engine(build([]), NullHost()) for _ in range(2)]
    for engine in (one, two, *alone):
        engine.start()
    cut = split % (len(events) + 1)
    for name in events[cut:] + events[:cut]:  # the second engine sees another order
        two.send(two.make_event(name))
        alone[1].send(alone[1].make_event(name))
    for name in events:
        one.send(one.make_event(name))
        alone[0].send(alone[0].make_event(name))
    assert _observe(one) == _observe(alone[0])
    assert _observe(two) == _observe(alone[1])


@given(kind=st.sampled_from(["shallow", "deep"]), events=st.lists(st.sampled_from("abcd")))
def test_plans_through_history_follow_what_it_recorded(kind: str, events: list[str]) -> None:
    """Re-entering P through its history node from the same configuration enters what P held
    when it was last left: the plan of `c` is one per recorded history, not one per
    configuration."""

    def build(log: Log) -> Chart:
        b = ChartBuilder("history", data={"n": 0})
        for node_id, parent in (("P", None), ("A", "P"), ("B", "P"), ("B1", "B"), ("B2", "B")):
            b.node(node_id, "state", parent, onentry=_logger(log, "entry", node_id))
        b.node("H", "history", "P", history=kind)
        b.node("Q", "state")
        b.initial("P", ("A",))
        b.initial("B", ("B1",))
        b.initial("H", ("A",), _logger(log, "default", "H"))
        b.initial(None, ("P",))
        b.transition("A", ("a",), ("B",))
        b.transition("B1", ("a",), ("B2",))
        b.transition("B2", ("d",), ("A",))
        b.transition("P", ("b",), ("Q",))
        b.transition("Q", ("c",), ("H",))
        return b.build()

    logs: tuple[Log, Log] = ([], [])
    reference, engine = BruteForce(build(logs[0])), Engine(build(logs[1]), NullHost())
    reference.start()
    engine.start()
    for name in ["a", "b", "c", "a", "b", "c", *events]:
        reference.send(name)
        engine.send(engine.make_event(name))
        assert _observe(engine) == _observe(reference)
    assert logs[1] == logs[0]


# --- event fillers --------------------------------------------------------------------------------

leaves = st.one_of(st.integers(), st.floats(allow_nan=False), st.text(max_size=3), st.booleans())
templates = st.recursive(
    st.dictionaries(st.text(max_size=3), leaves, max_size=3),
    lambda inner: st.dictionaries(
        st.text(max_size=3), st.one_of(leaves, inner, st.lists(leaves, max_size=2)), max_size=3
    ),
    max_leaves=10,
)
values = st.recursive(
    st.one_of(st.none(), leaves),
    lambda inner: st.one_of(
        st.dictionaries(st.text(max_size=3), inner, max_size=3), st.lists(inner, max_size=2)
    ),
    max_leaves=10,
)


@given(template=templates, data=st.one_of(st.none(), st.dictionaries(st.text(max_size=3), values)))
def test_compiled_fillers_fill_as_fill_fields(template: dict[str, Any], data: Any) -> None:
    """Same values, same key order, Records all the way down, and a new tree each time."""
    made = fields_filler(template)
    expected = fill_fields(data, template)
    got = made(data)
    assert got == expected
    assert _shape(got) == _shape(expected)
    assert made(data) is not got
    again = made(None)
    assert again == fill_fields(None, template) and again is not made(None)
    assert _shape(record(again)) == _shape(again)


def _shape(value: Any) -> Any:
    if isinstance(value, dict):
        return (type(value).__name__, [(k, _shape(v)) for k, v in value.items()])
    if isinstance(value, list):
        return ("list", [_shape(v) for v in value])
    return type(value).__name__


# --- the per-chart indexes and per-transition steps ------------------------------------------------

NAME_PARTS = ("a", "b", "", "*", "ab")
descriptors = st.lists(st.sampled_from(NAME_PARTS), min_size=1, max_size=3).map(".".join)


@given(
    events=st.lists(st.lists(descriptors, max_size=3), min_size=1, max_size=6),
    names=st.lists(descriptors, max_size=10),
)
def test_reactors_and_matching_find_what_matches_finds(
    events: list[list[str]], names: list[str]
) -> None:
    """The chart's descriptor index (`Tables.reactors`) and a node's token index (`matching`)
    give, for any name, exactly the transitions `Transition.matches` accepts, in document order:
    descriptors with dots, empty parts, `*` and `.*` in any place."""
    b = ChartBuilder("names")
    b.node("P", "state")
    for number in range(len(events)):
        b.node(f"S{number}", "state", "P")
    b.initial("P", ("S0",))
    b.initial(None, ("P",))
    for number, descriptors_of in enumerate(events):
        for owner in (f"S{number}", "P"):
            b.transition(owner, tuple(descriptors_of), ("P",))
    chart = b.build()
    tables = Tables(chart.nodes.values())
    for name in [*names, *(d for ds in events for d in ds), "unrelated"]:
        expected = {}
        for node in chart.nodes.values():
            found = tuple(t for t in node.transitions if t.events and t.matches(name))
            assert node.matching(name) == found
            if found:
                expected[node] = found
        assert tables.reactors(name) == expected


@settings(max_examples=80, deadline=None)
@given(build=charts(), events=st.lists(st.sampled_from(EVENTS), max_size=30))
def test_steps_plan_as_make_plan(build: Callable[[Log], Chart], events: list[str]) -> None:
    """A transition's Step (domain and entry set computed once, where they read no history)
    gives, from every configuration the engine reached and under the history it had there, the
    plan `make_plan` computes anew; and the engine's plans there are those of `make_plan`."""
    chart = build([])
    engine = Engine(chart, NullHost())
    engine.start()
    transitions = [t for node in chart.nodes.values() for t in node.transitions]
    for name in [*events, None]:
        if name is not None:
            engine.send(engine.make_event(name))
        config = frozenset(engine.config)
        for transition in transitions:
            step = Step.of(transition)
            if step is None:
                continue
            made = make_plan(config, (transition,), engine.history)
            assert _plan_view(step.plan(config)) == _plan_view(made)
        cfg = engine._tables.configuration(config)
        for enabled, plan in cfg.plans.items():
            while plan is not None:
                if plan.holds(engine.history):
                    assert _plan_view(plan) == _plan_view(
                        make_plan(config, enabled, engine.history)
                    )
                plan = plan.other


def _plan_view(plan: Plan) -> tuple[Any, ...]:
    return (
        plan.transitions,
        plan.exits,
        plan.records,
        plan.entries,
        plan.target,
        plan.read,
    )
