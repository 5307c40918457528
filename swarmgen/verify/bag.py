"""A counterexample as a ROS 2 bag (`--counterexample DIR` writes the directory `DIR/<code>/bag`), in
the format of replay and simulation bags (`swarmgen.trace`): the swarm's events on
`/swarm/events` and each member's active states, so `swarmgen timeline` and rosbags read it.

Stamps are virtual, as in replay bags: step n of the trace happens n seconds after the start,
the k-th event it sends k ms later, and the member's states after the step 1 ms after its last
event; every member's initial states are at 0 s. The same trace gives a byte-identical bag.
"""

from __future__ import annotations

import shutil
from collections.abc import Mapping
from pathlib import Path

from swarmgen.trace.recorder import BURST_NS, STEP_NS, BagRecorder, VirtualClock
from swarmgen.verify.counterexample import Trace

BAG_NAME = "bag"  # a rosbag2 directory (a `.bag` name would be read as a ROS 1 bag file)


def write_bag(trace: Trace, path: Path) -> Path:
    """The trace's events and state changes as a bag at `path` (a directory, replaced)."""
    if path.exists():
        shutil.rmtree(path)
    events: dict[int, list[tuple[str, object, str]]] = {}
    for number, name, data, sender in trace.events:
        events.setdefault(number, []).append((name, data, sender))
    records: list[tuple[int, int, str, object, str]] = []  # stamp, order, what, data, who
    for number, sends in events.items():
        for k, (name, data, sender) in enumerate(sends):
            records.append((number * STEP_NS + k * BURST_NS, len(records), name, data, sender))
    for number, member, active in trace.states:
        stamp = number * STEP_NS + len(events.get(number, ())) * BURST_NS
        records.append((stamp, len(records), "", active, member))
    with BagRecorder(path, clock=VirtualClock()) as recorder:
        for stamp, _, name, data, who in sorted(records, key=lambda r: r[:2]):
            if name:
                fields = data if isinstance(data, Mapping) else None
                recorder.record_event(name, fields, who, stamp)
            else:
                assert isinstance(data, tuple)
                recorder.record_states(who, data, stamp)
    return path
