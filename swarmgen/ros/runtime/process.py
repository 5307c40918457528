"""Running nodes in a process: ROS arguments, the executor, and spinning it in this thread."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence

import rclpy
from rclpy.context import Context as RosContext
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.experimental.events_executor import EventsExecutor


def ros_args(argv: Sequence[str] | None) -> list[str]:
    """The arguments rclpy parses (`--ros-args ...`): the process's own, or `argv`."""
    return list(sys.argv if argv is None else ["member", *argv])


def init_process(argv: Sequence[str] | None) -> tuple[RosContext, SingleThreadedExecutor]:
    """rclpy started on the default context (SIGINT/SIGTERM then end it cleanly), and an
    executor for the process's one node (a launch file's executable)."""
    context = rclpy.get_default_context()
    rclpy.init(args=ros_args(argv), context=context)
    return context, SingleThreadedExecutor(context=context)


def make_executor(kind: str, context: RosContext | None = None) -> Executor:
    """`events`: rclpy's EventsExecutor (no wait set rebuilt per callback: much faster with many
    entities); `single`: the SingleThreadedExecutor. Either is spun in the calling thread only
    (an EventsExecutor spun in another thread hangs on shutdown)."""
    if kind == "events":
        return EventsExecutor(context=context)
    return SingleThreadedExecutor(context=context)


def spin_until(
    executor: Executor,
    done: Callable[[], bool],
    timeout: float | None = None,
    step: float = 0.1,
) -> bool:
    """Spin in this thread until `done()` or the timeout; False on timeout.

    A SIGINT/SIGTERM shuts the context down from rclpy's signal handler, possibly between two
    `spin_once` calls: the next one then fails inside rcl ("context is not valid") instead of
    raising ExternalShutdownException. Both are the same clean shutdown to every caller."""
    deadline = None if timeout is None else time.monotonic() + timeout
    while not done():
        if deadline is not None and time.monotonic() > deadline:
            return False
        try:
            executor.spin_once(timeout_sec=step)
        except Exception:
            if executor.context.ok():
                raise
            raise ExternalShutdownException() from None
    return True
