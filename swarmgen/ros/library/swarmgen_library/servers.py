"""`servers SERVERS.json`: the behaviour servers process (its nodes are in `members`, the
algorithms in `sar_servers`); one module for the entry point, so neither of those imports the
other's user."""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from pathlib import Path

import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node

from .members import MemberNode, Swarm
from .sar_servers import attach, check
from .servers_config import ConfigError, ServersConfig, load


def serve(config: ServersConfig) -> int:
    """Run the servers until SIGINT/SIGTERM; 2 when a behaviour cannot be served."""
    try:
        check(config)
    except ConfigError as err:
        print(f"servers: {err}", file=sys.stderr)
        return 2
    rclpy.init()
    executor = SingleThreadedExecutor()
    nodes: list[Node] = []
    try:
        swarm = Swarm(config)
        nodes.append(swarm)
        # 0-based, over every member of the run in model order: the abstract world's index
        for index, member_config in enumerate(config.members):
            member = MemberNode(swarm, member_config, index)
            swarm.members[member.name] = member
            nodes.append(member)
            attach(member)
        for node in nodes:
            executor.add_node(node)
        print(json.dumps({"event": "ready", "members": list(swarm.members)}), flush=True)
        swarm.join_barrier(config.clients_timeout_s, lambda matched: _joined(swarm, matched))
        executor.spin()
    except ConfigError as err:
        print(f"servers: {err}", file=sys.stderr)
        return 2
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        # SIGINT/SIGTERM shut the context down between two callbacks; the next one's rcl call
        # (a timer's count_clients, seen under load) then fails: that is the shutdown, not a
        # fault. With the context still valid it is a real error.
        if rclpy.ok():
            raise
    finally:
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


def _joined(swarm: Swarm, matched: bool) -> None:
    """The servers take part in the world's steps from now on."""
    if not matched:
        swarm.get_logger().warning("not every behaviour server has its client yet: joining anyway")
    print(json.dumps({"event": "joined", "matched": matched}), flush=True)


def main(argv: Sequence[str] | None = None) -> int:
    """`servers SERVERS.json`."""
    args = list(sys.argv[1:] if argv is None else argv)
    args = rclpy.utilities.remove_ros_args(args)
    if len(args) != 1:
        print("usage: servers SERVERS.json", file=sys.stderr)
        return 2
    try:
        config = load(Path(args[0]))
    except ConfigError as err:
        print(f"servers: {err}", file=sys.stderr)
        return 2
    return serve(config)


if __name__ == "__main__":
    sys.exit(main())
