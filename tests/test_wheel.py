"""A wheel built with `pip wheel .` and installed (not editable) into a fresh venv carries the
templates and schemas and compiles the sample model to exactly the checked-in output."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

from tests.conftest import ROOT


def _run(*args: str | Path, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(a) for a in args], cwd=cwd, capture_output=True, text=True, timeout=300, check=False
    )


def test_wheel_installs_and_compiles(tmp_path: Path) -> None:
    built = _run(
        sys.executable,
        "-m",
        "pip",
        "wheel",
        "--no-deps",
        "-q",
        "-w",
        tmp_path / "dist",
        ROOT,
        cwd=tmp_path,
    )
    assert built.returncode == 0, built.stderr
    (wheel,) = (tmp_path / "dist").glob("swarmgen-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    assert "swarmgen/_data/schemas/ir.schema.json" in names
    assert "swarmgen/_data/templates/common/README.md.j2" in names
    packaged = zipfile.ZipFile(wheel).read("swarmgen/_data/schemas/ir.schema.json")
    assert packaged == (ROOT / "schemas" / "ir.schema.json").read_bytes()

    venv = tmp_path / "venv"
    assert _run(sys.executable, "-m", "venv", venv, cwd=tmp_path).returncode == 0
    installed = _run(venv / "bin" / "pip", "install", "-q", wheel, cwd=tmp_path)
    assert installed.returncode == 0, installed.stderr
    # run outside the repository, so nothing can come from the source tree
    out = tmp_path / "out"
    compiled = _run(
        venv / "bin" / "swarmgen",
        "compile",
        ROOT / "sample_models/sar/sar.xmi",
        "-o",
        out,
        cwd=tmp_path,
    )
    assert compiled.returncode == 0, compiled.stderr
    module = _run(
        venv / "bin" / "python",
        "-c",
        "import swarmgen, sys; print(swarmgen.__file__)",
        cwd=tmp_path,
    )
    assert str(venv) in module.stdout
    expected = ROOT / "generated" / "sar"
    produced = {p.relative_to(out): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}
    checked_in = {
        p.relative_to(expected): p.read_bytes() for p in sorted(expected.rglob("*")) if p.is_file()
    }
    assert produced == checked_in
