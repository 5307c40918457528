"""The auction's messages on the swarm's auction topic (std_msgs/msg/String, JSON): one object
per message, `{"type": "open" | "bid" | "result", ...the dataclass's fields}`, so any platform
can take part without a generated type (docs/detailed.md, "The behaviour servers")."""

from __future__ import annotations

import dataclasses
import json
from typing import Any

from .auction import AuctionOpen, AuctionResult, Bid

AuctionMessage = AuctionOpen | Bid | AuctionResult
TYPES: dict[str, type[AuctionOpen] | type[Bid] | type[AuctionResult]] = {
    "open": AuctionOpen,
    "bid": Bid,
    "result": AuctionResult,
}


def encode(message: AuctionMessage) -> str:
    """The JSON text of an auction message."""
    kind = next(name for name, cls in TYPES.items() if isinstance(message, cls))
    return json.dumps({"type": kind, **dataclasses.asdict(message)}, sort_keys=True)


def decode(text: str) -> AuctionMessage | None:
    """The auction message in `text`, or None when it is not one (ignored, not fatal: the topic
    is shared with whatever else the swarm runs)."""
    try:
        raw: Any = json.loads(text)
        cls = TYPES[raw.pop("type")]
        return cls(**raw)
    except (ValueError, KeyError, TypeError, AttributeError):
        return None
