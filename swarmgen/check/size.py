"""Size: how large each chart would be once submachines are inlined, computed without inlining.

Inlining copies a machine once per submachine state that uses it, so a machine used twice per
level doubles at every level: 18 levels of a 25 KB model are 2^18 copies, which the lowering (and
the data-flow check, which lowers) would build forever. The size is summed per machine, memoised,
and a chart past MAX_INLINED_STATES is refused (SG130) before anything is lowered.
"""

from __future__ import annotations

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Machine, Model, State
from swarmgen.ir.query import ModelIndex, walk

# States and pseudostates of one chart, submachines inlined. The largest benchmark has 10,000;
# lowering and rendering take about a second per 10,000.
MAX_INLINED_STATES = 100_000
_SHOWN_STEPS = 6


class _Sizes:
    """Inlined vertex counts per machine id; a cycle (SG104) counts its back edge as nothing."""

    def __init__(self, index: ModelIndex) -> None:
        self.index = index
        self.sizes: dict[str, int] = {}
        self.active: set[str] = set()

    def of(self, machine: Machine) -> int:
        known = self.sizes.get(machine.id)
        if known is not None:
            return known
        if machine.id in self.active:
            return 0
        self.active.add(machine.id)
        total = len(walk(machine))
        for state in _submachine_states(machine):
            sub = self.index.machines.get(state.submachine or "")
            if sub is not None:
                total += self.of(sub)
        self.active.discard(machine.id)
        self.sizes[machine.id] = total
        return total

    def chain(self, machine: Machine) -> list[str]:
        """The submachine states that carry the most size, from `machine` down."""
        steps: list[str] = []
        seen = {machine.id}
        while len(steps) < _SHOWN_STEPS:
            heaviest = self._heaviest(machine, seen)
            if heaviest is None:
                break
            state, sub, users = heaviest
            values = {"machine": machine.name, "state": state.name, "sub": sub.name}
            if users > 1:
                step = dg.MODEL_TOO_LARGE.note(
                    "inlines", users=users, states=self.of(sub), **values
                )
            else:
                step = dg.MODEL_TOO_LARGE.note("inlines-once", states=self.of(sub), **values)
            steps.append(step)
            machine = sub
            seen.add(sub.id)
        return steps

    def _heaviest(self, machine: Machine, seen: set[str]) -> tuple[State, Machine, int] | None:
        best: tuple[State, Machine, int] | None = None
        users: dict[str, int] = {}
        for state in _submachine_states(machine):
            sub = self.index.machines.get(state.submachine or "")
            if sub is None or sub.id in seen:
                continue
            users[sub.id] = users.get(sub.id, 0) + 1
            if best is None or self.of(sub) > self.of(best[1]):
                best = (state, sub, 0)
        return (best[0], best[1], users[best[1].id]) if best else None


def _submachine_states(machine: Machine) -> list[State]:
    return [p.vertex for p in walk(machine) if isinstance(p.vertex, State) and p.vertex.submachine]


def check_size(model: Model) -> list[Diagnostic]:
    """Every chart the lowering would build (member machines, and machines nothing uses as a
    submachine) must stay within MAX_INLINED_STATES."""
    index = ModelIndex(model)
    sizes = _Sizes(index)
    used_as_sub = {s for m in model.machines for s in index.submachines(m)}
    roots = {m.machine for m in model.member_types if m.machine} | {
        m.id for m in model.machines if m.id not in used_as_sub
    }
    found: list[Diagnostic] = []
    for machine in model.machines:
        if machine.id not in roots:
            continue
        total = sizes.of(machine)
        if total <= MAX_INLINED_STATES:
            continue
        found.append(
            dg.MODEL_TOO_LARGE.at(
                machine.span,
                notes=sizes.chain(machine),
                machine=machine.name,
                total=total,
                limit=MAX_INLINED_STATES,
            )
        )
    return found
