"""What a scripted server holds for one goal, whatever the behaviour's interface: the private
action, or a declared action, service or subscribed topic (`spec.Binding`).

The owner (the simulated behaviours, the replay driver) sees one shape, a `Served`: its `key`,
its `inputs()` as model values, and `finish(decide)`, where `decide(cancel_requested)` returns
the outcome (None: cancelled) and the answer made by `answer(outcome, outputs)`. `answer`
raises ValueError for outputs or an outcome the interface cannot carry; `failure()` is the
answer of a failed goal (None when the interface cannot say `aborted`: nothing is sent).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from .bindings import Resolved, renames
from .convert import build, get_path, renamed
from .messages import decode, encode, fits
from .spec import BehaviourSpec

# (outcome or None when cancelled, the answer)
Decide = Callable[[bool], tuple[str | None, Any]]
STATUS_OUTCOMES = ("succeeded", "aborted")  # what a goal status says without an outcome field


class Served:
    """One goal of a private action (the base: the other interfaces override the parts)."""

    def __init__(self, behaviour: BehaviourSpec, handle: Any, action: Any) -> None:
        self.behaviour = behaviour
        self.handle = handle
        self.action = action
        self.key: Any = bytes(handle.goal_id.uuid) if handle is not None else b""

    def inputs(self) -> dict[str, Any]:
        """The goal's inputs as model values."""
        request = self.handle.request
        return {
            f.name: decode(f.type, getattr(request, f.field), f.renames)[1]
            for f in self.behaviour.inputs
        }

    def running(self) -> None:
        """The goal started (the private action's feedback)."""
        self.handle.publish_feedback(self.action.Feedback(status="running"))

    def answer(self, outcome: str, outputs: Mapping[str, Any], strict: bool = True) -> Any:
        """The result; `strict`: an output its field cannot carry raises (else it is zero)."""
        result = self.action.Result(outcome=outcome)
        for output in self.behaviour.outputs:
            value = outputs.get(output.name)
            if strict and not fits(output.type, value, output.renames):
                raise ValueError(f"output {output.name}: {value!r} is not a {output.type}")
            if output.name in outputs:
                setattr(result, output.field, encode(output.type, value, output.renames))
        return result

    def failure(self) -> Any:
        """The answer of a goal that failed."""
        return self.action.Result(outcome="aborted")

    def cancelled(self) -> Any:
        """The answer of a cancelled goal."""
        return self.action.Result(outcome="preempted")

    def finish(self, decide: Decide) -> None:
        """End the goal (see the module docstring); the status follows the outcome."""
        self.handle.execute(lambda handle: _end_goal(handle, decide))


def _end_goal(handle: Any, decide: Decide) -> Any:
    outcome, answer = decide(bool(handle.is_cancel_requested))
    if outcome is None:
        handle.canceled()
    elif outcome == "aborted":
        handle.abort()
    else:
        handle.succeed()
    return answer


class _Declared(Served):
    """The parts every declared interface shares: inputs and answers by field path."""

    def __init__(self, resolved: Resolved, handle: Any, request: Any) -> None:
        super().__init__(resolved.behaviour, None, None)
        self.resolved = resolved
        self.handle = handle
        self.request = request

    def inputs(self) -> dict[str, Any]:
        """The inputs the binding maps, read from the goal, request or message (data type
        keys renamed back to the model's names, `Binding.renames`)."""
        return {
            name: renamed(
                get_path(self.request, path), renames(self.resolved, "input", name), False
            )
            for name, path in self.resolved.binding.inputs
        }

    def running(self) -> None:
        """Declared interfaces get no feedback from a script."""

    def answer(self, outcome: str, outputs: Mapping[str, Any], strict: bool = True) -> Any:
        """The result, response or message: outputs at their paths, the outcome in its field
        (ValueError, also ConversionError, if either cannot be carried)."""
        binding = self.resolved.binding
        answer_type = self.resolved.answer
        pairs: list[tuple[str, Any]] = [
            (path, renamed(outputs.get(name), renames(self.resolved, "output", name), True))
            for path, name in binding.outputs
        ]
        if binding.outcome:
            pairs.append((binding.outcome, _outcome_value(answer_type, binding.outcome, outcome)))
        elif outcome not in self.carried():
            raise ValueError(
                f"outcome {outcome!r} cannot be carried by {self.resolved.label} "
                "(the binding has no outcome field)"
            )
        return build(answer_type, pairs, self.behaviour.name)

    def carried(self) -> tuple[str, ...]:
        """The outcomes the interface says without an outcome field."""
        return STATUS_OUTCOMES

    def failure(self) -> Any:
        """The answer of a failed goal: aborted, if the interface can say so."""
        try:
            return self.answer("aborted", {})
        except ValueError:
            return None

    def cancelled(self) -> Any:
        """A cancelled goal's result: `preempted` in its outcome field if it has one."""
        try:
            return self.answer("preempted", {})
        except ValueError:
            return self.resolved.answer()


def _outcome_value(answer_type: Any, path: str, outcome: str) -> Any:
    """The outcome as its field holds it: the name (a string field) or success (a bool)."""
    default = get_path(answer_type(), path)
    if isinstance(default, bool):
        if outcome not in STATUS_OUTCOMES:
            raise ValueError(f"outcome {outcome!r} cannot be carried by the bool field {path!r}")
        return outcome == "succeeded"
    return outcome


class DeclaredGoal(_Declared):
    """A goal of a declared action: status from the outcome, result by field path."""

    def __init__(self, resolved: Resolved, handle: Any) -> None:
        super().__init__(resolved, handle, handle.request)
        self.key = bytes(handle.goal_id.uuid)

    def failure(self) -> Any:
        """The status says `aborted`; the result carries what it can."""
        answer = super().failure()
        return answer if answer is not None else self.resolved.answer()


class DeclaredCall(_Declared):
    """A request to a declared service; its response is sent when the owner finishes it."""

    def __init__(self, resolved: Resolved, request: Any, key: Any, send: Callable[[Any], None]):
        super().__init__(resolved, None, request)
        self.key = key
        self._send = send

    def carried(self) -> tuple[str, ...]:
        """A response says `succeeded` (no response, or `success: false`, is the failure)."""
        return ("succeeded",)

    def finish(self, decide: Decide) -> None:
        """Send the response (nothing for a cancelled or an unanswerable call)."""
        outcome, answer = decide(False)
        if outcome is not None and answer is not None:
            self._send(answer)


class DeclaredMessage(_Declared):
    """An activation of a state waiting for a message: finishing it publishes the message."""

    def __init__(self, resolved: Resolved, key: Any, publish: Callable[[Any], None]) -> None:
        super().__init__(resolved, None, resolved.request())
        self.key = key
        self._publish = publish

    def inputs(self) -> dict[str, Any]:
        """A subscriber behaviour sends nothing: no inputs reach the server."""
        return {}

    def carried(self) -> tuple[str, ...]:
        """A message says `succeeded`."""
        return ("succeeded",)

    def finish(self, decide: Decide) -> None:
        """Publish the message (nothing for a cancelled activation or a failure)."""
        outcome, answer = decide(False)
        if outcome is not None and answer is not None:
            self._publish(answer)
