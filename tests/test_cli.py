"""The `swarmgen` command line: exit codes, output streams, atomic writes, --check, determinism."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from swarmgen import pipeline
from tests.conftest import ROOT, SAMPLE_MODELS, XMI_SAMPLES, requires_shared, run_cli

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"


def test_validate_clean_model_exits_0() -> None:
    result = run_cli("validate", str(SAR))
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""
    assert "0 error(s), 0 warning(s)" in result.stderr


def test_validate_json_format(tmp_path: Path) -> None:
    broken = tmp_path / "broken.xmi"
    broken.write_text(
        SAR.read_text(encoding="utf-8").replace('value="altitude = altitude"', 'value="x"')
    )
    text = SAR.read_text(encoding="utf-8")
    # a trigger event that does not exist: a dangling reference
    first_event = text.index(' event="') + len(' event="')
    event_id = text[first_event : text.index('"', first_event)]
    broken.write_text(text.replace(f' event="{event_id}"', ' event="_doesNotExist0000000000"', 1))
    result = run_cli("validate", str(broken), "--format", "json")
    assert result.returncode == 1
    payload = json.loads(result.stdout)
    codes = {d["code"] for d in payload["diagnostics"]}
    assert "SG011" in codes
    (dangling,) = [d for d in payload["diagnostics"] if d["code"] == "SG011"]
    assert dangling["file"] == str(broken) and dangling["line"] > 0 and dangling["col"] > 0
    assert payload["summary"]["errors"] >= 1


def test_text_diagnostic_format(tmp_path: Path) -> None:
    broken = tmp_path / "model.xmi"
    text = SAR.read_text(encoding="utf-8")
    broken.write_text(
        text.replace('<subvertex xmi:type="uml:Pseudostate"', '<subvertex xmi:type="uml:State"', 1)
    )
    result = run_cli("validate", str(broken))
    assert result.returncode == 1
    first = next(line for line in result.stdout.splitlines() if ": error: " in line)
    # model.xmi:42:7: error: ... [SG101]
    location, severity, rest = first.split(": ", 2)
    path, line, col = location.rsplit(":", 2)
    assert path == str(broken) and int(line) > 0 and int(col) > 0
    assert severity == "error" and rest.endswith("]") and "[SG" in rest
    assert "  in: " in result.stdout and "  hint: " in result.stdout


def test_misuse_exits_2() -> None:
    assert run_cli("compile", str(SAR)).returncode == 2  # missing -o
    assert run_cli("frobnicate").returncode == 2


def test_compile_writes_tree_and_check_detects_drift(tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = run_cli("compile", str(SAR), "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""  # progress goes to stderr
    assert sorted(p.name for p in (out / "scxml").iterdir()) == ["UAV.scxml", "UGV.scxml"]
    manifest = json.loads((out / pipeline.MANIFEST).read_text())
    assert manifest["source"] == "sar.xmi" and "scxml/UAV.scxml" in manifest["files"]
    assert run_cli("compile", str(SAR), "-o", str(out), "--check").returncode == 0

    uav = out / "scxml" / "UAV.scxml"
    uav.write_text(uav.read_text().replace('id="Loitering"', 'id="Hovering"'))
    (out / "scxml" / "extra.scxml").write_text("<scxml/>")
    stale = run_cli("compile", str(SAR), "-o", str(out), "--check")
    assert stale.returncode == 1
    lines = stale.stdout.splitlines()
    assert any(line.startswith("-") and '<state id="Hovering"' in line for line in lines)
    assert any(line.startswith("+") and '<state id="Loitering"' in line for line in lines)
    assert "extra.scxml" not in stale.stdout  # a file swarmgen did not write is not compared
    assert 'id="Hovering"' in uav.read_text()  # --check writes nothing

    refused = run_cli("compile", str(SAR), "-o", str(out))  # an edited file is not overwritten
    assert refused.returncode == 2 and "scxml/UAV.scxml" in refused.stderr, refused.stderr
    assert 'id="Hovering"' in uav.read_text()
    uav.unlink()
    assert run_cli("compile", str(SAR), "-o", str(out)).returncode == 0
    assert (out / "scxml" / "extra.scxml").read_text() == "<scxml/>"  # the user's file is kept
    assert 'id="Hovering"' not in uav.read_text()


def test_compile_refuses_to_replace_a_foreign_directory(tmp_path: Path) -> None:
    precious = tmp_path / "project"
    precious.mkdir()
    (precious / "notes.txt").write_text("keep me")
    result = run_cli("compile", str(SAR), "-o", str(precious))
    assert result.returncode == 2
    assert "was not written by swarmgen" in result.stderr
    assert (precious / "notes.txt").read_text() == "keep me"
    assert sorted(p.name for p in precious.iterdir()) == ["notes.txt"]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no staging left over


@pytest.mark.parametrize("model", SAMPLE_MODELS, ids=[m.parent.name for m in SAMPLE_MODELS])
def test_generated_directory_is_current(model: Path) -> None:
    """CI fails when generated/ is stale: regenerate with `make demo`."""
    result = run_cli(
        "compile", str(model.relative_to(ROOT)), "-o", f"generated/{model.parent.name}", "--check"
    )
    assert result.returncode == 0, f"generated/ is stale, run `make demo`:\n{result.stdout[:4000]}"


def test_output_is_byte_identical_across_hash_seeds(tmp_path: Path) -> None:
    outputs = []
    for seed in ("0", "1", "12345"):
        out = tmp_path / f"out{seed}"
        env = {**os.environ, "PYTHONHASHSEED": seed}
        completed = subprocess.run(
            [sys.executable, "-m", "swarmgen", "compile", str(SAR), "-o", str(out)],
            env=env, capture_output=True, check=False, cwd=ROOT,
        )  # fmt: skip
        assert completed.returncode == 0
        outputs.append(
            {p.relative_to(out): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}
        )
    assert outputs[0] == outputs[1] == outputs[2]


def test_schema_is_current() -> None:
    """schemas/ir.schema.json matches the IR; regenerate with `make schema`."""
    result = run_cli("schema", "-o", "schemas", "--check")
    assert result.returncode == 0, result.stderr
    schema = json.loads((ROOT / "schemas" / "ir.schema.json").read_text())
    assert {"Machine", "State", "Transition", "Behaviour", "Event"} <= set(schema["$defs"])


def test_schema_check_fails_when_stale(tmp_path: Path) -> None:
    (tmp_path / "ir.schema.json").write_text("{}\n")
    assert run_cli("schema", "-o", str(tmp_path), "--check").returncode == 1
    assert run_cli("schema", "-o", str(tmp_path)).returncode == 0
    assert run_cli("schema", "-o", str(tmp_path), "--check").returncode == 0


def test_version_and_help() -> None:
    assert "swarmgen" in run_cli("--version").stdout
    help_text = run_cli("--help").stdout
    assert all(cmd in help_text for cmd in ("validate", "compile", "schema"))


def test_every_diagnostic_code_is_documented() -> None:
    from swarmgen.diagnostics import CODES

    doc = (ROOT / "docs" / "diagnostics.md").read_text()
    missing = [c.id for c in CODES.values() if f"| {c.id} | `{c.name}` |" not in doc]
    assert not missing, f"add these codes to docs/diagnostics.md: {missing}"


TIMERS_SAMPLE = str(XMI_SAMPLES / "papyrus_spring-sm_simple-timers.uml")


@requires_shared
def test_sarif_output() -> None:
    sample = TIMERS_SAMPLE
    result = run_cli("validate", sample, "--format", "sarif")
    assert result.returncode == 0
    log = json.loads(result.stdout)
    assert log["version"] == "2.1.0" and log["$schema"].endswith("sarif-2.1.0.json")
    (run,) = log["runs"]
    assert run["tool"]["driver"]["name"] == "swarmgen"
    # timers.uml: two entry actions in 'bean' (SG114), two states without a way out (SG202)
    assert [r["id"] for r in run["tool"]["driver"]["rules"]] == ["SG114", "SG202"]
    results = run["results"]
    assert sorted(r["ruleId"] for r in results) == ["SG114", "SG114", "SG202", "SG202"]
    for item in results:
        assert item["level"] == "warning"
        rule = run["tool"]["driver"]["rules"][item["ruleIndex"]]
        assert rule["id"] == item["ruleId"]
        region = item["locations"][0]["physicalLocation"]["region"]
        assert region["startLine"] > 0 and region["startColumn"] > 0


@requires_shared
def test_strict_and_disable() -> None:
    sample = TIMERS_SAMPLE
    assert run_cli("validate", sample).returncode == 0  # two warnings
    strict = run_cli("validate", sample, "--strict")
    assert strict.returncode == 1 and ": error: " in strict.stdout
    quiet = run_cli("validate", sample, "--disable", "SG114", "--disable", "SG202", "--strict")
    assert quiet.returncode == 0 and quiet.stdout == ""
    assert run_cli("validate", sample, "--disable", "SG999").returncode == 2


@requires_shared
def test_strict_compile_writes_nothing(tmp_path: Path) -> None:
    sample = TIMERS_SAMPLE
    result = run_cli("compile", sample, "-o", str(tmp_path / "out"), "--strict")
    assert result.returncode == 1
    assert not (tmp_path / "out").exists()


def test_text_diagnostics_stay_one_line_with_newlines_in_names(tmp_path: Path) -> None:
    from tests.modelkit import ModelKit

    kit = ModelKit("Multi\nLine")
    kit.event("go\nnow", sender="station")
    machine = kit.machine("M")
    machine.initial("A\nB")
    machine.state("A\nB")
    machine.state("Stuck")
    machine.transition("A\nB", "Stuck", "go\nnow")
    kit.member("Bot", machine=machine)
    path = tmp_path / "multi.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    result = run_cli("validate", str(path))
    findings = [line for line in result.stdout.splitlines() if not line.startswith(" ")]
    assert findings and all(line.startswith(str(path)) for line in findings), result.stdout
    assert "'Stuck'" in result.stdout and "\\n" in result.stdout
