"""`swarmgen optimize` with real optuna and real SQLite on a tiny world: the optimum found is the
one computed by hand, NSGA-II's front is non-dominated, a study killed with SIGKILL resumes with
nothing lost or repeated, the best variant validates and compiles, bad input is one line."""

from __future__ import annotations

import contextlib
import json
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import optuna
import pytest
from click.testing import CliRunner
from optuna.trial import TrialState

from swarmgen import diagnostics as dg
from swarmgen import pipeline
from swarmgen.cli import main
from swarmgen.commands.optimize import optimize
from swarmgen.ir.query import composition
from swarmgen.sim import objectives as obj
from swarmgen.sim import optimize as opt
from swarmgen.sim import params
from swarmgen.sim import scenario as sc
from tests.conftest import SAMPLE_MODELS

SAR = next(m for m in SAMPLE_MODELS if m.parent.name == "sar")
COVER = "minimize mean(coverage_100%)"
WAIT = 120.0  # seconds: the longest the killed study may take to reach its trials


@pytest.fixture()
def tiny(tmp_path: Path) -> Path:
    """The coverage scenario on a 15 x 15 world, 2 UAVs, 2 repetitions."""
    doc = sc.load("coverage").to_json()
    doc.update(world={"width": 15, "height": 15, "view": 1}, members={"UAV": [2]}, reps=2, seed=3)
    path = tmp_path / "tiny.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def run(*args: str) -> tuple[int, str]:
    """`swarmgen optimize SAR ...` in this process: exit code and stderr."""
    result = CliRunner().invoke(optimize, [str(SAR), *args])
    return result.exit_code, result.stderr


def completed(url: str, name: str = "swarmgen") -> list[optuna.trial.FrozenTrial]:
    study = optuna.load_study(study_name=name, storage=url)
    return study.get_trials(states=(TrialState.COMPLETE,))


CAMERA = "UAV.camera.fovRadius"
RADII = (0.2, 0.5, 0.8, 1.1, 1.4)  # views 0, 1, 2, 3, 4 over patches of 66/201 m


def test_finds_the_optimum_computed_by_hand(tiny: Path, tmp_path: Path) -> None:
    """The largest camera field of view covers the tiny world fastest: computed by hand
    (every choice's objective, straight from the simulator), then found by a study of 8
    trials, 4 at a time, whose best point goes into the model variant."""
    validation = pipeline.validate(SAR)
    assert validation.model is not None
    names = params.names_of(validation.model, validation.charts)
    base = sc.load(str(tiny))
    spec = opt.Study(SAR, base, [], [obj.parse(COVER)], names)
    by_radius = dict(
        zip(
            RADII,
            (v[0][0] for v in spec.evaluate_many([((CAMERA, r),) for r in RADII])),
            strict=True,
        )
    )
    assert min(by_radius, key=by_radius.__getitem__) == max(RADII), by_radius
    assert sorted(by_radius.values(), reverse=True) == list(by_radius.values())  # wider: faster
    out = tmp_path / "out"
    code, err = run(
        "--scenario", str(tiny), "--space", f"{CAMERA}={','.join(map(str, RADII))}",
        "--objective", COVER, "--trials", "8", "--parallel", "4", "-o", str(out),
    )  # fmt: skip
    assert code == 0, err
    best = json.loads((out / "best.json").read_text())["best"]
    assert best[0]["params"] == {CAMERA: max(RADII)}
    assert best[0]["values"][COVER] == pytest.approx(by_radius[max(RADII)])
    for name in ("trials.csv", "history.png", "history.svg", "best-scenario.json"):
        assert (out / name).is_file(), name
    assert not (out / "importance.png").exists()  # one parameter: no importance
    scenario = json.loads((out / "best-scenario.json").read_text())
    assert scenario["world"]["view"] == 1 and scenario["world"]["views"] == {"UAV": 4}
    camera = pipeline.validate(out / "best.xmi").model
    assert camera is not None
    radius = next(p for h in camera.hardware if h.name == "DownwardCamera" for p in h.parameters)
    assert radius.name == "fovRadius" and radius.default == max(RADII)


def test_parallel_trials_are_reproducible(tiny: Path, tmp_path: Path) -> None:
    """The same seed and batch size give the same study; a batch runs its trials together."""
    validation = pipeline.validate(SAR)
    assert validation.model is not None
    names = params.names_of(validation.model, validation.charts)
    space = [opt.parse_space(f"{CAMERA}=0.2:1.5"), opt.parse_space("UAV.count=1:3")]
    spec = opt.Study(SAR, sc.load(str(tiny)), space, [obj.parse(COVER)], names)
    sweeps: list[int] = []

    def started(done: int, total: int) -> None:
        if done == 0:
            sweeps.append(total)

    spec.progress = started
    # two studies in two in-memory databases (no file's schema to create and sync)
    studies = [
        opt.run_study(spec, "sqlite:///:memory:", "s", "tpe", 7, 5, parallel=4) for _ in "ab"
    ]
    assert sweeps == [8, 2] * 2  # batches of 4 and 1 trials, 2 runs each, in one sweep each
    a, b = ([(t.params, t.values) for t in s.get_trials()] for s in studies)
    assert a == b and len(a) == 5
    assert len({json.dumps(p, sort_keys=True) for p, _ in a}) == 5  # the liar spread the batch


def test_nsga2_front_is_non_dominated(tiny: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    code, err = run(
        "--scenario", str(tiny), "--space", "UAV.count=1:4", "--space", "world.view=0:3",
        "--objective", COVER, "--objective", "minimize mean(members)",
        "--trials", "12", "--seed", "2", "-o", str(out),
    )  # fmt: skip
    assert code == 0, err
    trials = completed(f"sqlite:///{out / 'study.db'}")
    best = json.loads((out / "best.json").read_text())["best"]
    assert best
    for point in best:
        mine = list(point["values"].values())
        for other in trials:
            dominates = all(a <= b for a, b in zip(other.values, mine, strict=True)) and any(
                a < b for a, b in zip(other.values, mine, strict=True)
            )
            assert not dominates, (point, other.values)
    for name in ("pareto.png", "importance.png", "history-1.png", "history-2.png"):
        assert (out / name).is_file(), name


def _start(tiny: Path, out: Path, trials: int, parallel: int = 1) -> subprocess.Popen[bytes]:
    script = (
        "import sys\nfrom swarmgen.commands.optimize import optimize\n"
        "optimize.main(sys.argv[1:], prog_name='swarmgen optimize')\n"
    )
    args = [
        str(SAR), "--scenario", str(tiny), "--space", "stop_level=0.3:1.0",
        "--space", "timing.takeoff=1:9", "--objective", "minimize mean(end_tick)",
        "--trials", str(trials), "--seed", "5", "--parallel", str(parallel), "-o", str(out),
    ]  # fmt: skip
    return subprocess.Popen(
        [sys.executable, "-c", script, *args], cwd=Path(__file__).resolve().parents[1],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )  # fmt: skip


def _complete_in(db: Path) -> int:
    """COMPLETE trials in the study database, read-only (optuna's own loader would create the
    tables, racing the process that is creating them)."""
    if not db.is_file():
        return 0
    try:
        with contextlib.closing(sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5)) as c:
            return int(
                c.execute("SELECT count(*) FROM trials WHERE state = 'COMPLETE'").fetchone()[0]
            )
    except sqlite3.OperationalError:  # no table yet
        return 0


def test_a_killed_study_resumes_with_nothing_lost_or_repeated(tiny: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    url = f"sqlite:///{out / 'study.db'}"
    process = _start(tiny, out, 100_000, parallel=2)  # killed with up to 2 trials running
    deadline = time.monotonic() + WAIT
    try:
        while True:
            assert process.poll() is None, process.stderr.read() if process.stderr else ""
            assert time.monotonic() < deadline, "the study never reached 3 trials"
            if _complete_in(out / "study.db") >= 3:
                break
            time.sleep(0.02)
    finally:
        process.send_signal(signal.SIGKILL)  # (a no-op if it has already ended)
        process.wait(timeout=WAIT)
    before = optuna.load_study(study_name="swarmgen", storage=url).get_trials()
    done_before = [t for t in before if t.state == TrialState.COMPLETE]
    running = [t for t in before if t.state == TrialState.RUNNING]
    best_before = min(t.value for t in done_before if t.value is not None)
    resumed = _start(tiny, out, len(done_before) + 3)
    _, err = resumed.communicate(timeout=WAIT)
    assert resumed.returncode == 0, err.decode()
    after = optuna.load_study(study_name="swarmgen", storage=url).get_trials()
    assert [t.number for t in after] == list(range(len(after)))  # numbering continues
    assert after[: len(before)] and all(
        a.params == b.params for a, b in zip(after, before, strict=False) if b.state.is_finished()
    )
    done = [t for t in after if t.state == TrialState.COMPLETE]
    assert len(done) == len(done_before) + 3
    keys = [json.dumps(t.params, sort_keys=True) for t in done]
    assert len(keys) == len(set(keys))  # a deterministic sampler repeated nothing
    for lost in running:  # the trial the kill interrupted: failed, then run with its params
        assert after[lost.number].state == TrialState.FAIL
        # the values it had drawn (a kill between two draws leaves only some) are run again
        assert any(lost.params.items() <= t.params.items() for t in done[len(done_before) :])
    assert min(t.value for t in done if t.value is not None) <= best_before
    assert (out / "trials.csv").is_file()


def test_best_variant_validates_and_compiles(tiny: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    code, err = run(
        "--scenario", str(tiny), "--space", "UAV.count=1:3", "--space", "world.view=1:2",
        "--objective", COVER, "--trials", "6", "--seed", "3", "-o", str(out),
    )  # fmt: skip
    assert code == 0, err
    best = json.loads((out / "best.json").read_text())["best"][0]["params"]
    validation = pipeline.validate(out / "best.xmi")
    assert validation.model is not None
    assert not dg.has_errors(validation.diagnostics)
    assert composition(validation.model)["UAV"] == best["UAV.count"]
    compiled = CliRunner().invoke(
        main, ["compile", str(out / "best.xmi"), "-o", str(tmp_path / "c")]
    )
    assert compiled.exit_code == 0, compiled.stderr
    # running it again (the study is complete) rewrites the same results, runs no trial
    code, err = run(
        "--scenario", str(tiny), "--space", "UAV.count=1:3", "--space", "world.view=1:2",
        "--objective", COVER, "--trials", "6", "--seed", "3", "-o", str(out),
    )  # fmt: skip
    assert code == 0, err
    assert (
        len(
            optuna.load_study(study_name="swarmgen", storage=f"sqlite:///{out / 'study.db'}").trials
        )
        == 6
    )
    # the tree is optimize's own: simulate, which removes only its own kind, refuses it
    assert json.loads((out / ".swarmgen.json").read_text())["command"] == "optimize"
    simulated = CliRunner().invoke(
        main, ["simulate", str(SAR), "--scenario", str(tiny), "-o", str(out)]
    )
    assert simulated.exit_code == 2, simulated.output
    assert (out / "best.json").is_file()


@pytest.mark.parametrize(
    ("space", "objective", "says"),
    [
        ("UAV.nope=1:2", COVER, "unknown parameter"),
        ("world.view=a:b", COVER, "write LOW:HIGH"),
        ("world.view=0.5:2.5", COVER, "expected an integer"),
        ("world.view=3:1", COVER, "HIGH > LOW"),
        ("UAV.flightController.maxSpeed=1:5", COVER, "the abstract simulator does not read"),
        ("world.view=0:2", "minimize mean(nope)", "unknown metric"),
        ("world.view=0:2", "minimize eval(coverage_100%)", "unknown function"),
        ("world.view=0:2", "minimize mean(coverage_100%", "write mean(METRIC)"),
        ("world.view=0:2", "__import__('os')", "unknown function"),
    ],
)
def test_bad_space_or_objective_is_one_line_exit_2(
    tiny: Path, tmp_path: Path, space: str, objective: str, says: str
) -> None:
    out = tmp_path / "out"
    code, err = run(
        "--scenario", str(tiny), "--space", space, "--objective", objective, "-o", str(out)
    )
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1, err
    assert says in err
    assert not out.exists()  # refused before any trial: no study, no directory


def test_objective_arithmetic() -> None:
    scenario = sc.load("coverage")
    parsed = obj.parse("maximize 2 * (count(coverage_50%) - 1) / 4 + p90(end_tick)")
    assert parsed.direction == "maximize"
    assert parsed.metrics() == {"coverage_50%", "end_tick"}
    obj.check(parsed, scenario)
    assert obj._aggregate("p90", [1.0, 2.0, None], 10.0) == 10.0
    assert obj._aggregate("count", [1.0, None], 10.0) == 1.0
    assert obj._aggregate("median", [3.0, 1.0, 2.0], 10.0) == 2.0


def test_cmaes_runs_a_seeded_reproducible_study(tiny: Path, tmp_path: Path) -> None:
    lines = []
    for name in ("a", "b"):
        code, err = run(
            "--scenario", str(tiny), "--space", "stop_level=0.3:1.0", "--space",
            "timing.takeoff=1:9", "--objective", "minimize mean(end_tick)", "--sampler", "cmaes",
            "--trials", "5", "-o", str(tmp_path / name),
        )  # fmt: skip
        assert code == 0, err
        lines.append((tmp_path / name / "trials.csv").read_text().splitlines())
    assert len(lines[0]) == 6  # a header and five trials
    assert lines[0] == lines[1]  # the same seed: the same study


def test_two_objectives_need_nsga2(tiny: Path, tmp_path: Path) -> None:
    code, err = run(
        "--scenario", str(tiny), "--space", "world.view=0:2", "--objective", COVER,
        "--objective", "mean(members)", "--sampler", "tpe", "-o", str(tmp_path / "out"),
    )  # fmt: skip
    assert code == 2, err
    assert "nsga2" in err
    assert not (tmp_path / "out").exists()
