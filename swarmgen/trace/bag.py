"""Swarm traces as ROS 2 bags: the format the recorder writes and the reader reads.

One bag per run, mcap by default or sqlite3:

- every event on `/swarm/events`, type `swarmgen_msgs/msg/Event` (id, stamp, sender, name,
  data = JSON object of the event's fields);
- every state change of a member on `/<member>/active_states`, type
  `swarmgen_msgs/msg/ActiveStates` (stamp, member, states).

Both definitions are swarmgen's own (`swarmgen.ros.interfaces.EVENT_MSG`, `ACTIVE_STATES_MSG`,
the ones the generated ROS 2 interface packages use) and are stored in the bag, so rosbags'
`AnyReader` and the ROS 2 tools read the bag without swarmgen. Bag time and message stamps are the
events' own timestamps (or a clock you pass, e.g. a `VirtualClock`), so the same events with the
same timestamps give byte-identical bags.

Writing: `swarmgen.trace.recorder` (`BagRecorder`, `record_replay`). Reading:
`swarmgen.trace.reader` (`read_events`, `read_run`), also of legacy CPSwarm ROS 1 bags.
"""

from __future__ import annotations

import re

from swarmgen.errors import SwarmgenError

__all__ = [
    "ACTIVE_STATES_TYPE",
    "BAG_SUFFIXES",
    "EVENTS_TOPIC",
    "EVENT_TYPE",
    "PACKAGE",
    "STATES_TOPIC",
    "STORAGES",
    "TraceError",
    "states_topic",
]

PACKAGE = "swarmgen_msgs"
EVENT_TYPE = f"{PACKAGE}/msg/Event"
ACTIVE_STATES_TYPE = f"{PACKAGE}/msg/ActiveStates"
EVENTS_TOPIC = "/swarm/events"
STATES_TOPIC = "active_states"
STORAGES = ("mcap", "sqlite3")
BAG_SUFFIXES = (".bag", ".mcap", ".db3")  # ROS 1 bag; rosbag2 storage files without metadata
_TOKEN = re.compile(r"[^A-Za-z0-9_]+")


class TraceError(SwarmgenError):
    """A bag cannot be written or read (a user error: path exists, not a bag, corrupt)."""


def states_topic(member: str) -> str:
    """`/<member>/active_states`, the member id made a valid ROS 2 name token."""
    token = re.sub(r"_+", "_", _TOKEN.sub("_", member)).strip("_") or "member"
    if token[0].isdigit():
        token = f"m{token}"
    return f"/{token}/{STATES_TOPIC}"
