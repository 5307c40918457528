"""Scripted servers whose goals end when their owner says so (the simulated behaviours, the
replay driver): one per behaviour, of the private action or of its declared interface.

- private or declared action: an action server at the behaviour's name; goals run without a
  coroutine each (`scripted_server`); a cancel request is passed on as `withdrawn(key)`.
- service: the callback records the request and returns a placeholder response, which the
  service's `send_response` (replaced on the instance) keeps with the request's header instead
  of sending; the owner's answer is sent later with that header. So a delayed answer blocks
  nothing and needs no coroutine (a pending rclpy task is polled on every executor turn) and no
  extra thread. Requests are numbered per behaviour from 1 in the order they arrive.
- topic, subscribe (the member waits for a message): the server watches the member's
  `active_states`; each entry of a state running the behaviour is an activation (a `Served`
  whose finish publishes the message), each exit withdraws it.
- topic, publish (the member publishes): a subscription recording what arrives (`received`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import Any

from rclpy.action.server import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.service import Service

from .bindings import Resolved, resolve
from .convert import plain
from .messages import STATES_TOPIC, Interfaces
from .served import DeclaredCall, DeclaredGoal, DeclaredMessage, Served
from .spec import BehaviourSpec, MemberSpec

TOPIC_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)  # as declared.py's
# every configuration the member publishes, also those published in a quick burst
WATCH_QOS = QoSProfile(
    depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
Accepted = Callable[[BehaviourSpec, Served], None]
Withdrawn = Callable[[Any], None]


def scripted_server(
    node: Node,
    action_type: Any,
    name: str,
    accepted: Callable[[Any], None],
    cancel: Callable[[Any], CancelResponse],
    callback_group: Any = None,
) -> ActionServer[Any, Any, Any]:
    """An action server whose goals run without a coroutine each.

    rclpy runs a goal as a task that awaits the execute callback, and a pending task is polled
    on every turn of the executor (the EventsExecutor polls it continuously). Here an accepted
    goal is only recorded (`accepted`); when its end is decided, the caller calls
    `handle.execute(callback)` with a plain function that sets the final state and returns the
    result, so the task completes at once. While it runs, the goal's status stays ACCEPTED.
    """
    return ActionServer(
        node,
        action_type,
        name,
        execute_callback=_not_used,
        goal_callback=lambda _goal: GoalResponse.ACCEPT,
        handle_accepted_callback=accepted,
        cancel_callback=cancel,
        callback_group=callback_group,
    )


def _not_used(handle: Any) -> Any:
    raise RuntimeError("goals of scripted servers end through handle.execute(callback)")


@dataclass(eq=False)
class ScriptedServers:
    """The scripted servers of one member's behaviours (see the module docstring)."""

    node: Node
    interfaces: Interfaces
    spec: MemberSpec
    accepted: Accepted
    withdrawn: Withdrawn
    endpoints: list[Any] = field(default_factory=list)
    received: list[tuple[str, Any]] = field(default_factory=list)  # (behaviour, message values)
    arrivals: dict[str, int] = field(default_factory=dict)  # service requests per behaviour
    _watched: dict[str, tuple[Resolved, Callable[[Any], None]]] = field(default_factory=dict)
    _active: dict[str, Served] = field(default_factory=dict)  # state -> topic activation
    _publishers: dict[str, tuple[Resolved, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        group = ReentrantCallbackGroup()
        for _, behaviour in sorted(self.spec.behaviours.items()):
            self.endpoints.append(self._endpoint(behaviour, group))
        if self._watched:
            self.node.create_subscription(
                self.interfaces.ActiveStates, STATES_TOPIC, self._on_states, WATCH_QOS
            )

    def _endpoint(self, behaviour: BehaviourSpec, group: Any) -> Any:
        node = self.node
        if behaviour.binding is None:
            action = self.interfaces.action(behaviour.action)
            on_goal = partial(self._on_goal, behaviour, lambda h: Served(behaviour, h, action))
            return scripted_server(
                node, action, behaviour.ros_name, on_goal, self._on_cancel, group
            )
        item = resolve(behaviour)
        name = item.binding.ros_name
        if item.binding.kind == "action":
            on_goal = partial(self._on_goal, behaviour, partial(DeclaredGoal, item))
            return scripted_server(node, item.type, name, on_goal, self._on_cancel, group)
        if item.binding.kind == "service":
            return self._service(item, group)
        if item.binding.direction == "subscribe":  # the member waits: this side publishes
            publisher = node.create_publisher(item.type, name, TOPIC_QOS)
            self._watched[behaviour.name] = (item, publisher.publish)
            self._publishers[behaviour.name] = (item, publisher)
            return publisher
        record = partial(self._record, behaviour.name)
        return node.create_subscription(item.type, name, record, TOPIC_QOS, callback_group=group)

    def _on_goal(
        self, behaviour: BehaviourSpec, wrap: Callable[[Any], Served], handle: Any
    ) -> None:
        self.accepted(behaviour, wrap(handle))

    def _on_cancel(self, handle: Any) -> CancelResponse:
        self.withdrawn(bytes(handle.goal_id.uuid))  # after rclpy marked the goal as canceling
        return CancelResponse.ACCEPT

    def _service(self, item: Resolved, group: Any) -> Service[Any, Any]:
        """A service whose responses are sent when the owner finishes the call."""
        name = item.behaviour.name
        held: dict[int, tuple[Any, dict[str, Any]]] = {}  # id(placeholder) -> (it, slot)

        def on_request(request: Any, response: Any) -> Any:
            number = self.arrivals[name] = self.arrivals.get(name, 0) + 1
            slot: dict[str, Any] = {}  # header (once rclpy hands it over), answer (once given)
            held[id(response)] = (response, slot)
            send = partial(_send_later, service, slot)
            self.accepted(item.behaviour, DeclaredCall(item, request, (name, number), send))
            return response

        def send_response(response: Any, header: Any) -> None:
            entry = held.pop(id(response), None)
            if entry is not None and entry[0] is response:
                entry[1]["header"] = header
                if "answer" in entry[1]:  # the owner answered before the header came
                    Service.send_response(service, entry[1]["answer"], header)
                return
            Service.send_response(service, response, header)

        service = self.node.create_service(item.type, item.binding.ros_name, on_request,
                                           callback_group=group)  # fmt: skip
        service.send_response = send_response  # type: ignore[method-assign]
        return service

    def _record(self, behaviour: str, message: Any) -> None:
        if len(self.received) < 10_000:  # a publisher in a loop must not fill memory
            self.received.append((behaviour, plain(message)))

    def _on_states(self, message: Any) -> None:
        """Entries and exits of the states that run a subscribed-topic behaviour."""
        active = set(message.states)
        for state in [s for s in self._active if s not in active]:
            self.withdrawn(self._active.pop(state).key)
        for name, (item, publish) in sorted(self._watched.items()):
            for state in self.states_of(name):
                if state in active and state not in self._active:
                    number = self.arrivals[name] = self.arrivals.get(name, 0) + 1
                    served = DeclaredMessage(item, (name, number), publish)
                    self._active[state] = served
                    self.accepted(item.behaviour, served)

    def states_of(self, behaviour: str) -> tuple[str, ...]:
        """The ids of the states of the member's chart that run `behaviour`."""
        if not hasattr(self, "_states"):
            nodes = self.spec.build().nodes.values()
            self._states: dict[str, tuple[str, ...]] = {}
            for node in sorted(nodes, key=lambda n: n.order):
                if node.call is not None:
                    key = node.call.behaviour
                    self._states[key] = (*self._states.get(key, ()), node.id)
        return self._states.get(behaviour, ())

    def matched(self) -> bool:
        """Every topic this side publishes has a subscriber (a message before that is lost)."""
        return all(
            publisher.get_subscription_count() > 0 for _, publisher in self._publishers.values()
        )

    def activation(self, state: str) -> Any:
        """The key of a state's running topic activation (None if none)."""
        served = self._active.get(state)
        return served.key if served is not None else None

    def forget(self) -> None:
        """Drop the topic activations (the member was reset)."""
        self._active.clear()


def _send_later(service: Service[Any, Any], slot: dict[str, Any], response: Any) -> None:
    """Send a held request's response (once its header is known)."""
    if "header" in slot:
        Service.send_response(service, response, slot["header"])
    else:
        slot["answer"] = response  # send_response sends it when the header comes
