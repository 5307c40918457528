"""User behaviour implementations served over ROS 2: the plug-in point of the asyncio package
(entry points of `<model package>.behaviours`, `--library MODULE:FACTORY`, `--no-plugins`,
docs/plugins.md) for the `simulated_behaviours` node (docs/ros2.md, "User behaviour code").

A behaviour a user implementation exists for is served by it, on the same endpoint (private
action, declared action, service or subscribed topic: `servers.ScriptedServers`); the others
keep their scripted server. The implementations are coroutines of the runtime's `Library`
contract (typed ones adapted by `plugins.Plugins`); they run on one asyncio event loop in a
daemon thread per process (`UserLoop`), since rclpy's executors cannot run asyncio code and the
EventsExecutor cannot be woken from another thread (no guard conditions). What comes back (the
end of a goal, an emitted event) is queued and handled in the executor's thread, polled on the
process's `Scheduler` every `POLL_S` while goals run. A goal withdrawn (cancel request, state
left) cancels its coroutine and ends as cancelled at once; a coroutine that raises, returns no
`Outcome`, an undeclared outcome or outputs the interface cannot carry aborts its goal (a log
line, one of the node's `errors`), never the node.
"""

from __future__ import annotations

import argparse
import asyncio
import concurrent.futures
import queue
import sys
import threading
from collections.abc import Callable, Coroutine, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

from rclpy.utilities import remove_ros_args

from ...runtime.member import Behaviour, Library, Outcome, Request
from ...runtime.plugins import Chain, PluginError, Plugins, load_factory
from .process import ros_args
from .served import Served
from .simulated import SimulatedBehaviours, run_simulated
from .spec import BehaviourSpec, MemberSpec

POLL_S = 0.01  # how often the executor's thread takes what the user coroutines sent back


class UserLoop:
    """An asyncio event loop running in a daemon thread (one per process)."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(
            target=self.loop.run_forever, name="user-behaviours", daemon=True
        )
        self._thread.start()

    def submit(self, coroutine: Coroutine[Any, Any, Any]) -> concurrent.futures.Future[Any]:
        """Run `coroutine` on the loop; its future (cancelling it cancels the coroutine)."""
        return asyncio.run_coroutine_threadsafe(coroutine, self.loop)

    def close(self, timeout: float = 1.0) -> None:
        """Cancel what still runs and stop the loop (a coroutine ignoring its cancellation is
        left to the daemon thread)."""

        def cancel_all() -> None:
            for task in asyncio.all_tasks(self.loop):
                task.cancel()
            self.loop.call_later(0.1, self.loop.stop)

        if self.loop.is_running():
            self.loop.call_soon_threadsafe(cancel_all)
            self._thread.join(timeout)


def load_library(
    plugins: Plugins | None,
    library: str | None,
    no_plugins: bool,
    time_scale: float,
    prog: str,
) -> Library | None:
    """The user implementations: `--library`'s first, then the installed entry points (unless
    `no_plugins`); None when there are none. Raises PluginError for an unusable one."""
    found: list[Library] = []
    if library:
        try:
            factory = load_factory(library)
        except PluginError as err:
            raise PluginError(f"--library: {err}") from None
        made = factory(time_scale)
        if not callable(getattr(made, "get", None)):
            raise PluginError(f"--library {library}: the factory returned no Library")
        found.append(made)
    if plugins is not None and not no_plugins:
        installed, providers = plugins.load()
        if providers:
            listed = ", ".join(map(str, providers))
            print(f"{prog}: behaviours from plug-ins: {listed}", file=sys.stderr)
            found.append(installed)
    return Chain(*found) if found else None


@dataclass(eq=False)
class _Running:
    behaviour: BehaviourSpec
    served: Served
    future: concurrent.futures.Future[Any] | None = None


class UserBehaviours(SimulatedBehaviours):
    """`SimulatedBehaviours` whose behaviours `library` implements run the user's code."""

    def __init__(self, library: Library, loop: UserLoop, *args: Any, **kwargs: Any) -> None:
        self.library = library
        self.user_loop = loop
        self._inbox: queue.SimpleQueue[Callable[[], None]] = queue.SimpleQueue()
        self._running: dict[Any, _Running] = {}  # by `Served.key`
        self._polling = False
        super().__init__(*args, **kwargs)

    def _accepted(self, behaviour: BehaviourSpec, served: Served) -> None:
        implementation = self.library.get(behaviour.name)
        if implementation is None:
            super()._accepted(behaviour, served)
            return
        running = _Running(behaviour, served)
        self._running[served.key] = running
        try:
            request = self._request(behaviour, served)
            self.started.append((behaviour.name, "started"))
            served.running()
            future = self.user_loop.submit(_call(implementation, request))
        except Exception as err:  # inputs the interface cannot give: the goal fails
            self._fail(running, f"{behaviour.name}: the goal could not start: {err!r}")
            return
        running.future = future
        future.add_done_callback(lambda done: self._post(partial(self._ended, running, done)))
        self._poll()

    def _request(self, behaviour: BehaviourSpec, served: Served) -> Request:
        """What the implementation gets: the member, the inputs and an `emit` (no member data:
        the member's process holds it)."""
        states = self.servers.states_of(behaviour.name)
        return Request(
            member_type=self.spec.member_type,
            member_id=self.member_id,
            state=states[0] if len(states) == 1 else "",
            behaviour=behaviour.name,
            args=served.inputs(),
            emit=self._emit_later,
            data={},
        )

    def _emit_later(self, event: str, data: Mapping[str, Any] | None, scope: str) -> None:
        """`Request.emit` for the user's thread: published from the executor's thread."""
        self._post(partial(self.publish_event, event, dict(data or {}), scope))

    def _post(self, callback: Callable[[], None]) -> None:
        self._inbox.put(callback)

    def _poll(self) -> None:
        if not self._polling:
            self._polling = True
            self.scheduler.call_later(POLL_S, self._drain)

    def _drain(self) -> None:
        """Run what the user's thread sent back; poll on while goals run."""
        self._polling = False
        while True:
            try:
                callback = self._inbox.get_nowait()
            except queue.Empty:
                break
            try:
                callback()
            except Exception as err:  # a bad emit (data that is no JSON): the node goes on
                self._failed(f"user behaviour: {err!r}")
        if self._running:
            self._poll()

    def _ended(self, running: _Running, future: concurrent.futures.Future[Any]) -> None:
        """The coroutine ended: the goal's outcome and answer from its `Outcome`."""
        if self._running.get(running.served.key) is not running:
            return  # withdrawn: already ended as cancelled
        name = running.behaviour.name
        if future.cancelled():
            self._cancel(running)
            return
        error = future.exception()
        result = future.result() if error is None else None
        if error is not None:
            self._fail(running, f"{name}: user implementation failed: {error!r}")
        elif not isinstance(result, Outcome):
            self._fail(running, f"{name}: user implementation returned {result!r:.80}")
        elif result.name not in running.behaviour.outcomes:
            self._fail(running, f"{name}: undeclared outcome {result.name!r}")
        else:
            self._answer(running, result)

    def _answer(self, running: _Running, result: Outcome) -> None:
        served, name = running.served, running.behaviour.name
        try:
            answer = served.answer(result.name, result.outputs)
        except Exception as err:  # outputs the interface cannot carry
            self._fail(running, f"{name}: user implementation's outputs: {err!r}")
            return
        self._running.pop(served.key, None)
        self.started.append((name, result.name))
        served.finish(lambda cancelled: (None, served.cancelled()) if cancelled else
                      (result.name, answer))  # fmt: skip

    def _fail(self, running: _Running, error: str) -> None:
        self._failed(error)
        self._running.pop(running.served.key, None)
        self.started.append((running.behaviour.name, "aborted"))
        served = running.served
        running.served.finish(lambda _cancelled: ("aborted", served.failure()))

    def _cancel(self, running: _Running) -> None:
        self._running.pop(running.served.key, None)
        self.started.append((running.behaviour.name, "preempted"))
        served = running.served
        served.finish(lambda _cancelled: (None, served.cancelled()))

    def _withdrawn(self, key: Any) -> None:
        running = self._running.pop(key, None)  # so the coroutine's end changes nothing
        if running is None:
            super()._withdrawn(key)
            return
        if running.future is not None:
            running.future.cancel()  # the coroutine gets CancelledError in the user's thread
        # after rclpy marked the goal as canceling (as the scripted goals)
        self.scheduler.call_later(0.0, partial(self._cancel, running))

    def destroy_node(self) -> None:
        """Cancel the coroutines still running, then destroy the node."""
        for running in self._running.values():
            if running.future is not None:
                running.future.cancel()
        self._running.clear()
        super().destroy_node()


async def _call(implementation: Behaviour, request: Request) -> Any:
    """The implementation's result (whatever it returns: `_ended` checks it)."""
    return await implementation(request)


def add_options(parser: argparse.ArgumentParser) -> None:
    """`--library` and `--no-plugins`, as the asyncio package has them."""
    parser.add_argument(
        "--library",
        default=None,
        metavar="MODULE:FACTORY",
        help="user behaviours: FACTORY(time_scale) returns a Library (before the plug-ins)",
    )
    parser.add_argument(
        "--no-plugins",
        action="store_true",
        help="ignore the behaviours installed plug-ins provide (entry points)",
    )


def run_served(
    specs: Mapping[str, MemberSpec],
    defaults: Mapping[str, Mapping[str, Any]],
    events: Mapping[str, tuple[str, str]],
    argv: Sequence[str] | None = None,
    plugins: Plugins | None = None,
) -> int:
    """`simulated_behaviours`: one member's behaviour servers, the user's implementations
    where found (`--library`, entry points; exit 2 for an unusable one), scripts elsewhere."""
    prog = "simulated_behaviours"
    parser = argparse.ArgumentParser(prog=prog, description="One member's behaviour servers.")
    add_options(parser)
    args = parser.parse_args(remove_ros_args(ros_args(argv))[1:])
    try:  # the time scale is a ROS parameter here: the factory gets 1.0
        library = load_library(plugins, args.library, args.no_plugins, 1.0, prog)
    except PluginError as err:
        parser.error(f"plug-ins: {err}")
    if library is None:
        return run_simulated(specs, defaults, events, argv)
    loop = UserLoop()
    try:
        return run_simulated(specs, defaults, events, argv, partial(UserBehaviours, library, loop))
    finally:
        loop.close()
