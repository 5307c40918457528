"""The pre-commit hooks (.pre-commit-hooks.yaml) parse, name commands that exist, and their
entries work: the validate hook over several models, the drift check with the user's args."""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path
from typing import Any

import pytest

from swarmgen.cli import main
from tests.conftest import ROOT, SAMPLE_MODELS

HOOKS = ROOT / ".pre-commit-hooks.yaml"
BAD = ROOT / "tests" / "fixtures" / "bad"


def _scalar(text: str) -> Any:
    return {"true": True, "false": False}.get(text, text)


def parse_hooks(text: str) -> list[dict[str, Any]]:
    """The subset of YAML the file uses: a list of flat mappings of plain scalars."""
    hooks: list[dict[str, Any]] = []
    for line in text.splitlines():
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if line.startswith("- "):
            hooks.append({})
            line = "  " + line[2:]
        assert line.startswith("  ") and hooks, f"not in the subset: {line!r}"
        key, _, value = line.strip().partition(": ")
        hooks[-1][key] = _scalar(value.strip())
    return hooks


HOOK_LIST = parse_hooks(HOOKS.read_text(encoding="utf-8"))
BY_ID = {hook["id"]: hook for hook in HOOK_LIST}


def test_the_subset_parser_reads_it_as_yaml_does() -> None:
    if importlib.util.find_spec("yaml") is None:
        pytest.skip("PyYAML is not installed (it comes with the `ros` extra): run `make ros`")
    import yaml

    assert yaml.safe_load(HOOKS.read_text(encoding="utf-8")) == HOOK_LIST


def test_hooks_name_existing_commands() -> None:
    assert sorted(BY_ID) == ["swarmgen-check", "swarmgen-validate"]
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert "swarmgen" in scripts["scripts"]
    for hook in HOOK_LIST:
        assert {"id", "name", "entry", "language"} <= set(hook), hook
        assert hook["language"] == "python"  # pre-commit installs this repository: swarmgen
        words = shlex.split(hook["entry"])
        command = words if words[0] == "swarmgen" else shlex.split(words[2])  # sh -c '...'
        invoked = command[command.index("swarmgen") + 1]
        assert invoked in main.commands, (hook["id"], invoked)
    assert re.search(BY_ID["swarmgen-validate"]["files"], "models/sar.xmi")
    assert not re.search(BY_ID["swarmgen-validate"]["files"], "models/sar.xmi.bak")
    assert BY_ID["swarmgen-check"]["pass_filenames"] is False  # the user's args name the model


def _entry(hook: str, *args: str | Path, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    """Run a hook's entry as pre-commit does: the hook's environment's bin/ first on PATH."""
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    return subprocess.run(
        [*shlex.split(BY_ID[hook]["entry"]), *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        timeout=120,
        check=False,
    )


def test_validate_hook_checks_every_model() -> None:
    assert _entry("swarmgen-validate", *SAMPLE_MODELS).returncode == 0
    bad = sorted(BAD.glob("*.xmi"))
    worst = max(_entry("swarmgen-validate", model).returncode for model in bad[:3])
    done = _entry("swarmgen-validate", *SAMPLE_MODELS, *bad[:3])
    assert worst > 0 and done.returncode == worst, done.stdout + done.stderr


def test_validate_hook_passes_every_file_in_one_call(tmp_path: Path) -> None:
    """No shell loop: pre-commit's file list goes to one `swarmgen validate`, worst exit wins."""
    hook = BY_ID["swarmgen-validate"]
    assert shlex.split(hook["entry"]) == ["swarmgen", "validate"]
    assert hook.get("pass_filenames", True) is True
    done = _entry("swarmgen-validate", SAMPLE_MODELS[0], tmp_path / "missing.xmi", *SAMPLE_MODELS)
    assert done.returncode == 2 and "no such file [SG001]" in done.stdout, done.stderr
    assert done.stderr.count(": 0 error(s), 0 warning(s)") == 1 + len(SAMPLE_MODELS)


def test_check_hook_runs_the_drift_test() -> None:
    model = SAMPLE_MODELS[0]
    out = ROOT / "generated" / model.parent.name
    done = _entry("swarmgen-check", model, "-o", out, "--check")
    assert done.returncode == 0, done.stdout + done.stderr
