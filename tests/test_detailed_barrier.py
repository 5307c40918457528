"""The exact lockstep barrier's rule (docs/detailed.md, "The lockstep barrier"), without ROS:
a step completes only when every reporter is idle, every message sent has been received, and
two waves in a row agree (one, when nothing reactive happened since the last step)."""

from __future__ import annotations

import json
from typing import Any

from swarmgen.ros.library.swarmgen_library.barrier import Barrier, imbalance, totals

EVENTS = "/swarm/events"


def _report(by: str, k: int, wave: int, sent: dict[str, int], received: dict[str, int],
            idle: bool = True) -> str:  # fmt: skip
    body: dict[str, Any] = {"k": k, "wave": wave, "by": by, "sent": sent,
                            "received": received, "idle": idle}  # fmt: skip
    return json.dumps(body)


def test_point_to_point_and_broadcast_channels_balance() -> None:
    reports = {
        "a": {"sent": {"goal": 2, EVENTS: 1}, "received": {"goal_response": 2, f"{EVENTS}@a": 3}},
        "b": {"sent": {"goal_response": 2, EVENTS: 2},
              "received": {"goal": 2, f"{EVENTS}@b": 3}},
    }  # fmt: skip
    assert set(imbalance(totals(reports, {})).values()) == {0}
    reports["b"]["received"][f"{EVENTS}@b"] = 2  # one event still on its way to b
    gaps = imbalance(totals(reports, {}))
    assert gaps[f"{EVENTS}@b"] == 1 and gaps["goal"] == 0
    reports["b"]["received"]["goal"] = 1  # a goal not yet at its server
    assert imbalance(totals(reports, {}))["goal"] == 1


def test_a_step_waits_for_every_idle_balanced_reporter_then_two_equal_waves() -> None:
    barrier = Barrier(("servers", "swarm"))
    assert barrier.begin(0, {}) == 1
    assert barrier.report(_report("servers", 0, 1, {"goal_response": 1}, {"goal": 1}))
    assert barrier.decide() == "wait"  # the swarm has not reported
    barrier.report(_report("swarm", 0, 1, {"goal": 1}, {}, idle=True))
    assert barrier.decide() == "wait"  # the goal's answer is on its way
    barrier.report(_report("swarm", 0, 1, {"goal": 1}, {"goal_response": 1}, idle=False))
    assert barrier.decide() == "wait"  # not idle
    barrier.report(_report("swarm", 0, 1, {"goal": 1}, {"goal_response": 1}))
    assert barrier.decide() == "probe" and barrier.wave.number == 2  # first wave: confirm
    assert not barrier.report(_report("swarm", 0, 1, {"goal": 1}, {"goal_response": 1}))
    barrier.report(_report("servers", 0, 2, {"goal_response": 1}, {"goal": 1}))
    barrier.report(_report("swarm", 0, 2, {"goal": 1}, {"goal_response": 1}))
    assert barrier.decide() == "done"
    # the next step: the same counts, so one wave is enough
    barrier.begin(1, {})
    barrier.report(_report("servers", 1, 1, {"goal_response": 1}, {"goal": 1}))
    barrier.report(_report("swarm", 1, 1, {"goal": 1}, {"goal_response": 1}))
    assert barrier.decide() == "done"


def test_a_change_between_the_waves_asks_for_another() -> None:
    barrier = Barrier(("a",))
    barrier.begin(3, {})
    barrier.report(_report("a", 3, 1, {"goal": 0}, {}))
    assert barrier.decide() == "probe"
    barrier.report(_report("a", 3, 2, {"request": 1}, {"request": 1}))
    assert barrier.decide() == "probe" and barrier.wave.number == 3
    barrier.report(_report("a", 3, 3, {"request": 1}, {"request": 1}))
    assert barrier.decide() == "done"


def test_the_world_s_own_topics_count_and_do_not_force_a_second_wave() -> None:
    topic = "/uav_1/pos_provider/pose"
    barrier = Barrier(("swarm",))
    for k in range(3):
        barrier.begin(k, {topic: k + 1})
        barrier.report(_report("swarm", k, 1, {}, {f"{topic}@/uav_1/uav": k}))
        assert barrier.decide() == "wait"  # the pose of step k is on its way
        barrier.report(_report("swarm", k, 1, {}, {f"{topic}@/uav_1/uav": k + 1}))
        assert barrier.decide() == "done"  # nothing reactive was ever sent: one wave


def test_a_timeout_is_counted_and_takes_the_gap_as_lost() -> None:
    barrier = Barrier(("a",))
    barrier.begin(0, {})
    barrier.report(_report("a", 0, 1, {"goal": 1}, {}))
    assert barrier.decide() == "wait"
    barrier.timed_out()
    assert barrier.timeouts == 1 and barrier.stuck[0]["gaps"] == {"goal": 1}
    barrier.begin(1, {})
    barrier.report(_report("a", 1, 1, {"goal": 1}, {}))
    assert barrier.decide() == "done"  # the lost goal costs no second timeout


def test_a_timeout_with_a_report_missing_moves_no_baseline() -> None:
    barrier = Barrier(("a", "b"))
    barrier.begin(0, {})
    barrier.report(_report("a", 0, 1, {"goal": 2}, {}))
    barrier.timed_out()  # b never answered step 0: its counts are unknown, not lost
    assert barrier.offsets == {} and barrier.stuck[0]["missing"] == ["b"]
    barrier.begin(1, {})
    barrier.report(_report("a", 1, 1, {"goal": 2}, {}))
    barrier.report(_report("b", 1, 1, {}, {"goal": 2}))
    assert barrier.decide() == "probe"
