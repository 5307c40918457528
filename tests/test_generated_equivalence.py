"""Generated charts, one semantics: hypothesis writes small random W3C SCXML documents (nested
compound states, parallel regions, shallow/deep history, finals with donedata, eventless
transitions, failing guards, `<raise>`, `<send>` to the external queue / with a delay / to
`#_internal` with `<param>`s, `<cancel>`, `<assign>`, `<if>`, `<foreach>`, `In()`, `done.state.*`
and `error.execution` transitions, internal transitions, prefix and `*` descriptors) and a
random scenario, and every replay backend (asyncio, smach and the emitted SCXML run in Qt
SCXML) must give the same trace.

CI runs a fixed, derandomized set of examples; hunt with more:
`SWARMGEN_FUZZ_EXAMPLES=500 SWARMGEN_FUZZ_SEED=7 pytest -q tests/test_generated_equivalence.py`.

Termination: every transition an event the document makes itself can take (internal names,
`*`, `error.*`, `done.*`, eventless) is guarded by a counter (`n < 6`, `n = n + 1` first), and
`n` only grows, so no document loops forever. Delayed sends appear only on transitions that
scenario events alone take, so no timer re-arms itself and a `wait` step is far from every due
time (delays of 40 and 80 ms, waits of 250 ms).
"""

from __future__ import annotations

import faulthandler
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

from swarmgen import pipeline, replay

BACKENDS = ("asyncio", "smach", "scxml")
EXAMPLES = int(os.environ.get("SWARMGEN_FUZZ_EXAMPLES", "40"))
SEED = int(os.environ.get("SWARMGEN_FUZZ_SEED", "0"))
NAME = "Gen"
EXTERNAL = ("a", "b", "c.d", "c.e")  # what scenario steps send
SCENARIO_DESCRIPTORS = ("a", "b", "c", "c.d", "a b", "c.*")  # only scenario events match them
OWN_DESCRIPTORS = ("i1", "i2", "i2.x", "q", "*", "error.execution", "error")  # also own events
DELAY_MS = 40
WAIT_MS = 250
GUARD = "n &lt; 6"  # the counter that bounds every self-triggered transition
CONDS = ("x &gt; 1", "x &lt; 3", "y == 0", "x % 2 == 0")
FAILING = "x / 0 &gt; 1"  # division by zero: error.execution, the transition not taken
EVENT_CONDS = ("_event.data.f == 1", "_event.data.f != 1")  # an event without f: error
# A cond that fails on a transition that the failure's own error.execution takes again (`*`,
# `error`, `error.execution`), or on an eventless one (W3C 3.13: eventless transitions are
# selected again after the error event), is a loop in every engine, W3C's algorithm included:
# failing conds only where the error cannot come back to them.
LOOPING = ("", "*", "error", "error.execution")


@dataclass
class Doc:
    """What the document drawn so far declares (for targets, `In()` and done events)."""

    states: list[str] = field(default_factory=list)
    # what In() may name: not a child of a <parallel> that has states of its own, which the
    # reader makes the region itself unless it has behaviour (docs/scxml-input.md, Mapping)
    testable: list[str] = field(default_factory=list)
    compounds: list[str] = field(default_factory=list)  # ids with a done.state event
    count: int = 0
    delays: bool = False

    def fresh(self, prefix: str) -> str:
        self.count += 1
        return f"{prefix}{self.count}"


def _action(draw: st.DrawFn, doc: Doc, delay_ok: bool, on_event: bool, depth: int = 0) -> str:
    """One action; `on_event`: in a transition with an event (entry and exit actions may not
    read `_event.data.f`: SG113, no triggering event is known to carry it)."""
    kinds = ["assign", "raise", "send", "send0", "internal", "cancel", "if", "foreach", "log"]
    if delay_ok:
        kinds += ["delayed", "delayed"]
    kind = draw(st.sampled_from(kinds))
    if kind == "assign":
        choices = [("x", "x + 1"), ("x", "x * 2"), ("y", "x"), ("y", "y + 10")]
        if on_event:  # an event without the field: error.execution
            choices.append(("y", "y + _event.data.f"))
        loc, value = draw(st.sampled_from(choices))
        return f'<assign location="{loc}" expr="{value}"/>'
    if kind == "raise":
        return f'<raise event="{draw(st.sampled_from(["i1", "i2.x"]))}"/>'
    if kind == "send":  # no target, no delay: the external queue
        return '<send event="q"/>'
    if kind == "send0":
        return '<send event="q" delay="0ms"/>'
    if kind == "internal":
        return '<send event="i2.x" target="#_internal"><param name="f" expr="x"/></send>'
    if kind == "cancel":
        return f'<cancel sendid="{draw(st.sampled_from(["t1", "t2"]))}"/>'
    if kind == "log":
        return '<log label="x" expr="x"/>'
    if kind == "delayed":
        doc.delays = True
        event, ident, ms = draw(
            st.sampled_from([("q", "t1", DELAY_MS), ("i1", "t2", 2 * DELAY_MS)])
        )
        return (
            f'<send event="{event}" delay="{ms}ms" id="{ident}"><param name="f" expr="y"/></send>'
        )
    if kind == "foreach":
        return '<foreach array="arr" item="it" index="ix"><assign location="y" expr="y + it"/></foreach>'
    if depth > 0:
        return '<assign location="x" expr="x + 1"/>'
    body = [_action(draw, doc, delay_ok, on_event, depth + 1) for _ in range(3)]
    cond1, cond2 = (draw(st.sampled_from((*CONDS, FAILING))) for _ in range(2))
    return f'<if cond="{cond1}">{body[0]}<elseif cond="{cond2}"/>{body[1]}<else/>{body[2]}</if>'


def _actions(
    draw: st.DrawFn, doc: Doc, delay_ok: bool, on_event: bool = False, most: int = 2
) -> str:
    count = draw(st.integers(0, most))
    return "".join(_action(draw, doc, delay_ok, on_event) for _ in range(count))


def _transition(draw: st.DrawFn, doc: Doc, targets: list[str]) -> str:
    kind = draw(st.sampled_from(["scenario", "scenario", "own", "done", "eventless"]))
    scenario = kind == "scenario"
    if scenario:
        event = draw(st.sampled_from(SCENARIO_DESCRIPTORS))
    elif kind == "own":
        event = draw(st.sampled_from(OWN_DESCRIPTORS))
    elif kind == "done" and doc.compounds:
        event = draw(st.sampled_from([f"done.state.{c}" for c in doc.compounds] + ["done.state.*"]))
    else:
        event = ""
    conds = list(CONDS) + [f"In('{s}')" for s in doc.testable]
    if event not in LOOPING:  # on an event without `f` (a raise): error.execution everywhere
        conds += [FAILING, *EVENT_CONDS]
    cond = draw(st.none() | st.sampled_from(conds))
    if not scenario:  # bounded: n only grows
        cond = GUARD if cond is None else f"{GUARD} &amp;&amp; {cond}"
    attrs = f' event="{event}"' if event else ""
    attrs += f' cond="{cond}"' if cond else ""
    target = draw(st.none() | st.sampled_from(targets))
    if target is not None:
        attrs += f' target="{target}"'
        if draw(st.booleans()):
            attrs += ' type="internal"'
    body = "" if scenario else '<assign location="n" expr="n + 1"/>'
    body += _actions(draw, doc, delay_ok=scenario, on_event=event not in LOOPING)  # SG113
    return f"<transition{attrs}>{body}</transition>"


@st.composite
def _tree(
    draw: st.DrawFn, doc: Doc, depth: int, final_ok: bool = True, region: bool = False
) -> tuple[Any, ...]:
    """(kind, id, children): the shape first, so transitions may target any state."""
    kinds = ["atomic"] + (["final"] if final_ok else [])
    if depth < 2:
        kinds += ["compound", "parallel"]
    kind = draw(st.sampled_from(kinds))
    ident = doc.fresh({"final": "f", "parallel": "p"}.get(kind, "s"))
    doc.states.append(ident)
    if not (region and kind in ("compound", "parallel")):
        doc.testable.append(ident)
    if kind == "compound":
        doc.compounds.append(ident)
        count = draw(st.integers(1, 3))
        children = [draw(_tree(doc, depth + 1)) for _ in range(count)]
        history = draw(st.sampled_from([None, "shallow", "deep"]))
        if history:
            children.append(("history", doc.fresh("h"), history))
            doc.states.append(children[-1][1])
        return (kind, ident, children)
    if kind == "parallel":
        doc.compounds.append(ident)
        return (
            kind,
            ident,
            [draw(_tree(doc, depth + 1, final_ok=False, region=True)) for _ in range(2)],
        )
    return (kind, ident, [])


def _render(draw: st.DrawFn, doc: Doc, node: tuple[Any, ...]) -> str:
    kind, ident, children = node
    if kind == "history":
        return f'<history id="{ident}" type="{children}"/>'  # its default: placed by _state
    if kind == "final":
        data = '<donedata><param name="f" expr="x"/></donedata>' if draw(st.booleans()) else ""
        entry = _actions(draw, doc, delay_ok=False, most=1)
        return (
            f'<final id="{ident}">'
            + (f"<onentry>{entry}</onentry>" if entry else "")
            + f"{data}</final>"
        )
    tag = "parallel" if kind == "parallel" else "state"
    states = [c[1] for c in children if c[0] not in ("history",)]
    start = ""
    if kind == "compound" and len(states) > 1 and draw(st.booleans()):
        start = f' initial="{draw(st.sampled_from(states[1:]))}"'
    parts = []
    for name in ("onentry", "onexit"):
        body = _actions(draw, doc, delay_ok=False)
        if body:
            parts.append(f"<{name}>{body}</{name}>")
    for _ in range(draw(st.integers(0, 2))):
        parts.append(_transition(draw, doc, doc.states))
    first = next((c[1] for c in children if c[0] != "history"), None)
    for child in children:
        if child[0] == "history":
            parts.append(
                f'<history id="{child[1]}" type="{child[2]}"><transition target="{first}"/></history>'
            )
        else:
            parts.append(_render(draw, doc, child))
    return f'<{tag} id="{ident}"{start}>' + "".join(parts) + f"</{tag}>"


@st.composite
def documents(draw: st.DrawFn) -> tuple[str, list[dict[str, Any]]]:
    """A document and a scenario for it."""
    doc = Doc()
    roots = [draw(_tree(doc, 0, final_ok=index > 0)) for index in range(draw(st.integers(1, 3)))]
    body = "".join(_render(draw, doc, node) for node in roots)
    text = (
        # the datamodel named: swarmgen reads a document without it as ECMAScript, Qt SCXML in
        # its null data model (docs/scxml-input.md, "Datamodels"), which `_as_written` compares
        '<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" datamodel="ecmascript" '
        f'initial="{roots[0][1]}" name="{NAME}"><datamodel>'
        '<data id="x" expr="0"/><data id="y" expr="0"/><data id="n" expr="0"/>'
        '<data id="arr" expr="[1, 2, 3]"/><data id="it" expr="0"/><data id="ix" expr="0"/>'
        f"</datamodel>{body}</scxml>"
    )
    step = st.builds(
        lambda e, f: {"event": e, "data": {"f": f}}, st.sampled_from(EXTERNAL), st.integers(0, 1)
    ) | st.builds(lambda e: {"event": e}, st.sampled_from(EXTERNAL))
    if doc.delays:
        step = step | st.just({"wait": WAIT_MS})
    return text, draw(st.lists(step, min_size=1, max_size=6))


def traces(path: Path, steps: list[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
    return {backend: replay.replay(path, NAME, steps, backend) for backend in BACKENDS}


@seed(SEED)
@settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize="SWARMGEN_FUZZ_SEED" not in os.environ,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(documents())
def test_generated_charts_run_alike_everywhere(
    tmp_path_factory: pytest.TempPathFactory, qt_available: None, case: tuple[str, list[Any]]
) -> None:
    text, steps = case
    path = tmp_path_factory.mktemp("gen") / f"{NAME}.scxml"
    path.write_text(text, encoding="utf-8")
    faulthandler.dump_traceback_later(120)  # a document that hangs a backend: where
    try:
        found = traces(path, steps)
    finally:
        faulthandler.cancel_dump_traceback_later()
    # SG216: Qt runs transitions taken together deepest first, not in W3C's order (measured,
    # docs/semantics.md); where it warns, the emitted SCXML in Qt is not the reference
    qt_order = any(d.code.id == "SG216" for d in pipeline.validate(path).diagnostics)
    reference = "asyncio" if qt_order else "scxml"
    for backend in ("asyncio", "smach"):
        assert found[backend] == found[reference], (
            f"{backend} differs from {reference}\n{text}\nsteps: {steps}\n"
            f"{backend}: {found[backend]}\n{reference}: {found[reference]}"
        )
    if ORIGINAL:
        _as_written(path, text, steps, found["scxml"])


ORIGINAL = os.environ.get("SWARMGEN_FUZZ_ORIGINAL") == "1"


def _as_written(path: Path, text: str, steps: list[dict[str, Any]], emitted: list[Any]) -> None:
    """Hunting only: Qt SCXML on the document as written against the one swarmgen emits (the
    reader's meaning). Skipped where plain ECMAScript differs on purpose (`x / 0` is Infinity,
    a missing field undefined: swarmgen raises error.execution, docs/semantics.md). Off by
    default (SWARMGEN_FUZZ_ORIGINAL=1): it runs every document twice in Qt. (Its first runs
    found Qt spinning on documents without a `datamodel` attribute: Qt reads those in its null
    data model, where `cond="n &lt; 6"` never stops an eventless self-transition; the documents
    now name `ecmascript`, as swarmgen reads them.)"""
    if FAILING in text or "_event.data" in text:
        return
    ids = set(re.findall(r' id="([^"]+)"', text))
    written = replay.run_qt(path, steps)

    def shape(trace: list[Any]) -> list[Any]:
        return [(sorted({a.split("__")[-1] for a in r["active"]} & ids), r["data"]) for r in trace]

    assert shape(written) == shape(emitted), f"as written vs emitted\n{text}\nsteps: {steps}"
