"""The interface packages of the declared-interface tests, rendered and built once per venv.

`platform_msgs` is built from the user interfaces directory (`interfaces/platform_msgs/action/`:
definition files only, as a platform team would supply them); `sgdeclared_interfaces` is the
swarm's own package (Event, ActiveStates) that a member node needs.
"""

from __future__ import annotations

import time
from pathlib import Path

from swarmgen.ros.interfaces import (
    ACTIVE_STATES_MSG,
    EVENT_MSG,
    build_and_install,
    render_interface_package,
)

HERE = Path(__file__).resolve().parent
USER_INTERFACES = HERE / "interfaces"
PLATFORM = "platform_msgs"
SWARM = "sgdeclared_interfaces"


def _definitions(kind: str) -> dict[str, str]:
    folder = USER_INTERFACES / PLATFORM / kind
    return {p.stem: p.read_text(encoding="utf-8") for p in sorted(folder.glob(f"*.{kind}"))}


def _write(files: dict[Path, str] | dict[object, str], root: Path) -> Path:
    for path, text in files.items():
        target = root / str(path)
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")
    return root


def build_packages(work: Path) -> dict[str, float]:
    """Render both packages under `work` and install them into this venv; seconds per build
    (a build whose sources are installed already is skipped: milliseconds)."""
    packages = {
        PLATFORM: render_interface_package(
            PLATFORM, {}, _definitions("action"), "test platform interfaces"
        ),
        SWARM: render_interface_package(
            SWARM,
            {"Event": EVENT_MSG, "ActiveStates": ACTIVE_STATES_MSG},
            {},
            "swarm interfaces of the declared-interface tests",
        ),
    }
    seconds = {}
    for name, files in packages.items():
        started = time.monotonic()
        build_and_install(_write(dict(files), work / name))
        seconds[name] = time.monotonic() - started
    return seconds
