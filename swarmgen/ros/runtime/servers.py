"""Action servers whose goals end when their owner says so: the scripted behaviours of a
simulation and the behaviours of a replay."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from functools import partial
from typing import Any

from rclpy.action.server import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node

from .messages import Interfaces
from .spec import BehaviourSpec


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


def scripted_servers(
    node: Node,
    interfaces: Interfaces,
    behaviours: Mapping[str, BehaviourSpec],
    accepted: Callable[[BehaviourSpec, Any], None],
    cancel: Callable[[Any], CancelResponse],
) -> list[ActionServer[Any, Any, Any]]:
    """One scripted server per behaviour (in name order), all in one reentrant callback group;
    `accepted` is called with the behaviour and the goal's handle."""
    group = ReentrantCallbackGroup()
    return [
        scripted_server(
            node,
            interfaces.action(behaviour.action),
            behaviour.ros_name,
            partial(accepted, behaviour),
            cancel,
            group,
        )
        for _, behaviour in sorted(behaviours.items())
    ]
