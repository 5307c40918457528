"""User errors are not bugs: every command with bad arguments, bad side files (scenarios, replay
scripts, bags) and bad output paths, and with a closed, full or broken stdout, ends with exit 2
(or 0 for a reader that stopped early) and one clear line: never exit 3, never a traceback,
never MemoryError, and nothing written on failure.

Cases where the process boundary matters (streams, argv bytes, exit codes) run the real entry
point (`tests.hostile.swarmgen`); the contents of side files are checked in-process."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from click.testing import CliRunner

from swarmgen import replay
from swarmgen.cli import main
from swarmgen.sim import scenario as sc
from tests.hostile import ROOT, SAMPLE, Outcome, assert_clean, assert_refused, snapshot, swarmgen

pytest.importorskip("rosbags", reason="rosbags comes with the `ros` extra: run `make ros`")

from swarmgen.trace.reader import read_events
from swarmgen.trace.recorder import record_replay

MISSION = ROOT / "sample_models" / "sar" / "scenarios" / "uav_mission.json"
LONG = "a/" * 2500  # a 5,000-character path
LONG_NAME = "n" * 300  # one component over 255 bytes


def one_error_line(outcome: Outcome, says: str) -> None:
    """Exit 2, exactly one `swarmgen: error:` line on stderr, mentioning `says`."""
    assert_refused(outcome, exit=2, says=says)
    errors = [line for line in outcome.stderr.splitlines() if line.startswith("swarmgen: error")]
    assert len(errors) == 1, str(outcome)


def readonly(tmp_path: Path) -> Path:
    """A directory nobody may create files in: mode 0555, or /sys when running as root (root
    ignores modes; sysfs refuses mkdir even to root)."""
    if os.geteuid() == 0:
        return Path("/sys")
    directory = tmp_path / "ro"
    directory.mkdir()
    directory.chmod(0o555)
    return directory


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small real bag (a replay trace recorded in-process, no model needed)."""
    path = tmp_path_factory.mktemp("bags") / "run1"
    steps = [{"event": "launch"}, {"event": "missionStart"}]
    trace = [{"step": i, "active": ["Idle"]} for i in range(3)]
    record_replay(path, "UAV", steps, trace)
    return path


# --- 1. schema -o


def test_schema_o_existing_file(tmp_path: Path) -> None:
    (tmp_path / "f").write_text("keep")
    outcome = swarmgen("schema", "-o", "f", cwd=tmp_path)
    one_error_line(outcome, "is a file, not a directory")
    assert (tmp_path / "f").read_text() == "keep"


def test_schema_o_below_a_file(tmp_path: Path) -> None:
    (tmp_path / "f").write_text("keep")
    before = snapshot(tmp_path)
    one_error_line(swarmgen("schema", "-o", "f/sub", cwd=tmp_path), "is a file")
    assert snapshot(tmp_path) == before


def test_schema_o_readonly_parent(tmp_path: Path) -> None:
    target = readonly(tmp_path) / "schemas"
    one_error_line(swarmgen("schema", "-o", target, cwd=tmp_path), "cannot create")
    assert not target.exists()


@pytest.mark.parametrize("name", ["too_long", "name_too_long"])
def test_schema_o_long_paths(tmp_path: Path, name: str) -> None:
    path = LONG if name == "too_long" else LONG_NAME
    one_error_line(swarmgen("schema", "-o", path, cwd=tmp_path), "too long")
    assert list(tmp_path.iterdir()) == []


def test_schema_check_target_is_a_directory(tmp_path: Path) -> None:
    (tmp_path / "ir.schema.json").mkdir()
    outcome = swarmgen("schema", "-o", tmp_path, "--check", cwd=tmp_path)
    assert_refused(outcome, exit=1, says="stale")


def test_schema_writes_atomically_where_it_may(tmp_path: Path) -> None:
    outcome = swarmgen("schema", "-o", "new/dir", cwd=tmp_path)
    assert_clean(outcome, (0,))
    assert json.loads((tmp_path / "new" / "dir" / "ir.schema.json").read_text())["$defs"]
    assert [p.name for p in (tmp_path / "new" / "dir").iterdir()] == ["ir.schema.json"]


# --- 2. timeline --csv/--plot, --record of replay and simulate


def _timeline(bag: Path, *args: str | Path) -> tuple[int, str]:
    result = CliRunner().invoke(main, ["timeline", str(bag), *map(str, args)])
    return result.exit_code, result.output


@pytest.mark.parametrize(
    ("option", "where", "says"),
    [
        ("--csv", "dir", "is a directory"),
        ("--csv", "below_file", "is a file"),
        ("--csv", "readonly", "cannot"),
        ("--csv", "too_long", "too long"),
        ("--csv", "name_too_long", "too long"),
        ("--plot", "dir.svg", "is a directory"),
        ("--plot", "below_file", "is a file"),
        ("--plot", "readonly", "cannot"),
        ("--plot", "readonly_missing_dir", "cannot create"),
    ],
)
def test_timeline_output_paths(
    bag: Path, tmp_path: Path, option: str, where: str, says: str
) -> None:
    (tmp_path / "f").write_text("keep")
    (tmp_path / "dir.svg").mkdir()
    suffix = ".svg" if option == "--plot" else ".csv"
    target = {
        "dir": tmp_path,
        "dir.svg": tmp_path / "dir.svg",
        "below_file": tmp_path / "f" / f"t{suffix}",
        "readonly": readonly(tmp_path) / f"t{suffix}",
        "readonly_missing_dir": readonly(tmp_path) / "missing" / f"t{suffix}",
        "too_long": tmp_path / f"{LONG}t{suffix}",
        "name_too_long": tmp_path / f"{LONG_NAME}{suffix}",
    }[where]
    before = snapshot(tmp_path)
    started = time.perf_counter()
    code, output = _timeline(bag, option, target)
    assert code == 2, output
    assert says in output and "internal error" not in output, output
    assert "event" not in output.splitlines()[0], "the table was printed before the refusal"
    assert snapshot(tmp_path) == before
    assert time.perf_counter() - started < 5


def test_timeline_plot_into_a_missing_directory_makes_it(bag: Path, tmp_path: Path) -> None:
    code, output = _timeline(bag, "--plot", tmp_path / "new" / "t.svg", "--csv", tmp_path / "t.csv")
    assert code == 0, output
    assert (tmp_path / "new" / "t.svg").read_bytes().startswith(b"<?xml")
    assert (tmp_path / "t.csv").read_text().startswith("event,runs,total_runs")


def test_timeline_failure_removes_the_directories_it_made(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    code, output = _timeline(tmp_path / "empty", "--csv", tmp_path / "made" / "t.csv")
    assert code == 2 and "no bags found in" in output, output
    assert not (tmp_path / "made").exists()


def _record_target(tmp_path: Path, where: str) -> Path | str:
    (tmp_path / "f").write_text("keep")
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    (tmp_path / "old").mkdir()
    targets: dict[str, Path | str] = {
        "below_file": tmp_path / "f" / "bag",
        "readonly": readonly(tmp_path) / "bag",
        "dangling_symlink": tmp_path / "dangling",
        "exists": tmp_path / "old",
        "too_long": LONG,
        "name_too_long": LONG_NAME,
    }
    return targets[where]


RECORD_CASES = [
    ("below_file", "is a file"),
    ("readonly", "cannot create"),
    ("dangling_symlink", "dangling symlink"),
    ("exists", "exists"),
    ("too_long", "too long"),
    ("name_too_long", "too long"),
]


@pytest.mark.parametrize(("where", "says"), RECORD_CASES)
def test_replay_record_paths(tmp_path: Path, where: str, says: str) -> None:
    target = _record_target(tmp_path, where)
    before = snapshot(tmp_path)
    args = ("replay", SAMPLE, "--member", "UAV", "--script", MISSION, "--record", target)
    outcome = swarmgen(*args, cwd=tmp_path)
    one_error_line(outcome, says)
    assert outcome.stdout == ""  # refused before the replay ran
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize(("where", "says"), RECORD_CASES[:3])
def test_simulate_record_paths(tmp_path: Path, where: str, says: str) -> None:
    target = _record_target(tmp_path, where)
    before = snapshot(tmp_path)
    args = ("simulate", SAMPLE, "--members", "UAV=1", "--reps", "1", "--record", target)
    outcome = swarmgen(*args, cwd=tmp_path)
    one_error_line(outcome, says)
    assert "swarmgen: simulate [" not in outcome.stderr  # refused before any run started
    assert snapshot(tmp_path) == before


# --- 3. closed, full and broken stdout


def shell(command: str, cwd: Path) -> Outcome:
    """`command` in bash with `SG` = the swarmgen entry point; the exit is swarmgen's (pipefail
    would report head's)."""
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    environment.pop("SWARMGEN_DEBUG", None)
    started = time.perf_counter()
    sg = f"{sys.executable} -m swarmgen"
    script = f'{command.replace("SG", sg)}; echo "exit=${{PIPESTATUS[0]}}" >&3'
    completed = subprocess.run(
        ["bash", "-c", f"exec 3>status; {script}"],
        cwd=cwd,
        env=environment,
        capture_output=True,
        timeout=60,
        check=False,
    )
    status = (cwd / "status").read_text().strip()
    return Outcome(
        (command,),
        int(status.removeprefix("exit=")),
        completed.stdout.decode(errors="replace"),
        completed.stderr.decode(errors="replace"),
        time.perf_counter() - started,
    )


REPLAY = f"SG replay {SAMPLE} --member UAV --script {MISSION}"
SARIF = f"SG validate {SAMPLE} --format sarif"


@pytest.mark.parametrize(
    ("name", "command", "exit", "says"),
    [
        ("replay_reader_gone", f"{REPLAY} | true", 0, None),
        ("replay_head_1", f"{REPLAY} | head -1 >/dev/null", 0, None),
        ("replay_both_streams_reader_gone", f"{REPLAY} 2>&1 | true", 0, None),
        ("validate_reader_gone", f"{SARIF} | true", 0, None),
        ("help_reader_gone", "SG --help | true", 0, None),
        ("replay_stdout_closed", f"{REPLAY} >&-", 2, "stdout: it is closed"),
        ("validate_stdout_closed", f"{SARIF} >&-", 2, "stdout: it is closed"),
        ("replay_dev_full", f"{REPLAY} >/dev/full", 2, "No space left on device"),
        ("validate_dev_full", f"{SARIF} >/dev/full", 2, "No space left on device"),
        ("help_dev_full", "SG --help >/dev/full", 2, "No space left on device"),
        ("stderr_dev_full", "SG validate nope.xmi 2>/dev/full >/dev/null", 2, None),
        ("schema_stdout_closed", "SG schema -o out >&-", 0, None),
    ],
)
def test_streams(tmp_path: Path, name: str, command: str, exit: int, says: str | None) -> None:
    outcome = shell(command, tmp_path)
    assert_clean(outcome, (exit,))
    assert "Exception ignored" not in outcome.stderr, str(outcome)
    if says is not None:
        one_error_line(outcome, says)
    if name == "schema_stdout_closed":  # nothing for stdout: stdout closed does not matter
        assert (tmp_path / "out" / "ir.schema.json").is_file()
        assert not any(p.name == "ir.schema.json" for p in tmp_path.iterdir())


def test_replay_dev_full_writes_no_bag(tmp_path: Path) -> None:
    outcome = shell(f"{REPLAY} --record bag >/dev/full", tmp_path)
    one_error_line(outcome, "No space left on device")
    assert not (tmp_path / "bag").exists()


# --- 4. scenario and replay-script contents


SCENARIOS: dict[str, tuple[str | bytes, str]] = {
    "spacing_string": ('{"placement": {"*": {"spacing": "abc"}}}', '$.placement["*"].spacing: expected a positive number'),
    "spacing_nan": ('{"placement": {"*": {"spacing": NaN}}}', '$.placement["*"].spacing: NaN'),
    "spacing_infinity": ('{"placement": {"UAV": {"spacing": Infinity}}}', "$.placement.UAV.spacing: Infinity"),
    "spacing_minus_1e308": ('{"placement": {"*": {"spacing": -1e308}}}', "got -1e+308"),
    "spacing_1e308": ('{"placement": {"*": {"spacing": 1e308}}}', "got 1e+308"),
    "number_too_large": ('{"stop_level": 1e400}', "$.stop_level: Infinity"),
    "width_zero": ('{"world": {"width": 0}}', "$.world.width: expected an integer from 1"),
    "height_negative": ('{"world": {"height": -5}}', "$.world.height: expected an integer"),
    "width_boolean": ('{"world": {"width": true}}', "$.world.width: expected an integer from 1 to 10,000, got true"),
    "width_huge": ('{"world": {"width": 1000000000}}', "$.world.width"),
    "view_huge": ('{"world": {"view": 5000}}', "$.world.view"),
    "world_list": ('{"world": [201, 201]}', "$.world: expected an object, got a list"),
    "members_list_of_object": ('{"members": {"UAV": [1, {}]}}', "$.members.UAV[1]: expected an integer"),
    "members_huge": ('{"members": {"UAV": 1000000}}', "$.members.UAV: expected an integer from 0 to 10,000"),
    "members_bad_string": ('{"members": {"UAV": "x"}}', '$.members.UAV: a string must be "=TYPE"'),
    "reps_float": ('{"reps": 1.5}', "$.reps: expected an integer"),
    "reps_zero": ('{"reps": 0}', "$.reps: expected an integer from 1"),
    "max_ticks_beyond_int32": ('{"max_ticks": 3000000000}', "$.max_ticks"),
    "station_string": ('{"station": "launch"}', '$.station: expected a list, got "launch"'),
    "station_tick_negative": ('{"station": [{"tick": -1, "event": "launch"}]}', "$.station[0].tick"),
    "station_event_number": ('{"station": [{"tick": 1, "event": 3}]}', "$.station[0].event: expected a string"),
    "station_data_nan": ('{"station": [{"event": "a", "data": {"v": NaN}}]}', "$.station[0].data.v: NaN"),
    "stop_level_zero": ('{"stop_level": 0}', "$.stop_level: expected a positive number"),
    "levels_not_fractions": ('{"coverage_levels": [0.5, 2]}', "$.coverage_levels[1]"),
    "unknown_key_did_you_mean": ('{"wrold": {}}', '$.wrold: unknown key; did you mean "world"?'),
    "unknown_nested_key": ('{"world": {"widht": 3}}', '$.world.widht: unknown key; did you mean "width"?'),
    "unknown_timing_key": ('{"timing": {"takeof": 3}}', 'did you mean "takeoff"?'),
    "duplicate_key": ('{"world": {"width": 3, "width": 4}}', '$.world: duplicate key "width"'),
    "more_targets_than_patches": ('{"world": {"width": 2, "height": 1}, "target_positions": [[0, 0], [1, 0], [0, 0]]}', "more targets than patches"),
    "target_outside": ('{"world": {"width": 2, "height": 2}, "target_positions": [[5, 0]]}', "$.target_positions[0][0]"),
    "top_level_list": ("[1, 2]", "$: expected an object, got a list"),
    "not_utf8": (b'{"name": "\xff"}', "not UTF-8"),
    "not_json": ('{"name": ', "not JSON"),
    "nested_100000_deep": ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
    "nested_100_deep_in_data": ('{"station": [{"event": "a", "data": ' + '{"a": ' * 100 + "1" + "}" * 100 + "}]}", "nested too deeply"),
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_scenario_contents(tmp_path: Path, name: str) -> None:
    text, says = SCENARIOS[name]
    path = tmp_path / "scenario.json"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    started = time.perf_counter()
    with pytest.raises(sc.ScenarioError) as caught:
        sc.load(str(path))
    message = str(caught.value)
    assert message.startswith(f"{path}:"), message
    assert says in message, message
    assert "\n" not in message
    assert time.perf_counter() - started < 5


def test_scenario_error_through_the_cli(tmp_path: Path) -> None:
    path = tmp_path / "scenario.json"
    path.write_text('{"placement": {"*": {"spacing": "abc"}}}')
    result = CliRunner().invoke(main, ["simulate", str(SAMPLE), "--scenario", str(path)])
    assert result.exit_code == 2, result.output
    expected = (
        f'{path}: $.placement["*"].spacing: expected a positive number in (0, 10000], got "abc"'
    )
    assert f"swarmgen: error: {expected}" in result.output


@pytest.mark.parametrize("name", ["fifo", "dev_zero", "proc_file", "directory"])
def test_scenario_and_script_files_that_are_not_files(tmp_path: Path, name: str) -> None:
    path = {"dev_zero": Path("/dev/zero"), "proc_file": Path("/proc/self/status")}.get(name)
    if name == "fifo":
        path = tmp_path / "fifo.json"
        os.mkfifo(path)
    elif name == "directory":
        path = tmp_path
    assert path is not None
    with pytest.raises(sc.ScenarioError, match=r"not a regular file|is a directory"):
        sc.load(str(path))
    with pytest.raises(replay.ReplayError, match=r"not a regular file|is a directory"):
        replay.load_scenario(path)


SCRIPTS: dict[str, tuple[str, str]] = {
    "nested_burst": ('[{"burst": [{"burst": [{"event": "launch"}]}]}]', "$[0].burst[0]: a burst cannot contain a burst"),
    "empty_burst": ('{"steps": [{"burst": []}]}', "$.steps[0].burst: expected a non-empty list"),
    "event_number": ('[{"event": 3}]', "$[0].event: expected a string, got 3"),
    "data_list": ('[{"event": "a", "data": [1]}]', "$[0].data: expected an object, got a list"),
    "unknown_step_key": ('[{"event": "a", "dat": {}}]', '$[0].dat: unknown key; did you mean "data"?'),
    "event_and_complete": ('[{"event": "a", "complete": "TakeOff"}]', "$[0].complete: unknown key"),
    "unknown_top_key": ('{"memberr": "UAV", "steps": []}', '$.memberr: unknown key; did you mean "member"?'),
    "no_steps": ('{"member": "UAV"}', 'a script is a list of steps or {"steps": [...]}'),
    "step_not_object": ('[["launch"]]', "$[0]: expected an object, got a list"),
    "duplicate_key": ('[{"event": "a", "event": "b"}]', '$[0]: duplicate key "event"'),
    "infinity_in_data": ('[{"event": "a", "data": {"x": -Infinity}}]', "$[0].data.x: -Infinity"),
    "nested_100000_deep": ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_replay_script_contents(tmp_path: Path, name: str) -> None:
    text, says = SCRIPTS[name]
    path = tmp_path / "script.json"
    path.write_text(text)
    with pytest.raises(replay.ReplayError) as caught:
        replay.load_scenario(path)
    message = str(caught.value)
    assert message.startswith(f"{path}:") and says in message, message


@pytest.mark.parametrize("name", ["nested_burst", "nested_100000_deep"])
def test_replay_script_through_the_cli(tmp_path: Path, name: str) -> None:
    (tmp_path / "script.json").write_text(SCRIPTS[name][0])
    args = ("replay", SAMPLE, "--member", "UAV", "--script", "script.json")
    outcome = swarmgen(*args, cwd=tmp_path, timeout=20)
    one_error_line(outcome, SCRIPTS[name][1])
    assert outcome.stdout == ""


# --- 5. limits on the sweep, checked before anything runs


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--members", "UAV=1000000"], "1000000 is not a count from 0 to 10,000"),
        (["--reps", "1000000"], "1000000 is not in the range 1<=x<=10000"),
        (["--scenario", "sar", "--targets", str(10**7)], "is not a count from 0 to 100,000"),
        (["--scenario", "sar", "--targets", "50000"], "more than the 40,401 patches"),
        (["--members", "UAV=0"], "has no members"),
        (["--members", "UAV=-1"], "-1 is not a count"),
        (["--members", "UAV=abc"], "'abc' is not a comma-separated list of integers"),
        (["--members", "UAV="], "is not a comma-separated list"),
        (["--members", "=3"], "write TYPE=COUNT"),
        (["--members", "NOPE=2"], "no such member type"),
        (["--members", "UVA=2"], "did you mean"),
        (["--members", "UAV=5000", "--reps", "50"], "members x repetitions"),
        (["--members", "UAV=1,2,3,4,5", "--reps", "10000"], "patches x repetitions"),
        (["--members", ",".join(["UAV=1"] + [str(n) for n in range(2, 1500)])], "more than 1,000"),
        (["--workers", "100000"], "100000 is not in the range 1<=x<=256"),
        (["--seed", "-1"], "is not in the range"),
        (["--members", "UAV=99999999999999999999999999"], "not a comma-separated list"),
    ],
    ids=lambda value: "_".join(value)[:60] if isinstance(value, list) else "",
)
def test_simulate_limits(args: list[str], says: str) -> None:
    started = time.perf_counter()
    result = CliRunner().invoke(main, ["simulate", str(SAMPLE), "--reps", "1", *args])
    assert result.exit_code == 2, result.output
    assert says in result.output, result.output
    assert "swarmgen: simulate [" not in result.output  # no run started
    assert time.perf_counter() - started < 5


def test_simulate_huge_members_as_a_process(tmp_path: Path) -> None:
    outcome = swarmgen("simulate", SAMPLE, "--members", "UAV=1000000", cwd=tmp_path, timeout=20)
    one_error_line(outcome, "is not a count")
    assert outcome.seconds < 10  # it used to run for minutes towards MemoryError


# --- 6. timeline over odd trees of bags


def _runs(*paths: Path) -> int:
    return len(read_events(paths))


def test_timeline_symlink_loop_counts_each_bag_once(bag: Path, tmp_path: Path) -> None:
    tree = tmp_path / "runs"
    tree.mkdir()
    (tree / "r1").symlink_to(bag)
    (tree / "again").symlink_to(bag)
    (tree / "loop").symlink_to(tree)
    (tree / "up").symlink_to(tmp_path)
    assert _runs(tree) == 1  # it was 41 before (the loop followed until the path was too long)
    assert _runs(tree, bag) == 1


def test_timeline_cli_on_a_loop(bag: Path, tmp_path: Path) -> None:
    (tmp_path / "r").symlink_to(bag)
    (tmp_path / "loop").symlink_to(tmp_path)
    outcome = swarmgen("timeline", tmp_path, cwd=tmp_path)
    assert_clean(outcome, (0,))
    assert "swarmgen: 1 run(s)" in outcome.stderr


BROKEN: dict[str, Callable[[Path, Path], Path]] = {}


def _broken(name: str) -> Callable[[Callable[[Path, Path], Path]], Callable[[Path, Path], Path]]:
    def register(make: Callable[[Path, Path], Path]) -> Callable[[Path, Path], Path]:
        BROKEN[name] = make
        return make

    return register


@_broken("truncated_mcap")
def _truncated(bag: Path, tmp: Path) -> Path:
    data = (bag / "run1.mcap").read_bytes()
    (tmp / "t.mcap").write_bytes(data[: len(data) // 2])
    return tmp / "t.mcap"


@_broken("random_db3")
def _random(bag: Path, tmp: Path) -> Path:
    (tmp / "r.db3").write_bytes(bytes(range(256)) * 8)
    return tmp / "r.db3"


@_broken("bad_metadata")
def _metadata(bag: Path, tmp: Path) -> Path:
    copy = tmp / "b"
    copy.mkdir()
    (copy / "run1.mcap").write_bytes((bag / "run1.mcap").read_bytes())
    (copy / "metadata.yaml").write_text("rosbag2_bagfile_information: [\n")
    return tmp


@_broken("missing_storage_file")
def _missing(bag: Path, tmp: Path) -> Path:
    copy = tmp / "b"
    copy.mkdir()
    (copy / "metadata.yaml").write_bytes((bag / "metadata.yaml").read_bytes())
    return copy


@_broken("empty_directory")
def _empty(bag: Path, tmp: Path) -> Path:
    (tmp / "e").mkdir()
    return tmp / "e"


@_broken("loop_without_bags")
def _loop(bag: Path, tmp: Path) -> Path:
    (tmp / "d").mkdir()
    (tmp / "d" / "loop").symlink_to(tmp / "d")
    return tmp / "d"


@_broken("not_a_bag")
def _text(bag: Path, tmp: Path) -> Path:
    (tmp / "notes.txt").write_text("hello")
    return tmp / "notes.txt"


@pytest.mark.parametrize("name", sorted(BROKEN))
def test_timeline_refuses_broken_bags(bag: Path, tmp_path: Path, name: str) -> None:
    target = BROKEN[name](bag, tmp_path)
    code, output = _timeline(target)
    assert code == 2, output
    lines = [line for line in output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("swarmgen: error: "), output
    expected = "no bags found in" if name in ("empty_directory", "loop_without_bags") else ""
    assert expected in lines[0]


# --- 7. every command with bad arguments


NON_UTF8 = os.fsdecode(b"caf\xe9.xmi")  # passed to the process as the raw byte 0xe9


@pytest.mark.parametrize(
    ("name", "args", "says"),
    [
        ("validate_empty_path", ["validate", ""], "empty path"),
        ("validate_newline_path", ["validate", "a\nb.xmi"], None),
        ("validate_control_chars", ["validate", "a\x01\x1b[31mb.xmi"], None),
        ("compile_non_utf8_path", ["compile", NON_UTF8, "-o", "out"], None),
        ("compile_empty_output", ["compile", str(SAMPLE), "-o", ""], "empty path"),
        ("compile_bad_backend", ["compile", str(SAMPLE), "-o", "out", "--backend", "cobol"], "unknown backend"),
        ("validate_unknown_code", ["validate", str(SAMPLE), "--disable", "SG999"], "unknown code"),
        ("graph_dash_model", ["graph", "-"], None),
        ("graph_bad_format", ["graph", str(SAMPLE), "--format", "png"], "Invalid value"),
        ("schema_empty_output", ["schema", "-o", ""], "empty path"),
        ("replay_dash_script", ["replay", str(SAMPLE), "--member", "UAV", "--script", "-"], "no such file"),
        ("replay_missing_member", ["replay", str(SAMPLE), "--script", str(MISSION)], "Missing option"),
        ("replay_bad_backend", ["replay", str(SAMPLE), "--member", "UAV", "--script", str(MISSION), "--backend", "x"], "Invalid value"),
        ("replay_unknown_member", ["replay", str(SAMPLE), "--member", "Robot", "--script", str(MISSION)], "no member type 'Robot'"),
        ("replay_newline_script", ["replay", str(SAMPLE), "--member", "UAV", "--script", "s\n.json"], "s\\n.json"),
        ("simulate_empty_scenario", ["simulate", str(SAMPLE), "--scenario", ""], "no scenario"),
        ("simulate_non_utf8_scenario", ["simulate", str(SAMPLE), "--scenario", NON_UTF8], "\\xe9"),
        ("timeline_dash", ["timeline", "-"], "no such file"),
        ("timeline_empty_path", ["timeline", ""], "empty path"),
        ("timeline_bad_alias", ["timeline", ".", "--alias", "nope"], "not OLD=NEW"),
        ("timeline_plot_pdf", ["timeline", ".", "--plot", "x.pdf"], ".png or .svg"),
        ("unknown_command", ["frobnicate"], "No such command"),
        ("simulate_scenario_name_too_long", ["simulate", str(SAMPLE), "--scenario", LONG_NAME], "no scenario"),
        ("schema_check_name_too_long", ["schema", "-o", LONG_NAME, "--check"], "too long"),
    ],
)  # fmt: skip
def test_bad_arguments(tmp_path: Path, name: str, args: list[str], says: str | None) -> None:
    before = snapshot(tmp_path)
    outcome = swarmgen(*args, cwd=tmp_path)
    assert_refused(outcome, says=says)
    assert outcome.exit == 2, str(outcome)
    assert snapshot(tmp_path) == before
    for line in outcome.stderr.splitlines():  # a path cannot forge a line of its own
        assert not line.startswith(("b.xmi", ".json", "[31m")), str(outcome)
