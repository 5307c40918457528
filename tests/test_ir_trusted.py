"""`ir.build` makes its nodes without pydantic's validation (`swarmgen.ir.trusted`): built both
ways, every model under tests/ and sample_models/, the SCXML documents of tests/golden (read as
SCXML input), the reference corpus's XMI samples and a synthetic model give the same IR: the same
`model_dump_json`, `repr` (enumeration members, tuples), equality, fields set and diagnostics."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pydantic
import pytest

from benchmarks.synth_model import generate
from swarmgen.frontend import load
from swarmgen.ir import trusted
from swarmgen.ir.build import build
from swarmgen.ir.nodes import Node, Part
from swarmgen.span import Span
from tests.conftest import HAS_SHARED, ROOT, XMI_SAMPLES

FIXTURES = sorted(
    [*ROOT.glob("tests/**/*.xmi"), *ROOT.glob("sample_models/**/*.xmi")]
    + sorted(ROOT.glob("tests/golden/**/*.scxml"))
    + (sorted(XMI_SAMPLES.rglob("*.xmi")) if HAS_SHARED else [])
)


def _nodes(value: object) -> list[pydantic.BaseModel]:
    """Every pydantic node under `value`, depth first."""
    found: list[pydantic.BaseModel] = []
    stack = [value]
    while stack:
        item = stack.pop()
        if isinstance(item, pydantic.BaseModel):
            found.append(item)
            stack.extend(item.__dict__.values())
        elif isinstance(item, tuple):
            stack.extend(item)
    return found


def _same_both_ways(path: Path) -> bool:
    """Build `path`'s raw model trusted and validated; False when it does not load."""
    raw, _ = load(path)
    if raw is None:
        return False
    fast, fast_found = build(raw)
    with trusted.validated():
        checked, checked_found = build(raw)
    assert fast.model_dump_json() == checked.model_dump_json()
    assert repr(fast) == repr(checked)
    assert fast == checked
    assert [n.model_fields_set for n in _nodes(fast)] == [
        n.model_fields_set for n in _nodes(checked)
    ]
    assert repr(fast_found) == repr(checked_found)
    return True


def test_every_fixture_builds_the_same_ir_both_ways() -> None:
    built = [path for path in FIXTURES if _same_both_ways(path)]
    assert len(built) >= 100, f"only {len(built)} of {len(FIXTURES)} fixtures loaded"


def test_a_synthetic_model_builds_the_same_ir_both_ways(tmp_path: Path) -> None:
    path = tmp_path / "synth.xmi"
    path.write_text(generate(300), encoding="utf-8")
    assert _same_both_ways(path)


def test_only_the_builder_skips_validation() -> None:
    span = Span(file="m.xmi")
    with pytest.raises(pydantic.ValidationError):
        Part(name="p", type_id="t", type_name="T", count="many", span=span)  # type: ignore[arg-type]
    with trusted.by_builder():
        assert trusted.active()
        loose = Part(name="p", type_id="t", type_name="T", count=2, span=span)
        with pytest.raises(TypeError, match="missing field 'span'"):
            Part(name="p", type_id="t", type_name="T", count=2)  # type: ignore[call-arg]
        with pytest.raises(TypeError, match="unknown fields"):
            Part(name="p", type_id="t", type_name="T", count=2, span=span, extra=1)  # type: ignore[call-arg]
        with trusted.validated():
            assert not trusted.active()
    assert not trusted.active()
    assert loose == Part(name="p", type_id="t", type_name="T", count=2, span=span)
    assert Part.model_validate(loose.model_dump()) == loose


def test_validate_builds_no_ir_validator() -> None:
    """A fresh `pipeline.validate` of SAR leaves every IR class's validator unbuilt."""
    probe = (
        "import pydantic\n"
        "from pathlib import Path\n"
        "from swarmgen import pipeline\n"
        "from swarmgen.ir import nodes\n"
        "pipeline.validate(Path('sample_models/sar/sar.xmi'))\n"
        "print(sorted(n for n, c in vars(nodes).items() if isinstance(c, type)\n"
        "      and issubclass(c, nodes.Node) and c.__pydantic_complete__))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT, timeout=60
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
    assert issubclass(Part, Node)
