"""Swarm traces as ROS 2 bags: the format the recorder writes and the reader reads.

One bag per run, mcap by default or sqlite3:

- every event on `/swarm/events`, type `swarmgen_msgs/msg/Event` (id, stamp, sender, name,
  data = JSON object of the event's fields);
- every state change of a member on `/<member>/active_states`, type
  `swarmgen_msgs/msg/ActiveStates` (stamp, member, states).
- feedback of a member's declared actions on `/<member>/feedback`, type
  `swarmgen_msgs/msg/Feedback` (stamp, member, state, behaviour, values = JSON object of the
  feedback message's fields, count = feedback messages coalesced into the record; `FEEDBACK_MSG`).

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
    "FEEDBACK_MSG",
    "FEEDBACK_TOPIC",
    "FEEDBACK_TYPE",
    "PACKAGE",
    "STATES_TOPIC",
    "STORAGES",
    "TraceError",
    "feedback_topic",
    "states_topic",
]

PACKAGE = "swarmgen_msgs"
EVENT_TYPE = f"{PACKAGE}/msg/Event"
ACTIVE_STATES_TYPE = f"{PACKAGE}/msg/ActiveStates"
EVENTS_TOPIC = "/swarm/events"
STATES_TOPIC = "active_states"
FEEDBACK_TYPE = f"{PACKAGE}/msg/Feedback"
FEEDBACK_TOPIC = "feedback"
# A declared action's feedback, as the rclpy nodes coalesce it (at most one per goal every
# 0.25 s, the latest values; `_ros/declared.py`, `FeedbackRecord`).
FEEDBACK_MSG = """builtin_interfaces/Time stamp
string member
string state
string behaviour
string values
uint32 count
"""
STORAGES = ("mcap", "sqlite3")
BAG_SUFFIXES = (".bag", ".mcap", ".db3")  # ROS 1 bag; rosbag2 storage files without metadata
_TOKEN = re.compile(r"[^A-Za-z0-9_]+")


class TraceError(SwarmgenError):
    """A bag cannot be written or read (a user error: path exists, not a bag, corrupt)."""


def _token(member: str) -> str:
    """The member id made a valid ROS 2 name token."""
    token = re.sub(r"_+", "_", _TOKEN.sub("_", member)).strip("_") or "member"
    return f"m{token}" if token[0].isdigit() else token


def states_topic(member: str) -> str:
    """`/<member>/active_states`, the member id made a valid ROS 2 name token."""
    return f"/{_token(member)}/{STATES_TOPIC}"


def feedback_topic(member: str) -> str:
    """`/<member>/feedback`, the member id made a valid ROS 2 name token."""
    return f"/{_token(member)}/{FEEDBACK_TOPIC}"
