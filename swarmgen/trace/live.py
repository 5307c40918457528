"""Record a live ROS 2 swarm into a bag: `/swarm/events` and every member's `active_states`,
subscribed raw (the CDR bytes exactly as on the wire go into the bag, nothing is re-encoded).

In a process that already has a node (the swarm launcher, a test's station):

    recorder = BagRecorder(out, package="<swarm>_interfaces")
    live = LiveRecorder(node, recorder, "<swarm>_interfaces")   # members found automatically
    ...spin...
    recorder.close()

or as its own process, next to a running swarm (stops on SIGINT/SIGTERM or after --duration):

    python -m swarmgen.trace.live OUT --package <swarm>_interfaces [--members uav_1,ugv_1]
        [--storage mcap|sqlite3] [--duration SECONDS]

The bag stores the messages under the interface package's own type names
(`<swarm>_interfaces/msg/Event`, `.../ActiveStates`, whose definitions are swarmgen's), so
`ros2 bag play` can feed them back to live nodes, and `swarmgen timeline` reads them. Bag time is
the recorder's clock on receipt; the messages keep the publishers' stamps.
"""

from __future__ import annotations

import argparse
import importlib
import signal
import sys
import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from swarmgen.trace.bag import EVENTS_TOPIC, STATES_TOPIC
from swarmgen.trace.recorder import BagRecorder

__all__ = ["LiveRecorder", "main"]

DISCOVERY_PERIOD_S = 0.2


def _qos() -> tuple[Any, Any]:
    """(events QoS, states QoS) compatible with the member nodes' publishers."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    events = QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=1000,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.VOLATILE,
    )
    # TRANSIENT_LOCAL: the configuration a member published before the recorder started
    states = QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=100,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
    return events, states


class LiveRecorder:
    """Raw subscriptions of `node` that write into `recorder`. `members`: member namespaces to
    record at once; with `discover` (default) every `<ns>/active_states` topic of the package's
    ActiveStates type that appears later is recorded too."""

    def __init__(
        self,
        node: Any,
        recorder: BagRecorder,
        package: str,
        members: Iterable[str] = (),
        *,
        discover: bool = True,
    ) -> None:
        msg = importlib.import_module(f"{package}.msg")
        self.node = node
        self.recorder = recorder
        self.package = package
        self.event_type = f"{package}/msg/Event"
        self.states_type = f"{package}/msg/ActiveStates"
        self._states_class = msg.ActiveStates
        self._events_qos, self._states_qos = _qos()
        self.topics: set[str] = set()
        self.received = 0
        self._subscriptions: list[Any] = [
            node.create_subscription(
                msg.Event,
                EVENTS_TOPIC,
                lambda raw: self._write(EVENTS_TOPIC, self.event_type, raw),
                self._events_qos,
                raw=True,
            )
        ]
        for member in members:
            self.add_states_topic(f"/{member.strip('/')}/{STATES_TOPIC}")
        if discover:
            self._timer = node.create_timer(DISCOVERY_PERIOD_S, self.discover)
            self.discover()

    def add_states_topic(self, topic: str) -> None:
        """Record an `active_states` topic (once)."""
        if topic in self.topics:
            return
        self.topics.add(topic)
        self._subscriptions.append(
            self.node.create_subscription(
                self._states_class,
                topic,
                lambda raw: self._write(topic, self.states_type, raw),
                self._states_qos,
                raw=True,
            )
        )

    def discover(self) -> None:
        """Record every member's `active_states` topic the graph shows now."""
        for topic, types in self.node.get_topic_names_and_types():
            if topic.endswith(f"/{STATES_TOPIC}") and self.states_type in types:
                self.add_states_topic(topic)

    def _write(self, topic: str, msgtype: str, raw: bytes) -> None:
        self.received += 1
        self.recorder.write_raw(topic, msgtype, bytes(raw), self.node.get_clock().now().nanoseconds)


def main(argv: Sequence[str] | None = None) -> int:
    """Record a running swarm into a bag until SIGINT/SIGTERM or `--duration`; the exit status."""
    parser = argparse.ArgumentParser(prog="python -m swarmgen.trace.live", description=__doc__)
    parser.add_argument("out", type=Path, help="the new bag directory")
    parser.add_argument("--package", required=True, help="the swarm's interface package")
    parser.add_argument("--members", default="", help="member namespaces, comma-separated")
    parser.add_argument("--storage", choices=["mcap", "sqlite3"], default="mcap")
    parser.add_argument("--duration", type=float, default=None, help="stop after these seconds")
    options = parser.parse_args(argv)

    import rclpy
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    stop = False

    def request_stop(*_: object) -> None:
        nonlocal stop
        stop = True

    signal.signal(signal.SIGINT, request_stop)
    signal.signal(signal.SIGTERM, request_stop)
    node = rclpy.create_node("swarmgen_recorder")
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    members = [m for m in options.members.split(",") if m.strip()]
    deadline = None if options.duration is None else time.monotonic() + options.duration
    with BagRecorder(options.out, storage=options.storage, package=options.package) as recorder:
        live = LiveRecorder(node, recorder, options.package, members)
        print(f"recording into {options.out}", file=sys.stderr, flush=True)
        try:
            while not stop and (deadline is None or time.monotonic() < deadline):
                executor.spin_once(timeout_sec=0.05)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            executor.shutdown()
            node.destroy_node()
            rclpy.try_shutdown()
    print(f"recorded {live.received} message(s) into {options.out}", file=sys.stderr, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
