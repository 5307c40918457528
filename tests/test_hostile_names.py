"""Model text never becomes code: a model whose names, strings, guards and effects carry
payloads for Python, XML, CMake, shell and launch files compiles with every backend, and the
payload markers appear in no position where they would run: never as a Python name token,
never as an XML element, never in CMake, never as a file outside the output directory."""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

from lxml import etree

from swarmgen import pipeline
from tests.modelkit import ModelKit

PAYLOADS = [
    'x"; PWNED_A() #',
    "y''';PWNED_B()#",  # no spaces: `requires` lists names separated by spaces
    'z""" + PWNED_C() + """',
    "w\nPWNED_D()",
    "</state><PWNED_E/><state>",
    "]]></scxml><PWNED_F/>",
    "--><PWNED_G/><!--",
    ") PWNED_H(FATAL_ERROR x) #",
    "$(PWNED_I) `PWNED_J`",
    "../../PWNED_K",
    "\u202ePWNED_L",
    "{{ PWNED_M }}{% PWNED_N %}",
]
MARKERS = [f"PWNED_{c}" for c in "ABCDEFGHIJKLMN"]


def hostile_model() -> ModelKit:
    kit = ModelKit(PAYLOADS[0])
    kit.hardware(PAYLOADS[1], "Sensor", params={"fov": ("Real", 1.0)})
    kit.behaviour(
        PAYLOADS[2],
        inputs={"level": "Integer"},
        outputs={"seen": "Integer"},
        requires=[PAYLOADS[1]],
    )
    kit.event(PAYLOADS[3], {"note": "String"}, sender="station")
    kit.event("stop", sender="station")
    m = kit.machine(PAYLOADS[4])
    m.initial(PAYLOADS[5])
    m.state(PAYLOADS[5], entry=f"label = {PAYLOADS[6]!r}".replace("\n", "\\n"))
    m.state(PAYLOADS[7], do=PAYLOADS[2], bindings="level = 2")
    m.final(PAYLOADS[8])
    m.transition(PAYLOADS[5], PAYLOADS[7], PAYLOADS[3], guard=f"event.note != {PAYLOADS[9]!r}")
    m.transition(PAYLOADS[7], PAYLOADS[8], "stop", effect=f"label = {PAYLOADS[10]!r}")
    m.transition(PAYLOADS[7], PAYLOADS[8], "succeeded")
    m.transition(PAYLOADS[7], PAYLOADS[8], "aborted")
    kit.member(
        PAYLOADS[11],
        machine=m,
        parts={"eye": PAYLOADS[1]},
        data={"label": ("String", PAYLOADS[3]), "seen": ("Integer", 0)},
    )
    kit.swarm("Fleet", {PAYLOADS[11]: 2})
    return kit


def test_hostile_names_compile_and_inject_nothing(tmp_path: Path) -> None:
    model = tmp_path / "hostile.xmi"
    model.write_text(hostile_model().xmi(), encoding="utf-8")
    result = pipeline.compile_model(model)
    errors = [d for d in result.validation.diagnostics if d.level.value == "error"]
    assert not errors, pipeline.dg.render_text(errors)
    out = tmp_path / "out"
    pipeline.write_tree(result.files, out)
    written = [p for p in out.rglob("*") if p.is_file()]
    assert all(p.resolve().is_relative_to(out.resolve()) for p in written)
    # file names come from safe identifiers (derived names may contain the marker text, harmlessly)
    assert all(
        re.fullmatch(r"[A-Za-z0-9_.\-]+", part)
        for p in written
        for part in p.relative_to(out).parts
    )
    kinds = {".py": 0, ".xml": 0, ".scxml": 0, ".txt": 0}
    for path in written:
        text = path.read_text(encoding="utf-8", errors="replace")
        if path.suffix == ".py":
            _python_is_clean(path, text)
        elif path.suffix in {".xml", ".scxml"}:
            _xml_is_clean(path, text)
        elif path.name == "CMakeLists.txt" or path.suffix in {".msg", ".action"}:
            assert not any(m in text for m in MARKERS), f"model text in {path}"
        kinds[path.suffix] = kinds.get(path.suffix, 0) + 1
    assert kinds[".py"] >= 10 and kinds[".scxml"] == 1 and kinds[".xml"] >= 2  # package.xml files
    assert any(p.name.endswith(".launch.py") for p in written)
    assert any(p.name == "CMakeLists.txt" for p in written)


def _python_is_clean(path: Path, text: str) -> None:
    ast.parse(text, filename=str(path))  # valid Python
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        # an injected `PWNED_A()` would show up as exactly that name token; identifiers derived
        # from the names (`PWNED_M_PWNED_N`) are safe
        if token.type == tokenize.NAME:
            assert token.string not in MARKERS, (
                f"{path}:{token.start[0]}: injected name {token.string}"
            )


def _xml_is_clean(path: Path, text: str) -> None:
    root = etree.fromstring(text.encode("utf-8"))
    tags = {etree.QName(e).localname for e in root.iter(etree.Element)}
    assert not tags & set(MARKERS), f"{path}: injected element"
