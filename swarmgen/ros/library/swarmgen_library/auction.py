"""Task allocation by auction, pure: the auctioneer (the UAV that found a target) and the
bidders (the UGVs), with the messages between them as plain dataclasses.

The auctioneer opens an auction for (target id, position) with a bidding window in simulated
seconds. Each bidder bids its horizontal distance to the target; the lowest bid wins, ties go
to the lowest member id (natural order: `ugv_2` before `ugv_10`). A bid counts when it names
this auction and was made at or before the deadline; one bid per bidder (its first). At the
deadline the auction closes: the result names the winner (`succeeded` for the auctioneer and
the winner, `aborted` for every loser) or nobody when no bid came (`aborted` for all). A bidder
that hears no result by the deadline plus its grace period aborts.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass

from .controllers import ABORTED, SUCCEEDED, Base
from .geometry import ZERO, Command, Pose, finite, positive


@dataclass(frozen=True)
class AuctionOpen:
    """An auction is open for a target until `deadline` (`cps_selection` request)."""

    auctioneer: str
    target_id: int
    x: float
    y: float
    opened: float
    deadline: float


@dataclass(frozen=True)
class Bid:
    """A bidder's offer for an auction, made at `t`."""

    auctioneer: str
    target_id: int
    bidder: str
    value: float
    t: float


@dataclass(frozen=True)
class AuctionResult:
    """How an auction ended (`cps_selected`); `winner` None: no bid, the auction aborted."""

    auctioneer: str
    target_id: int
    winner: str | None
    value: float | None
    t: float


def member_order(name: str) -> tuple[str, int, str]:
    """The sort key of a member id: its text, then the number it ends with, numerically."""
    match = re.fullmatch(r"(.*?)(\d+)", name)
    if match is None:
        return name, -1, name
    return match.group(1), int(match.group(2)), name


def member_number(name: str) -> int:
    """The number a member id ends with (`rover_id` in results), 0 when it has none."""
    match = re.search(r"(\d+)$", name)
    return int(match.group(1)) if match else 0


def winner(bids: Iterable[Bid]) -> Bid | None:
    """The lowest bid; among equal bids the lowest member id; None without bids."""
    return min(bids, key=lambda b: (b.value, member_order(b.bidder)), default=None)


class Auctioneer(Base):
    """Opens one auction for its target and closes it at the deadline."""

    moves = False

    def __init__(self, name: str, window: float) -> None:
        """`window`: seconds of simulated time bids are taken."""
        super().__init__()
        self.name = name
        self.window = positive("window", window)
        self.auction: AuctionOpen | None = None
        self.bids: dict[str, Bid] = {}
        self.result: AuctionResult | None = None

    def open(self, target_id: int, x: float, y: float, t: float) -> AuctionOpen:
        """Open the auction at `t` (forgetting an earlier one): the message to send."""
        self.start(Pose(x, y), t)
        self.bids, self.result = {}, None
        self.auction = AuctionOpen(self.name, target_id, x, y, t, t + self.window)
        return self.auction

    def receive(self, bid: Bid) -> bool:
        """Take a bid if it counts (this auction, in time, finite, the bidder's first)."""
        auction = self.auction
        if (
            auction is None
            or self.result is not None
            or bid.auctioneer != self.name
            or bid.target_id != auction.target_id
            or bid.t > auction.deadline
            or not math.isfinite(bid.value)
            or bid.bidder in self.bids
        ):
            return False
        self.bids[bid.bidder] = bid
        return True

    def close(self, t: float) -> AuctionResult | None:
        """At or after the deadline, once: the result to send (None before)."""
        auction = self.auction
        if auction is None or self.result is not None or t < auction.deadline:
            return None
        best = winner(self.bids.values())
        self.result = AuctionResult(
            self.name,
            auction.target_id,
            None if best is None else best.bidder,
            None if best is None else best.value,
            t,
        )
        if best is None:
            self.finish(ABORTED, rover_id=0, target_id=auction.target_id)
        else:
            self.finish(SUCCEEDED, rover_id=member_number(best.bidder), target_id=auction.target_id)
        return self.result

    def step(self, pose: Pose, t: float) -> Command:
        """Close the auction when its time has come (read `result`); never moves."""
        self.close(t)
        return ZERO


class Bidder(Base):
    """Bids for one auction and learns whether it won."""

    moves = False

    def __init__(self, name: str, grace: float) -> None:
        """`grace`: seconds past the deadline to wait for the result before aborting."""
        super().__init__()
        self.name = name
        self.grace = finite("grace", grace)
        self.auction: AuctionOpen | None = None

    def bid(self, auction: AuctionOpen, pose: Pose, t: float) -> Bid | None:
        """Bid the distance to the auction's target (None once this bidder is done or busy
        with another auction)."""
        if self._done is not None or (self.auction is not None and self.auction != auction):
            return None
        if self.auction is None:
            self.start(pose, t)
            self.auction = auction
        value = pose.distance_xy(auction.x, auction.y)
        return Bid(auction.auctioneer, auction.target_id, self.name, value, t)

    def learn(self, result: AuctionResult) -> str | None:
        """The result of the auction bid for: `succeeded` for the winner, `aborted` else."""
        auction = self.auction
        if (
            auction is None
            or result.auctioneer != auction.auctioneer
            or result.target_id != auction.target_id
        ):
            return None
        if result.winner == self.name:
            self.finish(
                SUCCEEDED,
                target_id=auction.target_id,
                target_pose={"x": auction.x, "y": auction.y, "z": 0.0},
            )
        else:
            self.finish(ABORTED, target_id=auction.target_id)
        return self._done

    def step(self, pose: Pose, t: float) -> Command:
        """Abort when no result came in time; never moves."""
        auction = self.auction
        if auction is not None and self._done is None and t > auction.deadline + self.grace:
            self.finish(ABORTED, target_id=auction.target_id)
        return ZERO
