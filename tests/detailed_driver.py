"""A scripted driver for the world node (tests/test_detailed_world.py): a real rclpy node that
answers every pose with a fixed stamped velocity, the way the behaviour servers do.

`python -m tests.detailed_driver CONFIG.json`, the config:
- `robots`: the robots' namespaces; `dt`: the world's step (to tell k from a stamp);
- `velocity`: [vx, vy, vz] for every robot, or {namespace: [vx, vy, vz]};
- `answer_until`: the last step answered (null: all), to make the world time out;
- `report`: publish one `/world/settle` report per step (`by` "driver"), `settle` true for the
  steps in `settle_at`;
- `record`: keep every pose and clock (false for long runs); `out`: where the summary goes.
It ends on the world's final `/world/status`, or on SIGINT/SIGTERM, and writes the summary:
the poses per robot ([stamp_ns, x, y, z]), the clocks seen, the counts, the final status.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import rclpy
from geometry_msgs.msg import PoseStamped, TwistStamped  # type: ignore[import-untyped]
from rclpy.executors import ExternalShutdownException
from rclpy.experimental.events_executor import EventsExecutor
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock  # type: ignore[import-untyped]
from std_msgs.msg import String  # type: ignore[import-untyped]

NS = 1_000_000_000
QOS = QoSProfile(depth=10, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE)


class Driver:
    """The driver node and what it saw."""

    def __init__(self, config: dict[str, Any]) -> None:
        self.config = config
        self.dt_ns = round(config["dt"] * NS)
        self.node = rclpy.create_node("detailed_driver")
        self.record = config.get("record", True)
        self.poses: dict[str, list[list[float]]] = {ns: [] for ns in config["robots"]}
        self.clock: list[int] = []
        self.counts = {"poses": 0, "cameras": 0, "clocks": 0, "answers": 0, "reports": 0}
        self.answered: dict[int, set[str]] = {}
        self.final: dict[str, Any] | None = None
        self.settle_pub = self.node.create_publisher(String, "/world/settle", QOS)
        self.pubs = {}
        for ns in config["robots"]:
            self.pubs[ns] = self.node.create_publisher(TwistStamped, f"/{ns}/cmd_vel", QOS)
            self.node.create_subscription(PoseStamped, f"/{ns}/pose", self._on_pose(ns), QOS)
            self.node.create_subscription(String, f"/{ns}/camera", self._on_camera, QOS)
        self.node.create_subscription(Clock, "/clock", self._on_clock, QOS)
        self.node.create_subscription(String, "/world/status", self._on_status, QOS)

    def velocity(self, ns: str) -> list[float]:
        v = self.config["velocity"]
        return list(v[ns] if isinstance(v, dict) else v)

    def _on_pose(self, ns: str) -> Any:
        def on_pose(msg: Any) -> None:
            stamp = msg.header.stamp.sec * NS + msg.header.stamp.nanosec
            p = msg.pose.position
            self.counts["poses"] += 1
            if self.record:
                self.poses[ns].append([stamp, p.x, p.y, p.z])
            k = round(stamp / self.dt_ns)
            until = self.config.get("answer_until")
            if until is not None and k > until:
                return
            answer = TwistStamped()
            answer.header.stamp = msg.header.stamp  # the step it answers (the contract)
            linear = answer.twist.linear
            linear.x, linear.y, linear.z = self.velocity(ns)
            self.pubs[ns].publish(answer)
            self.counts["answers"] += 1
            done = self.answered.setdefault(k, set())
            done.add(ns)
            if self.config.get("report") and len(done) == len(self.pubs):
                settle = k in self.config.get("settle_at", [])
                report = {"k": k, "by": "driver", "settle": settle}
                self.settle_pub.publish(String(data=json.dumps(report)))
                self.counts["reports"] += 1
                del self.answered[k]

        return on_pose

    def _on_camera(self, msg: Any) -> None:
        self.counts["cameras"] += 1

    def _on_clock(self, msg: Any) -> None:
        self.counts["clocks"] += 1
        if self.record:
            self.clock.append(msg.clock.sec * NS + msg.clock.nanosec)

    def _on_status(self, msg: Any) -> None:
        status = json.loads(msg.data)
        if status.get("final"):
            self.final = status

    def summary(self) -> dict[str, Any]:
        return {
            "poses": self.poses,
            "clock": self.clock,
            "counts": self.counts,
            "final": self.final,
        }


def main() -> int:
    config = json.loads(Path(sys.argv[1]).read_text(encoding="utf-8"))
    rclpy.init()
    driver = Driver(config)
    executor = EventsExecutor()
    executor.add_node(driver.node)
    print(json.dumps({"event": "ready"}), flush=True)
    try:
        while driver.final is None:
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        if rclpy.ok():
            raise  # a real error; a signal between two spins is a clean shutdown
    Path(config["out"]).write_text(json.dumps(driver.summary()), encoding="utf-8")
    executor.shutdown(timeout_sec=1.0)
    driver.node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
