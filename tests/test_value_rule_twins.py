"""The Qt harness (swarmgen/scxml/qt_script.py) runs under the system python3 and must not import
swarmgen, so it carries its own copy of the value rule (docs/semantics.md). This keeps the copy
honest: on random values and data types it gives exactly what the runtime's `fill` and
`fill_fields` give (dicts compared by value: the runtime's Records are dicts)."""

from __future__ import annotations

from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from swarmgen.runtime.chart import fill, fill_fields
from swarmgen.scxml import qt_script

KEYS = st.sampled_from(["x", "y", "z", "pose", "id", "header"])
SCALARS = st.none() | st.booleans() | st.integers(-5, 5) | st.floats(-2, 2) | st.text(max_size=3)
VALUES = st.recursive(
    SCALARS, lambda inner: st.dictionaries(KEYS, inner, max_size=3) | st.lists(inner, max_size=2),
    max_leaves=8,
)  # fmt: skip
# a data type's template: scalars' defaults (never None: a field has a zero) and nested types
TEMPLATES = st.recursive(
    st.booleans() | st.integers(-5, 5) | st.floats(-2, 2) | st.text(max_size=3),
    lambda inner: st.dictionaries(KEYS, inner, min_size=1, max_size=3),
    max_leaves=8,
)


def plain(value: Any) -> Any:
    """Records and dicts alike, as plain dicts (lists as lists)."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [plain(v) for v in value]
    return value


@settings(max_examples=300, deadline=None)
@given(value=VALUES, template=TEMPLATES)
def test_the_qt_harness_fills_a_value_as_the_runtime(value: Any, template: Any) -> None:
    assert plain(qt_script._fill(value, template)) == plain(fill(value, template))


@settings(max_examples=300, deadline=None)
@given(
    data=st.dictionaries(KEYS, VALUES, max_size=4),
    template=st.dictionaries(KEYS, TEMPLATES, max_size=4),
)
def test_the_qt_harness_fills_event_data_as_the_runtime(
    data: dict[str, Any], template: dict[str, Any]
) -> None:
    assert plain(qt_script._fill_fields(data, template)) == plain(fill_fields(data, template))
