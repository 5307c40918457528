"""The W3C SCXML IRP tests on swarmgen: conversion, compilation and a run on the runtime engine.

Each automatic test of the IRP manifest is converted with `confSwarmgen.xsl` (the IRP's
`conf:*` vocabulary into the ECMAScript subset swarmgen reads), compiled in process exactly as
`swarmgen validate` does (front end, build, checks, lowering) and, when that succeeds, its chart
is rendered by the asyncio backend and run on `swarmgen.runtime.engine` under a virtual clock:
timers fire in order of their due time, without waiting. The result is the final state reached
(`pass` or `fail`), or `timeout` when the machine neither finishes nor has anything left to do
within the bounds; a document the front end refuses is `not-run` with the feature it needs
(`features.feature`). Nothing in the compiler imports this package.
"""

from __future__ import annotations

import heapq
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from lxml import etree

from swarmgen import __version__, pipeline
from swarmgen import diagnostics as dg
from swarmgen.conformance.features import feature
from swarmgen.records import dataclass
from swarmgen.runtime.chart import Call, Chart, Node
from swarmgen.runtime.engine import Engine
from swarmgen.runtime.host import Event

CONF = "http://www.w3.org/2005/scxml-conformance"
HERE = Path(__file__).resolve().parent
STYLESHEET = HERE / "confSwarmgen.xsl"
MAX_EVENTS = 1000  # events delivered to one test's engine before it is a timeout
MAX_VIRTUAL_MS = 60_000  # virtual time a test may wait for its timers


@dataclass(frozen=True)
class Test:
    """One automatic IRP test: its manifest id, conformance and start documents."""

    id: str
    mandatory: bool
    documents: tuple[Path, ...]


@dataclass(frozen=True)
class Outcome:
    """One test's result on one engine, with what explains it (feature or end state)."""

    result: str  # pass | fail | timeout | not-run | load-error
    detail: str = ""  # not-run: the first refusal's feature; otherwise the end state
    features: tuple[str, ...] = ()  # not-run: every refused feature, sorted


def tests(irp: Path) -> list[Test]:
    """The manifest's automatic tests in manifest order (test 403 has three start documents)."""
    manifest = etree.parse(str(irp / "manifest.xml"), _parser())
    found: dict[str, Test] = {}
    for test in manifest.iter("test"):
        if test.get("manual") != "false":
            continue
        test_id = test.get("id", "")
        starts = tuple(
            irp / "txml" / Path(start.get("uri", "")).name for start in test.iter("start")
        )
        found.setdefault(test_id, Test(test_id, test.get("conformance") == "mandatory", starts))
    return list(found.values())


def _parser() -> etree.XMLParser:
    return etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)


def stylesheet(path: Path = STYLESHEET) -> etree.XSLT:
    """A conversion stylesheet, without file or network access."""
    deny = etree.XSLTAccessControl.DENY_ALL  # type: ignore[attr-defined]  # missing in the stubs
    return etree.XSLT(etree.parse(str(path), _parser()), access_control=deny)


def convert(transform: etree.XSLT, txml: Path) -> bytes:
    """The SCXML document a test template converts to."""
    return bytes(transform(etree.parse(str(txml), _parser())))


def leftover(document: bytes) -> str | None:
    """The first conformance-vocabulary name the stylesheet did not translate, if any."""
    root = etree.fromstring(document, _parser())
    for node in root.iter():
        if isinstance(node.tag, str) and node.tag.startswith(f"{{{CONF}}}"):
            return f"conf:{etree.QName(node).localname}"
        for name in map(str, node.attrib):
            if name.startswith(f"{{{CONF}}}"):
                return f"conf:{etree.QName(name).localname}"
    return None


def run_test(transform: etree.XSLT, test: Test, work: Path) -> Outcome:
    """A test's result: every start document must pass (403a/b/c); the first other wins."""
    for txml in test.documents:
        for data in txml.parent.glob(f"{txml.stem}*.txt"):  # `<data src>`'s, beside it
            if not (work / data.name).exists():
                shutil.copy(data, work / data.name)
        for sub in sorted(txml.parent.glob(f"{txml.stem}sub*.txml")):  # `<invoke src>`'s
            (work / f"{sub.stem}.scxml").write_bytes(convert(transform, sub))
        outcome = run_document(convert(transform, txml), work / f"{txml.stem}.scxml")
        if outcome.result != "pass":
            return outcome
    return Outcome("pass")


def run_document(document: bytes, path: Path) -> Outcome:
    """Compile one converted document and run it; `not-run` with its feature when refused."""
    untranslated = leftover(document)
    if untranslated is not None:
        return Outcome("not-run", f"untranslated {untranslated}", (f"untranslated {untranslated}",))
    path.write_bytes(document)
    try:
        validation = pipeline.validate(path)
    except Exception as err:  # a compiler bug (a traceback where a diagnostic belongs): shown
        crash = f"internal error: {type(err).__name__}"
        return Outcome("not-run", crash, (crash,))
    errors = sorted(
        (d for d in validation.diagnostics if d.level is dg.Severity.ERROR),
        key=lambda d: d.sort_key(),
    )
    if errors:
        root = etree.fromstring(document, _parser())
        named = [feature(d, root) for d in errors]
        return Outcome("not-run", named[0], tuple(sorted(set(named))))
    if not validation.charts:
        return Outcome("not-run", "no state machine")
    return run_chart(build(validation.charts[0]))


def build(chart: Any) -> Chart:
    """The runtime chart of a lowered chart: the asyncio backend's module, executed."""
    from swarmgen.backends.pycommon import member_view
    from swarmgen.backends.pyrender import chart_code
    from swarmgen.render import render

    common = {"version": __version__, "source": "irp", "runtime": "swarmgen.runtime"}
    code = render("asyncio/member.py.j2", **member_view(chart, common, chart_code(chart)))
    namespace: dict[str, Any] = {"__name__": f"swarmgen_irp_{chart.name}"}
    exec(compile(code, f"<irp {chart.name}>", "exec"), namespace)
    built: Chart = namespace["build"]()
    return built


class VirtualHost:
    """The engine's host on a virtual clock: events to itself queue in order, timers fire by
    due time (then start order); behaviours and the swarm bus do not exist in the IRP."""

    def __init__(self) -> None:
        self.now: float = 0
        self.queue: list[Event] = []
        self.timers: list[tuple[float, int, str, str]] = []  # (due, order, state id, event)
        self._order = 0
        # delayed raises by their order in `timers` (where their state id is ""): (key, event)
        self.delayed: dict[int, tuple[str, Event]] = {}

    def start_call(self, node: Node, call: Call, args: dict[str, Any], activation: int) -> None:
        """No IRP test calls a swarmgen behaviour (its `<invoke>`s are SCXML sessions, which
        the engine runs itself)."""

    def cancel_call(self, node: Node, activation: int) -> None:
        """Nothing runs, so nothing is cancelled."""

    def start_timer(self, node: Node, event: str, delay_ms: int) -> None:
        """Schedule the timer's event `delay_ms` of virtual time from now."""
        self._order += 1
        heapq.heappush(self.timers, (self.now + delay_ms, self._order, node.id, event))

    def cancel_timer(self, node: Node, event: str) -> None:
        """Drop the state's pending timer for `event`."""
        self.timers = [t for t in self.timers if (t[2], t[3]) != (node.id, event)]
        heapq.heapify(self.timers)

    def start_delayed(self, key: str, event: Event, delay_ms: float) -> None:
        """Schedule the delayed event `delay_ms` of virtual time from now."""
        self._order += 1
        self.delayed[self._order] = (key, event)
        heapq.heappush(self.timers, (self.now + delay_ms, self._order, "", event.name))

    def cancel_delayed(self, key: str) -> None:
        """Drop the pending delayed events of `key`."""
        for order in [o for o, (k, _) in self.delayed.items() if k == key]:
            del self.delayed[order]

    def send_swarm(self, event: Event) -> None:
        """The IRP has no swarm: a send to it goes nowhere."""

    def deliver(self, event: Event) -> None:
        """Queue an event to this member (behind those already waiting)."""
        self.queue.append(event)

    def next_events(self, engine: Engine) -> Iterator[Event]:
        """The events to deliver in order: queued ones first, then the earliest timer."""
        while True:
            if self.queue:
                yield self.queue.pop(0)
            elif self.timers and self.timers[0][0] <= MAX_VIRTUAL_MS:
                due, order, state, name = heapq.heappop(self.timers)
                if state or order in self.delayed:  # a delayed raise cancelled: nothing
                    self.now = due
                    delayed = self.delayed.pop(order, None)
                    yield delayed[1] if delayed else engine.make_event(name, None, "timer")
            else:
                return


def run_chart(chart: Chart) -> Outcome:
    """Start the chart and deliver its own events until it finishes or the bounds are hit."""
    host = VirtualHost()
    engine = Engine(chart, host, "irp", clock=lambda: host.now / 1000)
    engine.start()
    for count, event in enumerate(host.next_events(engine)):
        if engine.finished or count >= MAX_EVENTS:
            break
        engine.send(event)
    return _verdict(engine)


def _verdict(engine: Engine) -> Outcome:
    # by model name: the id of `pass` is `pass_` (a Python keyword is no identifier)
    active = sorted(node.name for node in engine.config)
    if engine.finished:
        if "pass" in active:
            return Outcome("pass")
        return Outcome("fail", "in fail" if "fail" in active else f"ended in {active}")
    return Outcome("timeout", f"waiting in {active}")


def run_all(irp: Path, transform: etree.XSLT | None = None) -> dict[str, Outcome]:
    """Every automatic test's outcome on swarmgen's engine, by test id."""
    transform = transform or stylesheet()
    with tempfile.TemporaryDirectory(prefix="swarmgen-irp-") as tmp:
        return {t.id: run_test(transform, t, Path(tmp)) for t in tests(irp)}
