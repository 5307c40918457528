"""Simulated behaviours as ROS 2 action servers: one server per behaviour in each member's
namespace, driven by a script (the ROS counterpart of `runtime.simulated`).

A script maps behaviour names to what a goal does (times are simulated seconds, multiplied by
the time scale):

    {"behaviours": {
       "TakeOff":  {"duration": 2.0},
       "Coverage": {"forever": true},
       "TargetMonitoring": {"forever": true, "every": {"period": 4.0, "emit": [
           {"event": "targetFound", "data": {"target_id": "${member.index * 100 + tick}"}}]}},
       "TaskBidding": {"duration": 5.0, "outcome": "aborted", "until": {
           "event": "targetAssigned", "when": "event.target_id == goal.target_id",
           "outcome": "${'succeeded' if event.rover_id == member.index else 'aborted'}"}}},
     "member_types": {"UGV": {"behaviours": {...}}}}

- `duration`, `outcome` (default "succeeded"), `outputs` and `emit` (events published when the
  goal ends): the goal ends after `duration` unless `forever` (then only preemption ends it).
- `every`: while the goal runs, emit events every `period` (first after `start`, default
  `period`) when `when` holds (always if absent); `tick` counts the periods.
- `until`: end early when a swarm event named `event` arrives and `when` holds; `outcome`,
  `outputs` and `emit` of the `until` block then apply.
- Strings of the form `"${expression}"` are computed; `${...}` inside a longer string is
  replaced by the value's text. Expressions are a small, safe subset of Python (literals,
  arithmetic, comparisons, `and`/`or`/`not`, `x if c else y`, attribute access and
  `min max abs round int float str len`) over the names `goal` (the goal's inputs), `member`
  (`id`, `index`, `type`), `swarm` (members per type), `count` (goals this server started),
  `tick`, and in `until` also `event` (the event's data) and `sender`.
Events are published on behalf of the member (sender = member id) with ids from 2**40 up, so
they never collide with the ids of the member's own events.
"""

from __future__ import annotations

import ast
import itertools
import json
import operator
import re
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import rclpy
from rclpy.action.server import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.context import Context as RosContext
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter as RosParameter

from ...runtime.chart import Record, record
from .node import (
    EVENTS_QOS,
    LOCAL_TOPIC,
    SWARM_TOPIC,
    BehaviourSpec,
    Handle,
    Interfaces,
    MemberSpec,
    Scheduler,
    decode,
    encode,
    fits,
    ros_args,
    ros_time,
    spin_until,
)

EMITTED_ID_BASE = 1 << 40


class ScriptError(ValueError):
    """A simulation script that cannot be used."""


# --- safe expressions


MAX_POWER = 1024  # |exponent| of `**` on integers; `2 ** 10 ** 9` would block the executor
MAX_REPEAT = 100_000  # items a repeated string or list may have (`"x" * 10 ** 12`)


def _pow(base: Any, exponent: Any) -> Any:
    if isinstance(exponent, int) and isinstance(base, int) and abs(exponent) > MAX_POWER:
        raise ValueError(f"integer exponent {exponent} is above {MAX_POWER}")
    return operator.pow(base, exponent)


def _mul(left: Any, right: Any) -> Any:
    for sequence, count in ((left, right), (right, left)):
        repeated = isinstance(sequence, str | list | tuple) and isinstance(count, int)
        if repeated and len(sequence) * count > MAX_REPEAT:
            raise ValueError(f"a repetition of more than {MAX_REPEAT} items")
    return operator.mul(left, right)


# Scripts come from files a user edits: their expressions are bounded, so that a typo cannot
# keep the executor (every member of the process) busy or exhaust its memory.
_BINARY: dict[type[ast.operator], Callable[[Any, Any], Any]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: _mul,
    ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv,
    ast.Mod: operator.mod,
    ast.Pow: _pow,
}
_COMPARE: dict[type[ast.cmpop], Callable[[Any, Any], Any]] = {
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
    ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b,
}
_FUNCTIONS: dict[str, Callable[..., Any]] = {
    "min": min,
    "max": max,
    "abs": abs,
    "round": round,
    "int": int,
    "float": float,
    "str": str,
    "len": len,
}
_TEMPLATE = re.compile(r"\$\{(.*?)\}")


def compile_expression(text: str) -> ast.Expression:
    """Parse an expression and check that it only uses the allowed subset."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as err:
        raise ScriptError(f"bad expression {text!r}: {err.msg}") from None
    for node in ast.walk(tree):
        allowed = (
            ast.Expression,
            ast.Constant,
            ast.Name,
            ast.Load,
            ast.Attribute,
            ast.BinOp,
            ast.UnaryOp,
            ast.BoolOp,
            ast.Compare,
            ast.IfExp,
            ast.Call,
            ast.List,
            ast.Tuple,
            ast.Dict,
            ast.And,
            ast.Or,
            ast.Not,
            ast.USub,
            ast.UAdd,
            *_BINARY,
            *_COMPARE,
        )
        if not isinstance(node, allowed):
            raise ScriptError(f"{type(node).__name__} is not allowed in expression {text!r}")
        if isinstance(node, ast.Attribute) and node.attr.startswith("_"):
            raise ScriptError(f"private attribute {node.attr!r} in expression {text!r}")
        if isinstance(node, ast.Call) and (
            not isinstance(node.func, ast.Name) or node.func.id not in _FUNCTIONS or node.keywords
        ):
            raise ScriptError(f"only {sorted(_FUNCTIONS)} may be called in {text!r}")
    return tree


def evaluate(tree: ast.AST, names: Mapping[str, Any]) -> Any:
    """Evaluate a checked expression tree (no `eval`: an interpreter over the allowed nodes)."""
    if isinstance(tree, ast.Expression):
        return evaluate(tree.body, names)
    if isinstance(tree, ast.Constant):
        return tree.value
    if isinstance(tree, ast.Name):
        if tree.id in _FUNCTIONS:
            return _FUNCTIONS[tree.id]
        if tree.id not in names:
            raise NameError(f"unknown name {tree.id!r}")
        return names[tree.id]
    if isinstance(tree, ast.Attribute):
        value = evaluate(tree.value, names)
        if isinstance(value, Mapping):
            return value.get(tree.attr)
        raise TypeError(f"{tree.attr!r}: only the fields of records can be read")
    if isinstance(tree, ast.BinOp):
        return _BINARY[type(tree.op)](evaluate(tree.left, names), evaluate(tree.right, names))
    if isinstance(tree, ast.UnaryOp):
        operand = evaluate(tree.operand, names)
        if isinstance(tree.op, ast.Not):
            return not operand
        return -operand if isinstance(tree.op, ast.USub) else +operand
    if isinstance(tree, ast.BoolOp):
        result: Any = isinstance(tree.op, ast.And)
        for value_node in tree.values:
            result = evaluate(value_node, names)
            if isinstance(tree.op, ast.And) and not result:
                return result
            if isinstance(tree.op, ast.Or) and result:
                return result
        return result
    if isinstance(tree, ast.Compare):
        left = evaluate(tree.left, names)
        for op, right_node in zip(tree.ops, tree.comparators, strict=True):
            right = evaluate(right_node, names)
            if not _COMPARE[type(op)](left, right):
                return False
            left = right
        return True
    if isinstance(tree, ast.IfExp):
        test = evaluate(tree.test, names)
        return evaluate(tree.body if test else tree.orelse, names)
    if isinstance(tree, ast.Call):
        function = _FUNCTIONS[tree.func.id]  # type: ignore[attr-defined]
        return function(*(evaluate(a, names) for a in tree.args))
    if isinstance(tree, ast.List | ast.Tuple):
        return [evaluate(e, names) for e in tree.elts]
    if isinstance(tree, ast.Dict):
        return {
            evaluate(k, names): evaluate(v, names)
            for k, v in zip(tree.keys, tree.values, strict=True)
            if k is not None
        }
    raise ScriptError(f"cannot evaluate {type(tree).__name__}")


def _check_template(value: Any) -> None:
    if isinstance(value, str):
        for match in _TEMPLATE.finditer(value):
            compile_expression(match.group(1))
    elif isinstance(value, Mapping):
        for item in value.values():
            _check_template(item)
    elif isinstance(value, list):
        for item in value:
            _check_template(item)


def render(value: Any, names: Mapping[str, Any]) -> Any:
    """A script value with its `${...}` expressions computed."""
    if isinstance(value, str):
        whole = _TEMPLATE.fullmatch(value)
        if whole is not None:
            return evaluate(compile_expression(whole.group(1)), names)
        return _TEMPLATE.sub(lambda m: str(evaluate(compile_expression(m.group(1)), names)), value)
    if isinstance(value, Mapping):
        return {str(k): render(v, names) for k, v in value.items()}
    if isinstance(value, list):
        return [render(v, names) for v in value]
    return value


# --- scripts


@dataclass(frozen=True)
class Emission:
    event: str
    data: Mapping[str, Any] = field(default_factory=dict)
    scope: str | None = None


@dataclass(frozen=True)
class Ending:
    outcome: str = "succeeded"
    outputs: Mapping[str, Any] = field(default_factory=dict)
    emit: tuple[Emission, ...] = ()


@dataclass(frozen=True)
class Periodic:
    period: float
    start: float
    emit: tuple[Emission, ...]
    when: ast.Expression | None = None


@dataclass(frozen=True)
class Until:
    event: str
    when: ast.Expression | None
    ending: Ending


@dataclass(frozen=True)
class Script:
    duration: float = 1.0
    ending: Ending = Ending()
    forever: bool = False
    every: Periodic | None = None
    until: Until | None = None


_SCRIPT_KEYS = {"duration", "outcome", "outputs", "emit", "forever", "every", "until"}


def _number(value: Any, where: str) -> float:
    if not isinstance(value, int | float) or isinstance(value, bool) or value < 0:
        raise ScriptError(f"{where}: expected a number >= 0, got {value!r}")
    return float(value)


def _mapping(value: Any, where: str) -> Mapping[str, Any]:
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise ScriptError(f"{where}: expected an object, got {value!r}")
    _check_template(value)
    return value


def _emissions(value: Any, where: str) -> tuple[Emission, ...]:
    if value is None:
        return ()
    if not isinstance(value, list):
        raise ScriptError(f"{where}: expected a list of events")
    found = []
    for number, item in enumerate(value, start=1):
        if not isinstance(item, Mapping) or not isinstance(item.get("event"), str):
            raise ScriptError(f"{where}[{number}]: expected {{'event': name, 'data': {{...}}}}")
        scope = item.get("scope")
        if scope not in (None, "swarm", "local"):
            raise ScriptError(f"{where}[{number}]: scope is 'swarm' or 'local'")
        found.append(Emission(item["event"], _mapping(item.get("data"), where), scope))
    return tuple(found)


def _ending(raw: Mapping[str, Any], where: str) -> Ending:
    outcome = raw.get("outcome", "succeeded")
    if not isinstance(outcome, str):
        raise ScriptError(f"{where}: outcome must be a string")
    _check_template(outcome)
    return Ending(
        outcome,
        _mapping(raw.get("outputs"), f"{where}.outputs"),
        _emissions(raw.get("emit"), f"{where}.emit"),
    )


def _condition(when: Any, where: str) -> ast.Expression | None:
    if when is None:
        return None
    if not isinstance(when, str):
        raise ScriptError(f"{where} must be an expression")
    whole = _TEMPLATE.fullmatch(when.strip())
    return compile_expression(whole.group(1) if whole else when)


def parse_script(raw: Any, where: str = "script") -> Script:
    if not isinstance(raw, Mapping):
        raise ScriptError(f"{where}: expected an object")
    unknown = set(raw) - _SCRIPT_KEYS
    if unknown:
        raise ScriptError(f"{where}: unknown keys {sorted(unknown)}")
    every = None
    if raw.get("every") is not None:
        block = _mapping(raw["every"], f"{where}.every")
        period = _number(block.get("period"), f"{where}.every.period")
        if period <= 0:
            raise ScriptError(f"{where}.every.period must be > 0")
        start = _number(block.get("start", period), f"{where}.every.start")
        every = Periodic(
            period,
            start,
            _emissions(block.get("emit"), f"{where}.every.emit"),
            _condition(block.get("when"), f"{where}.every.when"),
        )
    until = None
    if raw.get("until") is not None:
        block = _mapping(raw["until"], f"{where}.until")
        if not isinstance(block.get("event"), str):
            raise ScriptError(f"{where}.until needs the name of an event")
        condition = _condition(block.get("when"), f"{where}.until.when")
        until = Until(block["event"], condition, _ending(block, f"{where}.until"))
    return Script(
        duration=_number(raw.get("duration", 1.0), f"{where}.duration"),
        ending=_ending(raw, where),
        forever=bool(raw.get("forever", False)),
        every=every,
        until=until,
    )


def load_scripts(
    defaults: Mapping[str, Mapping[str, Any]],
    member_type: str,
    source: Mapping[str, Any] | str | Path | None = None,
) -> dict[str, Script]:
    """The scripts of one member type: the generated defaults, replaced behaviour by behaviour by
    the file's `behaviours`, then by its `member_types.<type>.behaviours`."""
    raw: Any = source
    if isinstance(source, str | Path):
        try:
            raw = json.loads(Path(source).read_text(encoding="utf-8"))
        except (OSError, ValueError) as err:
            raise ScriptError(f"{source}: cannot read the script: {err}") from None
    raw = raw or {}
    if not isinstance(raw, Mapping):
        raise ScriptError("a script is a JSON object")
    merged: dict[str, Any] = dict(defaults)
    merged.update(_mapping(raw.get("behaviours"), "behaviours"))
    per_type = _mapping(raw.get("member_types"), "member_types").get(member_type) or {}
    merged.update(_mapping(per_type.get("behaviours"), f"member_types.{member_type}.behaviours"))
    return {name: parse_script(value, f"behaviours.{name}") for name, value in merged.items()}


# --- the servers


@dataclass(eq=False)
class _Goal:
    handle: Any
    behaviour: BehaviourSpec
    names: dict[str, Any]
    timers: list[Handle] = field(default_factory=list)
    until: Until | None = None
    done: bool = False


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


class SimulatedBehaviours(Node):
    """The scripted action servers of one member (node `simulated_behaviours` in its namespace).

    Parameters: `member_type`, `member_id`, `member_index`, `script` (a JSON file, optional),
    `time_scale` and `swarm` (JSON object: members per type), when not given to the constructor.
    """

    def __init__(
        self,
        specs: Mapping[str, MemberSpec],
        defaults: Mapping[str, Mapping[str, Any]],
        events: Mapping[str, tuple[str, str]],
        *,
        member_type: str | None = None,
        member_id: str | None = None,
        member_index: int | None = None,
        swarm: Mapping[str, int] | None = None,
        script: Mapping[str, Any] | str | None = None,
        time_scale: float = 1.0,
        namespace: str = "",
        scheduler: Scheduler | None = None,
        context: RosContext | None = None,
        parameter_overrides: Sequence[RosParameter[Any]] = (),
    ) -> None:
        super().__init__(
            "simulated_behaviours",
            namespace=namespace,
            context=context,
            parameter_overrides=list(parameter_overrides),
        )
        default_type = member_type or next(iter(specs))
        self.member_type = str(self.declare_parameter("member_type", default_type).value)
        if self.member_type not in specs:
            raise ScriptError(f"unknown member type {self.member_type!r}: {sorted(specs)}")
        self.spec = specs[self.member_type]
        default_id = self.get_namespace().strip("/").replace("/", "_") or self.spec.node_name
        self.member_id = str(self.declare_parameter("member_id", member_id or default_id).value)
        tail = self.member_id.rsplit("_", 1)[-1]
        index = member_index or (int(tail) if tail.isdigit() else 1)
        self.member_index = int(self.declare_parameter("member_index", index).value)
        self.time_scale = float(self.declare_parameter("time_scale", float(time_scale)).value)
        counts = json.dumps(dict(swarm or {}))
        self.swarm = Record(json.loads(str(self.declare_parameter("swarm", counts).value)))
        script_param = str(self.declare_parameter("script", "").value)
        source = script if script is not None else (script_param or None)
        self.scripts = load_scripts(defaults, self.spec.chart_name, source)
        self.events = dict(events)
        self.interfaces = Interfaces(self.spec.interfaces)
        self.scheduler = scheduler or Scheduler(self)
        self.started: list[tuple[str, str]] = []  # (behaviour, "started" | outcome)
        self.errors: list[str] = []  # script failures (each aborted a goal or an emission)
        self._ids = itertools.count(EMITTED_ID_BASE)
        self._counts: dict[str, int] = {}
        self._goals: dict[bytes, _Goal] = {}
        self.swarm_publisher = self.create_publisher(self.interfaces.Event, SWARM_TOPIC, EVENTS_QOS)
        self._local = self.create_publisher(self.interfaces.Event, LOCAL_TOPIC, EVENTS_QOS)
        group = ReentrantCallbackGroup()
        if any(s.until is not None for s in self.scripts.values()):
            self.create_subscription(self.interfaces.Event, SWARM_TOPIC, self._on_event, EVENTS_QOS)
        self.servers = [
            scripted_server(
                self,
                self.interfaces.action(behaviour.action),
                behaviour.ros_name,
                partial(self._accepted, behaviour),
                self._on_cancel,
                group,
            )
            for _, behaviour in sorted(self.spec.behaviours.items())
        ]

    def _accepted(self, behaviour: BehaviourSpec, handle: Any) -> None:
        """A goal starts; if starting it fails, it is aborted (an exception here would leave
        rclpy's executor, and stop every node of the process)."""
        try:
            self._start(behaviour, handle)
        except Exception as err:
            self._failed(f"{behaviour.name}: the goal could not start: {err!r}")
            goal = self._goals.get(bytes(handle.goal_id.uuid)) or _Goal(handle, behaviour, {})
            self._finish(goal, Ending(outcome="aborted"))

    def _start(self, behaviour: BehaviourSpec, handle: Any) -> None:
        """A goal starts: its end is scheduled (duration, `until`), its emissions too."""
        action = self.interfaces.action(behaviour.action)
        script = self.scripts.get(behaviour.name) or Script(forever=True)
        count = self._counts[behaviour.name] = self._counts.get(behaviour.name, 0) + 1
        inputs = {
            f.name: decode(f.type, getattr(handle.request, f.field))[1] for f in behaviour.inputs
        }
        names: dict[str, Any] = {
            "goal": record(inputs),
            "member": Record(id=self.member_id, index=self.member_index, type=self.member_type),
            "swarm": self.swarm,
            "count": count,
            "tick": 0,
        }
        goal = _Goal(handle, behaviour, names, until=script.until)
        self._goals[bytes(handle.goal_id.uuid)] = goal
        self.started.append((behaviour.name, "started"))
        handle.publish_feedback(action.Feedback(status="running"))
        if not script.forever:
            goal.timers.append(
                self.scheduler.call_later(
                    script.duration * self.time_scale, partial(self._finish, goal, script.ending)
                )
            )
        if script.every is not None:
            self._periodic(goal, script.every, script.every.start)

    def _finish(self, goal: _Goal, ending: Ending | None) -> None:
        """The goal ends (`None`: it was cancelled): its final state and result are set."""
        if goal.done:
            return
        goal.done = True
        for timer in goal.timers:
            timer.cancel()
        self._goals.pop(bytes(goal.handle.goal_id.uuid), None)
        goal.handle.execute(partial(self._result, goal, ending))

    def _result(self, goal: _Goal, ending: Ending | None, handle: Any) -> Any:
        behaviour = goal.behaviour
        action = self.interfaces.action(behaviour.action)
        if ending is None or handle.is_cancel_requested:
            handle.canceled()
            self.started.append((behaviour.name, "preempted"))
            return action.Result(outcome="preempted")
        try:
            outcome = str(render(ending.outcome, goal.names))
            outputs = render(dict(ending.outputs), goal.names)
            result = action.Result(outcome=outcome)
            for output in behaviour.outputs:
                value = outputs.get(output.name)
                if not fits(output.type, value):  # the wrong type: a failing behaviour
                    raise ValueError(f"output {output.name}: {value!r} is not a {output.type}")
                if output.name in outputs:
                    setattr(result, output.field, encode(output.type, value))
            for emission in ending.emit:
                self.emit(emission, goal.names)
        except Exception as err:  # a failing script aborts the goal, not the server's node
            self._failed(f"{behaviour.name}: script failed: {err!r}")
            handle.abort()
            self.started.append((behaviour.name, "aborted"))
            return action.Result(outcome="aborted")
        if outcome == "aborted":
            handle.abort()
        else:
            handle.succeed()
        self.started.append((behaviour.name, outcome))
        return result

    def _periodic(self, goal: _Goal, every: Periodic, delay: float) -> None:
        def tick() -> None:
            if goal.done:
                return
            goal.names["tick"] += 1
            try:
                if every.when is None or evaluate(every.when, goal.names):
                    for emission in every.emit:
                        self.emit(emission, goal.names)
            except Exception as err:
                self._failed(f"{goal.behaviour.name}: emission failed: {err!r}")
            self._periodic(goal, every, every.period)

        goal.timers.append(self.scheduler.call_later(delay * self.time_scale, tick))

    def _on_cancel(self, handle: Any) -> CancelResponse:
        goal = self._goals.get(bytes(handle.goal_id.uuid))
        if goal is not None:  # after rclpy marked the goal as canceling
            self.scheduler.call_later(0.0, partial(self._finish, goal, None))
        return CancelResponse.ACCEPT

    def _on_event(self, msg: Any) -> None:
        for goal in list(self._goals.values()):
            until = goal.until
            if until is None or goal.done:
                continue
            if self.events.get(until.event, (until.event, ""))[0] != msg.name:
                continue
            try:
                data = json.loads(msg.data) if msg.data else {}
                names = {
                    **goal.names,
                    "event": record(data if isinstance(data, dict) else {}),
                    "sender": msg.sender,
                }
                if until.when is None or evaluate(until.when, names):
                    goal.names = names
                    self._finish(goal, until.ending)
            except Exception as err:
                self._failed(f"{goal.behaviour.name}: `until` failed: {err!r}")

    def _failed(self, error: str) -> None:
        self.get_logger().error(error)
        if len(self.errors) < 100:  # a script failing on every tick must not fill memory
            self.errors.append(error)

    def emit(self, emission: Emission, names: Mapping[str, Any]) -> None:
        """Publish an event on behalf of the member."""
        ident, declared_scope = self.events.get(emission.event, (emission.event, "swarm"))
        data = render(dict(emission.data), names)
        msg = self.interfaces.Event(
            id=next(self._ids),
            stamp=ros_time(self.get_clock().now().nanoseconds / 1e9),
            sender=self.member_id,
            name=ident,
            data=json.dumps(data, default=str, sort_keys=True),
        )
        scope = emission.scope or declared_scope or "swarm"
        (self._local if scope == "local" else self.swarm_publisher).publish(msg)


def run_simulated(
    specs: Mapping[str, MemberSpec],
    defaults: Mapping[str, Mapping[str, Any]],
    events: Mapping[str, tuple[str, str]],
    argv: Sequence[str] | None = None,
) -> int:
    """The simulated behaviours of one member in this process (the launch file's executable),
    configured with ROS parameters; runs until SIGINT/SIGTERM."""
    context = rclpy.get_default_context()  # the default one: SIGINT/SIGTERM end it cleanly
    rclpy.init(args=ros_args(argv), context=context)
    executor = SingleThreadedExecutor(context=context)
    try:
        node = SimulatedBehaviours(specs, defaults, events, context=context)
    except ScriptError as err:
        print(f"simulated_behaviours: {err}", file=sys.stderr)
        rclpy.try_shutdown(context=context)
        return 2
    executor.add_node(node)
    try:
        spin_until(executor, lambda: False)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return 0
