"""Run converted IRP tests in Qt SCXML: system python3 with PySide2 (Debian), not the venv.

Usage: python3 qt_irp.py TESTS.json SECONDS
TESTS.json is a list of [test id, [document path, ...]]. Every document is loaded and started
at once in one event loop (each machine keeps its own timers, so they do not disturb each
other), and the loop runs until every machine has finished or SECONDS have passed. Prints one
JSON object: test id -> [result, detail], result one of pass, fail, timeout, load-error (a
test with several documents passes when all of them pass). Standard library and PySide2 only:
it must not import swarmgen.
"""

import json
import os
import sys
from typing import Any


def _quiet() -> None:
    """Qt logs every executable-content error and the IRP's <log> outcomes: not ours to show."""
    from PySide2.QtCore import qInstallMessageHandler

    def handler(mode: object, context: object, message: str) -> None:
        pass

    qInstallMessageHandler(handler)


def _verdict(machine: Any) -> list[str]:
    if machine.isActive("pass"):
        return ["pass", ""]
    if machine.isActive("fail"):
        return ["fail", "in fail"]
    active = sorted(machine.activeStateNames(False))
    if not machine.isRunning():
        return ["fail", f"ended in {active}"]
    return ["timeout", f"waiting in {active}"]


def main(tests_file: str, seconds: float) -> None:
    """Load, start and wait for every test; print the verdicts."""
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide2.QtCore import QCoreApplication, QTimer
    from PySide2.QtScxml import QScxmlStateMachine

    app = QCoreApplication.instance() or QCoreApplication([])
    _quiet()
    with open(tests_file, encoding="utf-8") as handle:
        tests = json.load(handle)
    machines: dict[str, list[Any]] = {}
    results: dict[str, list[str]] = {}
    pending = [0]
    for test_id, paths in tests:
        for path in paths:
            machine = QScxmlStateMachine.fromFile(path)
            errors = [e.toString() for e in machine.parseErrors()]
            if errors:
                results[test_id] = ["load-error", errors[0][:200]]
                break
            machines.setdefault(test_id, []).append(machine)
    for test_id, group in machines.items():
        if test_id in results:
            continue
        for machine in group:
            pending[0] += 1

            def done(count: list[int] = pending) -> None:
                count[0] -= 1
                if count[0] == 0:
                    app.quit()

            machine.finished.connect(done)
            machine.start()
    if pending[0]:
        QTimer.singleShot(int(seconds * 1000), app.quit)
        app.exec_()
    for test_id, group in machines.items():
        if test_id not in results:
            verdicts = [_verdict(m) for m in group]
            results[test_id] = next((v for v in verdicts if v[0] != "pass"), ["pass", ""])
        for machine in group:
            machine.stop()
    print(json.dumps(results, sort_keys=True))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: qt_irp.py TESTS.json SECONDS")
    main(sys.argv[1], float(sys.argv[2]))
