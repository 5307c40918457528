"""The IRP tests in Qt SCXML, converted with the IRP's own confEcma.xsl, for comparison.

confEcma.xsl writes its comparison conds (`conf:idVal="1=1"` -> `Var1==1`, ...) with XSLT 2.0's
`xsl:analyze-string`, which libxslt (an XSLT 1.0 processor in forwards-compatible mode) skips:
the cond comes out empty, which is *true*. `fill_xslt2` writes those attributes first, with
confEcma.xsl's own regular expressions and output, so the stylesheet sees plain attributes.
All documents (child documents `*sub1` and the data files beside them) go into one directory
and run in one system python3 process (`qt_irp.py`).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path

from lxml import etree

from swarmgen.conformance.irp import CONF, Outcome, stylesheet, tests

SYSTEM_PYTHON = "/usr/bin/python3"
SCRIPT = Path(__file__).resolve().parent / "qt_irp.py"
WAIT_SECONDS = 10.0  # wall time the whole set may run in Qt (all at once; passes end by 3 s)
_COMPARE = re.compile(r"([0-9]+)([=<>]=?)(.*)")
_PAIR = re.compile(r"([0-9]+)(\W+)([0-9]+)")


def _op(op: str, equals: str = "==") -> str:
    return equals if op == "=" else op


def _groups(
    pattern: re.Pattern[str], write: Callable[[re.Match[str]], str]
) -> Callable[[str], str]:
    """analyze-string's meaning: each match written, the text between matches dropped."""
    return lambda value: "".join(write(m) for m in pattern.finditer(value))


# attribute -> (attribute written, its value): confEcma.xsl's analyze-string templates
_XSLT2: dict[str, tuple[str, Callable[[str], str]]] = {
    "idVal": ("cond", _groups(_COMPARE, lambda m: f"Var{m[1]}{_op(m[2])}{m[3]}")),
    "varIdVal": ("cond", _groups(_COMPARE, lambda m: f"Var{m[1]}{_op(m[2])}Var{m[3]}")),
    "namelistIdVal": ("cond", _groups(_COMPARE, lambda m: f"Var{m[1]}{_op(m[2], '===')}{m[3]}")),
    "VarEqVar": ("cond", _groups(_PAIR, lambda m: f"Var{m[1]}===Var{m[3]}")),
    "VarEqVarStruct": ("cond", _groups(_PAIR, lambda m: f"Var{m[1]}==Var{m[3]}")),
    "idQuoteVal": ("cond", _groups(_COMPARE, lambda m: f"Var{m[1]}{_op(m[2])}'{m[3]}'")),
    "compareIDVal": (
        "cond",
        _groups(
            re.compile(r"([0-9]+)([=<>]=?)([0-9+])"),
            lambda m: f"Var{m[1]}{_op(m[2], '=')}Var{m[3]}",
        ),
    ),
    "eventvarVal": (
        "cond",
        _groups(_COMPARE, lambda m: f"_event.data['Var{m[1]}']{_op(m[2])}{m[3]}"),
    ),
    "idSystemVarVal": ("cond", _groups(_COMPARE, lambda m: f"Var{m[1]}{_op(m[2])}{m[3]}")),
    "varPrefix": (
        "cond",
        _groups(
            re.compile(r"(\w+)(\W)(\w+)"),
            lambda m: (
                f"(function(str, starts){{if (starts === '') return true;"
                f"if (str == null || starts == null) return false;"
                f"str = String(str); starts = String(starts);"
                f"return str.length >= starts.length && str.slice(0, starts.length) === starts;}})"
                f"(Var{m[3]}, Var{m[1]})"
            ),
        ),
    ),
    "multipleNamelist": ("namelist", _groups(re.compile(r"([0-9]+)"), lambda m: f"Var{m[1]}\n")),
}


def fill_xslt2(tree: etree._ElementTree) -> etree._ElementTree:
    """Write the attributes confEcma.xsl's XSLT 2.0 templates would have written (in place)."""
    for element in tree.iter():
        if not isinstance(element.tag, str):
            continue
        for local, (written, value) in _XSLT2.items():
            name = f"{{{CONF}}}{local}"
            if name in element.attrib:
                element.set(written, value(str(element.attrib.pop(name))))
    return tree


def convert_ecma(transform: etree.XSLT, txml: Path) -> bytes:
    """A template converted for Qt: the XSLT 2.0 fill, then confEcma.xsl."""
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
    return bytes(transform(fill_xslt2(etree.parse(str(txml), parser))))


def qt_available() -> bool:
    """Whether the system python3 has Qt SCXML (Debian python3-pyside2.qtscxml)."""
    try:
        probe = subprocess.run(
            [SYSTEM_PYTHON, "-c", "import PySide2.QtScxml"], capture_output=True, check=False
        )
    except FileNotFoundError:
        return False
    return probe.returncode == 0


def run_all(irp: Path, seconds: float = WAIT_SECONDS) -> dict[str, Outcome]:
    """Every automatic test's outcome in Qt SCXML, by test id (one process, all at once)."""
    transform = stylesheet(irp / "confEcma.xsl")
    with tempfile.TemporaryDirectory(prefix="swarmgen-irp-qt-") as tmp:
        work = Path(tmp)
        for txml in sorted((irp / "txml").glob("*.txml")):
            (work / f"{txml.stem}.scxml").write_bytes(convert_ecma(transform, txml))
        for data in (irp / "txml").glob("*.txt"):
            shutil.copy(data, work / data.name)
        listed = [[t.id, [str(work / f"{d.stem}.scxml") for d in t.documents]] for t in tests(irp)]
        (work / "tests.json").write_text(json.dumps(listed), encoding="utf-8")
        env = {k: v for k, v in os.environ.items() if not k.startswith("_ROS_WHEELS")}
        env.pop("LD_LIBRARY_PATH", None)
        env["QT_QPA_PLATFORM"] = "offscreen"
        completed = subprocess.run(
            [SYSTEM_PYTHON, str(SCRIPT), str(work / "tests.json"), str(seconds)],
            capture_output=True,
            text=True,
            cwd=work,
            env=env,
            timeout=seconds + 120,
            check=False,
        )
    if completed.returncode != 0:
        raise RuntimeError(f"Qt SCXML run failed: {completed.stderr.strip()[-500:]}")
    raw: dict[str, list[str]] = json.loads(completed.stdout)
    return {test_id: Outcome(result, detail) for test_id, (result, detail) in raw.items()}
