"""The bookkeeping of one lockstep run of the world node, without ROS.

`Run` holds the world, what arrived for the current step (answers by stamp, step reports),
the counters of the faults (timeouts, stale answers, late reports), the rescues and the
coverage samples, and makes the status message and the result file. The world node
(`world_node.py`) only moves messages in and out; the rules are here and in docs/detailed.md,
"The world node".
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

from .barrier import json_object
from .geometry import ZERO, Command
from .world import World
from .worldfile import NS_PER_S, WorldFile


class Run:
    """One run: the world stepped in lockstep with the answers of its robots' servers."""

    def __init__(self, config: WorldFile) -> None:
        """A run at step 0: the world at its start, nothing received yet."""
        self.config = config
        self.world = World(config.spec)
        self.names = [r.name for r in config.spec.robots]
        self.dt_ns = config.dt_ns
        self.limit_ns = round(config.stop.time_s * NS_PER_S)
        self.target_ids = [t.id for t in config.spec.targets]
        self.answers: dict[str, Command] = {}
        self.reporters: set[str] = set()
        self.settle = False
        self.unserved: set[str] = set()
        self.timeouts = dict.fromkeys(self.names, 0)
        self.report_timeouts = 0
        self.stale = 0
        self.bad_messages = 0
        self.rescued: dict[int, tuple[float, str]] = {}
        self.samples: list[tuple[int, float]] = [(0, self.world.coverage())]

    # --- the current step

    @property
    def k(self) -> int:
        """The current step."""
        return self.world.steps

    @property
    def t_ns(self) -> int:
        """The current step's stamp in integer nanoseconds (k * dt_ns: exact)."""
        return self.world.steps * self.dt_ns

    def begin_step(self) -> None:
        """Forget what arrived for the previous step."""
        self.answers.clear()
        self.reporters.clear()
        self.settle = False

    def answer(self, robot: str, stamp_ns: int, vx: float, vy: float, vz: float) -> None:
        """A cmd_vel: kept when it answers the current step (first one wins), else stale."""
        if stamp_ns != self.t_ns or robot in self.answers:
            self.stale += 1
            return
        try:
            self.answers[robot] = Command(float(vx), float(vy), float(vz))
        except (TypeError, ValueError):
            self.bad_messages += 1

    def waiting_for(self) -> list[str]:
        """The served robots whose answer to the current step has not arrived."""
        return [n for n in self.names if n not in self.answers and n not in self.unserved]

    def report(self, text: str) -> None:
        """A step report (`{"k", "by", "settle"}`): counted for the current step only; a
        late one that asks to settle still settles, before the next step."""
        message = json_object(text)
        k = None if message is None else message.get("k")
        if message is None or isinstance(k, bool) or not isinstance(k, int) or k > self.k:
            self.bad_messages += 1
            return
        self.settle = self.settle or message.get("settle") is True
        if k == self.k:
            self.reporters.add(str(message.get("by", "")))
        else:
            self.stale += 1

    def rescue(self, text: str) -> None:
        """A rescue (`{"target", "robot", "k"}`): the target's rescue time is k * dt."""
        message = json_object(text)
        target = None if message is None else message.get("target")
        if message is None or target not in self.target_ids or isinstance(target, bool):
            self.bad_messages += 1
            return
        k = message.get("k", self.k)
        if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k <= self.k:
            k = self.k  # a step still to come, or none given: the current one
        self.rescued.setdefault(int(target), (k * self.config.spec.dt, str(message.get("robot"))))

    def apply(self) -> None:
        """Hold every answer as its robot's command; a robot without one keeps its command
        (counted as a timeout), an unserved robot gets zero."""
        for name in self.names:
            if name in self.answers:
                try:
                    cmd = self.answers[name]
                    self.world.command(name, cmd.vx, cmd.vy, cmd.vz)
                except ValueError:  # NaN or infinite: refused, the command is kept
                    self.bad_messages += 1
            elif name in self.unserved:
                self.world.command(name, ZERO.vx, ZERO.vy, ZERO.vz)
            else:
                self.timeouts[name] += 1

    def advance(self) -> None:
        """Step the world and sample the coverage."""
        self.world.step()
        if self.k % self.config.sample_every == 0:
            self.samples.append((self.k, self.world.coverage()))

    def stop_reason(self) -> str | None:
        """Why the run ends at the current step, or None."""
        stop = self.config.stop
        if stop.coverage is not None and self.world.coverage() >= stop.coverage:
            return "coverage"
        if stop.all_rescued and len(self.rescued) == len(self.target_ids):
            return "all_rescued"
        if self.t_ns >= self.limit_ns:
            return "time_limit"
        return None

    # --- what the run tells

    def targets(self) -> dict[str, dict[str, Any]]:
        """Per target: first detection time, rescue time and rescuer (None: not yet)."""
        first = self.world.first_detections()
        out: dict[str, dict[str, Any]] = {}
        for target_id in self.target_ids:
            rescue = self.rescued.get(target_id)
            out[str(target_id)] = {
                "first_detection": first.get(target_id),
                "rescued": None if rescue is None else rescue[0],
                "robot": None if rescue is None else rescue[1],
            }
        return out

    def status(self, final: bool) -> dict[str, Any]:
        """The `/world/status` message."""
        return {
            "k": self.k,
            "t": self.world.time,
            "coverage": self.world.coverage(),
            "targets": self.targets(),
            "final": final,
        }

    def result(self, reason: str, wall_s: float) -> dict[str, Any]:
        """The result file: everything but `wall` is the same on every run of one file."""
        if self.samples[-1][0] != self.k:
            self.samples.append((self.k, self.world.coverage()))
        sim_s = self.world.time
        return {
            "complete": reason != "signal",
            "reason": reason,
            "seed": self.config.seed,
            "dt": self.config.spec.dt,
            "substeps": self.config.spec.substeps,
            "steps": self.k,
            "sim_s": sim_s,
            "coverage": self.world.coverage(),
            "samples": [list(s) for s in self.samples],
            "targets": self.targets(),
            "timeouts": sum(self.timeouts.values()),
            "timeouts_by_robot": dict(self.timeouts),
            "report_timeouts": self.report_timeouts,
            "stale": self.stale,
            "bad_messages": self.bad_messages,
            "unserved": sorted(self.unserved),
            "wall": {
                "wall_s": wall_s,
                "steps_per_s": self.k / wall_s if wall_s > 0 else None,
                "real_time_factor": sim_s / wall_s if wall_s > 0 else None,
            },
        }


def write_atomic(path: Path, data: dict[str, Any]) -> None:
    """Write JSON so that a reader sees the old file or the whole new one, never a part."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            json.dump(data, out)
            out.write("\n")
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
