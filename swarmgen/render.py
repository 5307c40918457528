"""Jinja2 rendering: thin templates over precomputed view models, strict about undefined names."""

from __future__ import annotations

from functools import cache
from typing import Any

import jinja2

from swarmgen.resources import data_dir


@cache
def environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(data_dir("templates"))),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        autoescape=False,
        trim_blocks=True,
        lstrip_blocks=True,
    )


def render(template: str, **view: Any) -> str:
    return environment().get_template(template).render(**view)
