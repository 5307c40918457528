"""Run by the system python3 with PySide2 (Debian python3-pyside2.qtscxml), not the venv.

Usage:
  python3 qt_script.py load FILE...      one JSON line per file: {"file", "errors", "active"}
  python3 qt_script.py run FILE STEPS    STEPS: a JSON list of steps (see swarmgen.runtime.replay);
                                         one JSON line per step: {"step", "input", "active", "data"}
  python3 qt_script.py runmany FILE PATH PATH: a JSON file holding a list of step lists; the lines
                                         carry "scenario" (its index)
Standard library and PySide2 only: it must not import swarmgen.
"""

import json
import os
import sys
from typing import Any


def _load(paths: list[str]) -> None:
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide2.QtCore import QCoreApplication
    from PySide2.QtScxml import QScxmlStateMachine

    app = QCoreApplication.instance() or QCoreApplication([])
    for path in paths:
        machine = QScxmlStateMachine.fromFile(path)
        errors = [e.toString() for e in machine.parseErrors()]
        active = []
        if not errors:
            machine.start()
            for _ in range(5):
                app.processEvents()
            active = sorted(machine.activeStateNames())
        print(json.dumps({"file": path, "errors": errors, "active": active}), flush=True)


def _settle(app: object, rounds: int = 10) -> None:
    for _ in range(rounds):
        app.processEvents()  # type: ignore[attr-defined]


def _wait(app: object, seconds: float) -> None:
    """Let `seconds` of real time pass, processing Qt's events (its timers, delayed sends)."""
    import time

    _settle(app)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        app.processEvents()  # type: ignore[attr-defined]
        time.sleep(min(0.002, max(0.0, end - time.monotonic())))


SCXML = "{http://www.w3.org/2005/07/scxml}"
SG = "{urn:swarmgen:scxml:1}"


class _Document:
    """What the harness reads from the document: data ids, the states that run behaviours
    (document order) and the declared fields of each event with their defaults."""

    def __init__(self, path: str) -> None:
        import xml.etree.ElementTree as ET

        root = ET.parse(path).getroot()
        self.data = sorted(e.get("id", "") for e in _own(root, f"{SCXML}data"))
        self.calls = _calls(root)
        self.fields: dict[str, dict[str, Any]] = {}
        for event in _own(root, f"{SG}event"):
            defaults = {
                f.get("name", ""): json.loads(f.get("default", "null"))
                for f in event.findall(f"{SG}field")
                if f.get("default") is not None
            }
            if defaults:
                self.fields[event.get("id", "")] = defaults


def _own(root: Any, tag: str | None = None) -> list[Any]:
    """The document's elements (of `tag`), without those of the documents it invokes."""
    found, stack = [], [root]
    while stack:
        element = stack.pop()
        if tag is None or element.tag == tag:
            found.append(element)
        stack.extend(k for k in reversed(list(element)) if k.tag != f"{SCXML}invoke")
    return found


def _calls(root: Any) -> list[tuple[str, str]]:
    calls = []
    for element in _own(root):
        if element.tag in (f"{SCXML}state", f"{SCXML}parallel"):
            for onentry in element.findall(f"{SCXML}onentry"):
                for call in onentry.findall(f"{SG}call"):
                    calls.append((element.get("id", ""), call.get("behaviour", "")))
    return calls


def _fill(value: Any, template: Any) -> Any:
    """The value rule (as the runtime's `fill`): a field the sender left out holds its default,
    a field its data type does not have is dropped."""
    if isinstance(template, dict):
        given = value if isinstance(value, dict) else {}
        return {key: _fill(given.get(key), default) for key, default in template.items()}
    return template if value is None else value


def _fill_fields(data: dict[str, Any], template: dict[str, Any]) -> dict[str, Any]:
    """An event's data (as the runtime's `fill_fields`): declared fields filled, others kept."""
    return {**data, **{key: _fill(data.get(key), default) for key, default in template.items()}}


class _Errors:
    """Counts Qt's error.execution (Qt logs each error it raises in qt.scxml.statemachine)."""

    count = 0

    @classmethod
    def install(cls) -> None:
        from PySide2.QtCore import qInstallMessageHandler

        def handler(mode: object, context: object, message: str) -> None:
            if " had error " in message:
                cls.count += 1
            elif "qt.scxml" not in message and "DynamicStateMachine" not in message:
                sys.stderr.write(message + "\n")

        qInstallMessageHandler(handler)


def _expand(step: dict[str, Any]) -> list[Any]:
    burst = step.get("burst")
    return list(burst) if isinstance(burst, list) else [step]


def _describe(step: dict[str, Any]) -> str:
    if "burst" in step:
        return " + ".join(_describe(s) for s in _expand(step))
    if "complete" in step:
        return f"{step['complete']} -> {step.get('outcome', 'succeeded')}"
    if "wait" in step:
        return f"wait {step['wait']} ms"
    return str(step.get("event", "?"))


def _submit(machine: object, step: dict[str, Any], document: _Document) -> None:
    """The same rules as swarmgen.runtime.replay: a `complete` step ends the behaviour of the
    first active state (document order) that runs it, or of the state named; the host says so
    with `done.invoke.<state>.<outcome>` (the document's finalize transition takes it)."""
    if "complete" in step:
        active = set(machine.activeStateNames(False))  # type: ignore[attr-defined]
        wanted = step.get("state")
        for state, behaviour in document.calls:
            if (
                behaviour == step["complete"]
                and state in active
                and (wanted is None or wanted == state)
            ):
                outcome = step.get("outcome", "succeeded")
                machine.submitEvent(f"done.invoke.{state}.{outcome}", step.get("outputs") or {})  # type: ignore[attr-defined]
                return
        return
    name = str(step["event"])
    data = step.get("data") or {}
    if name in document.fields:
        data = _fill_fields(data, document.fields[name])
    machine.submitEvent(name, data)  # type: ignore[attr-defined]


def _run(path: str, steps: list[dict[str, Any]], scenario: int | None = None) -> None:
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    # Qt reports each error.execution only in this category's debug log: read, not shown.
    os.environ["QT_LOGGING_RULES"] = "qt.scxml.statemachine.debug=true"
    _Errors.install()
    from PySide2.QtCore import QCoreApplication
    from PySide2.QtScxml import QScxmlStateMachine

    app = QCoreApplication.instance() or QCoreApplication([])
    machine = QScxmlStateMachine.fromFile(path)
    errors = [e.toString() for e in machine.parseErrors()]
    if errors:
        print(json.dumps({"errors": errors}), flush=True)
        return
    document = _Document(path)
    _Errors.count = 0
    machine.start()
    _settle(app)
    _report(machine, 0, None, document.data, scenario)
    for number, step in enumerate(steps, start=1):
        if isinstance(step, list):  # the older [event, data] form
            step = {"event": step[0], "data": step[1]}
        for item in _expand(step):
            if "wait" in item:
                _wait(app, float(item["wait"]) / 1000)
            else:
                _submit(machine, item, document)
        _settle(app)
        _report(machine, number, _describe(step), document.data, scenario)
    machine.stop()
    machine.deleteLater()
    _settle(app, 2)


def _report(
    machine: object, number: int, described: object, names: list[str], scenario: int | None
) -> None:
    model = machine.dataModel()  # type: ignore[attr-defined]
    data = {n: model.scxmlProperty(n) for n in names}
    active = sorted(machine.activeStateNames(False))  # type: ignore[attr-defined]
    record = {
        "step": number,
        "input": described,
        "active": active,
        "data": data,
        "errors": _Errors.count,
    }
    if scenario is not None:
        record["scenario"] = scenario
    print(json.dumps(record, default=str), flush=True)


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] == "load":
        _load(sys.argv[2:])
    elif len(sys.argv) == 4 and sys.argv[1] == "run":
        _run(sys.argv[2], json.loads(sys.argv[3]))
    elif len(sys.argv) == 4 and sys.argv[1] == "runmany":
        with open(sys.argv[3], encoding="utf-8") as scenarios:
            for number, steps in enumerate(json.load(scenarios)):
                _run(sys.argv[2], steps, number)
    else:
        sys.exit(
            "usage: qt_script.py load FILE... | run FILE STEPS_JSON | runmany FILE SCENARIOS_FILE"
        )
