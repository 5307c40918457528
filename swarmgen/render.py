"""Jinja2 rendering: thin templates over precomputed view models, strict about undefined names.

`compile --templates DIR` puts DIR before the shipped templates (a `ChoiceLoader`): a file of DIR
with a shipped template's relative path (`asyncio/member.py.j2`) replaces that template only.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from functools import lru_cache
from pathlib import Path
from typing import Any

import jinja2

from swarmgen.precompiled import ShippedLoader
from swarmgen.resources import data_dir

# The override of the compile being run. A context variable, not a parameter, so that the
# backends' signatures stay `(Model, [Chart]) -> Files`; set only by `templates_from`.
_OVERRIDE: ContextVar[Path | None] = ContextVar("swarmgen_templates", default=None)


@lru_cache(maxsize=8)
def environment(override: Path | None = None) -> jinja2.Environment:
    """The Jinja2 environment of the shipped templates, with `override`'s first if given."""
    # the shipped templates through their compiled modules (swarmgen/precompiled.py)
    loader: jinja2.BaseLoader = ShippedLoader(str(data_dir("templates")))
    if override is not None:
        loader = jinja2.ChoiceLoader([jinja2.FileSystemLoader(str(override)), loader])
    return jinja2.Environment(
        loader=loader,
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        autoescape=False,
        trim_blocks=True,
        lstrip_blocks=True,
    )


@contextmanager
def templates_from(directory: Path | None) -> Iterator[None]:
    """Render with `directory`'s templates before the shipped ones (None: the shipped only)."""
    token = _OVERRIDE.set(directory.resolve() if directory is not None else None)
    try:
        yield
    finally:
        _OVERRIDE.reset(token)


def render(template: str, **view: Any) -> str:
    """One template (a path relative to the template directory) rendered over a view model."""
    return environment(_OVERRIDE.get()).get_template(template).render(**view)
