"""The vendored runtimes' import rewriting (swarmgen/backends/vendor.py)."""

from __future__ import annotations

import re

import pytest

from swarmgen.backends import vendor

# The patterns as they were written first: an anchor, then the text.
WORD_ANCHORED = re.compile(r"\bfrom swarmgen\.runtime\.(\w+) import")
LINE_ANCHORED = re.compile(r"^from \.\.\.runtime\.(\w+) import", re.MULTILINE)
RUNTIME = r"from .\1 import"
ROS = r"from .._runtime.\1 import"

TRICKY = [
    "from swarmgen.runtime.chart import Chart\n",
    "xfrom swarmgen.runtime.chart import Chart\n",
    "_from swarmgen.runtime.a import b; from swarmgen.runtime.c import d\n",
    "éfrom swarmgen.runtime.a import b\n(from swarmgen.runtime.a import b)\n",
    "    from swarmgen.runtime.values import x\nfrom swarmgen.runtime.values import\n",
    "from ...runtime.spec import X\n  from ...runtime.spec import Y\nxfrom ...runtime.a import b",
    "\r\nfrom ...runtime.a import b\n\nfrom ...runtime.b import c",
    "from swarmgen.runtime.from swarmgen.runtime.a import b",
    "",
]


def _sources() -> list[str]:
    folders = (vendor.RUNTIME_DIR, vendor.ROS_RUNTIME_DIR)
    return [p.read_text(encoding="utf-8") for folder in folders for p in folder.glob("*.py")]


@pytest.mark.parametrize("text", TRICKY)
def test_rewrite_is_the_anchored_substitution(text: str) -> None:
    word = vendor.rewrite(text, vendor._IMPORT, RUNTIME, vendor._word_start)
    assert word == WORD_ANCHORED.sub(RUNTIME, text)
    line = vendor.rewrite(text, vendor._ROS_IMPORT, ROS, vendor._line_start)
    assert line == LINE_ANCHORED.sub(ROS, text)


def test_every_runtime_source_is_rewritten_as_before() -> None:
    sources = _sources()
    assert len(sources) > 30
    changed = 0
    for text in sources:
        word = vendor.rewrite(text, vendor._IMPORT, RUNTIME, vendor._word_start)
        assert word == WORD_ANCHORED.sub(RUNTIME, text)
        line = vendor.rewrite(text, vendor._ROS_IMPORT, ROS, vendor._line_start)
        assert line == LINE_ANCHORED.sub(ROS, text)
        changed += (word != text) + (line != text)
    assert changed > 10
