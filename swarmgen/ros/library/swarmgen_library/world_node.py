"""The world node: `world.World` on rclpy, stepped in lockstep with the robots' servers.

`world WORLD.json` (console script) or `python -m swarmgen_library.world_node WORLD.json`.
Per step it publishes `/clock`, then per robot `camera` and `pose` (and the pose's extra
topics), waits for one stamped `cmd_vel` per served robot and one report per reporter (or
`step_timeout_s`), settles when a report asks, steps the world, and goes on as fast as the
answers come (not paced by the wall clock). It writes the result file atomically and exits 0
when the stop condition holds, 1 on SIGINT/SIGTERM (the result marked partial), 2 on a bad world
file or an output that cannot be written (one line, no traceback). The protocol: docs/detailed.md, "The ROS step"; the node and its
file: "The world node".
"""

from __future__ import annotations

import faulthandler
import importlib
import json
import signal
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from types import FrameType
from typing import Any

from .barrier import Barrier
from .worldfile import NS_PER_S, WorldFile, WorldFileError, load
from .worldrun import Run, write_atomic

POLL_S = 0.1  # longest blocking spin: how fast a signal is noticed
TEARDOWN_S = 15.0

FINAL_ACK_S = 5.0  # how long the final /world/status waits for every subscriber's ack


class Interrupted(Exception):
    """SIGINT or SIGTERM arrived: end the run, marked partial."""


def _msg(package: str, name: str) -> Any:
    """A message class by name (message packages ship no type information)."""
    return getattr(importlib.import_module(f"{package}.msg"), name)


class WorldNode:
    """The rclpy side of a run: publishers, subscriptions and the lockstep loop."""

    def __init__(self, config: WorldFile, context: Any) -> None:
        """Create the node, its topics and the executor on an initialised `context`."""
        import rclpy
        from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

        self.config = config
        self.run = Run(config)
        self.signalled: int | None = None
        # reliable, keep-last 10: a server is never more than one pose behind (the world waits
        # for its answer), so 10 only matters after timeouts, when old poses are stale anyway
        qos = QoSProfile(
            depth=10, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE
        )
        self.node = rclpy.create_node("world", context=context)
        self.executor = _executor(config, context)
        self.executor.add_node(self.node)
        string = _msg("std_msgs", "String")
        pose = _msg("geometry_msgs", "PoseStamped")
        twist = _msg("geometry_msgs", "TwistStamped")
        self._string = string
        self.clock_msg = _msg("rosgraph_msgs", "Clock")()
        self.clock_pub = self.node.create_publisher(type(self.clock_msg), "/clock", qos)
        self.status_pub = self.node.create_publisher(string, "/world/status", qos)
        self.cmd_topics: dict[str, str] = {}
        self.own: dict[str, int] = {}  # the barrier's channels the world sends on: counts
        self.outputs: list[tuple[str, Any, Any, list[Any]]] = []
        for topics in config.topics:
            ns = f"/{topics.namespace}"
            message = pose()
            message.header.frame_id = "map"
            message.pose.orientation.w = 1.0
            extra = [self.node.create_publisher(pose, f"{ns}/{t}", qos) for t in topics.pose_topics]
            camera = self.node.create_publisher(string, f"{ns}/camera", qos)
            main = self.node.create_publisher(pose, f"{ns}/pose", qos)
            self.outputs.append((topics.name, message, camera, [main, *extra]))
            for t in topics.pose_topics:  # reactive for the members: counted by the barrier
                self.own[f"{ns}/{t}"] = 0
            self.cmd_topics[topics.name] = f"{ns}/cmd_vel"
            self.node.create_subscription(twist, f"{ns}/cmd_vel", self._on_cmd(topics.name), qos)
        self.node.create_subscription(string, "/world/settle", self._on_report, qos)
        self.node.create_subscription(string, "/world/rescue", self._on_rescue, qos)
        self.reporters = len(config.reporters) or config.settle_reporters
        self.barrier = Barrier(config.reporters) if config.barrier else None
        self.probe_pub = self.node.create_publisher(string, "/world/settle/probe", qos)
        self.phase = "step"  # the barrier's phase of the current step: `clock`, then `step`

    # --- callbacks

    def _on_cmd(self, robot: str) -> Callable[[Any], None]:
        run = self.run

        def on_cmd(msg: Any) -> None:
            stamp, linear = msg.header.stamp, msg.twist.linear
            run.answer(robot, stamp.sec * NS_PER_S + stamp.nanosec, linear.x, linear.y, linear.z)

        return on_cmd

    def _on_report(self, msg: Any) -> None:
        if self.barrier is not None:
            self.barrier.report(msg.data)  # a wave's report (older ones are dropped)
        else:
            self.run.report(msg.data)

    def _on_rescue(self, msg: Any) -> None:
        self.run.rescue(msg.data)

    # --- the loop

    def spin_until(self, done: Callable[[], bool], seconds: float) -> bool:
        """Handle messages until `done()` or `seconds` of wall time; whether done."""
        deadline = time.monotonic() + seconds
        while not done():
            if self.signalled is not None:
                raise Interrupted()
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            self.executor.spin_once(timeout_sec=min(left, POLL_S))
        return True

    def wait_start(self) -> None:
        """Wait until every robot's server, every reporter and every status reader is there (or
        the start timeout): the robots still missing then start unserved."""

        def ready() -> bool:
            return (not self._missing() and self._live_reporters() >= self.reporters
                    and self._counted_topics_matched() and self._status_readers_matched())  # fmt: skip

        self.spin_until(ready, self.config.start_timeout_s)
        self.run.unserved = set(self._missing())
        self.reporters = min(self.reporters, self._live_reporters())
        if self.barrier is not None:
            self.reporters = 0  # the barrier waits for its reporters itself

    def _missing(self) -> list[str]:
        missing = []
        for name, _, _, pubs in self.outputs:
            if pubs[0].get_subscription_count() == 0 or not self._served(name):
                missing.append(name)
        return missing

    def _counted_topics_matched(self) -> bool:
        """With the barrier, every reporter hears the probes and every extra pose topic (counted:
        members subscribe to it) has its subscriber: a step-0 message sent before the match
        would be lost, a barrier timeout."""
        if self.barrier is None:
            return True
        if self.probe_pub.get_subscription_count() < len(self.config.reporters):
            return False  # a reporter that misses the first probe would not answer step 0
        return all(p.get_subscription_count() > 0 for *_, pubs in self.outputs for p in pubs[1:])

    def _status_readers_matched(self) -> bool:
        return bool(self.status_pub.get_subscription_count() >= self.config.status_readers)

    def status_unmatched(self) -> int:
        """How many of the world file's status readers the final status would miss, after
        waiting (bounded) for the late ones: DDS discovers them in its own threads, so nothing
        is spun and no message is handled after the last step."""
        deadline = time.monotonic() + (FINAL_ACK_S if self.signalled is None else 0.0)
        while not self._status_readers_matched() and time.monotonic() < deadline:
            time.sleep(POLL_S)
        return max(0, self.config.status_readers - int(self.status_pub.get_subscription_count()))

    def _served(self, robot: str) -> bool:
        return bool(self.node.count_publishers(self.cmd_topics[robot]) > 0)

    def _live_reporters(self) -> int:
        return int(self.node.count_publishers("/world/settle"))

    def run_loop(self) -> str:
        """Step until the stop condition; its reason."""
        run = self.run
        while True:
            reason = run.stop_reason()
            if reason is not None:
                return reason
            if run.k % self.config.status_every == 0:
                self.publish_status(final=False)
            self.step_once()

    def step_once(self) -> None:
        """One lockstep step: publish, collect the answers, settle, step the world."""
        run = self.run
        run.begin_step()
        for name in [n for n in run.unserved if self._served(n)]:
            run.unserved.discard(name)  # a server came (back): wait for it again
        if self.barrier is None and self.reporters < self.config.settle_reporters:
            self.reporters = min(self.config.settle_reporters, self._live_reporters())
        if self.barrier is not None:
            # phase 1: the clock alone, and what the members do on it (timers, station events)
            # settles first, so the servers hold those goals before they act on step k
            self.publish_clock()
            self.phase = "clock"
            self.probe(self.barrier.begin(run.k, self.own))
            if not self.spin_until(self._barrier_done, self.config.barrier_timeout_s):
                self.barrier.timed_out()
            self.publish_step(clock=False)
            self.phase = "step"  # phase 2: the servers act on step k; the reactions settle
            self.probe(self.barrier.next_phase(self.own))
        else:
            self.publish_step()

        def complete() -> bool:
            return not run.waiting_for() and len(run.reporters) >= self.reporters

        if not self.spin_until(complete, self.config.step_timeout_s):
            self._after_timeout()
        run.apply()
        if self.barrier is not None:
            if not self.spin_until(self._barrier_done, self.config.barrier_timeout_s):
                self.barrier.timed_out()
        elif run.settle and self.config.settle_s > 0:
            self.spin_until(lambda: False, self.config.settle_s)
        run.advance()

    def _barrier_done(self) -> bool:
        """The barrier's decision on what has arrived; a new wave is asked for at once."""
        assert self.barrier is not None
        decision = self.barrier.decide()
        if decision == "probe":
            self.probe(self.barrier.wave.number)
        return decision == "done"

    def probe(self, wave: int) -> None:
        """Ask every reporter for its report of `wave` of the current step."""
        text = json.dumps({"k": self.run.k, "wave": wave, "t_ns": self.run.t_ns,
                           "phase": self.phase})  # fmt: skip
        self.probe_pub.publish(self._string(data=text))

    def _after_timeout(self) -> None:
        """A robot without any cmd_vel publisher is unserved from now on; a reporter that is
        gone is no longer waited for."""
        run = self.run
        for name in run.waiting_for():
            if not self._served(name):
                run.unserved.add(name)
                run.timeouts[name] += 1  # its last timeout: not waited for from now on
        if len(run.reporters) < self.reporters:
            run.report_timeouts += 1
            self.reporters = min(self.reporters, self._live_reporters())

    def publish_clock(self) -> None:
        """`/clock` at the current step."""
        sec, nanosec = divmod(self.run.t_ns, NS_PER_S)
        self.clock_msg.clock.sec, self.clock_msg.clock.nanosec = sec, nanosec
        self.clock_pub.publish(self.clock_msg)

    def publish_step(self, clock: bool = True) -> None:
        """`/clock` (unless published already), then per robot its camera and its pose (on
        every pose topic)."""
        run, world = self.run, self.run.world
        sec, nanosec = divmod(run.t_ns, NS_PER_S)
        if clock:
            self.publish_clock()
        k, t = run.k, world.time
        camera_msg = self._string()
        for name, message, camera, pubs in self.outputs:
            seen = [{"id": s.id, "x": s.x, "y": s.y} for s in world.visible(name)]
            camera_msg.data = json.dumps({"k": k, "t": t, "targets": seen})
            camera.publish(camera_msg)
            pose = world.pose(name)
            message.header.stamp.sec, message.header.stamp.nanosec = sec, nanosec
            position = message.pose.position
            position.x, position.y, position.z = pose.x, pose.y, pose.z
            for pub in pubs:
                pub.publish(message)
        for topic in self.own:
            self.own[topic] += 1

    def publish_status(self, final: bool) -> None:
        """The `/world/status` message (the final one is waited for: the node ends next)."""
        self.status_pub.publish(self._string(data=json.dumps(self.run.status(final))))
        if final:
            from rclpy.duration import Duration

            # bounded, and over at once when acknowledged; 1 s was seen to lose it under load
            self.status_pub.wait_for_all_acked(Duration(seconds=FINAL_ACK_S))

    def result(self, reason: str, wall_s: float) -> dict[str, Any]:
        """The run's result, with the barrier's timeouts (and, timing only, its waves)."""
        result = self.run.result(reason, wall_s)
        result["status_unmatched"] = self.status_unmatched()
        if self.barrier is not None:
            result["barrier_timeouts"] = self.barrier.timeouts
            result["wall"]["waves"] = self.barrier.waves  # how many depends on timing
            result["wall"]["barrier_stuck"] = self.barrier.stuck[:20]
        return result

    def close(self) -> None:
        """Destroy the node and the executor."""
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()


def _executor(config: WorldFile, context: Any) -> Any:
    """rclpy's EventsExecutor (spun in this thread only), or the SingleThreadedExecutor."""
    if config.executor == "single":
        from rclpy.executors import SingleThreadedExecutor

        return SingleThreadedExecutor(context=context)
    from rclpy.experimental.events_executor import EventsExecutor

    return EventsExecutor(context=context)


def run_world(config: WorldFile) -> int:
    """Run one world file to its end; the exit code (0 complete, 1 interrupted, 2 the result
    could not be written)."""
    import rclpy
    from rclpy.signals import SignalHandlerOptions

    context = rclpy.context.Context()
    # our own handlers: the loop notices a signal within POLL_S and still writes the result
    rclpy.init(args=["world"], context=context, signal_handler_options=SignalHandlerOptions.NO)
    node = WorldNode(config, context)

    def on_signal(signum: int, frame: FrameType | None) -> None:
        node.signalled = signum

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    started = time.monotonic()
    try:
        node.wait_start()
        started = time.monotonic()  # the rate counts stepping, not discovery
        reason = node.run_loop()
    except Interrupted:
        reason = "signal"
    wall_s = time.monotonic() - started
    code = 1 if reason == "signal" else 0
    try:
        write_atomic(config.output, node.result(reason, wall_s))
    except OSError as err:  # checked at the start; gone since (disk full, folder removed)
        print(f"world: output: cannot write {config.output}: {err.strerror or err}",
              file=sys.stderr)  # fmt: skip
        code = 2
    # the result is safe; a teardown that wedges in rcl (seen once, with the single-threaded
    # executor) must not keep the process: dump where it hangs and exit
    faulthandler.dump_traceback_later(TEARDOWN_S, exit=True)
    node.publish_status(final=True)
    node.close()
    rclpy.shutdown(context=context)
    faulthandler.cancel_dump_traceback_later()
    for signum, handler in previous.items():  # a signal in the teardown changes nothing now
        signal.signal(signum, handler)
    return code


def main(argv: Sequence[str] | None = None) -> int:
    """The console script `world WORLD.json`."""
    args = list(sys.argv[1:] if argv is None else argv)
    args = args[: args.index("--ros-args")] if "--ros-args" in args else args
    if len(args) != 1:
        print("usage: world WORLD.json", file=sys.stderr)
        return 2
    try:
        config = load(Path(args[0]))
    except WorldFileError as err:
        print(f"world: {err}", file=sys.stderr)
        return 2
    return run_world(config)


if __name__ == "__main__":
    sys.exit(main())
