"""World sub-steps (docs/detailed.md, "Sub-steps"): the cameras look at n frames per step while
the commands stay per step. Hand-computed cases on binary-exact numbers (a frame of 0.125 s or
0.25 s at 1 m/s), so every position and time below is exact."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from swarmgen.ros.library.swarmgen_library import (
    Area,
    Detection,
    RobotSpec,
    TargetSpec,
    World,
    WorldSpec,
)
from swarmgen.ros.library.swarmgen_library.worldfile import WorldFileError, parse
from swarmgen.sim.detailed.params import DetailedParams, _params


def uav_world(
    dt: float,
    substeps: int,
    *,
    fov: float = 0.5,
    targets: tuple[TargetSpec, ...] = (),
    airborne_z: float = 0.0,
) -> World:
    robot = RobotSpec("uav_1", "uav", 1.0, fov, 1.5, 5.5)
    spec = WorldSpec(Area(10, 10), (robot,), targets, 0.5, dt, airborne_z, substeps)
    return World(spec)


def test_frames_cover_what_a_world_stepping_at_the_frame_period_covers() -> None:
    """dt 0.5 s in 4 frames against dt 0.125 s in 1: the same cells at the same times, and the
    same pose at every shared instant (both exact in binary)."""
    coarse, fine = uav_world(0.5, 4), uav_world(0.125, 1)
    for world in (coarse, fine):
        world.command("uav_1", 0.75, 0.5)
    for _ in range(10):
        coarse.step()
        for _ in range(4):
            fine.step()
        assert coarse.pose("uav_1") == fine.pose("uav_1")
        assert coarse.time == fine.time
    assert coarse.covered_cells == fine.covered_cells > 0
    assert coarse.cell_times() == fine.cell_times()
    # one frame per step at dt 0.5 s sees less of the band: the discs 0.5 m apart leave gaps
    sparse = uav_world(0.5, 1)
    sparse.command("uav_1", 0.75, 0.5)
    for _ in range(10):
        sparse.step()
    assert sparse.pose("uav_1") == coarse.pose("uav_1")
    assert sparse.covered_cells < coarse.covered_cells


def test_a_target_passed_between_two_steps_is_detected_at_its_frame() -> None:
    """FOV 0.3 m, target at x = 3.0 on the path y = 5.5. Steps of 1 s end at x = 2.5 and 3.5
    (0.5 m away: never in view); frames of 0.25 s see it at x = 2.75, 3.0, 3.25 (t = 1.25 s)."""
    target = TargetSpec(4, 3.0, 5.5)
    blind = uav_world(1.0, 1, fov=0.3, targets=(target,))
    framed = uav_world(1.0, 4, fov=0.3, targets=(target,))
    for world in (blind, framed):
        world.command("uav_1", 1.0, 0.0)
    assert [blind.step() for _ in range(3)] == [(), (), ()]
    assert blind.first_detections() == {}
    assert framed.step() == () and framed.visible("uav_1") == ()
    assert framed.step() == (Detection("uav_1", 4, 3.0, 5.5, 1.25),)
    # the camera reports what it saw during the step, though the target is behind it now
    assert framed.pose("uav_1").x == 3.5 and framed.visible("uav_1") == (target,)
    assert framed.step() == () and framed.visible("uav_1") == ()
    assert framed.first_detections() == {4: 1.25}


def test_a_uav_camera_starts_at_the_frame_it_is_airborne() -> None:
    """Up at 1 m/s from the ground, airborne at z 0.5: the frame at t = 0.5 s of a 1 s step."""
    world = uav_world(1.0, 4, airborne_z=0.5)
    assert world.coverage() == 0.0
    world.command("uav_1", 0.0, 0.0, 1.0)
    world.step()
    assert world.pose("uav_1").z == 1.0
    assert world.cell_times()[11 * 20 + 3] == 0.5  # the cell under (1.5, 5.5)


def test_substeps_must_be_a_whole_number_of_at_least_one() -> None:
    robot = RobotSpec("uav_1", "uav", 1.0, 0.5, 1.0, 1.0)
    for bad in (0, -2):
        with pytest.raises(ValueError, match="substeps"):
            WorldSpec(Area(4, 4), (robot,), substeps=bad)
    raw = {"robots": [{"name": "uav_1", "kind": "uav", "max_speed": 1.0, "x": 1, "y": 1}],
           "area": {"width": 4, "height": 4}, "output": "r.json", "stop": {"time_s": 1}}  # fmt: skip
    assert parse({**raw, "substeps": 3}, Path("/tmp")).spec.substeps == 3
    assert parse(json.loads(json.dumps(raw)), Path("/tmp")).spec.substeps == 1
    for bad_file in (0, 1.5, "2", True):
        with pytest.raises(WorldFileError, match="substeps"):
            parse({**raw, "substeps": bad_file}, Path("/tmp"))


@pytest.mark.parametrize(
    ("dt", "frame_s", "substeps"),
    [(0.1, 0.1, 1), (0.5, 0.1, 5), (0.35, 0.1, 4), (0.5, 0.5, 1), (0.05, 0.1, 1)],
)
def test_the_planner_takes_the_fewest_frames_within_frame_s(
    dt: float, frame_s: float, substeps: int
) -> None:
    params = _params({"dt": dt, "frame_s": frame_s})
    assert params.substeps == substeps
    assert DetailedParams().substeps == 1  # dt 0.1 s, frames of 0.1 s
