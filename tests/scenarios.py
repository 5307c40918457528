"""Scenario generation for equivalence tests: seeded walks that mostly feed a member what its
active states react to (so the walks go deep), with noise, behaviour failures, bursts of inputs
queued back to back, and an abort in the middle of every state reached; plus families aimed at
the corners of the semantics (`ScenarioMaker.edge_scenarios`):

- guarded triggers: every guarded transition, reached by the shortest known prefix, triggered
  with values on and just beside the constants its guard compares against (outputs of the
  behaviour that ends for an outcome, event fields otherwise), with outputs left out, event
  fields left out and zero divisors (guards that raise);
- untaken outcomes: outcomes no transition takes (declared but unhandled, handled but every
  guard false, and an outcome the behaviour does not declare), then one more step;
- history re-entry: deep inside a state with a history, leave it, come back, and take the
  transitions that target the history;
- submachine completion: a submachine state run to its final state by its behaviours' outcomes;
- mixed bursts: a behaviour's outcome queued back to back with a swarm or station event, and
  the outcomes of two parallel behaviours together.
- descriptor names: every transition on an event, reached by the shortest known prefix, given
  a longer name its descriptor matches by W3C's token prefix (`e.more`, with the event's data)
  and one that only shares its text (`ex`, matched by nothing), then one more step;
- near livelocks: every input that runs the transitions of a potential microstep cycle (the
  step bound's, docs/semantics.md), alone, twice back to back, and followed by noise (each
  external event starts the bound's count again).

Values come from the guards: `GuardValues` walks the guard expressions (swarmgen.expr) for
the constants each member datum, output and event field is compared against, divisors (zero)
and booleans; flows through `raise`/`send` parameters (`raise lowBattery(level = battery)`
gives `battery` the constants `event.level` is compared with).

The guide is the chart as the asyncio backend renders it, run on the runtime engine and fed
with the replay's own submission rules (`swarmgen.runtime.replay`), so it follows guards,
effects, raised events and histories; it only guides the choice of inputs: the oracle is the
comparison between backends (Qt SCXML is an independent engine). Everything is deterministic
for a seed.
"""

from __future__ import annotations

import hashlib
import math
import random
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from swarmgen import expr as x
from swarmgen.chart import model as c
from swarmgen.runtime import chart as rc
from swarmgen.runtime.chart import ChartBuilder
from swarmgen.runtime.engine import Engine, NullHost
from swarmgen.runtime.replay import expand, outcome_event, running_state

Step = dict[str, Any]
Scenario = list[Step]
Path = tuple[str, ...]  # ("battery",), ("home", "x"), ("event", "level")

_VALUES: dict[str | None, Any] = {"Integer": 3, "Real": 2.5, "Boolean": True, "String": "s"}
COMPARISONS = frozenset({"==", "!=", "<", "<=", ">", ">="})
ARITHMETIC = frozenset({"+", "-", "*", "/", "%"})
OUTCOME_PREFIXES = ("outcome.", "done.invoke.")
UNDECLARED_OUTCOME = "unplanned"  # an outcome no behaviour declares
FAMILY_LIMIT = 40  # scenarios per family and chart at most
DESCRIPTOR_LIMIT = 4  # descriptor names per chart: the matching rule is one, not per transition
UNSET_FIELD = 0.2  # chance a data type's field is left out of a generated value


def _value(type_name: str | None, rng: random.Random, template: Any = None) -> Any:
    if type_name in {"Integer", "Real"}:
        return rng.randint(0, 40) if type_name == "Integer" else round(rng.uniform(0, 40), 2)
    if type_name in _VALUES:
        return _VALUES[type_name]
    if isinstance(template, dict):
        return _shaped(template, rng)
    return {"x": rng.randint(0, 9), "y": rng.randint(0, 9)}  # a data type such as Pose


def _shaped(template: dict[str, Any], rng: random.Random) -> dict[str, Any]:
    """A data type's value in the shape of its initial value (the model's type, nested): its
    numbers drawn, Booleans flipped at random, some fields left out (unset data, which every
    backend fills from the type's initial value the same way)."""
    value: dict[str, Any] = {}
    for key, held in template.items():
        if rng.random() < UNSET_FIELD:
            continue
        if isinstance(held, dict):
            value[key] = _shaped(held, rng)
        elif isinstance(held, bool):
            value[key] = rng.random() < 0.5
        elif isinstance(held, int | float):
            value[key] = rng.randint(0, 9)
        else:
            value[key] = held
    return value


def _zero(type_name: str | None) -> Any:
    return {"Integer": 0, "Real": 0.0, "Boolean": False, "String": ""}.get(type_name or "", 0)


# --- the guide


_BUILT: dict[str, rc.Chart] = {}


def semantic_chart(chart: c.Chart) -> rc.Chart:
    """The runtime chart the asyncio backend generates for `chart` (built once per process)."""
    from swarmgen import __version__
    from swarmgen.backends.asyncio_backend import render_member

    common = {"version": __version__, "source": chart.source, "runtime": "swarmgen.runtime"}
    code = render_member(chart, common)
    key = hashlib.sha256(code.encode()).hexdigest()
    if key not in _BUILT:
        namespace: dict[str, Any] = {"__name__": f"_scenario_guide_{chart.name}"}
        exec(compile(code, f"<guide {chart.name}>", "exec"), namespace)  # our own rendering
        _BUILT[key] = namespace["build"]()
    return _BUILT[key]


def guide(chart: c.Chart) -> Engine:
    """A started engine with the chart's full semantics (guards, effects, raised events)."""
    engine = Engine(semantic_chart(chart), NullHost())
    engine.start()
    return engine


def skeleton(chart: c.Chart) -> Engine:
    """A lighter guide: the chart's structure, its behaviours and the events its actions
    raise (without data), but no guards nor assignments."""
    builder = ChartBuilder(chart.name)

    def raising(actions: Sequence[c.Action]) -> rc.Action | None:
        names = [a.event for a in actions if isinstance(a, c.Raise)]
        if not names:
            return None

        def act(ctx: rc.Context) -> None:
            for name in names:
                ctx.raise_event(name)

        return act

    def add(node: c.Node, parent: str | None) -> None:
        call = None
        if node.call is not None:
            call = rc.Call(node.call.behaviour, node.call.kind, lambda ctx: {})
        builder.node(
            node.id,
            node.kind,
            parent,
            history=node.history or "",
            call=call,
            onentry=raising(node.onentry),
            onexit=raising(node.onexit),
        )
        if node.initial is not None:
            builder.initial(node.id, node.initial.targets)
        for child in node.children:
            add(child, node.id)
        for transition in node.transitions:
            builder.transition(
                node.id,
                transition.events,
                transition.targets,
                action=raising(transition.actions),
                bounded=transition.bounded,  # else an unguarded cycle would spin in the guide
            )

    for node in chart.children:
        add(node, None)
    builder.initial(None, chart.initial)
    engine = Engine(builder.build(), NullHost())
    engine.start()
    return engine


def _outcome_name(engine: Engine, node: rc.Node, outcome: str) -> str:
    """The replay's own outcome event (`swarmgen.runtime.replay.outcome_event`); if the chart
    waits for this state's outcomes only under the other naming (`outcome.` or
    `done.invoke.`), that one: the guide then still follows a compiler and runtime in step."""
    name = outcome_event(node, outcome)
    descriptors = _descriptors(engine)

    def waited(prefix: str) -> bool:
        return any(
            d == f"{prefix}{node.id}" or d.startswith(f"{prefix}{node.id}.") for d in descriptors
        )

    if waited(name[: len(name) - len(f"{node.id}.{outcome}")]):
        return name
    for prefix in OUTCOME_PREFIXES:
        if waited(prefix):
            return f"{prefix}{node.id}.{outcome}"
    return name


def _descriptors(engine: Engine) -> set[str]:
    found = getattr(engine, "_scenario_descriptors", None)
    if found is None:
        found = {e for n in engine.chart.nodes.values() for t in n.transitions for e in t.events}
        engine._scenario_descriptors = found  # type: ignore[attr-defined]
    return found


def follow(engine: Engine, step: Step) -> None:
    """Feed one step to a guide exactly as `swarmgen.runtime.replay` submits it: every input of
    a burst is decided against the configuration before the burst, then they run in order."""
    active = set(engine.active())
    events = []
    for item in expand(step):
        if "complete" in item:
            node = running_state(engine.chart, active, str(item["complete"]), item.get("state"))
            if node is None:
                continue  # nothing runs that behaviour now: no effect
            name = _outcome_name(engine, node, str(item.get("outcome", "succeeded")))
            origin = (node.id, engine.activation(node.id))
            outputs = dict(item.get("outputs") or {})
            events.append(engine.make_event(name, outputs, "replay", origin=origin))
        else:
            events.append(engine.make_event(str(item["event"]), item.get("data"), "station"))
    for event in events:
        engine.send(event)


# --- values from the guards


def _path(e: x.Expr) -> Path | None:
    if isinstance(e, x.Name):
        return (e.name,)
    if isinstance(e, x.EventField):
        return ("event", e.field)
    if isinstance(e, x.Attr):
        inner = _path(e.obj)
        return (*inner, e.name) if inner is not None else None
    return None


def _walk(e: x.Expr) -> Iterator[x.Expr]:
    yield e
    if isinstance(e, x.Unary):
        yield from _walk(e.operand)
    elif isinstance(e, x.Binary):
        yield from _walk(e.left)
        yield from _walk(e.right)
    elif isinstance(e, x.Attr):
        yield from _walk(e.obj)


def _action_exprs(actions: Sequence[c.Action]) -> Iterator[x.Expr]:
    """The expressions of actions: values, event fields, delays, and `if` conditions with the
    actions of their branches (their comparisons and divisors are as interesting as guards')."""
    for action in c.flat(tuple(actions)):
        if isinstance(action, c.Assign):
            yield action.value
        elif isinstance(action, c.If):
            yield from (cond for cond, _ in action.branches if cond is not None)
        elif isinstance(action, c.ForEach):
            yield action.array
        elif isinstance(action, c.Raise | c.Send):
            if isinstance(action, c.Raise) and action.delay is not None:
                yield action.delay.amount
            for param in action.params:
                if _is_expr(param.value):
                    yield param.value  # type: ignore[misc]


def _is_expr(value: object) -> bool:
    return isinstance(value, x.Const | x.Name | x.EventField | x.Attr | x.Unary | x.Binary)


def _sort_key(value: Any) -> tuple[str, str]:
    return (type(value).__name__, repr(value))


class GuardValues:
    """The constants, divisors and booleans guards and effects compare member data, behaviour
    outputs and event fields with (see the module docstring)."""

    def __init__(self, chart: c.Chart) -> None:
        self.chart = chart
        self.data: dict[Path, set[Any]] = {}  # data path -> constants
        self.fields: dict[tuple[str, Path], set[Any]] = {}  # (event descriptor, path) -> consts
        self.divisors: set[tuple[str, Path]] = set()  # ("", data path) or (event, field path)
        self.booleans: set[tuple[str, Path]] = set()
        for node in chart.walk():
            for transition in node.transitions:
                events = transition.events
                if transition.cond is not None and _is_expr(transition.cond):
                    self._scan(transition.cond, events, whole=True)
                for value in _action_exprs(transition.actions):
                    self._scan(value, events, whole=False)
            for value in _action_exprs((*node.onentry, *node.onexit)):
                self._scan(value, (), whole=False)
        self._flow()

    def _add(self, path: Path, value: Any, events: Sequence[str]) -> None:
        if path[0] == "event":
            for event in events:
                self.fields.setdefault((event, path[1:]), set()).add(value)
        else:
            self.data.setdefault(path, set()).add(value)

    def _mark(self, where: set[tuple[str, Path]], path: Path, events: Sequence[str]) -> None:
        if path[0] == "event":
            where.update((event, path[1:]) for event in events)
        else:
            where.add(("", path))

    def _scan(self, e: x.Expr, events: Sequence[str], *, whole: bool) -> None:
        top = _path(e)
        if whole and top is not None:  # a guard that is a name: a boolean
            self._mark(self.booleans, top, events)
        for sub in _walk(e):
            if isinstance(sub, x.Binary) and sub.op in COMPARISONS:
                for side, other in ((sub.left, sub.right), (sub.right, sub.left)):
                    if not isinstance(other, x.Const) or other.value is None:
                        continue
                    path = _path(side)
                    if path is not None:
                        self._add(path, other.value, events)
                    elif isinstance(side, x.Binary) and side.op in ARITHMETIC:
                        for inner in _walk(side):  # operands of arithmetic: the constant, 1
                            p = _path(inner)
                            if p is not None and isinstance(inner, x.Name | x.EventField):
                                self._add(p, other.value, events)
                                self._add(p, 1, events)
            if isinstance(sub, x.Binary) and sub.op in {"/", "%"}:
                path = _path(sub.right)
                if path is not None:
                    self._mark(self.divisors, path, events)
            if isinstance(sub, x.Binary) and sub.op in {"and", "or"}:
                for side in (sub.left, sub.right):
                    path = _path(side)
                    if path is not None:
                        self._mark(self.booleans, path, events)
            if isinstance(sub, x.Unary) and sub.op == "not":
                path = _path(sub.operand)
                if path is not None:
                    self._mark(self.booleans, path, events)

    def _flow(self) -> None:
        """`raise e(f = name)` / `send e(f = name)`: what `event.f` is compared with is also a
        value worth giving `name` (to a fixpoint: a few rounds suffice)."""
        for _ in range(3):
            for node in self.chart.walk():
                for transition in node.transitions:
                    for action in transition.actions:
                        if not isinstance(action, c.Raise | c.Send):
                            continue
                        for param in action.params:
                            if not _is_expr(param.value):
                                continue
                            source = _path(param.value)  # type: ignore[arg-type]
                            if source is None or source[0] == "event":
                                continue
                            wanted = self.fields.get((action.event, (param.name,)), set())
                            self.data.setdefault(source, set()).update(wanted)
                            if (action.event, (param.name,)) in self.divisors:
                                self.divisors.add(("", source))

    # --- candidates

    def candidates(self, keys: Sequence[tuple[str, Path]], type_name: str | None) -> list[Any]:
        """Values worth trying for a datum or field of this type: each constant it is
        compared with and its neighbours, zero if it divides, both booleans if it is one."""
        constants: set[Any] = set()
        zero = boolean = False
        for event, path in keys:
            constants |= (
                self.data.get(path, set()) if not event else self.fields.get((event, path), set())
            )
            zero = zero or (event, path) in self.divisors
            boolean = boolean or (event, path) in self.booleans
        found: set[Any] = set()
        for value in constants:
            found |= _neighbours(value, type_name)
        if zero:
            found.add(_zero(type_name) if type_name in {"Integer", "Real"} else 0)
        if boolean:
            found |= {True, False}
        return sorted(found, key=_sort_key)


def _neighbours(value: Any, type_name: str | None) -> set[Any]:
    if isinstance(value, bool):
        return {True, False}
    if isinstance(value, str):
        if type_name in {None, "String"}:
            return {value, value + "_"}
        # an enumeration literal (`mode == Mode.track`): the literal itself, nothing near it
        return {value} if type_name not in {"Integer", "Real", "Boolean"} else set()
    if not isinstance(value, int | float):
        return set()
    if type_name == "Integer" or (type_name is None and isinstance(value, int)):
        low, high = math.floor(value), math.ceil(value)
        return {low - 1, low, high, high + 1}
    if type_name in {"Real", None}:
        return {round(value - 0.01, 6), float(value), round(value + 0.01, 6)}
    return set()


def _spread(values: Sequence[Any], count: int) -> list[Any]:
    """`count` values spread evenly over a sorted list (both ends included)."""
    if len(values) <= count:
        return list(values)
    if count == 1:
        return [values[len(values) // 2]]
    return [values[round(i * (len(values) - 1) / (count - 1))] for i in range(count)]


# --- the maker


def _config(engine: Engine) -> frozenset[str]:
    return frozenset(engine.active())


class ScenarioMaker:
    def __init__(self, chart: c.Chart, seed: int, *, semantic: bool = True) -> None:
        self.chart = chart
        self.seed = seed
        self.semantic = semantic
        self.rng = random.Random(seed)
        self.nodes = {n.id: n for n in chart.walk()}
        self.parents = {child.id: n.id for n in chart.walk() for child in n.children}
        self.events = {e.ident: e for e in chart.events}
        self.behaviours = {b.name: b for b in chart.behaviours}
        self.values = GuardValues(chart)
        triggers = {
            ev
            for n in chart.walk()
            for t in n.transitions
            for ev in t.events
            if not ev.startswith(("outcome.", "done.", "after.", "error.")) and ev != "*"
        }
        self.event_names = sorted(triggers | set(self.events))
        self._explored: dict[frozenset[str], Scenario] | None = None

    # --- guides

    def fresh(self) -> Engine:
        return guide(self.chart) if self.semantic else skeleton(self.chart)

    def replayed(self, steps: Sequence[Step]) -> Engine:
        engine = self.fresh()
        for step in steps:
            follow(engine, step)
        return engine

    # --- steps

    def _event_keys(self, name: str, field: str) -> list[tuple[str, Path]]:
        return [(name, (field,))]

    def _output_keys(self, node: c.Node, output: str) -> list[tuple[str, Path]]:
        assert node.call is not None
        results = dict(node.call.results)
        keys: list[tuple[str, Path]] = [("", (results.get(output, output),))]
        for transition in node.transitions:
            for event in transition.events:
                if event.startswith(OUTCOME_PREFIXES):
                    keys.append((event, (output,)))
        return keys

    def _pick(
        self, keys: list[tuple[str, Path]], type_name: str | None, bias: float, template: Any
    ) -> Any:
        options = self.values.candidates(keys, type_name)
        if options and self.rng.random() < bias:
            return self.rng.choice(options)
        value = _value(type_name, self.rng, template)
        if isinstance(value, dict):  # a data type: its fields from the guards, if any
            for name in value:
                sub = self.values.candidates([(e, (*p, name)) for e, p in keys], "Real")
                if sub and self.rng.random() < bias:
                    value[name] = self.rng.choice(sub)
        return value

    def event_step(self, name: str, bias: float = 0.5) -> Step:
        info = self.events.get(name)
        fields = info.fields if info else ()
        defaults = dict(info.defaults) if info else {}
        data = {
            f: self._pick(self._event_keys(name, f), t, bias, defaults.get(f)) for f, t in fields
        }
        return {"event": name, "data": data}

    def event_variants(self, name: str) -> list[Step]:
        """An event with each field at each interesting value (others random), each field left
        out, and all fields left out: guards that read or divide by a missing field raise."""
        info = self.events.get(name)
        if info is None or not info.fields:
            return [{"event": name, "data": {}}]
        base = self.event_step(name, bias=0.0)
        variants = []
        for f, t in info.fields:
            for value in self.values.candidates(self._event_keys(name, f), t):
                variants.append({"event": name, "data": {**base["data"], f: value}})
        for f, _ in info.fields:
            variants.append(
                {"event": name, "data": {k: v for k, v in base["data"].items() if k != f}}
            )
        variants.append({"event": name, "data": {}})
        return _unique(variants)

    def complete_step(self, node: c.Node, outcome: str | None = None, bias: float = 0.5) -> Step:
        assert node.call is not None
        info = self.behaviours[node.call.behaviour]
        chosen = outcome or self.rng.choice(info.outcomes)
        initials = dict(info.output_initials)
        outputs = {
            name: self._pick(self._output_keys(node, name), t, bias, initials.get(name))
            for name, t in info.outputs
        }
        return {"complete": info.name, "state": node.id, "outcome": chosen, "outputs": outputs}

    def output_variants(self, node: c.Node, outcome: str, limit: int | None = None) -> list[Step]:
        """The outcome with each output at each interesting value (others random; `limit`
        spreads a few over the range), with no outputs (written as their zeros) and with one
        output left out."""
        assert node.call is not None
        info = self.behaviours[node.call.behaviour]
        base = self.complete_step(node, outcome, bias=0.0)
        variants = []
        for name, t in info.outputs:
            options = self.values.candidates(self._output_keys(node, name), t)
            for value in _spread(options, limit) if limit else options:
                variants.append({**base, "outputs": {**base["outputs"], name: value}})
        if not variants:
            variants.append(base)
        if info.outputs:
            variants.append({**base, "outputs": {}})
            if len(info.outputs) > 1:
                first = info.outputs[0][0]
                partial = {k: v for k, v in base["outputs"].items() if k != first}
                variants.append({**base, "outputs": partial})
        return _unique(variants)

    def enabled_steps(self, active: set[str]) -> list[Step]:
        steps: list[Step] = []
        for node_id in sorted(active):
            node = self.nodes.get(node_id)
            if node is None:
                continue
            if node.call is not None:
                steps.append(self.complete_step(node))
            for transition in node.transitions:
                steps += [self.event_step(e) for e in transition.events if e in self.event_names]
        return steps

    def _running(self, engine: Engine) -> list[c.Node]:
        active = set(engine.active())
        return [n for n in self.chart.walk() if n.call is not None and n.id in active]

    def branching_steps(self, engine: Engine) -> list[Step]:
        """A few inputs per reaction of the configuration (for the explorations)."""
        steps: list[Step] = []
        active = set(engine.active())
        for node in self._running(engine):
            info = self.behaviours[node.call.behaviour]  # type: ignore[union-attr]
            for outcome in info.outcomes:
                guarded = any(
                    t.cond is not None
                    and any(e.endswith(f".{node.id}.{outcome}") for e in t.events)
                    for t in node.transitions
                )
                steps += (
                    self.output_variants(node, outcome, 4)
                    if guarded
                    else [self.complete_step(node, outcome, bias=0.8)]
                )
        for node_id in sorted(active):
            node = self.nodes.get(node_id)
            for transition in node.transitions if node is not None else ():
                for event in transition.events:
                    if event not in self.event_names:
                        continue
                    if transition.cond is not None:
                        steps += _spread(self.event_variants(event), 5)
                    else:
                        steps.append(self.event_step(event, bias=0.8))
        return _unique(steps)

    # --- walks

    def walk(self, length: int) -> list[Step]:
        guide_engine = self.fresh()
        steps: list[Step] = []
        for _ in range(length):
            if not guide_engine.running:
                break
            enabled = self.enabled_steps(set(guide_engine.active()))
            roll = self.rng.random()
            if enabled and roll < 0.75:
                step = self.rng.choice(enabled)
            elif roll < 0.85 and len(enabled) >= 2:
                step = {"burst": self.rng.sample(enabled, 2)}
            elif self.event_names:
                step = self.event_step(self.rng.choice(self.event_names))
            else:
                continue
            steps.append(step)
            follow(guide_engine, step)
        return steps

    def _follow(self, guide_engine: Engine, step: Step) -> None:
        follow(guide_engine, step)

    def aborts(self, prefix_walks: list[list[Step]]) -> list[list[Step]]:
        """For every state a walk reaches: the walk up to there, then each station event."""
        station = [e.ident for e in self.chart.events if e.sender == "station"] or self.event_names
        found: dict[str, list[Step]] = {}
        for walk in prefix_walks:
            guide_engine = self.fresh()
            for index, step in enumerate(walk):
                follow(guide_engine, step)
                for state in guide_engine.active():
                    found.setdefault(state, walk[: index + 1])
        scenarios = []
        for state in sorted(found):
            for event in station:
                scenarios.append([*found[state], self.event_step(event)])
        return scenarios

    # --- exploration

    def explore(self, limit: int = 80, depth: int = 30) -> dict[frozenset[str], Scenario]:
        """Shortest known input sequence to each configuration (breadth first, from the start)."""
        if self._explored is not None:
            return self._explored
        found: dict[frozenset[str], Scenario] = {_config(self.fresh()): []}
        queue: deque[Scenario] = deque([[]])
        while queue and len(found) < limit:
            prefix = queue.popleft()
            engine = self.replayed(prefix)
            if not engine.running or len(prefix) >= depth:
                continue
            for step in self.branching_steps(engine):
                after = self.replayed(prefix)
                follow(after, step)
                key = _config(after)
                if key not in found:
                    found[key] = [*prefix, step]
                    queue.append(found[key])
                    if len(found) >= limit:
                        break
        self._explored = found
        return found

    def reach(self, state: str) -> Scenario | None:
        """The shortest known prefix after which `state` is active."""
        for config, prefix in self.explore().items():
            if state in config:
                return list(prefix)
        return None

    def search(
        self,
        prefix: Sequence[Step],
        goal: Callable[[Engine], bool],
        *,
        only: Callable[[Step], bool] | None = None,
        depth: int = 6,
        budget: int = 300,
    ) -> Scenario | None:
        """The shortest input sequence (after `prefix`) that reaches `goal`."""
        start = self.replayed(prefix)
        if goal(start):
            return []
        seen = {_config(start)}
        queue: deque[Scenario] = deque([[]])
        while queue and budget > 0:
            path = queue.popleft()
            if len(path) >= depth:
                continue
            engine = self.replayed([*prefix, *path])
            if not engine.running:
                continue
            for step in self.branching_steps(engine):
                if only is not None and not only(step):
                    continue
                budget -= 1
                after = self.replayed([*prefix, *path])
                follow(after, step)
                if goal(after):
                    return [*path, step]
                key = _config(after)
                if key not in seen:
                    seen.add(key)
                    queue.append([*path, step])
        return None

    def _tail(self, steps: Sequence[Step]) -> Scenario:
        """The steps and one more input the guide's configuration reacts to (an observation)."""
        engine = self.replayed(steps)
        enabled = self.enabled_steps(set(engine.active())) if engine.running else []
        return [*steps, self.rng.choice(enabled)] if enabled else list(steps)

    # --- the families

    def guarded_triggers(self) -> list[Scenario]:
        """Every guarded transition, triggered from the shortest prefix to its source with the
        values around its guard's constants, outputs or fields left out and zero divisors."""
        scenarios: list[Scenario] = []
        done: set[tuple[str, str]] = set()
        for node in self.chart.walk():
            for transition in node.transitions:
                if transition.cond is None:
                    continue
                for event in transition.events:
                    if (node.id, event) in done:
                        continue
                    done.add((node.id, event))
                    for source, variants in self._trigger_variants(node, event):
                        prefix = self.reach(source)
                        if prefix is not None:
                            scenarios += [self._tail([*prefix, v]) for v in variants]
        return _limit(scenarios, self.rng)

    def descriptor_names(self) -> list[Scenario]:
        """Every evented transition's descriptor `e` from its source: `e.more` (taken: a
        descriptor matches the names it is a token prefix of) and `ex` (not taken)."""
        scenarios: list[Scenario] = []
        done: set[tuple[str, str]] = set()
        for node in self.chart.walk():
            for transition in node.transitions:
                for event in transition.events:
                    if event not in self.event_names or (node.id, event) in done:
                        continue
                    done.add((node.id, event))
                    prefix = self.reach(node.id)
                    if prefix is None:
                        continue
                    data = self.event_step(event)["data"]
                    for name in (f"{event}.more", f"{event}x"):
                        scenarios.append(self._tail([*prefix, {"event": name, "data": data}]))
        return _limit(scenarios, self.rng, DESCRIPTOR_LIMIT)

    def _trigger_variants(self, node: c.Node, event: str) -> list[tuple[str, list[Step]]]:
        for prefix in OUTCOME_PREFIXES:
            if event.startswith(prefix):
                sid, _, outcome = event[len(prefix) :].rpartition(".")
                runner = self.nodes.get(sid)
                if runner is None or runner.call is None:
                    return []
                return [(sid, self.output_variants(runner, outcome))]
        if event in self.event_names:
            return [(node.id, self.event_variants(event))]
        return []

    def untaken_outcomes(self) -> list[Scenario]:
        """Outcomes no transition takes, with outputs (which must still be written): declared
        and unhandled, handled but every guard false, and one the behaviour does not declare."""
        scenarios: list[Scenario] = []
        for node in self.chart.walk():
            if node.call is None:
                continue
            prefix = self.reach(node.id)
            if prefix is None:
                continue
            info = self.behaviours[node.call.behaviour]
            engine = self.replayed(prefix)
            before = (_config(engine), engine.activation(node.id))
            for outcome in [*info.outcomes, UNDECLARED_OUTCOME]:
                taken = [t for t in node.transitions if _takes(t, node.id, outcome)]
                if taken and all(t.cond is None for t in taken):
                    continue  # always taken
                for variant in self.output_variants(node, outcome):
                    after = self.replayed([*prefix, variant])
                    if not taken or (_config(after), after.activation(node.id)) == before:
                        scenarios.append(self._tail([*prefix, variant]))
                        break
        return _limit(scenarios, self.rng)

    def history_reentry(self) -> list[Scenario]:
        """For each history: deep inside its parent, leave the parent, come back, then take a
        transition that targets the history (if one is reachable from there)."""
        scenarios: list[Scenario] = []
        explored = self.explore()
        for history in [n for n in self.chart.walk() if n.kind == "history"]:
            parent = self.parents.get(history.id)
            if parent is None:
                continue
            inside = self._descendants(parent)
            starts = sorted(
                (p for config, p in explored.items() if parent in config),
                key=lambda p: (-len(inside & _config(self.replayed(p))), len(p)),
            )[:2]
            sources = [
                n.id for n in self.chart.walk() for t in n.transitions if history.id in t.targets
            ]
            for start in starts:
                gone = self.search(start, lambda e, p=parent: not e.is_active(p))
                if gone is None:
                    continue
                back = self.search([*start, *gone], lambda e, p=parent: e.is_active(p))
                if back is None:
                    continue
                scenario = [*start, *gone, *back]
                scenarios.append(self._tail(scenario))
                for source in sources:
                    there = self.search(scenario, lambda e, s=source: e.is_active(s))
                    if there is None:
                        continue
                    node = self.nodes[source]
                    for transition in node.transitions:
                        if history.id in transition.targets:
                            for event in transition.events:
                                for _, variants in self._trigger_variants(node, event)[:1]:
                                    steps = [*scenario, *there, variants[0]]
                                    scenarios.append(self._tail(steps))
        return _limit(_unique_lists(scenarios), self.rng)

    def submachine_completion(self) -> list[Scenario]:
        """Each submachine state run to its final state by its behaviours' outcomes."""
        scenarios: list[Scenario] = []
        for node in self.chart.walk():
            if node.submachine is None:
                continue
            prefix = self.reach(node.id)
            if prefix is None:
                continue
            path = self.search(
                prefix,
                lambda e, s=node.id: not e.is_active(s),
                only=lambda step: "complete" in step and step.get("outcome") == "succeeded",
            ) or self.search(
                prefix, lambda e, s=node.id: not e.is_active(s), only=lambda s: "complete" in s
            )
            if path is not None:
                scenarios.append(self._tail([*prefix, *path]))
                if len(path) >= 2:  # the same outcomes back to back
                    scenarios.append(self._tail([*prefix, {"burst": path}]))
        return _limit(scenarios, self.rng)

    def mixed_bursts(self) -> list[Scenario]:
        """Outcomes queued back to back with swarm and station events (both orders), and the
        outcomes of two behaviours running in parallel regions, together."""
        scenarios: list[Scenario] = []
        for _config_key, prefix in sorted(self.explore().items(), key=lambda kv: len(kv[1])):
            engine = self.replayed(prefix)
            if not engine.running:
                continue
            running = self._running(engine)
            if not running:
                continue
            events = [s for s in self.branching_steps(engine) if "event" in s]
            noise = [self.event_step(self.rng.choice(self.event_names))] if self.event_names else []
            event = self.rng.choice(events or noise) if events or noise else None
            first = self._interesting_complete(running[0])
            if event is not None:
                scenarios.append(self._tail([*prefix, {"burst": [first, event]}]))
                scenarios.append(self._tail([*prefix, {"burst": [event, first]}]))
            if len(running) >= 2:
                second = self._interesting_complete(running[1])
                scenarios.append(self._tail([*prefix, {"burst": [first, second]}]))
                third = [event] if event is not None else []
                scenarios.append(self._tail([*prefix, {"burst": [second, first, *third]}]))
        return _limit(scenarios, self.rng)

    def near_livelocks(self) -> list[Scenario]:
        """From each configuration explored: every input after which the guide took bounded
        transitions (a potential microstep cycle ran, up to the step bound or not), alone,
        twice back to back, and followed by an event of the model (the count starts again)."""
        if not any(t.bounded for n in self.chart.walk() for t in n.transitions):
            return []
        scenarios: list[Scenario] = []
        for _config_key, prefix in sorted(self.explore().items(), key=lambda kv: len(kv[1])):
            engine = self.replayed(prefix)
            if not engine.running:
                continue
            for step in self.branching_steps(engine) or [
                self.event_step(e) for e in self.event_names
            ]:
                after = self.replayed(prefix)
                follow(after, step)
                if after.bounded_steps == 0:
                    continue
                scenarios.append([*prefix, step, step])
                scenarios.append([*prefix, {"burst": [step, step]}])
                noise = [self.event_step(e) for e in self.event_names[:1]]
                scenarios.append(self._tail([*prefix, step, *noise]))
        return _limit(scenarios, self.rng)

    def _interesting_complete(self, node: c.Node) -> Step:
        assert node.call is not None
        info = self.behaviours[node.call.behaviour]
        outcome = "succeeded" if "succeeded" in info.outcomes else info.outcomes[0]
        return self.complete_step(node, outcome, bias=1.0)

    def _descendants(self, node_id: str) -> set[str]:
        found, stack = set(), [self.nodes[node_id]]
        while stack:
            node = stack.pop()
            for child in node.children:
                found.add(child.id)
                stack.append(child)
        return found

    def edge_scenarios(self) -> list[Scenario]:
        """All the families of the module docstring, in a fixed order."""
        return [
            *self.guarded_triggers(),
            *self.untaken_outcomes(),
            *self.history_reentry(),
            *self.submachine_completion(),
            *self.mixed_bursts(),
            *self.descriptor_names(),
            *self.near_livelocks(),
        ]


def _takes(transition: c.Transition, state: str, outcome: str) -> bool:
    """Whether a model transition waits for this outcome of this state (the targetless
    `done.invoke.` transitions that write the outputs are the compiler's, not the model's)."""
    if transition.events and all(e.startswith("done.invoke.") for e in transition.events):
        return False
    return any(
        e in {f"outcome.{state}", f"outcome.{state}.{outcome}", "*", "outcome", "outcome.*"}
        for e in transition.events
    )


def _unique(steps: list[Step]) -> list[Step]:
    seen: set[str] = set()
    found = []
    for step in steps:
        key = repr(step)
        if key not in seen:
            seen.add(key)
            found.append(step)
    return found


def _unique_lists(scenarios: list[Scenario]) -> list[Scenario]:
    seen: set[str] = set()
    found = []
    for scenario in scenarios:
        key = repr(scenario)
        if key not in seen:
            seen.add(key)
            found.append(scenario)
    return found


def _limit(
    scenarios: list[Scenario], rng: random.Random, limit: int = FAMILY_LIMIT
) -> list[Scenario]:
    scenarios = _unique_lists(scenarios)
    if len(scenarios) <= limit:
        return scenarios
    keep = sorted(rng.sample(range(len(scenarios)), limit))
    return [scenarios[i] for i in keep]


def failure_scenarios(chart: c.Chart, walks: list[list[Step]]) -> list[list[Step]]:
    """Every `complete` step of the walks turned into the failure outcome `aborted`."""
    scenarios = []
    for walk in walks:
        failed = [{**s, "outcome": "aborted"} if "complete" in s else s for s in walk]
        if failed != walk:
            scenarios.append(failed)
    return scenarios
