"""Sweeps over any model parameter (`--param`, `--sweep`): parsing and its errors, factorial and
design files, that a swept parameter really changes the simulation, and the result columns."""

from __future__ import annotations

import csv
import io
import json
import statistics
from dataclasses import replace
from pathlib import Path

import pytest
from click.testing import CliRunner

from swarmgen import pipeline
from swarmgen.cli import main
from swarmgen.sim import params, sweep
from swarmgen.sim import scenario as sc
from swarmgen.sim.batch import RunResult
from swarmgen.sim.machines import compile_machines
from tests.conftest import SAMPLE_MODELS
from tests.modelkit import ModelKit

SAR = next(m for m in SAMPLE_MODELS if m.parent.name == "sar")
SMALL = ["--scenario", "coverage", "--members", "UAV=2", "--reps", "3", "--seed", "4"]


def simulate(*args: str) -> tuple[int, str]:
    """`swarmgen simulate SAR ...`: exit code and stderr."""
    result = CliRunner().invoke(main, ["simulate", str(SAR), *args])
    return result.exit_code, result.stderr


def rows(path: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(path.read_text(encoding="utf-8"))))


@pytest.fixture(scope="module")
def sar_names() -> params.Names:
    validation = pipeline.validate(SAR)
    assert validation.model is not None
    return params.names_of(validation.model, validation.charts)


# --- values ------------------------------------------------------------------------------------


def test_values_lists_and_ranges() -> None:
    assert params.parse_option("world.view=1,2,3") == ("world.view", [1, 2, 3])
    assert params.parse_option("UAV.data.altitude=0.5, 2") == ("UAV.data.altitude", [0.5, 2])
    assert params.parse_option("allocation=nearest,paired") == (
        "allocation",
        ["nearest", "paired"],
    )
    assert params.parse_option("x=true") == ("x", [True])
    # ranges include STOP when the steps reach it, and stop before it otherwise
    assert params.parse_option("seed=1:10:3") == ("seed", [1, 4, 7, 10])
    assert params.parse_option("seed=1:10:2") == ("seed", [1, 3, 5, 7, 9])
    assert params.parse_option("stop_level=0.1:0.5:0.1")[1] == [0.1, 0.2, 0.3, 0.4, 0.5]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("world.view", "write NAME=V1,V2,..."),
        ("=1,2", "write NAME=V1,V2,..."),
        ("world.view=", "write NAME=V1,V2,..."),
        ("world.view=1,,2", "an empty value"),
        ("world.view=1:5", "write START:STOP:STEP"),
        ("world.view=a:5:1", "write START:STOP:STEP"),
        ("world.view=5:1:1", "STOP >= START"),
        ("world.view=1:5:0", "STEP > 0"),
        ("world.view=1:5:-1", "STEP > 0"),
        ("seed=0:100000:1", "more than 1,000 values"),
    ],
)
def test_bad_values(text: str, message: str) -> None:
    with pytest.raises(params.ParamError, match=message):
        params.parse_option(text)


def test_nan_is_not_a_number() -> None:
    _, values = params.parse_option("UAV.data.altitude=NaN")
    assert values == ["NaN"]  # a word, which the datum's type then refuses


# --- sweep files -------------------------------------------------------------------------------


def test_factorial_and_design_files(tmp_path: Path) -> None:
    factorial = tmp_path / "f.json"
    factorial.write_text(json.dumps({"factorial": {"world.view": [1, 2], "UAV.count": [1, 2, 4]}}))
    points = params.load_file(factorial)
    assert len(points) == 6 and points[0] == (("world.view", 1), ("UAV.count", 1))
    assert points[-1] == (("world.view", 2), ("UAV.count", 4))
    design = tmp_path / "d.toml"
    design.write_text(
        '[[design]]\n"world.view" = 1\ntargets = 2\n[[design]]\n"world.view" = 3\ntargets = 0\n'
    )
    assert params.load_file(design) == [
        (("world.view", 1), ("targets", 2)),
        (("world.view", 3), ("targets", 0)),
    ]
    both = tmp_path / "b.json"
    both.write_text(json.dumps({"factorial": {"seed": [1, 2]}, "design": [{"world.view": 1}]}))
    assert params.load_file(both) == [
        (("seed", 1), ("world.view", 1)),
        (("seed", 2), ("world.view", 1)),
    ]


@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        ("a.json", '{"factorail": {}}', 'unknown key; did you mean "factorial"'),
        ("a.json", "{}", "needs `factorial` or `design`"),
        ("a.json", '{"factorial": {"seed": []}}', "non-empty list"),
        ("a.json", '{"factorial": {"seed": [[1]]}}', "expected a number, boolean or string"),
        ("a.json", '{"design": [3]}', "expected an object"),
        ("a.json", '{"design": [{"seed": 1}], "factorial": {"seed": [2]}}', "both swept"),
        ("a.json", "{nope", "a.json"),
        ("a.toml", "x = [", "not TOML"),
    ],
)
def test_bad_sweep_files(tmp_path: Path, name: str, text: str, message: str) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(params.ParamError, match=message):
        params.load_file(path)


# --- names and values against the model and the scenario ---------------------------------------


def test_points_apply_to_the_scenario(sar_names: params.Names) -> None:
    base = sc.load("coverage")
    point = (("UAV.count", 3), ("world.view", 2), ("timing.takeoff", 7), ("targets", 4))
    variant = params.apply(base, point, sar_names, "--param")
    chosen = variant.scenario
    assert chosen.members["UAV"] == [3] and "UAV" in chosen.given
    assert (chosen.view, chosen.timing["takeoff"], chosen.targets) == (2, 7, [4])
    assert variant.columns() == (("world.view", 2), ("timing.takeoff", 7))
    spacing = params.apply(base, (("placement.UAV.spacing", 2.5),), sar_names, "--param")
    assert spacing.scenario.placement_of("UAV").spacing == 2.5
    assert spacing.scenario.placement_of("UAV").headings == "fan"  # the rest from "*"
    data = params.apply(base, (("UAV.data.altitude", 3),), sar_names, "--param")
    assert data.data == {"UAV": {"altitude": 3.0}}


@pytest.mark.parametrize(
    ("param", "message"),
    [
        ("UAV.cuont=1", "unknown parameter UAV.cuont; did you mean UAV.count?"),
        ("world.veiw=1", "did you mean world.view?"),
        ("wind=1", "unknown parameter wind"),
        ("UAV.camera.fovRadus=1", "did you mean UAV.camera.fovRadius?"),
        ("UAV.camera.fovRadius=wide", "UAV.camera.fovRadius: expected a Real"),
        ("UAV.camera.fovRadius=-0.5", "expected a radius >= 0"),
        ("UAV.camera.fovRadius=0.5,9", "a view of 27 patches (9 m over patches of 0.328358 m"),
        ("UGV.frontCamera.fovRadius=1", "no behaviour of the UGV machine covers or monitors"),
        ("UGV.drive.maxSpeed=1", "a hardware parameter the abstract simulator does not read"),
        ("UAV.camera.frameRate=10", "it reads a camera's fovRadius"),
        ("UAV.data.maxSpeed=1", "no guard, effect or behaviour input of the UAV machine reads"),
        ("world.view=abc", 'world.view="abc": $.world.view: expected an integer'),
        ("world.view=1.5", "expected an integer from 0 to 16"),
        ("world.view=17", "expected an integer from 0 to 16"),
        ("UAV.count=-1", "expected an integer from 0 to 10,000"),
        ("allocation=best", "choose one of paired, nearest"),
        ("UAV.data.altitude=high", "UAV.data.altitude: expected a Real"),
        ("UAV.data.target_id=1.5", "expected an Integer"),
        ("UAV.data.target_id=true", "expected an Integer"),
    ],
)
def test_bad_parameters_refused_before_any_run(param: str, message: str) -> None:
    code, err = simulate(*SMALL, "--param", param)
    assert code == 2, err
    assert err.startswith("swarmgen: error: --param") and message in err, err
    assert "simulate [" not in err  # refused before the progress bar: nothing ran


def test_the_limits_of_every_point_are_checked() -> None:
    big = ["--param", "world.width=10000", "--param", "world.height=50,10000"]
    code, err = simulate(*SMALL, *big)
    assert code == 2 and "patches x repetitions" in err and "simulate [" not in err, err
    code, err = simulate(*SMALL, "--reps", "1000", "--param", "seed=1:101:1")
    assert code == 2 and "more than the limit of 100,000" in err, err


def test_bad_sweep_file_refused_before_any_run(tmp_path: Path) -> None:
    path = tmp_path / "sweep.json"
    path.write_text(json.dumps({"design": [{"world.view": 1}, {"world.view": "wide"}]}))
    code, err = simulate(*SMALL, "--sweep", str(path))
    assert code == 2 and "sweep.json" in err and 'world.view="wide"' in err, err
    assert "simulate [" not in err


def test_study_options_need_the_abstract_level() -> None:
    code, err = simulate(*SMALL, "--level", "detailed", "--param", "seed=1,2")
    assert code == 2 and "--param, --sweep and --cluster are for --level abstract" in err
    code, err = simulate(*SMALL, "--cluster", "local:2", "--workers", "2")
    assert code == 2 and "--workers is for local runs" in err
    code, err = simulate(*SMALL, "--cluster", "nowhere")
    assert code == 2 and "write tcp://HOST:PORT or local:N" in err


# --- a swept parameter changes the simulation; results have a column per parameter -------------


def test_view_changes_the_runs_and_is_a_column(tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = ["--param", "world.view=1,3", "--param", "world.width=41", "--param", "world.height=41"]
    code, err = simulate(*SMALL, *args, "-o", str(out))
    assert code == 0, err
    runs = rows(out / "runs.csv")
    head = ["UAV", "UGV", "targets", "world.view", "world.width", "world.height", "rep"]
    assert list(runs[0])[:7] == head
    assert len(runs) == 2 * 3  # every point x reps, one row each
    assert [r["world.view"] for r in runs] == ["1", "1", "1", "3", "3", "3"]
    # a larger view covers sooner, on the mean by far
    full = {v: [int(r["coverage_100%"]) for r in runs if r["world.view"] == v] for v in "13"}
    assert statistics.fmean(full["3"]) < statistics.fmean(full["1"]) / 2, full
    coverage = rows(out / "coverage.csv")
    assert len(coverage) == 2 * 6 and list(coverage[0])[3:6] == head[3:6]
    payload = json.loads((out / "results.json").read_text())
    point = {"world.view": 1, "world.width": 41, "world.height": 41}
    assert payload["configurations"][0] == {
        "members": {"UAV": 2, "UGV": 0},
        "targets": 0,
        "params": point,
    }
    assert payload["summary"]["coverage"][0]["params"] == point
    assert (out / "coverage.png").stat().st_size > 0
    svg = (out / "coverage.svg").read_text()  # one panel per point, titled with it
    assert "world.view=1, world.width=41" in svg and "world.view=3, world.width=41" in svg


def test_a_camera_radius_is_the_view_it_maps_to(sar_names: params.Names) -> None:
    """`UAV.camera.fovRadius` r sets the UAVs' view to floor(r / patch_m) patches (patches of
    0.5 m here, the scenario's `detailed.patch_m`): the runs, finds and rescues included, are
    those of `world.view` swept to the same views. The UGVs keep `world.view` (1): the camera
    points run a world of two sight classes, the view points one."""
    base = replace(
        sc.load("sar"), width=25, height=25, members={"UAV": [2], "UGV": "=UAV"}, targets=[2],
        reps=3, seed=6, detailed={"patch_m": 0.5},
    )  # fmt: skip
    radii = [(("UAV.camera.fovRadius", r),) for r in (0.3, 1.2)]
    by_camera = params.variants(base, radii, sar_names, "--param")
    by_view = params.variants(base, [(("world.view", v),) for v in (0, 2)], sar_names, "--param")
    assert [v.scenario.views for v in by_camera] == [{"UAV": 0}, {"UAV": 2}]
    assert by_camera[1].columns() == (("UAV.camera.fovRadius", 1.2),)
    machines = compile_machines(SAR)

    def runs(variants: list[params.Variant]) -> list[RunResult]:
        points = [(machines, v.scenario, v.columns()) for v in variants]
        return sweep.simulate(machines, base, points=points).runs

    camera, view = runs(by_camera), runs(by_view)
    assert camera == view and camera[0] != camera[3]
    assert all(r.reason == "rescued" for r in camera), camera


def test_targets_change_the_runs(tmp_path: Path) -> None:
    out = tmp_path / "out"
    world = ["--param", "world.width=21", "--param", "world.height=21"]
    base = ["--scenario", "sar", "--members", "UAV=1", "--reps", "3", "--seed", "2"]
    code, err = simulate(*base, "--param", "targets=1,3", *world, "-o", str(out))
    assert code == 0, err
    runs = rows(out / "runs.csv")
    assert [r["targets"] for r in runs] == ["1", "1", "1", "3", "3", "3"]
    assert all(r["reason"] == "rescued" and r["rescue_100%"] != "" for r in runs)
    # three targets take longer to rescue than one, run by run (the same streams)
    one = [int(r["rescue_100%"]) for r in runs if r["targets"] == "1"]
    three = [int(r["rescue_100%"]) for r in runs if r["targets"] == "3"]
    assert statistics.fmean(three) > statistics.fmean(one), (one, three)
    assert len(rows(out / "rescue.csv")) == 2 * 5


def test_counts_as_parameters_match_members(tmp_path: Path) -> None:
    by_param, by_members = tmp_path / "p", tmp_path / "m"
    base = ["--scenario", "coverage", "--reps", "2", "--seed", "9"]
    assert simulate(*base, "--param", "UAV.count=1,2", "--param", "world.width=31", "-o",
                    str(by_param))[0] == 0  # fmt: skip
    assert simulate(*base, "--members", "UAV=1,2", "--param", "world.width=31", "-o",
                    str(by_members))[0] == 0  # fmt: skip
    assert (by_param / "runs.csv").read_bytes() == (by_members / "runs.csv").read_bytes()


def mission(tmp_path: Path) -> Path:
    """A UAV that covers after take-off only when its datum `search` is true."""
    kit = ModelKit("Gate")
    kit.hardware("Camera", "Sensor")
    kit.hardware("Flight", "Controller")
    kit.behaviour("TakeOff", "HardwareFunction", requires=["Flight"])
    kit.behaviour("Coverage", requires=["Camera"])
    kit.event("launch", sender="station")
    m = kit.machine("Mission")
    m.initial("Idle")
    m.state("Idle")
    m.state("Up", do="TakeOff")
    m.state("Work", do="Coverage")
    m.final("Done")
    m.transition("Idle", "Up", "launch")
    m.transition("Up", "Work", "succeeded", guard="search")
    m.transition("Up", "Done", "succeeded", guard="not search")
    kit.member(
        "UAV",
        machine=m,
        parts={"cam": "Camera", "fc": "Flight"},
        data={"search": ("Boolean", False)},
    )
    kit.swarm("Swarm", {"UAV": 1})
    path = tmp_path / "gate.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


def test_a_data_default_changes_what_the_machine_does(tmp_path: Path) -> None:
    scenario = tmp_path / "s.json"
    scenario.write_text(
        json.dumps(
            {
                "name": "gate",
                "world": {"width": 15, "height": 15},
                "station": [{"tick": 0, "event": "launch"}],
                "clock_origin": "launch",
                "max_ticks": 50_000,
                "reps": 2,
            }
        )
    )
    out = tmp_path / "out"
    args = ["simulate", str(mission(tmp_path)), "--scenario", str(scenario)]
    result = CliRunner().invoke(
        main, [*args, "--param", "UAV.data.search=false,true", "-o", str(out)]
    )
    assert result.exit_code == 0, result.stderr
    runs = rows(out / "runs.csv")
    bad = CliRunner().invoke(main, [*args, "--param", "UAV.data.search=1"])
    assert bad.exit_code == 2 and "UAV.data.search: expected a Boolean, got 1" in bad.stderr
    assert [(r["UAV.data.search"], r["reason"]) for r in runs] == [
        ("false", "stalled"),
        ("false", "stalled"),
        ("true", "coverage"),
        ("true", "coverage"),
    ]
