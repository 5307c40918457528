"""Hostile and clumsy output directories: swarmgen removes only what its manifest lists with a
digest it can verify, keeps every other file, refuses what it cannot do safely (naming the files),
and a kill at any step of a write loses nothing (docs/security.md).

The commands run as real processes (tests/hostile.py); the crash tests kill a real writer process
with SIGKILL at its n-th file-system call, for every n, and check what is left on disk.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
import textwrap
from collections.abc import Callable
from pathlib import Path, PurePosixPath

import pytest

from swarmgen import outtree
from tests.hostile import ROOT, SAMPLE, assert_clean, assert_refused, snapshot, swarmgen

SMALL = ROOT / "tests" / "fixtures" / "bad" / "valid_base.xmi"
GIT_HEAD = "ref: refs/heads/main\n"


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def _project(root: Path, manifest: str | None) -> Path:
    """A user's directory: a git repository, notes, and (maybe) a planted manifest."""
    root.mkdir()
    (root / ".git").mkdir()
    (root / ".git" / "HEAD").write_text(GIT_HEAD)
    (root / "notes.txt").write_text("keep me\n")
    if manifest is not None:
        (root / outtree.MANIFEST).write_text(manifest)
    return root


def _manifest(files: dict[str, str], **fields: object) -> str:
    payload = {"generator": "swarmgen", "command": "compile", "format": 1, "files": files}
    payload.update(fields)
    return json.dumps(payload)


BAD_MANIFESTS = {
    "empty_object": "{}",
    "empty_file": "",
    "list": "[]",
    "null": "null",
    "not_json": "swarmgen was here",
    "binary": "\x00\x01\x02",
    "other_generator": _manifest({}, generator="protoc"),
    "future_format": _manifest({}, format=2),
    "unknown_command": _manifest({}, command="rm -rf"),
    "files_not_object": _manifest([]),  # type: ignore[arg-type]
    "digest_not_hex": _manifest({"notes.txt": "x" * 64}),
    "digest_short": _manifest({"notes.txt": "ab"}),
    "parent_path": _manifest({"../outside.txt": _digest("x")}),
    "absolute_path": _manifest({"/etc/passwd": _digest("x")}),
    "git_file_with_its_digest": _manifest({".git/HEAD": _digest(GIT_HEAD)}),
    "double_slash": _manifest({"a//notes.txt": _digest("keep me\n")}),
    "backslash": _manifest({"..\\notes.txt": _digest("keep me\n")}),
    "deep_json": "[" * 100_000 + "]" * 100_000,
}


@pytest.mark.parametrize("name", sorted(BAD_MANIFESTS))
def test_a_planted_manifest_is_not_trusted(tmp_path: Path, name: str) -> None:
    project = _project(tmp_path / "project", BAD_MANIFESTS[name])
    before = snapshot(project)
    outcome = swarmgen("compile", SMALL, "-o", project, "--backend", "scxml", cwd=tmp_path)
    assert_refused(outcome, exit=2, says="project")
    assert snapshot(project) == before


@pytest.mark.parametrize("command", ["compile", "graph", "simulate"])
def test_an_empty_manifest_protects_the_repository_for_every_command(
    tmp_path: Path, command: str
) -> None:
    project = _project(tmp_path / "project", "{}")
    before = snapshot(project)
    args = {"compile": ["--backend", "scxml"], "graph": [], "simulate": ["--reps", "1"]}[command]
    outcome = swarmgen(command, SAMPLE, "-o", project, *args, cwd=tmp_path, timeout=60)
    assert_refused(outcome, exit=2, says="not a valid swarmgen manifest")
    assert snapshot(project) == before


def test_a_valid_manifest_listing_a_correct_digest_still_spares_unlisted_files(
    tmp_path: Path,
) -> None:
    """A real manifest of an earlier compile: only its files go; the repository stays."""
    out = tmp_path / "out"
    assert swarmgen("compile", SMALL, "-o", out, cwd=tmp_path).exit == 0
    (out / ".git").mkdir()
    (out / ".git" / "HEAD").write_text(GIT_HEAD)
    assert swarmgen("compile", SMALL, "-o", out, "--backend", "scxml", cwd=tmp_path).exit == 0
    assert (out / ".git" / "HEAD").read_text() == GIT_HEAD
    assert not (out / "asyncio").exists()  # swarmgen's own files, no longer generated, are gone


@pytest.mark.parametrize("kind", ["symlink_to_passwd", "symlink_to_valid", "directory", "fifo"])
def test_a_manifest_that_is_not_a_regular_file_is_refused(tmp_path: Path, kind: str) -> None:
    out = tmp_path / "out"
    assert swarmgen("compile", SMALL, "-o", out, "--backend", "scxml", cwd=tmp_path).exit == 0
    manifest = out / outtree.MANIFEST
    valid = tmp_path / "valid.json"
    shutil.move(manifest, valid)
    if kind == "symlink_to_passwd":
        manifest.symlink_to("/etc/passwd")
    elif kind == "symlink_to_valid":
        manifest.symlink_to(valid)
    elif kind == "directory":
        manifest.mkdir()
    else:
        os.mkfifo(manifest)
    before = snapshot(out)
    outcome = swarmgen("compile", SMALL, "-o", out, cwd=tmp_path, timeout=30)
    assert_refused(outcome, exit=2, says="manifest")
    assert snapshot(out) == before


# --- the user's files in an output tree


def _user_files(out: Path) -> dict[str, str]:
    planted = {
        "notes.md": "my notes\n",
        "venv/bin/python": "#!/bin/sh\n",
        "rclpy/build/log.txt": "colcon build\n",
        "rclpy/install/setup.bash": "# colcon\n",
        "scxml/__pycache__/x.pyc": "cache\n",
        "asyncio/mine.py": "print('mine')\n",
    }
    for relative, text in planted.items():
        (out / relative).parent.mkdir(parents=True, exist_ok=True)
        (out / relative).write_text(text)
    return planted


def test_files_a_user_adds_to_an_output_tree_survive_recompiles(tmp_path: Path) -> None:
    out = tmp_path / "out"
    assert swarmgen("compile", SMALL, "-o", out, cwd=tmp_path).exit == 0
    planted = _user_files(out)
    for backends in (["--backend", "scxml"], [], []):
        outcome = swarmgen("compile", SMALL, "-o", out, *backends, cwd=tmp_path)
        assert_clean(outcome, (0,))
    assert {r: (out / r).read_text() for r in planted} == planted
    check = swarmgen("compile", SMALL, "-o", out, "--check", cwd=tmp_path)
    assert check.exit == 0, check  # the user's files are not drift


@pytest.mark.parametrize(
    ("first", "second"),
    [("compile", "simulate"), ("compile", "graph"), ("simulate", "compile"), ("graph", "compile")],
)
def test_a_directory_of_another_command_is_refused(tmp_path: Path, first: str, second: str) -> None:
    out = tmp_path / "out"
    extra = {"simulate": ["--reps", "1"], "compile": ["--backend", "scxml"], "graph": []}
    assert swarmgen(first, SAMPLE, "-o", out, *extra[first], cwd=tmp_path, timeout=60).exit == 0
    before = snapshot(out)
    outcome = swarmgen(second, SAMPLE, "-o", out, *extra[second], cwd=tmp_path, timeout=60)
    assert_refused(outcome, exit=2, says=f"output of `swarmgen {first}`")
    assert snapshot(out) == before


def test_an_edited_file_is_named_and_kept(tmp_path: Path) -> None:
    out = tmp_path / "out"
    assert swarmgen("compile", SMALL, "-o", out, "--backend", "scxml", cwd=tmp_path).exit == 0
    edited = next((out / "scxml").glob("*.scxml"))
    edited.write_text(edited.read_text() + "<!-- my fix -->\n")
    before = snapshot(out)
    outcome = swarmgen("compile", SMALL, "-o", out, cwd=tmp_path)
    assert_refused(outcome, exit=2, says=f"scxml/{edited.name}")
    assert snapshot(out) == before


def _plant_file_named_asyncio(out: Path) -> None:
    (out / "asyncio").write_text("a file where a directory goes\n")


def _plant_generated_path(out: Path) -> None:
    (out / "README.md").unlink()
    manifest = json.loads((out / outtree.MANIFEST).read_text())
    del manifest["files"]["README.md"]
    (out / outtree.MANIFEST).write_text(json.dumps(manifest))
    (out / "README.md").write_text("the user's own README\n")


def _plant_directory_symlink(out: Path) -> None:
    elsewhere = out.parent / "elsewhere"
    elsewhere.mkdir()
    shutil.rmtree(out / "scxml")
    (out / "scxml").symlink_to(elsewhere, target_is_directory=True)


def _plant_file_symlink(out: Path) -> None:
    victim = out.parent / "victim.txt"
    victim.write_text("not yours\n")
    target = next((out / "scxml").glob("*.scxml"))
    target.unlink()
    target.symlink_to(victim)


PLANTS: dict[str, Callable[[Path], None]] = {
    "file_where_a_directory_goes": _plant_file_named_asyncio,
    "user_file_at_a_generated_path": _plant_generated_path,
    "directory_symlink_out_of_the_tree": _plant_directory_symlink,
    "file_symlink_to_a_victim": _plant_file_symlink,
}


@pytest.mark.parametrize("plant", sorted(PLANTS))
def test_swarmgen_never_writes_over_or_through_what_it_did_not_write(
    tmp_path: Path, plant: str
) -> None:
    out = tmp_path / "out"
    assert swarmgen("compile", SMALL, "-o", out, "--backend", "scxml", cwd=tmp_path).exit == 0
    PLANTS[plant](out)
    before, around = snapshot(out), snapshot(tmp_path)
    outcome = swarmgen("compile", SMALL, "-o", out, cwd=tmp_path)
    assert_refused(outcome, exit=2)
    assert snapshot(out) == before and snapshot(tmp_path) == around


# --- the output path itself


def test_a_symlink_to_a_directory_is_followed_and_kept(tmp_path: Path) -> None:
    real = tmp_path / "real"
    link = tmp_path / "link"
    real.mkdir()
    link.symlink_to(real, target_is_directory=True)
    for _ in range(2):
        assert swarmgen("compile", SMALL, "-o", link, "--backend", "scxml", cwd=tmp_path).exit == 0
    assert link.is_symlink() and (real / outtree.MANIFEST).is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "real"]  # no debris


def _dangling(tmp: Path) -> Path:
    (tmp / "gone").symlink_to(tmp / "nowhere")
    return tmp / "gone"


def _below_a_file(tmp: Path) -> Path:
    (tmp / "file.txt").write_text("x")
    return tmp / "file.txt" / "out"


def _a_file(tmp: Path) -> Path:
    (tmp / "file.txt").write_text("x")
    return tmp / "file.txt"


def _too_long(tmp: Path) -> Path:
    return tmp / ("n" * 300)


def _model_directory(tmp: Path) -> Path:
    shutil.copy(SMALL, tmp / "model.xmi")
    return tmp


def _symlink_loop(tmp: Path) -> Path:
    (tmp / "a").symlink_to(tmp / "b")
    (tmp / "b").symlink_to(tmp / "a")
    return tmp / "a"


BAD_OUTPUTS: dict[str, Callable[[Path], Path]] = {
    "dangling_symlink": _dangling,
    "below_a_file": _below_a_file,
    "a_regular_file": _a_file,
    "name_over_255_bytes": _too_long,
    "the_model_s_own_directory": _model_directory,
    "symlink_loop": _symlink_loop,
}


@pytest.mark.parametrize("command", ["compile", "graph", "simulate"])
@pytest.mark.parametrize("case", sorted(BAD_OUTPUTS))
def test_an_output_path_that_cannot_be_used_is_refused_cleanly(
    tmp_path: Path, case: str, command: str
) -> None:
    work = tmp_path / "work"
    work.mkdir()
    out = BAD_OUTPUTS[case](work)
    before = snapshot(work)
    extra = {"compile": ["--backend", "scxml"], "graph": [], "simulate": ["--reps", "1"]}
    model = SAMPLE if command == "simulate" else SMALL  # simulate's scenarios name SAR's types
    outcome = swarmgen(command, model, "-o", out, *extra[command], cwd=work, timeout=60)
    assert_refused(outcome, exit=2, says=out.name)
    assert snapshot(work) == before  # no debris either


def test_simulate_checks_its_output_before_it_runs(tmp_path: Path) -> None:
    project = _project(tmp_path / "project", None)
    outcome = swarmgen("simulate", SAMPLE, "-o", project, "--reps", "50", cwd=tmp_path)
    assert_refused(outcome, exit=2, says="not written by swarmgen")
    assert "runs of" not in outcome.stderr  # refused before any run, not after


def test_dot_dot_in_the_output_path(tmp_path: Path) -> None:
    out = tmp_path / "out"
    assert swarmgen("compile", SMALL, "-o", out, "--backend", "scxml", cwd=tmp_path).exit == 0
    (out / "sub").mkdir()  # the user's, empty: kept
    outcome = swarmgen("compile", SMALL, "-o", f"{out}/sub/..", cwd=tmp_path)
    assert_clean(outcome, (0,))
    assert (out / "asyncio").is_dir() and (out / "sub").is_dir()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


@pytest.mark.parametrize(
    ("umask", "directory", "file"), [(0o022, 0o755, 0o644), (0o077, 0o700, 0o600)]
)
def test_modes_follow_the_umask(tmp_path: Path, umask: int, directory: int, file: int) -> None:
    out = tmp_path / "out"
    script = (
        f"import os, sys; os.umask({umask}); sys.argv = ['swarmgen', 'compile', {str(SMALL)!r}, "
        f"'-o', {str(out)!r}, '--backend', 'scxml']; from swarmgen.cli import run; run()"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, check=False
    )
    assert done.returncode == 0, done.stderr
    assert out.stat().st_mode & 0o777 == directory
    assert (out / "scxml").stat().st_mode & 0o777 == directory
    assert (out / "README.md").stat().st_mode & 0o777 == file


def test_an_existing_directory_keeps_its_mode(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    out.chmod(0o750)
    for backends in (["--backend", "scxml"], []):
        assert swarmgen("compile", SMALL, "-o", out, *backends, cwd=tmp_path).exit == 0
        assert out.stat().st_mode & 0o777 == 0o750


# --- crash safety: SIGKILL at every step of a write

WRITER = textwrap.dedent(
    """
    import json, os, signal, sys
    from pathlib import Path, PurePosixPath
    from swarmgen import outtree

    kill_at, spec = int(sys.argv[1]), json.loads(sys.argv[2])
    calls = [0]

    def counted(function):
        def call(*args, **kwargs):
            calls[0] += 1
            if calls[0] == kill_at:
                os.kill(os.getpid(), signal.SIGKILL)
            return function(*args, **kwargs)
        return call

    for name in ("rename", "replace", "unlink", "rmdir", "mkdir", "chmod"):
        setattr(os, name, counted(getattr(os, name)))
    Path.write_bytes = counted(Path.write_bytes)
    outtree._exchange = counted(outtree._exchange)
    files = {PurePosixPath(p): t for p, t in spec["files"].items()}
    outtree.write(files, Path(spec["out"]))
    print(calls[0])
    """
)


def _tree(version: str, paths: list[str]) -> dict[str, str]:
    files: dict[PurePosixPath, str | bytes] = {PurePosixPath(p): f"{p} {version}\n" for p in paths}
    files[PurePosixPath(outtree.MANIFEST)] = outtree.manifest_text("compile", "m.xmi", files)
    return {str(p): str(t) for p, t in files.items()}


OLD = _tree("old", ["README.md", "scxml/A.scxml", "scxml/B.scxml", "asyncio/pkg/a.py"])
NEW = _tree("new", ["README.md", "scxml/A.scxml", "smach/pkg/a.py", "smach/pkg/b.py"])
USER = {"notes.md": "mine\n", "asyncio/pkg/__pycache__/a.pyc": "cache\n", "venv/x": "v\n"}


def _write(spec: dict[str, object], kill_at: int) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", WRITER, str(kill_at), json.dumps(spec)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
        timeout=30,
    )


def _lay_out(out: Path, tree: dict[str, str] | None, user: dict[str, str]) -> None:
    for relative, text in {**(tree or {}), **user}.items():
        (out / relative).parent.mkdir(parents=True, exist_ok=True)
        (out / relative).write_text(text)


def _contents(out: Path) -> dict[str, str]:
    return {
        p.relative_to(out).as_posix(): p.read_text() for p in sorted(out.rglob("*")) if p.is_file()
    }


@pytest.mark.parametrize(
    ("start", "user"),
    [(None, {}), ("old", {}), ("old", USER)],
    ids=["new_directory", "only_swarmgen_files_exchange", "with_user_files_in_place"],
)
def test_a_kill_at_any_step_loses_nothing_and_the_next_run_recovers(
    tmp_path: Path, start: str | None, user: dict[str, str]
) -> None:
    steps, killed_at = 0, 0
    for kill_at in range(1, 200):
        case = tmp_path / f"k{kill_at}"
        out = case / "out"
        case.mkdir()
        if start is not None:
            _lay_out(out, OLD, user)
        done = _write({"files": NEW, "out": str(out)}, kill_at)
        if done.returncode == 0:
            steps = int(done.stdout)
            break
        assert done.returncode == -9, done.stderr
        killed_at = kill_at
        left = _contents(out) if out.exists() else {}
        if start is not None:
            assert out.is_dir(), f"killed at step {kill_at}: the output directory is gone"
        for relative, text in user.items():
            assert left.get(relative) == text, f"killed at step {kill_at}: lost {relative}"
        for relative, text in left.items():
            known = {OLD.get(relative), NEW.get(relative), user.get(relative)}
            assert text in known or relative == outtree.MANIFEST, (kill_at, relative, text)
        recovered = _write({"files": NEW, "out": str(out)}, 0)
        assert recovered.returncode == 0, f"killed at step {kill_at}: {recovered.stderr}"
        assert _contents(out) == {**NEW, **user}, f"killed at step {kill_at}"
        assert sorted(p.name for p in case.iterdir()) == ["out"], f"debris after {kill_at}"
    assert steps > 0 and killed_at == steps, "every step was interrupted once"


def _immutable(path: Path) -> bool:
    """Make `path` unwritable even for root (ext4's immutable flag); False where that cannot be
    done (no chattr, another file system, no privilege)."""
    chattr = shutil.which("chattr")
    return (
        bool(chattr)
        and subprocess.run([chattr, "+i", str(path)], capture_output=True).returncode == 0
    )


@pytest.mark.parametrize("command", ["compile", "simulate"])
def test_an_unwritable_parent_is_one_clear_line(tmp_path: Path, command: str) -> None:
    parent = tmp_path / "locked"
    parent.mkdir()
    if os.geteuid() != 0:
        parent.chmod(0o555)
    elif not _immutable(parent):
        pytest.skip("no way to make a directory unwritable for root here")
    try:
        extra = ["--backend", "scxml"] if command == "compile" else ["--reps", "1"]
        model = SAMPLE if command == "simulate" else SMALL
        outcome = swarmgen(command, model, "-o", parent / "out", *extra, cwd=tmp_path, timeout=60)
    finally:
        subprocess.run(["chattr", "-i", str(parent)], capture_output=True, check=False)
        parent.chmod(0o755)
    assert_refused(outcome, exit=2, says="cannot write")
    assert list(parent.iterdir()) == []
