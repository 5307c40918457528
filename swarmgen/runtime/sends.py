"""The W3C `<send>` services of an engine (`Engine` inherits them; docs/semantics.md,
"Delayed events", "Targets", "Invoked sessions"): delayed raises and their cancellation, send
targets, types and id locations, and sends between invoked sessions. Kept apart from the
interpretation algorithm (`engine`): they only make events and give them to the host.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from swarmgen.runtime.chart import CommunicationError, Record
from swarmgen.runtime.host import PROCESSOR, Event, Host

if TYPE_CHECKING:
    from swarmgen.runtime.sessions import Sessions


class Sends:
    """What `Engine` gives these services (its fields, `make_event`, `raise_internal`)."""

    host: Host
    member_id: str
    session_id: str
    data: Record
    root_host: Host
    sessions: Sessions | None
    parent_sessions: Sessions | None
    invokeid: str | None
    serial: int
    _sends: int

    if TYPE_CHECKING:

        def make_event(
            self, name: str, data: Mapping[str, Any] | None = None, sender: str = "", **extra: Any
        ) -> Event:
            """`Engine.make_event`."""

        def raise_internal(self, name: str, data: Mapping[str, Any] | None) -> None:
            """`Engine.raise_internal`."""

    def raise_delayed(
        self, name: str, data: Mapping[str, Any] | None, delay_ms: Any, sendid: str | None
    ) -> None:
        """`raise e after N ms [as id]`: the host delivers it to this member's external queue
        after the delay (W3C: a delayed `<send>` to the session itself), as an input from
        outside (the step bound restarts); after 0 ms at once, as `raise e(f = ...)`. A delay
        that is no number, or is negative, is error.execution: the event is not raised."""
        self.raise_delayed_event(self.make_event(name, data, self.member_id), delay_ms, sendid)

    def raise_targeted(
        self,
        name: str,
        data: Mapping[str, Any] | None,
        target: Any,
        delay_ms: Any,
        sendid: str | None,
    ) -> None:
        """`raise e to target`: `#_internal` is `raise e` (delays are for sessions); this
        session's `#_scxml_<_sessionid>` its external queue, as a delayed raise; another
        session's is error.communication (swarmgen reaches no other session; as every error
        of executable content it ends the block, W3C 4.9, as in Qt SCXML); anything else is
        no target: error.execution, the block ends."""
        if target == "#_internal" and not delay_ms:
            self.raise_internal(name, data)
        elif self._to_session(name, data, target, delay_ms, sendid):
            pass
        elif target == f"#_scxml_{self.session_id}":
            self.raise_delayed(name, data, delay_ms, sendid)
        elif isinstance(target, str) and target.startswith("#_scxml_"):
            raise CommunicationError(f"no session {target[len('#_scxml_') :]!r} to send to")
        else:
            raise ValueError(f"{target!r} is not a target this member can send to")

    def raise_through(
        self,
        name: str,
        data: Mapping[str, Any] | None,
        options: tuple[Any, Any, str | None, Any],
        into: str | None,
    ) -> None:
        """`raise e [to t] via p [after d] [into v]`, options (target, delay_ms, sendid, via):
        W3C's `<send type|typeexpr>` (only the SCXML event processor, by its URI or
        `"scxml"`: any other value is error.execution, nothing sent) and `idlocation` (a send
        id made here, unique in the session, written to the datum `into` first). The error
        event of a send that fails carries its send id (W3C 5.10.1)."""
        target, delay_ms, sendid, via = options
        if into is not None:
            self._sends += 1
            sendid = self.data[into] = f"send.{self._sends}"
        try:
            if via is not None and via not in (PROCESSOR, "scxml"):
                raise ValueError(f"{via!r} is not an event I/O processor this member has")
            if target is not None:
                self.raise_targeted(name, data, target, delay_ms or 0, sendid)
            elif delay_ms is not None:
                self.raise_delayed(name, data, delay_ms, sendid)
            else:  # `<send target="#_internal">`: the back of the external queue, as with data
                self.raise_internal(name, data if data is not None else {})
        except (ValueError, CommunicationError) as err:
            err.sendid = sendid or ""  # type: ignore[union-attr]  # read by `_error`
            raise

    def cancel_delayed(self, sendid: str) -> None:
        """`cancel id`: the host drops the pending delayed events raised as `id`."""
        self.host.cancel_delayed(sendid)

    def _to_session(
        self, name: str, data: Mapping[str, Any] | None, target: Any, delay: Any, sendid: str | None
    ) -> bool:
        """`#_parent` from an invoked session, `#_<invokeid>` to one of its children: the
        event, sent now or after the delay (docs/semantics.md, "Invoked sessions"). False:
        the target names no such session."""
        up = target == "#_parent" and self.parent_sessions is not None
        child = None
        if not up and isinstance(target, str) and target.startswith("#_") and self.sessions:
            child = self.sessions.active.get(target[2:])
        if not up and (child is None or not child.engine.running):
            return False
        event = self.make_event(name, data, self.member_id)
        if not delay:
            if up and self.parent_sessions is not None:
                self.parent_sessions.to_parent(event, self)
            elif child is not None:
                child.host.deliver(event)
            return True
        if up and self.parent_sessions is not None:
            event.invokeid, event.session = self.invokeid, self.serial
            event.to = self.parent_sessions.engine.path
        elif child is not None:
            event.to = child.engine.path
        self.raise_delayed_event(event, delay, sendid)
        return True

    def raise_delayed_event(self, event: Event, delay_ms: Any, sendid: str | None) -> None:
        """A delayed event made by the caller (one for another session): as `raise_delayed`."""
        if isinstance(delay_ms, bool) or not isinstance(delay_ms, int | float) or delay_ms < 0:
            raise ValueError(f"the delay of {event.name!r} is {delay_ms!r}, not a duration")
        if sendid is None:  # a key no `as <name>` can give (a name has no dot)
            self._sends += 1
            key = f"send.{self._sends}"
        else:
            key = sendid
        event.sendid = sendid or ""
        if delay_ms == 0:  # W3C 6.2.4: dispatched at once, in document order (as Qt SCXML)
            event.kind = "raised"
            self.host.deliver(event)
        else:
            self.host.start_delayed(key, event, delay_ms)
