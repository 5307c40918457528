"""Scenario generation for equivalence tests: seeded walks that mostly feed a member what its
active states react to (so the walks go deep), with noise, behaviour failures, bursts of inputs
queued back to back, and an abort in the middle of every state reached.

The Python engine only guides the choice of inputs; the oracle is the comparison between
backends (Qt SCXML is an independent engine).
"""

from __future__ import annotations

import random
from typing import Any

from swarmgen.chart import model as c
from swarmgen.runtime.chart import ChartBuilder
from swarmgen.runtime.engine import Engine, NullHost

Step = dict[str, Any]

_VALUES: dict[str | None, Any] = {"Integer": 3, "Real": 2.5, "Boolean": True, "String": "s"}


def _value(type_name: str | None, rng: random.Random) -> Any:
    if type_name in {"Integer", "Real"}:
        return rng.randint(0, 40) if type_name == "Integer" else round(rng.uniform(0, 40), 2)
    if type_name in _VALUES:
        return _VALUES[type_name]
    return {"x": rng.randint(0, 9), "y": rng.randint(0, 9)}  # a data type such as Pose


def skeleton(chart: c.Chart) -> Engine:
    """A guidance engine: the chart's structure with events but without guards or actions."""
    builder = ChartBuilder(chart.name)

    def add(node: c.Node, parent: str | None) -> None:
        builder.node(node.id, node.kind, parent, history=node.history or "")
        if node.initial is not None:
            builder.initial(node.id, node.initial.targets)
        for child in node.children:
            add(child, node.id)
        for transition in node.transitions:
            builder.transition(node.id, transition.events, transition.targets)

    for node in chart.children:
        add(node, None)
    builder.initial(None, chart.initial)
    engine = Engine(builder.build(), NullHost())
    engine.start()
    return engine


class ScenarioMaker:
    def __init__(self, chart: c.Chart, seed: int) -> None:
        self.chart = chart
        self.rng = random.Random(seed)
        self.nodes = {n.id: n for n in chart.walk()}
        self.events = {e.ident: e for e in chart.events}
        triggers = {
            ev
            for n in chart.walk()
            for t in n.transitions
            for ev in t.events
            if not ev.startswith(("outcome.", "done.", "after.", "error."))
        }
        self.event_names = sorted(triggers | set(self.events))

    def event_step(self, name: str) -> Step:
        info = self.events.get(name)
        data = {f: _value(t, self.rng) for f, t in info.fields} if info else {}
        return {"event": name, "data": data}

    def complete_step(self, node: c.Node, outcome: str | None = None) -> Step:
        assert node.call is not None
        info = next(b for b in self.chart.behaviours if b.name == node.call.behaviour)
        chosen = outcome or self.rng.choice(info.outcomes)
        outputs = {name: _value(t, self.rng) for name, t in info.outputs}
        return {"complete": info.name, "state": node.id, "outcome": chosen, "outputs": outputs}

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

    def walk(self, length: int) -> list[Step]:
        guide = skeleton(self.chart)
        steps: list[Step] = []
        for _ in range(length):
            if not guide.running:
                break
            enabled = self.enabled_steps(set(guide.active()))
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
            self._follow(guide, step)
        return steps

    def _follow(self, guide: Engine, step: Step) -> None:
        for item in step.get("burst", [step]):
            if "complete" in item:
                name = f"outcome.{item['state']}.{item['outcome']}"
                if item["state"] in guide.active():
                    guide.send(guide.make_event(name))
            else:
                guide.send(guide.make_event(item["event"]))

    def aborts(self, prefix_walks: list[list[Step]]) -> list[list[Step]]:
        """For every state a walk reaches: the walk up to there, then each station event."""
        station = [e.ident for e in self.chart.events if e.sender == "station"] or self.event_names
        found: dict[str, list[Step]] = {}
        for walk in prefix_walks:
            guide = skeleton(self.chart)
            for index, step in enumerate(walk):
                self._follow(guide, step)
                for state in guide.active():
                    found.setdefault(state, walk[: index + 1])
        scenarios = []
        for state in sorted(found):
            for event in station:
                scenarios.append([*found[state], self.event_step(event)])
        return scenarios


def failure_scenarios(chart: c.Chart, walks: list[list[Step]]) -> list[list[Step]]:
    """Every `complete` step of the walks turned into the failure outcome `aborted`."""
    scenarios = []
    for walk in walks:
        failed = [{**s, "outcome": "aborted"} if "complete" in s else s for s in walk]
        if failed != walk:
            scenarios.append(failed)
    return scenarios
