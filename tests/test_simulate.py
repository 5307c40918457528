"""`swarmgen simulate`: the science of the paper's abstract simulation, run on the compiled
behaviours. Coverage time against swarm size and coverage level, search against rescue,
reproducibility, tiny worlds worked out by hand, the CLI, and that the machines are in charge."""

from __future__ import annotations

import json
import statistics
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from swarmgen.cli import main
from swarmgen.sim import scenario as sc
from swarmgen.sim.batch import Batch
from swarmgen.sim.machines import Machines, compile_machines
from swarmgen.sim.run import outputs
from swarmgen.sim.stats import estimate, kth, t975
from swarmgen.sim.sweep import Simulation, configurations, simulate
from tests.conftest import SAMPLE_MODELS
from tests.modelkit import ModelKit

SAR = next(m for m in SAMPLE_MODELS if m.parent.name == "sar")
STATION = [{"tick": 0, "event": "launch"}, {"tick": 10, "event": "missionStart"}]


@pytest.fixture(scope="module")
def sar_machines() -> Machines:
    return compile_machines(SAR)


def scenario(**fields: Any) -> sc.Scenario:
    payload: dict[str, Any] = {"name": "test", "station": STATION, "clock_origin": "missionStart"}
    payload.update(fields)
    return sc.parse(payload)


def means(result: Simulation, pick: Any) -> dict[int, list[float]]:
    """config index -> per level, the mean over repetitions (every run must reach it)."""
    out: dict[int, list[float]] = {}
    for index in range(len(result.configs)):
        runs = [r for r in result.runs if r.config == index]
        values = [pick(r) for r in runs]
        assert all(v is not None for row in values for v in row), "a run missed a level"
        out[index] = [statistics.fmean(column) for column in zip(*values, strict=True)]
    return out


# --- coverage ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def coverage(sar_machines: Machines) -> Simulation:
    """The paper's coverage experiment (201 x 201, 1/2/4/8 UAVs, to 100 percent), 30 reps."""
    chosen = sc.load("coverage").with_overrides(reps=30, seed=11)
    return simulate(sar_machines, chosen, workers=2)


def test_coverage_time_halves_when_the_swarm_doubles(coverage: Simulation) -> None:
    """Doubling the UAVs roughly halves the time to 50 .. 96.875 percent (they cover
    disjoint ground most of the time, so the area per tick doubles)."""
    sizes = [dict(c.counts)["UAV"] for c in coverage.configs]
    assert sizes == [1, 2, 4, 8]
    mean = means(coverage, lambda r: r.coverage)
    for small, big in zip(range(3), range(1, 4), strict=True):
        for level in range(5):  # 50, 75, 87.5, 93.75, 96.875 percent
            ratio = mean[small][level] / mean[big][level]
            assert 1.7 < ratio < 2.35, (sizes[small], level, ratio)
    assert all(r.reason == "coverage" and r.coverage_final == 1.0 for r in coverage.runs)


def test_coverage_time_rises_steeply_with_the_level(coverage: Simulation) -> None:
    """Each halving of the uncovered area takes about as long as covering the first half
    (uncovered area decays exponentially in time): the levels 50, 75, 87.5, 93.75, 96.875
    percent are reached at about 1, 2, 3, 4, 5 times the 50 percent time; the last patch
    takes several times longer again."""
    for row in means(coverage, lambda r: r.coverage).values():
        assert row == sorted(row)
        half = row[0]
        for k in range(1, 5):
            assert 0.8 * (k + 1) < row[k] / half < 1.25 * (k + 1), (k, row)
        assert row[5] / half > 8  # 100 percent


# --- search and rescue ------------------------------------------------------------------------


def test_rescue_follows_search(sar_machines: Machines) -> None:
    """Every target is first found, then rescued when its UGV has driven there: never before,
    and on average later by at least the drive."""
    chosen = sc.load("sar").with_overrides({"UAV": [1, 4]}, [4], reps=6, seed=3)
    result = simulate(sar_machines, chosen)
    assert all(r.reason == "rescued" for r in result.runs)
    for run in result.runs:
        for found, rescued in zip(run.found, run.rescued, strict=True):
            assert found is not None and rescued is not None
            assert rescued > found
    summary = outputs(result)
    payload = json.loads(summary["results.json"])
    for search, rescue in zip(
        payload["summary"]["search"], payload["summary"]["rescue"], strict=True
    ):
        assert rescue["mean"] > search["mean"]
    # more UAVs find every target sooner
    one = [kth(r.found, 1.0, 4) or 0 for r in result.runs if r.config == 0]
    four = [kth(r.found, 1.0, 4) or 0 for r in result.runs if r.config == 1]
    assert statistics.fmean(four) < statistics.fmean(one)
    # without -o the command prints tables only: the same files, the figures left out
    tables = outputs(result, figures=False)
    assert {"coverage.png", "coverage.svg", "sar.png", "sar.svg"} <= set(summary)
    assert tables == {k: v for k, v in summary.items() if not k.endswith((".png", ".svg"))}


# --- reproducibility --------------------------------------------------------------------------


def test_same_seed_same_numbers_whatever_the_workers(sar_machines: Machines) -> None:
    """One configuration, so two workers split its repetitions into separate batches in
    separate processes: the numbers must not change."""
    chosen = sc.load("sar").with_overrides({"UAV": [2]}, [3], reps=4, seed=7)
    one = simulate(sar_machines, chosen, workers=1)
    two = simulate(sar_machines, chosen, workers=2)
    again = simulate(sar_machines, chosen, workers=1)
    assert one.runs == two.runs == again.runs
    other = simulate(sar_machines, chosen.with_overrides(seed=8), workers=1)
    assert [r.found for r in other.runs] != [r.found for r in one.runs]


# --- tiny worlds, by hand ---------------------------------------------------------------------


def test_tiny_coverage_world_by_hand(sar_machines: Machines) -> None:
    """A 3 x 5 world (15 patches), one UAV at the centre of the south side, patch (1, 0).
    launch at tick 0, TakeOff takes 5 ticks, missionStart at tick 10 = time 0; one UAV departs
    north (the single direction dividing 180 degrees). It sees its patch and the 8 around it,
    and the world is 3 wide, so it sees whole rows:
        time 0: at y=0, rows 0-1 seen:  6 patches
        time 1: at y=1, rows 0-2:       9
        time 2: at y=2, rows 0-3:      12
        time 3: at y=3, rows 0-4:      15 = 100 percent (it never reaches the north edge)
    Levels: 50% needs ceil(7.5) = 8 patches -> time 1; 75% needs 12 -> 2; 87.5% needs
    ceil(13.125) = 14 -> 3; 93.75% and 96.875% need 15 -> 3; 100% -> 3. The run ends at
    tick 13."""
    chosen = scenario(world={"width": 3, "height": 5}, members={"UAV": [1], "UGV": 0}, reps=1)
    (result,) = simulate(sar_machines, chosen).runs
    assert result.coverage == [1, 2, 3, 3, 3, 3]
    assert (result.reason, result.end_tick, result.coverage_final) == ("coverage", 13, 1.0)
    assert result.events == 3  # launch, TakeOff's outcome, missionStart


def test_tiny_sar_world_by_hand(sar_machines: Machines) -> None:
    """A 3 x 9 world, one UAV and its UGV at (1, 0), one target at (1, 8).
    The UAV flies north from time 0; the target's row 8 comes into view when the UAV is at
    y = 7: found at time 7 (targetFound: the UAV goes to SelectRover, the UGV to Bidding).
    The auction closes after 1 tick: time 8, the UGV is assigned and drives from (1, 0) to
    (1, 8), 8 patches at 1 per tick: arrives at time 16, and Rescue (0 ticks) rescues it:
    time 16. Everything rescued: the run ends at tick 10 + 16 = 26."""
    chosen = scenario(
        world={"width": 3, "height": 9},
        members={"UAV": [1], "UGV": "=UAV"},
        target_positions=[[1, 8]],
        stop="rescued",
        reps=1,
    )
    batch = Batch(sar_machines, chosen, configurations(sar_machines, chosen)[0], [0])
    (result,) = batch.run_all()
    assert (result.found, result.rescued) == ([7], [16])
    assert (result.reason, result.end_tick) == ("rescued", 26)
    uav, ugv = batch.members
    assert "Coverage" in uav.engine.active()  # the UAV resumed coverage
    assert "Ready" in ugv.engine.active()
    assert batch.world.where(ugv.g) == (1.0, 8.0)
    names = [e.name for e in batch.buses[0].log]
    assert names == ["targetFound", "targetAssigned", "targetRescued"]


# --- the compiled machines are in charge ------------------------------------------------------


def mini(tmp_path: Path, cover: str | None) -> Path:
    """A UAV that takes off and then covers with behaviour `cover` (None: only hovers)."""
    kit = ModelKit("Mini")
    kit.hardware("Camera", "Sensor")
    kit.hardware("Flight", "Controller")
    kit.behaviour("TakeOff", "HardwareFunction", requires=["Flight"])
    for name in ("Coverage", "Survey"):
        kit.behaviour(name, requires=["Camera"])
    kit.event("launch", sender="station")
    kit.event("missionAbort", sender="station")
    m = kit.machine("Mission")
    m.initial("Idle")
    m.state("Idle")
    m.state("Up", do="TakeOff")
    m.state("Work", do=cover)
    m.final("Done")
    m.transition("Idle", "Up", "launch")
    m.transition("Up", "Work", "succeeded")
    m.transition("Work", "Done", "missionAbort")
    kit.member("UAV", machine=m, parts={"cam": "Camera", "fc": "Flight"})
    kit.swarm("Swarm", {"UAV": 2})
    path = tmp_path / f"mini_{cover}.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("cover", "library", "covered"),
    [
        ("Coverage", {}, True),
        (None, {}, False),  # the machine never starts Coverage
        ("Survey", {}, False),  # an unknown behaviour: the generic one (runs, moves nothing)
        ("Survey", {"Survey": "Coverage"}, True),  # mapped onto Coverage by the scenario
    ],
)
def test_the_machine_decides_what_runs(
    tmp_path: Path, cover: str | None, library: dict[str, str], covered: bool
) -> None:
    machines = compile_machines(mini(tmp_path, cover))
    chosen = scenario(
        world={"width": 21, "height": 21},
        station=[{"tick": 0, "event": "launch"}],
        clock_origin="launch",
        library=library,
        max_ticks=20_000,
        reps=2,
    )
    result = simulate(machines, chosen)
    assert [dict(c.counts) for c in result.configs] == [{"UAV": 2}]  # the model's composition
    for run in result.runs:
        if covered:
            assert run.reason == "coverage" and run.coverage_final == 1.0
        else:
            assert run.reason == "stalled" and run.coverage_final == 0.0
            assert run.coverage == [None] * 6


# --- the command ------------------------------------------------------------------------------


def test_cli_end_to_end(tmp_path: Path) -> None:
    out = tmp_path / "results"
    args = ["simulate", str(SAR), "--scenario", "sar", "--members", "UAV=1,2", "--targets", "1,2"]
    args += ["--reps", "3", "--seed", "5", "--workers", "2", "-o", str(out)]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    assert "12 runs of 4 configuration(s)" in result.output
    assert "12/12 runs" in result.output  # the progress bar
    names = {p.name for p in out.iterdir()}
    expected = {"coverage", "sar"}
    assert {f"{n}.{x}" for n in expected for x in ("png", "svg")} <= names
    assert {"runs.csv", "search.csv", "rescue.csv", "results.json", ".swarmgen.json"} <= names
    header = (out / "search.csv").read_text().splitlines()[0]
    assert header.startswith("UAV,UGV,targets,level,n,missing,mean,sd,ci95_half")
    payload = json.loads((out / "results.json").read_text())
    assert payload["scenario"]["seed"] == 5 and len(payload["runs"]) == 12
    assert (out / "coverage.svg").read_bytes().count(b"<dc:date>") == 0
    first = {p.name: p.read_bytes() for p in out.iterdir()}
    again = CliRunner().invoke(main, [*args[:-4], "--workers", "1", "-o", str(out)])
    assert again.exit_code == 0, again.output  # replaces its own output
    assert {p.name: p.read_bytes() for p in out.iterdir()} == first  # same seed, same bytes


def test_cli_refuses_bad_input(tmp_path: Path) -> None:
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "keep.txt").write_text("mine")
    base = ["simulate", str(SAR), "--members", "UAV=1", "--reps", "1"]
    cases = [
        ([*base, "--scenario", "nope"], "no scenario 'nope'"),
        ([*base, "--members", "Robot=2"], "Robot"),
        ([*base, "--targets", "x"], "not a comma-separated list"),
        ([*base, "--scenario", "coverage", "-o", str(foreign)], "not written by swarmgen"),
    ]
    for args, message in cases:
        result = CliRunner().invoke(main, args)
        assert result.exit_code == 2, (args, result.output)
        assert message in result.output
    assert (foreign / "keep.txt").read_text() == "mine"


def test_scenario_files_are_checked() -> None:
    with pytest.raises(sc.ScenarioError, match="unknown key"):
        sc.parse({"name": "x", "wrold": {}})
    with pytest.raises(sc.ScenarioError, match="clock_origin"):
        sc.parse({"name": "x", "clock_origin": "missionStart"})
    for name in ("coverage", "sar"):
        shipped = sc.load(name)
        assert (shipped.width, shipped.height, shipped.reps) == (201, 201, 50)
        assert sc.parse(shipped.to_json()) == shipped


def test_confidence_intervals() -> None:
    assert t975(1) == pytest.approx(12.7062, abs=1e-4)
    assert t975(49) == pytest.approx(2.009575, abs=1e-6)
    assert t975(200) == pytest.approx(1.971896, abs=1e-6)
    e = estimate([1.0, 2.0, 3.0, None])
    assert (e.n, e.missing, e.mean) == (3, 1, 2.0)
    assert e.half == pytest.approx(4.302653 * 1.0 / 3**0.5)
    assert kth([5, None, 3, 9], 0.0, 4) == 3 and kth([5, None, 3, 9], 0.75, 4) == 9
    assert kth([5, None, 3, 9], 1.0, 4) is None


def test_cli_records_one_bag_per_run(tmp_path: Path) -> None:
    """`--record DIR`: one bag per run, read back by rosbags alone, the same bytes whatever the
    workers; `swarmgen timeline` over them has launch first, and in every run the first
    targetFound comes before the first targetRescued."""
    pytest.importorskip("rosbags", reason="rosbags comes with the `ros` extra: run `make ros`")
    from swarmgen.trace.reader import read_events
    from tests.conftest import run_cli
    from tests.test_trace import read_with_rosbags_only

    args = ["simulate", str(SAR), "--scenario", "sar", "--members", "UAV=1,2", "--targets", "2"]
    args += ["--reps", "2", "--seed", "4"]
    bags = {}
    for workers in ("1", "3"):
        record = tmp_path / f"bags{workers}"
        result = CliRunner().invoke(main, [*args, "--workers", workers, "--record", str(record)])
        assert result.exit_code == 0, result.output
        assert f"recorded 4 run(s) into {record} (mcap)" in result.output
        bags[workers] = {p.relative_to(record): p.read_bytes() for p in record.rglob("*.mcap")}
    assert bags["1"] == bags["3"]  # deterministic, independent of the workers
    record = tmp_path / "bags1"
    names = sorted(p.name for p in record.iterdir())
    assert names == [f"UAV{n}_UGV{n}_targets2-{r:04d}" for n in (1, 2) for r in (0, 1)]

    content = read_with_rosbags_only(*(record / n for n in names))
    for bag in content.values():
        messages = bag["messages"]
        assert bag["types"]["/swarm/events"] == "swarmgen_msgs/msg/Event"
        events = [m[2]["name"] for m in messages if m[0] == "/swarm/events"]
        assert events[:2] == ["launch", "done.invoke.TakeOff.succeeded"]
        assert {"UAV-1", "UGV-1"} <= {m[2]["member"] for m in messages if m[0] != "/swarm/events"}

    runs = read_events([record])
    assert len(runs) == 4
    for run in runs:
        found, rescued = run.first("targetFound"), run.first("targetRescued")
        assert found is not None and rescued is not None  # stop = rescued: both occur
        assert run.first("launch") == run.events[0] and run.events[0].stamp_ns == 0
        assert found.stamp_ns <= rescued.stamp_ns
        assert run.events.index(found) < run.events.index(rescued)
        states = {s.member: s.states for s in run.states}
        assert states["UAV-1"] and states["UGV-1"]

    timeline = run_cli("timeline", str(record))
    assert timeline.returncode == 0, timeline.stderr
    rows = [line.split() for line in timeline.stdout.splitlines()[1:]]
    order = [row[0] for row in rows]
    assert order[0] == "launch" and rows[0][1] == "4/4"
    assert order.index("missionStart") < order.index("targetFound") < order.index("targetRescued")
    assert rows[order.index("missionStart")][3] == "10.000"  # tick 10, 1000 ms per tick

    again = CliRunner().invoke(main, [*args, "--record", str(record)])
    assert again.exit_code == 2 and "exists" in again.output
