"""Run by the system python3 with PySide2 (Debian python3-pyside2.qtscxml), not the venv.

Usage:
  python3 qt_script.py load FILE...      one JSON line per file: {"file", "errors", "active"}
  python3 qt_script.py run FILE STEPS    STEPS is a JSON list of [event, data] pairs; prints one
                                         JSON line per step: {"event", "active", "data"}
Standard library and PySide2 only: it must not import swarmgen.
"""

import json
import os
import sys


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


def _run(path: str, steps: list[list[object]]) -> None:
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide2.QtCore import QCoreApplication
    from PySide2.QtScxml import QScxmlStateMachine

    app = QCoreApplication.instance() or QCoreApplication([])
    machine = QScxmlStateMachine.fromFile(path)
    errors = [e.toString() for e in machine.parseErrors()]
    if errors:
        print(json.dumps({"errors": errors}), flush=True)
        return
    names = _data_names(path)
    machine.start()
    _settle(app)
    _report(machine, None, names)
    for event, data in steps:
        machine.submitEvent(str(event), data if data is not None else {})
        _settle(app)
        _report(machine, event, names)


def _data_names(path: str) -> list[str]:
    import xml.etree.ElementTree as ET

    tree = ET.parse(path)
    return sorted(e.get("id", "") for e in tree.iter("{http://www.w3.org/2005/07/scxml}data"))


def _report(machine: object, event: object, names: list[str]) -> None:
    model = machine.dataModel()  # type: ignore[attr-defined]
    data = {n: model.scxmlProperty(n) for n in names}
    active = sorted(machine.activeStateNames(False))  # type: ignore[attr-defined]
    print(json.dumps({"event": event, "active": active, "data": data}, default=str), flush=True)


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] == "load":
        _load(sys.argv[2:])
    elif len(sys.argv) == 4 and sys.argv[1] == "run":
        _run(sys.argv[2], json.loads(sys.argv[3]))
    else:
        sys.exit("usage: qt_script.py load FILE... | run FILE STEPS_JSON")
