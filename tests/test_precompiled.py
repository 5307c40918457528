"""The compiled template modules (swarmgen/_templates/, `python -m swarmgen.precompiled`)."""

from __future__ import annotations

from pathlib import Path

import jinja2
import pytest

from swarmgen import precompiled
from swarmgen.render import environment
from swarmgen.resources import data_dir


def test_modules_are_current(tmp_path: Path) -> None:
    """Every shipped template has its module, compiled from its current source by this Jinja2
    (run `make templates` when this fails)."""
    built = precompiled.build(environment(None), tmp_path, log=lambda _: None)
    shipped = sorted(p.name for p in precompiled.DIRECTORY.glob("*.py"))
    assert shipped == sorted(p.name for p in built)
    for path in built:
        assert (precompiled.DIRECTORY / path.name).read_text(encoding="utf-8") == path.read_text(
            encoding="utf-8"
        ), f"{path.name} is stale: run `make templates`"


def _fresh(directory: Path) -> jinja2.Environment:
    shipped = environment(None)
    return jinja2.Environment(
        loader=precompiled.ShippedLoader(str(directory)),
        undefined=shipped.undefined,
        keep_trailing_newline=True,
        autoescape=False,
        trim_blocks=True,
        lstrip_blocks=True,
    )


def test_shipped_templates_come_from_their_modules(monkeypatch: pytest.MonkeyPatch) -> None:
    env = _fresh(data_dir("templates"))

    def no_compile(*args: object, **kwargs: object) -> None:
        raise AssertionError("a shipped template was compiled")

    monkeypatch.setattr(env, "compile", no_compile)
    names = env.list_templates(extensions=["j2"])
    assert len(names) >= 19
    for name in names:
        assert env.get_template(name).name == name
    text = env.get_template("rclpy/setup.cfg.j2").render(header="# h", package="p_q")
    assert (
        text
        == "# h\n[develop]\nscript_dir=$base/lib/p_q\n[install]\ninstall_scripts=$base/lib/p_q\n"
    )


def test_renders_as_the_source_does() -> None:
    """Each shipped template renders the same text from its module as compiled from source."""
    plain = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(data_dir("templates"))),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    view = {"package": "pkg", "header": "# h", "runtime": "pkg._runtime"}
    for name in ("rclpy/setup.cfg.j2", "common/main.py.j2"):
        expected = plain.get_template(name).render(**view)
        assert "pkg" in expected
        assert _fresh(data_dir("templates")).get_template(name).render(**view) == expected


def test_an_edited_template_is_compiled_from_its_source(tmp_path: Path) -> None:
    """A template whose source is not what its module was compiled from (edited after the
    build) is compiled as before: the module never decides the text."""
    edited = tmp_path / "rclpy" / "setup.cfg.j2"
    edited.parent.mkdir()
    edited.write_text("edited {{ package }}\n", encoding="utf-8")
    assert _fresh(tmp_path).get_template("rclpy/setup.cfg.j2").render(package="x") == "edited x\n"


def test_another_jinja2_compiles_from_source(monkeypatch: pytest.MonkeyPatch) -> None:
    env = _fresh(data_dir("templates"))
    calls: list[str] = []
    compile_source = env.compile

    def counted(source: str, name: str | None = None, *args: object, **kwargs: object) -> object:
        calls.append(str(name))
        return compile_source(source, name, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(env, "compile", counted)
    monkeypatch.setattr(jinja2, "__version__", "0.0-other")
    env.get_template("rclpy/setup.cfg.j2")
    assert calls == ["rclpy/setup.cfg.j2"]
