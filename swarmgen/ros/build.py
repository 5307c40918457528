"""Build a generated ROS 2 interface package with cmake, from the ROS 2 wheels on PyPI, into a
Python prefix (by default this venv); skipped when the same sources are already installed."""

from __future__ import annotations

import argparse
import fcntl
import hashlib
import logging
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from swarmgen.errors import SwarmgenError
from swarmgen.ros.idl_names import check_package_name

_log = logging.getLogger(__name__)

BUILD_STAMP = ".swarmgen-build-hash"
_INSTALL_MANIFEST = ".swarmgen-install-manifest"
# Bump when the build recipe changes in a way that must rebuild installed packages.
_RECIPE_VERSION = "2"  # 2: C and Python only, Ninja, one C type support


class InterfaceBuildError(SwarmgenError, RuntimeError):
    """cmake failed to configure, build or install an interface package."""


_WHEEL_INCLUDE = re.compile(r"/opt/python/cp3\d*-cp3\d*/include/python3\.\d+")
_WHEEL_SITE = re.compile(r"/opt/python/cp3\d*-cp3\d*/lib/python3\.\d+/site-packages")


def fix_wheel_cmake_files(prefix: Path) -> list[Path]:
    """Point the ROS wheels' exported CMake targets at this interpreter.

    The wheels were built under `/opt/python/cp3XX-cp3XX/`, and their `share/*/cmake/*.cmake`
    files still name that interpreter's include and site-packages directories. Only files that
    contain `/opt/python/cp3` are rewritten (atomically), so calling this again does nothing.
    Returns the files it changed.
    """
    include = sysconfig.get_path("include")
    site = sysconfig.get_path("purelib")
    changed = []
    for path in sorted(prefix.glob("share/*/cmake/*.cmake")):
        text = path.read_text(encoding="utf-8")
        if "/opt/python/cp3" not in text:
            continue
        fixed = _WHEEL_SITE.sub(site, _WHEEL_INCLUDE.sub(include, text))
        if fixed == text:
            continue
        tmp = path.with_name(f".{path.name}.swarmgen-tmp")
        tmp.write_text(fixed, encoding="utf-8")
        os.replace(tmp, path)
        changed.append(path)
    if changed:
        _log.info("fixed the wheel build paths in %d CMake files under %s", len(changed), prefix)
    return changed


def _package_name(package_dir: Path) -> str:
    try:
        root = ET.parse(package_dir / "package.xml").getroot()
    except (OSError, ET.ParseError) as exc:
        raise InterfaceBuildError(f"{package_dir}: no readable package.xml ({exc})") from exc
    return check_package_name((root.findtext("name") or "").strip())


def _source_hash(package_dir: Path, skip: Path | None) -> str:
    digest = hashlib.sha256()
    digest.update(f"recipe {_RECIPE_VERSION} python {sys.version}\n".encode())
    for path in sorted(p for p in package_dir.rglob("*") if p.is_file()):
        if skip is not None and path.is_relative_to(skip):
            continue
        digest.update(path.relative_to(package_dir).as_posix().encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()


@contextmanager
def _lock(prefix: Path, package: str) -> Iterator[None]:
    key = hashlib.sha256(str(prefix).encode()).hexdigest()[:16]
    lock_path = Path(tempfile.gettempdir()) / f"swarmgen-ros-{key}-{package}.lock"
    with lock_path.open("a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def _remove_previous_install(prefix: Path, share: Path) -> None:
    """Remove what the previous build of this package installed (a message may be gone)."""
    manifest = share / _INSTALL_MANIFEST
    if not manifest.is_file():
        return
    root = prefix.resolve()
    parents: set[Path] = set()
    for line in manifest.read_text(encoding="utf-8").splitlines():
        path = Path(line.strip())
        if not line.strip() or not path.is_absolute() or not path.resolve().is_relative_to(root):
            continue
        path.unlink(missing_ok=True)
        parents.add(path.parent)
        for cached in (path.parent / "__pycache__").glob(f"{path.stem}.*.pyc"):
            cached.unlink(missing_ok=True)
    # Prune the directories this left empty (deepest first), never the prefix's own.
    for directory in sorted(parents, key=lambda p: len(p.parts), reverse=True):
        while (
            directory.resolve().is_relative_to(root) and len(directory.parts) > len(root.parts) + 1
        ):
            cache = directory / "__pycache__"
            if cache.is_dir() and not any(cache.iterdir()):
                cache.rmdir()
            if not directory.is_dir() or any(directory.iterdir()):
                break
            directory.rmdir()
            directory = directory.parent


def _run(args: list[str], env: dict[str, str], timeout: float, step: str) -> None:
    try:
        proc = subprocess.run(
            args,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            timeout=timeout,
            check=False,
        )
    except subprocess.TimeoutExpired as exc:
        raise InterfaceBuildError(f"cmake {step} timed out after {timeout:.0f} s") from exc
    except FileNotFoundError as exc:
        raise InterfaceBuildError(f"cmake is not installed ({exc})") from exc
    if proc.returncode != 0:
        tail = "\n".join(proc.stdout.splitlines()[-40:])
        raise InterfaceBuildError(
            f"cmake {step} failed (exit {proc.returncode}): {' '.join(args)}\n{tail}"
        )


def build_and_install(
    package_dir: Path,
    prefix: Path | None = None,
    build_dir: Path | None = None,
    *,
    jobs: int | None = None,
    timeout: float = 900.0,
) -> Path:
    """Build the interface package in `package_dir` with cmake and install it into `prefix`.

    `prefix` defaults to `sys.prefix` (this venv): the generated Python package then imports
    with no PYTHONPATH or LD_LIBRARY_PATH (the ROS wheels' bootstrapper already puts
    `<venv>/lib` on the library path). The ROS wheels (rclpy, rosidl and ament generators) must
    be installed in this interpreter's environment (`make ros`).

    The build is skipped when the same sources are already installed: a hash of the package's
    files is stored in `<prefix>/share/<package>/.swarmgen-build-hash`. A rebuild first removes
    the files the previous build installed. `build_dir` defaults to a temporary directory.
    Returns `<prefix>/share/<package>`; raises InterfaceBuildError with the tail of cmake's
    output on failure.
    """
    package_dir = package_dir.resolve()
    prefix = (prefix or Path(sys.prefix)).resolve()
    package = _package_name(package_dir)
    share = prefix / "share" / package
    stamp = share / BUILD_STAMP
    source_hash = _source_hash(package_dir, build_dir.resolve() if build_dir else None)

    with _lock(prefix, package):
        if stamp.is_file() and stamp.read_text(encoding="utf-8").strip() == source_hash:
            _log.info("%s is up to date in %s", package, prefix)
            return share
        started = time.monotonic()
        env = _build_env(prefix)
        _remove_previous_install(prefix, share)
        with tempfile.TemporaryDirectory(prefix=f"swarmgen-{package}-build-") as tmp:
            build = build_dir.resolve() if build_dir else Path(tmp)
            _cmake(package_dir, prefix, build, env, jobs or os.cpu_count() or 2, timeout)
            manifest = build / "install_manifest.txt"
            if manifest.is_file():
                (share / _INSTALL_MANIFEST).write_text(
                    manifest.read_text(encoding="utf-8"), encoding="utf-8"
                )
        stamp.write_text(source_hash + "\n", encoding="utf-8")
        _log.info("built and installed %s in %.1f s", package, time.monotonic() - started)
    return share


def _build_env(prefix: Path) -> dict[str, str]:
    """The environment of the build: the ROS wheels of this venv (their CMake files fixed to
    this interpreter) and `prefix` on the ament, CMake and executable paths."""
    wheels = Path(sys.prefix).resolve()
    fix_wheel_cmake_files(wheels)
    prefixes = os.pathsep.join(dict.fromkeys([str(prefix), str(wheels)]))
    env = dict(os.environ)
    env["AMENT_PREFIX_PATH"] = prefixes
    env["CMAKE_PREFIX_PATH"] = prefixes
    env["PATH"] = os.pathsep.join(
        [*dict.fromkeys([str(prefix / "bin"), str(wheels / "bin")]), env.get("PATH", "")]
    )
    return env


def configure_options(env: dict[str, str]) -> list[str]:
    """The cmake options that make the build fast: Ninja when installed (faster than make at
    the same -j), no tests, and only the C type support the RMW of this environment loads (the
    generated CMakeLists.txt then skips generating the others)."""
    options = ["-G", "Ninja"] if shutil.which("ninja", path=env.get("PATH")) else []
    options.append("-DBUILD_TESTING=OFF")
    typesupport = _rmw_typesupport(env)
    if typesupport:
        options.append(f"-DSTATIC_ROSIDL_TYPESUPPORT_C={typesupport}")
    return options


# The C type support each RMW implementation of the ROS wheels loads first.
_RMW_TYPESUPPORT_C = {"rmw_fastrtps_cpp": "rosidl_typesupport_fastrtps_c"}


def _rmw_typesupport(env: dict[str, str]) -> str | None:
    """The one C type support to build, or None (all of them) when the RMW is another one or
    its type support is not installed."""
    rmw = env.get("RMW_IMPLEMENTATION") or "rmw_fastrtps_cpp"  # rclpy's default
    typesupport = _RMW_TYPESUPPORT_C.get(rmw)
    if typesupport is None:
        return None
    for prefix in env.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        index = Path(prefix) / "share" / "ament_index" / "resource_index"
        if prefix and (index / "rosidl_typesupport_c" / typesupport).is_file():
            return typesupport
    return None


def _cmake(
    package_dir: Path, prefix: Path, build: Path, env: dict[str, str], jobs: int, timeout: float
) -> None:
    """Configure the package in `build`, then build and install it into `prefix`."""
    _run(
        [
            "cmake",
            "-S",
            str(package_dir),
            "-B",
            str(build),
            *configure_options(env),
            f"-DCMAKE_INSTALL_PREFIX={prefix}",
            f"-DPython3_EXECUTABLE={sys.executable}",
        ],
        env,
        timeout,
        "configure",
    )
    _run(
        ["cmake", "--build", str(build), "--target", "install", f"-j{jobs}"],
        env,
        timeout,
        "build",
    )


def main(argv: list[str] | None = None) -> int:
    """`python -m swarmgen.ros.build --fix-wheels [PREFIX]`: what `make ros` runs so that cmake
    and colcon work with the wheels (the fix `build_and_install` also applies before a build)."""
    parser = argparse.ArgumentParser(prog="python -m swarmgen.ros.build", description=main.__doc__)
    parser.add_argument("--fix-wheels", action="store_true", required=True)
    parser.add_argument("prefix", nargs="?", type=Path, default=Path(sys.prefix))
    args = parser.parse_args(argv)
    changed = fix_wheel_cmake_files(args.prefix)
    print(f"fixed the wheel build paths in {len(changed)} CMake files under {args.prefix}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
