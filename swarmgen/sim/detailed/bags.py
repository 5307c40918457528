"""`--record` at the detailed level: a run's swarm trace as a ROS 2 bag, in the format of the
abstract level's bags (`swarmgen.trace`: `/swarm/events` and each member's `active_states`,
stamped with simulated time), read back by `swarmgen timeline` and rosbags alike.

The swarm process runs with `--trace --events`: one JSON line per member step (`t`, `member`,
`active`) and per swarm event (`t`, `sender`, `name`, `data`), `t` in simulated seconds; the
bag is written from those lines after the run, so recording costs the run nothing.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from swarmgen.trace.recorder import BagRecorder

NS = 1_000_000_000


def record_run(log: Path, bag: Path, storage: str) -> int:
    """Write the trace lines of `log` into the new bag `bag`; the number of records."""
    written = 0
    with BagRecorder(bag, storage=storage, clock=lambda: 0) as recorder:
        for line in log.read_text(encoding="utf-8", errors="replace").splitlines():
            record = _record(line)
            if record is None:
                continue
            stamp = round(float(record["t"]) * NS)
            if "member" in record and "active" in record:
                recorder.record_states(str(record["member"]), record["active"], stamp)
            elif "name" in record and "sender" in record:
                data = record.get("data")
                recorder.record_event(
                    str(record["name"]), data if isinstance(data, dict) else {},
                    str(record["sender"]), stamp,
                )  # fmt: skip
            else:
                continue
            written += 1
    return written


def _record(line: str) -> dict[str, Any] | None:
    """A trace line's JSON object with a numeric `t`, else None (log text, the summary)."""
    if not line.startswith("{"):
        return None
    try:
        record = json.loads(line)
    except ValueError:
        return None
    if not isinstance(record, dict) or not isinstance(record.get("t"), int | float):
        return None
    return record
