"""One-shot callbacks on one ROS timer, shared by the nodes of a process.

Times are seconds on the scheduler's clock: `time.monotonic()`, or under `use_sim_time` (the
standard ROS parameter, e.g. `--ros-args -p use_sim_time:=true` for every node of a process)
the simulated time of `/clock`, so model timers, scripted behaviours and the station program run
on simulated time; the ROS timer follows the node's clock in both cases.
"""

from __future__ import annotations

import heapq
import itertools
import time
from collections.abc import Callable
from typing import Any

from rclpy.node import Node
from rclpy.timer import Timer


class Handle:
    """A scheduled callback; `cancel` keeps it from running."""

    __slots__ = ("callback", "cancelled", "when")

    def __init__(self, when: int, callback: Callable[[], None]) -> None:
        self.when = when  # integer nanoseconds on the scheduler's clock
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        """The callback will not run."""
        self.cancelled = True


class Scheduler:
    """`call_later` on a single rclpy timer, re-armed for the earliest deadline.

    rclpy slows down (and warns) with many timers on one clock, and scripted behaviours and model
    timers need many short-lived delays; so a process shares one scheduler between its nodes.
    Callbacks run in the executor, like every other callback.
    """

    def __init__(self, node: Node) -> None:
        # deadlines in integer nanoseconds: a float deadline a rounding above a /clock stamp
        # would fire one simulated step late, depending on when the timer was armed
        self._heap: list[tuple[int, int, Handle]] = []
        self._order = itertools.count()
        self._armed: int | None = None
        self._logger = node.get_logger()
        self._timer: Timer = node.create_timer(3600.0, self._fire, autostart=False)
        self._clock = node.get_clock()
        self.simulated = bool(node.get_parameter("use_sim_time").value)
        self.lockstep: Any = None  # the process's `lockstep.Lockstep`, when the barrier is on

    def now(self) -> float:
        """Seconds on the scheduler's clock (simulated under `use_sim_time`)."""
        return self.now_ns() / 1e9

    def now_ns(self) -> int:
        """Integer nanoseconds on the scheduler's clock."""
        return int(self._clock.now().nanoseconds) if self.simulated else time.monotonic_ns()

    def call_later(self, delay: float, callback: Callable[[], None]) -> Handle:
        """Run `callback` in the executor after `delay` seconds (at once for 0 or less)."""
        handle = Handle(self.now_ns() + max(0, round(delay * 1e9)), callback)
        heapq.heappush(self._heap, (handle.when, next(self._order), handle))
        self._arm()
        return handle

    def reached(self, t_ns: int) -> bool:
        """The clock is at `t_ns` (nanoseconds) or later."""
        return bool(self._clock.now().nanoseconds >= t_ns)

    def due(self) -> bool:
        """A callback is due: the timer is ready, its callback has not run yet."""
        if self._armed is None:
            return False
        left = self._timer.time_until_next_call()
        return left is not None and left <= 0

    def __len__(self) -> int:
        return sum(1 for _, _, h in self._heap if not h.cancelled)

    def _arm(self) -> None:
        while self._heap and self._heap[0][2].cancelled:
            heapq.heappop(self._heap)
        if not self._heap:
            if self._armed is not None:
                self._timer.cancel()
                self._armed = None
            return
        when = self._heap[0][0]
        if self._armed is not None and self._armed <= when:
            return  # already armed for this deadline or an earlier one
        self._timer.timer_period_ns = max(1000, when - self.now_ns())
        self._timer.reset()
        self._armed = when

    def _fire(self) -> None:
        self._armed = None
        now = self.now_ns()
        while self._heap and self._heap[0][0] <= now:
            _, _, handle = heapq.heappop(self._heap)
            if handle.cancelled:
                continue
            handle.cancelled = True
            try:
                handle.callback()
            except Exception as err:  # a failing callback must not stop the others
                self._logger.error(f"scheduled callback failed: {err!r}")
        self._arm()
        if self.lockstep is not None:
            self.lockstep.check()  # what the callbacks did, reported at once
