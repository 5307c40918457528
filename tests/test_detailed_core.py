"""The detailed level's pure core (swarmgen/ros/library/swarmgen_library, docs/detailed.md)
against hand-computed cases: the world's motion, clipping, clamping, coverage and detections,
the behaviour controllers, the auction, the random stream, and the package as ROS users get it
(importable as the top-level `swarmgen_library`, built by real colcon)."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmgen.ros.library import swarmgen_library as lib
from swarmgen.ros.library.swarmgen_library import (
    ZERO,
    Area,
    Auctioneer,
    Bid,
    Bidder,
    Command,
    Pose,
    RobotSpec,
    Stream,
    TargetSpec,
    World,
    WorldSpec,
)
from swarmgen.sim.grid import GAMMAS, mix64
from tests.conftest import ROOT

PACKAGE_ROOT = ROOT / "swarmgen" / "ros" / "library"


def one_uav(
    x: float,
    y: float,
    *,
    size: float = 10.0,
    speed: float = 1.0,
    fov: float | None = 0.5,
    dt: float = 0.1,
    targets: tuple[TargetSpec, ...] = (),
) -> World:
    spec = WorldSpec(
        Area(size, size), (RobotSpec("uav_1", "uav", speed, fov, x, y),), targets, 1.0, dt
    )
    return World(spec)


def cover(world: World, ctrl: lib.RandomDirection, steps: int) -> list[int]:
    """Run the coverage controller in the loop; the step numbers at which it turned."""
    ctrl.start(world.pose("uav_1"), world.time)
    turned = []
    for k in range(steps):
        turns = ctrl.turns
        world.command("uav_1", *astuple(ctrl.step(world.pose("uav_1"), world.time)))
        if ctrl.turns != turns:
            turned.append(k)
        world.step()
    return turned


def astuple(c: Command) -> tuple[float, float, float]:
    return c.vx, c.vy, c.vz


# --- random-direction legs


@pytest.mark.parametrize(
    ("dt", "speed", "turn_step", "x_at_turn"),
    [
        (0.125, 1.0, 72, 10.0),  # binary-exact steps: x = 1 + k/8 reaches the wall exactly
        (0.1, 0.8, 112, 9.96),  # 1 + 0.08 k + 0.08 > 10 first for k = 112
    ],
)
def test_a_straight_leg_turns_where_geometry_says(
    dt: float, speed: float, turn_step: int, x_at_turn: float
) -> None:
    world = one_uav(1.0, 1.0, speed=speed, dt=dt)
    ctrl = lib.RandomDirection(world.area, speed, dt, Stream(7), heading=0.0)
    ctrl.start(world.pose("uav_1"), 0.0)
    for k in range(turn_step):
        command = ctrl.step(world.pose("uav_1"), world.time)
        assert (command.vx, command.vy) == (speed, 0.0) and ctrl.turns == 0, k
        world.command("uav_1", command.vx, command.vy)
        world.step()
    pose = world.pose("uav_1")
    assert pose.x == pytest.approx(x_at_turn, abs=1e-9) and pose.y == 1.0
    ctrl.step(pose, world.time)
    assert ctrl.turns == 1  # the next step would have left the area: a new direction


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**64 - 1),
    heading=st.floats(0.0, 2 * math.pi),
    x=st.floats(0.0, 5.0),
    y=st.floats(0.0, 3.0),
    speed=st.floats(0.2, 2.0),
)
def test_random_direction_never_leaves_the_area(
    seed: int, heading: float, x: float, y: float, speed: float
) -> None:
    """Every step stays inside as computed (the world never has to clamp a covering body)."""
    spec = WorldSpec(Area(5.0, 3.0), (RobotSpec("uav_1", "uav", speed, 0.5, x, y),), (), 1.0, 0.1)
    world = World(spec)
    ctrl = lib.RandomDirection(world.area, speed, 0.1, Stream(seed), heading=heading)
    ctrl.start(world.pose("uav_1"), 0.0)
    for _ in range(400):
        before = world.pose("uav_1")
        held = world.command("uav_1", *astuple(ctrl.step(before, world.time)))
        world.step()
        after = world.pose("uav_1")
        assert (after.x, after.y) == (before.x + held.vx * 0.1, before.y + held.vy * 0.1)
        assert world.area.contains(after.x, after.y)
    assert ctrl.turns > 0


def test_seeded_runs_are_identical_bit_for_bit() -> None:
    def run(seed: int) -> list[str]:
        robots = tuple(
            RobotSpec(f"uav_{i}", "uav", 0.8, 0.5, 31.0 + 2 * i, 0.0) for i in range(1, 5)
        )
        world = World(WorldSpec(Area(66.0, 66.0), robots, (), 0.5, 0.1))
        ctrls = {
            r.name: lib.RandomDirection(world.area, 0.8, 0.1, Stream(lib.member_key(seed, i)))
            for i, r in enumerate(robots)
        }
        for name, ctrl in ctrls.items():
            ctrl.start(world.pose(name), 0.0)
        trace = []
        for _ in range(3000):
            for name, ctrl in ctrls.items():
                world.command(name, *astuple(ctrl.step(world.pose(name), world.time)))
            world.step()
            trace.extend(f"{p.x.hex()},{p.y.hex()}" for p in map(world.pose, ctrls))
        trace.append(repr(world.cell_times()))
        return trace

    first = run(11)
    assert first == run(11)
    assert first != run(12)


def test_the_stream_is_the_abstract_worlds_generator() -> None:
    key = lib.member_key(123456789, 3)
    stream = Stream(key)
    ours = [stream.uniform() for _ in range(8)]
    z = mix64(np.uint64(key) + GAMMAS[1:9])
    theirs = ((z >> np.uint64(11)).astype(np.float64) * (1.0 / 9007199254740992.0)).tolist()
    assert ours == theirs


# --- the world


def test_commands_are_clipped_to_max_speed_and_held() -> None:
    world = World(
        WorldSpec(
            Area(10.0, 10.0),
            (
                RobotSpec("uav_1", "uav", 1.0, None, 5, 5),
                RobotSpec("ugv_1", "ugv", 0.5, None, 1, 1),
            ),
            (),
            1.0,
            0.5,
        )
    )
    held = world.command("uav_1", 3.0, 4.0, -7.0)
    assert (held.vx, held.vy, held.vz) == pytest.approx((0.6, 0.8, -1.0), abs=1e-15)
    assert math.hypot(held.vx, held.vy) <= 1.0
    assert world.command("uav_1", 0.3, 0.4, 0.2) == Command(0.3, 0.4, 0.2)  # within: as given
    assert world.command("ugv_1", 10.0, 0.0, 3.0) == Command(0.5, 0.0, 0.0)  # UGVs stay down
    for _ in range(2):  # held until changed
        world.step()
    # explicit Euler, exactly: x(k+1) = x(k) + vx * dt
    assert world.pose("uav_1") == Pose(
        5.0 + 0.3 * 0.5 + 0.3 * 0.5, 5.0 + 0.4 * 0.5 + 0.4 * 0.5, 0.2 * 0.5 + 0.2 * 0.5
    )
    assert world.pose("ugv_1") == Pose(1.5, 1.0, 0.0)
    with pytest.raises(ValueError, match="finite"):
        world.command("uav_1", math.nan, 0.0)
    with pytest.raises(KeyError, match="no robot"):
        world.command("uav_9", 0.0, 0.0)


def test_bodies_are_clamped_into_the_area() -> None:
    world = one_uav(9.9, 0.05, speed=1.0, dt=0.5)
    world.command("uav_1", 1.0, -1.0, -1.0)
    world.step()
    assert world.pose("uav_1") == Pose(10.0, 0.0, 0.0)
    world.command("uav_1", 0.0, 1.0)  # slides along the wall
    world.step()
    assert world.pose("uav_1") == Pose(10.0, 0.5, 0.0)


def test_coverage_of_a_single_pass_is_the_swept_band() -> None:
    """FOV radius 1.2 along y = 5.5 from x = 1.5 to 7.5 over 1 m cells: row 5 (distance 0)
    holds the centres 0.5 .. 8.5 (9 cells), rows 4 and 6 (distance 1, half chord
    sqrt(1.2² - 1) = 0.663) the centres 1.5 .. 7.5 (7 each): 23 cells."""
    world = one_uav(1.5, 5.5, fov=1.2)
    world.command("uav_1", 1.0, 0.0)
    for _ in range(60):
        world.step()
    world.command("uav_1", 0.0, 0.0)
    world.step()
    assert world.pose("uav_1").x == pytest.approx(7.5)
    assert world.covered_cells == 23 and world.coverage() == 0.23
    times = world.cell_times()
    assert times[5 * 10 + 0] == 0.0  # in view at the start
    # centre (7.5, 4.5) enters when x >= 7.5 - 0.663: first at x = 6.9, step 54
    assert times[4 * 10 + 7] == 54 * 0.1
    assert times[3 * 10 + 5] is None and times[4 * 10 + 8] is None


def test_a_detection_exactly_when_the_target_enters_the_fov() -> None:
    """Target at (5.05, 5.5), FOV 0.5: in view from x >= 4.55, i.e. step 31 (x = 4.6), out of
    view past x = 5.55 (step 41 is x = 5.6)."""
    world = one_uav(1.5, 5.5, targets=(TargetSpec(7, 5.05, 5.5), TargetSpec(8, 9.0, 9.0)))
    world.command("uav_1", 1.0, 0.0)
    seen = {}
    for _ in range(70):
        for detection in world.step():
            seen.setdefault(detection.target, []).append(world.steps)
        if world.steps == 35:
            assert [t.id for t in world.visible("uav_1")] == [7]
        if world.steps == 41:
            assert world.visible("uav_1") == ()
    assert seen == {7: [31]}
    assert world.first_detections() == {7: 31 * 0.1}


def test_world_spec_refuses_impossible_worlds() -> None:
    uav = RobotSpec("uav_1", "uav", 1.0, 0.5, 1, 1)
    with pytest.raises(ValueError, match="unique"):
        WorldSpec(Area(4, 4), (uav, uav))
    with pytest.raises(ValueError, match="outside"):
        WorldSpec(Area(4, 4), (RobotSpec("u", "uav", 1.0, None, 5, 1),))
    with pytest.raises(ValueError, match="divide"):
        WorldSpec(Area(4, 4), (uav,), (), cell=1.5)
    with pytest.raises(ValueError, match="max_speed"):
        RobotSpec("u", "uav", 0.0)


# --- controllers


def drive(world: World, ctrl: lib.Controller, steps: int, name: str = "uav_1") -> int:
    """Step until done (or `steps`): the number of steps taken."""
    ctrl.start(world.pose(name), world.time)
    for k in range(steps):
        command = ctrl.step(world.pose(name), world.time)
        if ctrl.done is not None:
            return k
        world.command(name, *astuple(command))
        world.step()
    return steps


def test_move_to_arrives_within_tolerance() -> None:
    world = one_uav(1.0, 1.0, speed=1.0, dt=0.5)
    ctrl = lib.MoveTo(4.0, 5.0, None, 1.0, 0.5, 0.01)
    assert drive(world, ctrl, 100) == 10  # 5 m at 0.5 m per step
    assert ctrl.done == lib.SUCCEEDED
    assert world.pose("uav_1").distance_xy(4.0, 5.0) <= 0.01


def test_take_off_and_land() -> None:
    world = one_uav(2.0, 2.0, speed=2.0, dt=0.25)
    up = lib.TakeOff(1.5, 2.0, 0.25, 0.01)
    assert drive(world, up, 100) == 3 and up.done == lib.SUCCEEDED  # 0.5 m per step
    assert world.pose("uav_1") == Pose(2.0, 2.0, 1.5)
    down = lib.Land(2.0, 0.25, 0.01)
    assert drive(world, down, 100) == 3 and world.pose("uav_1").z == 0.0


def test_positioning_holds_the_pose() -> None:
    world = one_uav(1.0, 1.0, dt=0.5)
    ctrl = lib.Positioning(2.0, 1.0, None, 1.0, 0.5, 0.01)
    assert drive(world, ctrl, 20) == 20 and ctrl.done is None
    assert world.pose("uav_1") == Pose(2.0, 1.0, 0.0)


@pytest.mark.parametrize(
    "make",
    [
        lambda area: lib.MoveTo(9.0, 9.0, None, 1.0, 0.1, 0.01),
        lambda area: lib.RandomDirection(area, 1.0, 0.1, Stream(1), heading=0.5),
        lambda area: lib.LocalCoverage(area, 1.0, 0.1, 1.0, 100.0),
        lambda area: lib.Tracking(3, 1.0, 0.1, (9.0, 1.0)),
        lambda area: lib.TakeOff(5.0, 1.0, 0.1, 0.01),
    ],
)
def test_stop_zeroes_motion_within_one_step(make: object) -> None:
    world = one_uav(2.0, 2.0)
    ctrl = make(world.area)  # type: ignore[operator]
    drive(world, ctrl, 5)
    assert world.held("uav_1") != ZERO
    world.command("uav_1", *astuple(ctrl.stop()))
    assert ctrl.done == lib.PREEMPTED
    stopped = world.pose("uav_1")
    world.step()
    assert world.pose("uav_1") == stopped
    assert ctrl.step(stopped, world.time) == ZERO


def test_local_coverage_spirals_then_aborts_or_succeeds() -> None:
    world = one_uav(5.0, 5.0, dt=0.1)
    ctrl = lib.LocalCoverage(world.area, 1.0, 0.1, 1.0, 20.0)
    drive(world, ctrl, 1000)
    assert ctrl.done == lib.ABORTED and world.time == pytest.approx(20.0)
    # 20 m of spiral with 1 m between turns: radius sqrt(2 * 20 * b), b = 1 / 2 pi
    radius = world.pose("uav_1").distance_xy(5.0, 5.0)
    assert radius == pytest.approx(math.sqrt(2 * 20.0 / (2 * math.pi)), rel=0.05)
    again = lib.LocalCoverage(world.area, 1.0, 0.1, 1.0, 20.0, target=4)
    again.start(world.pose("uav_1"), world.time)
    again.target_found(5, 1.0, 1.0)
    assert again.done is None
    again.target_found(4, 1.0, 2.0)
    assert again.done == lib.SUCCEEDED
    assert again.outputs == {"target_id": 4, "target_pose": {"x": 1.0, "y": 2.0, "z": 0.0}}


def test_tracking_follows_until_rescued_or_lost() -> None:
    world = one_uav(1.0, 1.0, dt=0.5)
    ctrl = lib.Tracking(3, 1.0, 0.5, (4.0, 1.0))
    drive(world, ctrl, 10)
    assert world.pose("uav_1") == Pose(4.0, 1.0, 0.0) and ctrl.done is None
    ctrl.update(3, 4.0, 3.0)
    drive(world, ctrl, 4)
    assert world.pose("uav_1") == Pose(4.0, 3.0, 0.0)
    ctrl.rescued(2)
    assert ctrl.done is None
    ctrl.lost(3)
    assert ctrl.done == lib.TARGET_LOST
    other = lib.Tracking(3, 1.0, 0.5)
    other.start(world.pose("uav_1"), 0.0)
    other.rescued(3)
    assert other.done == lib.SUCCEEDED


def test_monitoring_reports_each_find_once_and_tracked_losses() -> None:
    monitor = lib.TargetMonitoring()
    assert not monitor.moves
    monitor.start(Pose(0, 0), 0.0)
    found = monitor.observe([(2, 1.0, 1.0), (1, 3.0, 3.0)], 0.5)
    assert [(e.name, e.target_id) for e in found] == [("targetFound", 1), ("targetFound", 2)]
    monitor.know(5)  # reported by another member
    assert monitor.observe([(2, 1.0, 1.0), (5, 2.0, 2.0)], 1.0) == []
    monitor.track(2)
    lost = monitor.observe([], 1.5)
    assert lost == [lib.TargetEvent("targetLost", 2, 1.0, 1.0, 1.5)]
    monitor.forget(1)
    assert [e.target_id for e in monitor.observe([(1, 3.0, 3.0)], 2.0)] == [1]


# --- the auction


def test_the_auction_gives_the_target_to_the_lowest_bid_ties_by_id() -> None:
    auctioneer = Auctioneer("uav_1", window=1.0)
    opened = auctioneer.open(4, 10.0, 0.0, t=2.0)
    bidders = {name: Bidder(name, grace=0.5) for name in ("ugv_2", "ugv_10", "ugv_3")}
    poses = {"ugv_2": Pose(13.0, 0.0), "ugv_10": Pose(10.0, 1.5), "ugv_3": Pose(8.5, 0.0)}
    for name, bidder in bidders.items():
        bid = bidder.bid(opened, poses[name], 2.5)
        assert bid is not None and auctioneer.receive(bid)
    assert auctioneer.close(2.9) is None  # before the deadline
    late = Bid("uav_1", 4, "ugv_1", 0.0, 3.01)
    assert not auctioneer.receive(late)
    result = auctioneer.close(3.0)
    assert result is not None and (result.winner, result.value) == ("ugv_3", 1.5)
    assert auctioneer.done == lib.SUCCEEDED and auctioneer.outputs["rover_id"] == 3
    outcomes = {name: b.learn(result) for name, b in bidders.items()}
    assert outcomes == {"ugv_2": "aborted", "ugv_10": "aborted", "ugv_3": "succeeded"}
    assert bidders["ugv_3"].outputs["target_pose"] == {"x": 10.0, "y": 0.0, "z": 0.0}


def test_an_auction_without_bids_aborts_and_a_bidder_without_result_too() -> None:
    auctioneer = Auctioneer("uav_1", window=1.0)
    opened = auctioneer.open(1, 0.0, 0.0, t=0.0)
    auctioneer.step(Pose(0, 0), 1.0)
    assert auctioneer.result is not None and auctioneer.result.winner is None
    assert auctioneer.done == lib.ABORTED and auctioneer.outputs["rover_id"] == 0
    bidder = Bidder("ugv_1", grace=0.5)
    assert bidder.bid(opened, Pose(1.0, 0.0), 0.2) is not None
    bidder.step(Pose(1.0, 0.0), 1.5)
    assert bidder.done is None
    bidder.step(Pose(1.0, 0.0), 1.6)
    assert bidder.done == lib.ABORTED


def test_ties_go_to_the_lowest_member_id_in_natural_order() -> None:
    bids = [Bid("a", 1, name, 2.0, 0.0) for name in ("ugv_10", "ugv_9", "ugv_11")]
    best = lib.winner(bids)
    assert best is not None and best.bidder == "ugv_9"
    assert lib.winner([]) is None


# --- the package as ROS users get it


def _trajectory_script() -> str:
    return textwrap.dedent(
        """
        import json, swarmgen_library as lib
        w = lib.World(lib.WorldSpec(lib.Area(6.0, 6.0),
                                    (lib.RobotSpec("uav_1", "uav", 0.8, 0.5, 3.0, 0.0),)))
        c = lib.RandomDirection(w.area, 0.8, 0.1, lib.Stream(5))
        c.start(w.pose("uav_1"), 0.0)
        for _ in range(500):
            k = c.step(w.pose("uav_1"), w.time)
            w.command("uav_1", k.vx, k.vy)
            w.step()
        p = w.pose("uav_1")
        print(json.dumps([lib.__file__, p.x.hex(), p.y.hex(), w.coverage()]))
        """
    )


def _in_process_trajectory() -> list[object]:
    world = World(WorldSpec(Area(6.0, 6.0), (RobotSpec("uav_1", "uav", 0.8, 0.5, 3.0, 0.0),)))
    ctrl = lib.RandomDirection(world.area, 0.8, 0.1, Stream(5))
    drive(world, ctrl, 500)
    pose = world.pose("uav_1")
    return [pose.x.hex(), pose.y.hex(), world.coverage()]


def test_the_package_imports_as_top_level_swarmgen_library(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(PACKAGE_ROOT)}
    run = subprocess.run(
        [sys.executable, "-c", _trajectory_script()],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    where, *result = json.loads(run.stdout)
    assert Path(where).is_relative_to(PACKAGE_ROOT)
    assert result == _in_process_trajectory()


def test_colcon_builds_and_installs_the_package(tmp_path: Path) -> None:
    pytest.importorskip("colcon_core", reason="colcon comes with the `ros` extra: run `make ros`")
    venv = Path(sys.prefix)
    command = [
        venv / "bin" / "colcon", "--log-base", tmp_path / "log", "build",
        "--base-paths", PACKAGE_ROOT,
        "--build-base", tmp_path / "build", "--install-base", tmp_path / "install",
    ]  # fmt: skip
    env = {**os.environ, "AMENT_PREFIX_PATH": str(venv), "CMAKE_PREFIX_PATH": str(venv)}
    built = subprocess.run(
        [str(c) for c in command],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert built.returncode == 0, built.stdout[-3000:] + built.stderr[-3000:]
    install = tmp_path / "install" / "swarmgen_library"
    marker = install / "share" / "ament_index" / "resource_index" / "packages" / "swarmgen_library"
    assert marker.is_file() and (install / "share" / "swarmgen_library" / "package.xml").is_file()
    site = next(install.glob("lib/python3*/site-packages"))
    run = subprocess.run(
        [sys.executable, "-c", _trajectory_script()],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(site)},
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    where, *result = json.loads(run.stdout)
    assert Path(where).is_relative_to(site)
    assert result == _in_process_trajectory()
    assert not list(PACKAGE_ROOT.glob("*.egg-info")), "the build wrote into the source tree"


def test_a_uav_camera_sees_and_covers_only_when_airborne() -> None:
    target = TargetSpec(1, 2.5, 2.7)
    robots = (
        RobotSpec("uav_1", "uav", 1.0, 0.5, 2.5, 2.5),
        RobotSpec("ugv_1", "ugv", 1.0, 0.5, 2.5, 2.9),
    )
    world = World(WorldSpec(Area(10, 10), robots, (target,), 1.0, 0.125, airborne_z=0.5))
    # on the ground the UAV is blind; the UGV's camera is always on (and never covers)
    assert world.visible("uav_1") == () and world.visible("ugv_1") == (target,)
    assert world.coverage() == 0.0
    world.command("uav_1", 0.0, 0.0, 1.0)  # up at 0.125 m per step: z = 0.5 at step 4
    found = [world.step() for _ in range(5)]
    assert found[:3] == [(), (), ()] and found[4] == ()
    assert found[3] == (lib.Detection("uav_1", 1, 2.5, 2.7, 0.5),)
    times = world.cell_times()
    assert times[2 * 10 + 2] == 0.5 and world.coverage() == 0.01  # the cell under it, at step 4
    world.command("uav_1", 0.0, 0.0, -1.0)
    world.step()  # z = 0.5: still sees
    world.step()  # z = 0.375: blind again
    assert world.visible("uav_1") == () and world.visible("ugv_1") == (target,)
    with pytest.raises(ValueError, match="airborne_z"):
        WorldSpec(Area(10, 10), robots, (), 1.0, 0.125, airborne_z=-1.0)
