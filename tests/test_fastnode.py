"""IR and expression nodes are made without pydantic when validation would keep the values as
given (`swarmgen.fastnode`), and through pydantic's validation otherwise. Built both ways, every
model under tests/ and sample_models/, the SCXML documents of tests/golden (read as SCXML
input), the reference corpus's XMI samples and a synthetic model give the same IR (dump, `repr`,
equality, fields set), charts and diagnostics; values of another form are converted or refused
exactly as validation does."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pydantic
import pytest

from benchmarks.synth_model import generate
from swarmgen import expr, fastnode, pipeline
from swarmgen.ir.nodes import HardwareKind, Part, Trigger, TriggerKind
from swarmgen.span import Span
from tests.conftest import HAS_SHARED, ROOT, XMI_SAMPLES

FIXTURES = sorted(
    [*ROOT.glob("tests/**/*.xmi"), *ROOT.glob("sample_models/**/*.xmi")]
    + sorted(ROOT.glob("tests/golden/**/*.scxml"))
    + (sorted(XMI_SAMPLES.rglob("*.xmi")) if HAS_SHARED else [])
)
SPAN = Span(file="m.xmi")


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
    """Validate `path` with and without the fast path; False when it has no IR."""
    fast = pipeline.validate(path)
    with fastnode.validating():
        checked = pipeline.validate(path)
    assert repr(fast.diagnostics) == repr(checked.diagnostics)
    assert repr(fast.charts) == repr(checked.charts)
    if fast.model is None or checked.model is None:
        assert fast.model is checked.model
        return False
    assert fast.model.model_dump_json() == checked.model.model_dump_json()
    assert repr(fast.model) == repr(checked.model)
    assert fast.model == checked.model
    fast_nodes, checked_nodes = _nodes(fast.model), _nodes(checked.model)
    assert [type(n) for n in fast_nodes] == [type(n) for n in checked_nodes]
    assert [n.model_fields_set for n in fast_nodes] == [n.model_fields_set for n in checked_nodes]
    return True


def test_every_fixture_validates_the_same_both_ways() -> None:
    built = [path for path in FIXTURES if _same_both_ways(path)]
    assert len(built) >= 100, f"only {len(built)} of {len(FIXTURES)} fixtures have an IR"


def test_a_synthetic_model_validates_the_same_both_ways(tmp_path: Path) -> None:
    path = tmp_path / "synth.xmi"
    path.write_text(generate(300), encoding="utf-8")
    assert _same_both_ways(path)


@pytest.mark.parametrize(
    "make",
    [
        lambda: Part(name="p", type_id="t", type_name="T", count="2", span=SPAN),  # str for int
        lambda: Trigger(kind="event", name="go", span=SPAN),  # str for the enumeration
        lambda: expr.Raise(event="go", args=[]),  # a list for a tuple
        lambda: expr.Const(value=True, enum=None),  # a bool in the value union: kept as is
    ],
)
def test_values_of_another_form_are_validated(make: object) -> None:
    assert callable(make)
    fast = make()
    with fastnode.validating():
        checked = make()
    assert repr(fast) == repr(checked) and fast.model_fields_set == checked.model_fields_set


@pytest.mark.parametrize(
    "make",
    [
        lambda: Part(name="p", type_id="t", type_name="T", count="many", span=SPAN),
        lambda: Part(name="p", type_id="t", type_name="T", count=2),  # no span
        lambda: Part(name="p", type_id="t", type_name="T", count=2, span=SPAN, other=1),
        lambda: expr.Name(name="__class__"),  # the identifier validator
        lambda: expr.Name(name="else"),  # a keyword
        lambda: expr.Const(value=float("inf")),  # the field validator
        lambda: expr.Const(value="x", enum="not an identifier"),  # a validator inside a union
        lambda: expr.Unary(op="-", operand=expr.Else()),  # `else` as an operand
        lambda: expr.Attr(obj=expr.Const(value=1), name="x"),  # attribute of a literal
        lambda: expr.Raise(event="go", args=(expr.Arg(name="a", value=expr.Const(value=1)),) * 2),
        lambda: expr.Binary(op="**", left=expr.Name(name="a"), right=expr.Name(name="b")),
    ],
)
def test_invalid_values_are_refused_as_validation_refuses_them(make: object) -> None:
    assert callable(make)
    with pytest.raises(pydantic.ValidationError) as fast:
        make()
    with fastnode.validating(), pytest.raises(pydantic.ValidationError) as checked:
        make()
    assert str(fast.value) == str(checked.value)
    assert fast.value.errors(include_context=False) == checked.value.errors(include_context=False)


def test_kinds_stay_enumeration_members() -> None:
    part_kind = Trigger(kind=TriggerKind.EVENT, name="go", span=SPAN).kind
    assert type(part_kind) is TriggerKind
    assert HardwareKind("Sensor") is HardwareKind.SENSOR


def test_validate_builds_no_pydantic_validator() -> None:
    """A fresh `validate` of SAR builds no node class's validator and looks for no pydantic
    plugin (no `importlib.metadata`)."""
    probe = (
        "import sys\n"
        "from pathlib import Path\n"
        "from swarmgen import pipeline\n"
        "from swarmgen.expr import tree\n"
        "from swarmgen.ir import nodes\n"
        "pipeline.validate(Path('sample_models/sar/sar.xmi'))\n"
        "built = [n for m in (nodes, tree) for n, c in vars(m).items() if isinstance(c, type)\n"
        "         and issubclass(c, (nodes.Node, tree._Model)) and c.__pydantic_complete__]\n"
        "print(sorted(built), 'importlib.metadata' in sys.modules)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT, timeout=60
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[] False"
