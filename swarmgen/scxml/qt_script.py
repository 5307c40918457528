"""Run by the system python3 with PySide2 (Debian python3-pyside2.qtscxml), not the venv.

Usage: python3 qt_script.py load FILE...   -> one JSON line per file: {"file", "errors", "active"}
Standard library and PySide2 only: it must not import swarmgen.
"""

import json
import os
import sys


def _load(paths: list[str]) -> None:
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide2.QtCore import QCoreApplication  # type: ignore[import-not-found]
    from PySide2.QtScxml import QScxmlStateMachine  # type: ignore[import-not-found]

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


if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] != "load":
        sys.exit("usage: qt_script.py load FILE...")
    _load(sys.argv[2:])
