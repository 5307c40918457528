"""`swarmgen graph`: Mermaid and DOT of every machine and of the swarm, laid out by the real
Graphviz `dot`; names and colours; hostile names; determinism; the command line."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from functools import cache
from pathlib import Path, PurePosixPath

import pytest

from swarmgen import diagnostics as dg
from swarmgen import graph, pipeline
from swarmgen.graph import dot, mermaid, view
from swarmgen.ir.nodes import BehaviourKind, FinalState, Machine, Model, State
from swarmgen.ir.query import ModelIndex, walk
from tests.conftest import ROOT, SAMPLE_MODELS, run_cli, xmi_sample_files
from tests.modelkit import ModelKit

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
PATROL = ROOT / "sample_models" / "patrol" / "patrol.xmi"
HOSTILE_FIXTURE = ROOT / "tests" / "fixtures" / "bad" / "hostile_names.xmi"
SVG = "{http://www.w3.org/2000/svg}"
MODELS = [*SAMPLE_MODELS, *xmi_sample_files()]

# Text as Mermaid sees it after escaping: safe ASCII, any other printable character, entity
# codes, and the line breaks swarmgen itself puts into titles.
_T = r"(?:[A-Za-z0-9 _.,=+\-*/()!?'@$^~]|[^\x00-\x7f]|#\d+;|<br/>)*"
_ID = r"[A-Za-z0-9_]+"
_MERMAID_LINES = [
    rf"%% swarmgen: {_T}",
    r"stateDiagram-v2",
    r"flowchart LR",
    rf"\s*state \"{_T}\" as {_ID}",
    rf"\s*state {_ID} \{{",
    rf"\s*state {_ID} <<(choice|fork|join)>>",
    r"\s*\}",
    r"\s*--",
    rf"\s*{_ID} : {_T}",
    rf"\s*({_ID}|\[\*\]) --> ({_ID}|\[\*\])( : {_T})?",
    r"\s*classDef \w+ [\w:#,.\-]+",
    r"\s*class [\w,]+ \w+",
    rf"\s*{_ID}\[\"{_T}\"\]",
    rf"\s*{_ID} (-->|-\.->)\|\"{_T}\"\| {_ID}",
]
_MERMAID_LINE = re.compile("|".join(f"(?:{p})" for p in _MERMAID_LINES))


@cache
def _model(path: Path) -> Model:
    result = pipeline.validate(path)
    assert result.model is not None, dg.render_text(result.diagnostics)
    assert not dg.has_errors(result.diagnostics)
    return result.model


def _svg(dot_text: str) -> ET.Element:
    """Lay out with the real Graphviz and parse the SVG (it must be well-formed XML)."""
    if not shutil.which("dot"):  # a failure under `make test`, which installs it (tests/skips.py)
        pytest.skip("Graphviz is not installed: run `make sysdeps`")
    return ET.fromstring(dot.svg(dot_text))


def _svg_nodes(root: ET.Element) -> dict[str, ET.Element]:
    """Node id (its <title>) -> its <g> element."""
    found = {}
    for g in root.iter(f"{SVG}g"):
        if g.get("class") == "node":
            title = g.find(f"{SVG}title")
            assert title is not None and title.text is not None
            found[title.text] = g
    return found


def _svg_texts(root: ET.Element) -> set[str]:
    return {(t.text or "").strip() for t in root.iter(f"{SVG}text")}


def _unescape(text: str) -> str:
    return re.sub(r"#(\d+);", lambda m: chr(int(m[1])), text)


def _mermaid_labels(text: str) -> dict[str, str]:
    """Mermaid id -> its first label line, unescaped."""
    labels = {}
    for match in re.finditer(rf'state "({_T})" as ({_ID})$', text, re.MULTILINE):
        labels[match[2]] = _unescape(match[1].split("<br/>")[0])
    return labels


def _mermaid_classes(text: str) -> dict[str, str]:
    """Mermaid id -> the fill colour of its class."""
    fills = dict(re.findall(r"classDef (\w+) fill:(#[0-9a-f]{6})", text))
    styled = {}
    for ids, name in re.findall(r"^\s*class ([\w,]+) (\w+)$", text, re.MULTILINE):
        for mid in ids.split(","):
            styled[mid] = fills[name]
    return styled


def _expected_nodes(model: Model, machine: Machine) -> int:
    """Graphviz nodes drawn for a machine, counted from the IR: every vertex but the composite
    states (clusters, with an invisible anchor), one legend entry per behaviour kind."""
    index = ModelIndex(model)
    vertices = list(walk(machine))
    kinds = {
        index.behaviours[p.vertex.activity.behaviour].kind
        for p in vertices
        if isinstance(p.vertex, State)
        and p.vertex.activity is not None
        and p.vertex.activity.behaviour in index.behaviours
    }
    composites = [p for p in vertices if isinstance(p.vertex, State) and p.vertex.regions]
    return len(vertices) - len(composites) + len(kinds)


def _state_names(machine: Machine) -> list[str]:
    return [p.vertex.name for p in walk(machine) if isinstance(p.vertex, State | FinalState)]


def _hue(fill: str) -> str:
    r, g, b = (int(fill[i : i + 2], 16) for i in (1, 3, 5))
    if r > b + 20 and g > b + 20 and abs(r - g) < 30:
        return "yellow"
    return {r: "red", g: "green", b: "blue"}[max(r, g, b)] if len({r, g, b}) == 3 else "grey"


# --- every sample and reference model


@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_every_model_gives_mermaid_and_dot_that_graphviz_lays_out(path: Path) -> None:
    model = _model(path)
    stems = view.machine_stems(model)
    mermaid_files = graph.files(model, "mermaid")
    dot_files = graph.files(model, "dot")
    expected = {f"{stems[m.id]}" for m in model.machines} | {"swarm"}
    assert {p.stem for p in mermaid_files} == expected == {p.stem for p in dot_files}
    for text in mermaid_files.values():
        bad = [line for line in text.splitlines() if not _MERMAID_LINE.fullmatch(line)]
        assert not bad, bad
    for machine in model.machines:
        stem = stems[machine.id]
        root = _svg(dot_files[PurePosixPath(f"{stem}.dot")])
        assert len(_svg_nodes(root)) == _expected_nodes(model, machine)
        texts = _svg_texts(root)
        labels = set(_mermaid_labels(mermaid_files[PurePosixPath(f"{stem}.mmd")]).values())
        for name in _state_names(machine):
            assert name.strip() in texts, f"{name!r} missing from {stem}.svg"
            assert name in labels or f"◉ {name}" in labels, f"{name!r} missing from {stem}.mmd"
    swarm = _svg(dot_files[PurePosixPath("swarm.dot")])
    assert len(_svg_nodes(swarm)) >= len(model.member_types) + len(model.swarms)
    swarm_texts = _svg_texts(swarm)
    names = [n.name for n in model.swarms] + [n.name for n in model.member_types]
    assert set(names + [n.name for n in model.hardware]) <= swarm_texts


@pytest.mark.parametrize(
    ("path", "machine", "state", "colour"),
    [
        (SAR, "UgvRescue", "Rescuing", "red"),  # Rescue: ComplexBehavior
        (SAR, "SarBehavior", "Coverage", "green"),  # SwarmBehavior
        (SAR, "UavMission", "TargetMonitoring", "blue"),  # SwarmFunction
        (SAR, "UavMission", "Positioning", "yellow"),  # UwbPositioning: HardwareFunction
        (SAR, "SarBehavior", "Idle", "grey"),  # no behaviour
        (PATROL, "ScoutPatrol", "Sweeping", "green"),  # PatrolZone
        (PATROL, "ScoutPatrol", "GetZone", "blue"),  # ZoneAssignment
        (PATROL, "ScoutPatrol", "Charging", "yellow"),  # Charge
        (PATROL, "RelayMission", "Grounded", "grey"),
    ],
)
def test_states_are_coloured_by_behaviour_type(
    path: Path, machine: str, state: str, colour: str
) -> None:
    model = _model(path)
    (diagram,) = [d for d in view.diagrams(model) if d.name == machine]
    (vid,) = [v.id for v in diagram.vertices() if v.name == state]
    node = _svg_nodes(_svg(dot.state_diagram(diagram)))[vid]
    shape = next(e for e in node if e.tag in {f"{SVG}path", f"{SVG}polygon"})
    assert _hue(shape.get("fill", "")) == colour
    text = mermaid.state_diagram(diagram)
    (mid,) = [m for m, label in _mermaid_labels(text).items() if label == state]
    assert _hue(_mermaid_classes(text)[mid]) == colour


def test_legend_names_each_behaviour_type_shown() -> None:
    (diagram,) = [d for d in view.diagrams(_model(SAR)) if d.name == "UgvRescue"]
    texts = _svg_texts(_svg(dot.state_diagram(diagram)))
    assert {"complex behaviour", "swarm function", "hardware function"} <= texts
    assert "swarm behaviour" not in texts  # UgvRescue runs none
    assert diagram.kinds() == [
        BehaviourKind.COMPLEX,
        BehaviourKind.SWARM_FUNCTION,
        BehaviourKind.HARDWARE_FUNCTION,
    ]


def test_structure_clusters_submachines_and_labels() -> None:
    files = graph.files(_model(SAR), "dot")
    uav = files[PurePosixPath("UavMission.dot")]
    # the orthogonal state is a cluster with one dashed cluster per region
    assert 'subgraph "cluster_Mission" {' in uav
    assert uav.count('subgraph "cluster_Mission__') == 3
    # the submachine state links to its machine's own diagram, not inlined
    assert 'URL="SarBehavior.dot"' in uav and "Coverage" not in uav
    svg_uav = graph.files(_model(SAR), "svg")[PurePosixPath("UavMission.svg")]
    assert 'xlink:href="SarBehavior.svg"' in svg_uav
    assert "Generated by graphviz version" not in svg_uav
    # transitions into a composite state end at its border
    assert '"Initial" -> "Mission" [lhead="cluster_Mission"];' in uav
    text = graph.files(_model(PATROL), "mermaid")[PurePosixPath("ScoutPatrol.mmd")]
    assert (
        "    Sweeping --> Investigate : intrusion #91;event.zone == zone_id and not alarm_rai…"
        in (text)
    )
    assert "GoToZone : → GoTo.mmd" in text
    assert "state Assess <<choice>>" in text and 'state "H*" as History' in text


def test_member_selects_its_machines_and_composition() -> None:
    model = _model(SAR)
    files = graph.files(model, "mermaid", member="UAV")
    assert set(files) == {
        PurePosixPath(p) for p in ("UavMission.mmd", "SarBehavior.mmd", "swarm.mmd")
    }
    swarm = files[PurePosixPath("swarm.mmd")]
    assert "UAV" in swarm and "UGV" not in swarm and "WheelDrive" not in swarm
    assert "SonarRangeFinder" in swarm and 'RangeFinder"]' in swarm  # generalisation kept
    with pytest.raises(graph.GraphError, match="no member type 'Rover'; choose one of: UAV, UGV"):
        graph.files(model, "mermaid", member="Rover")


def test_compile_writes_mermaid_diagrams() -> None:
    model = _model(SAR)
    files = pipeline.compile_model(SAR).files
    diagrams = {p.relative_to("diagrams"): t for p, t in files.items() if p.parts[0] == "diagrams"}
    assert diagrams == graph.files(model, "mermaid")
    assert {p.name for p in diagrams} == {
        "UavMission.mmd", "UgvRescue.mmd", "SarBehavior.mmd", "swarm.mmd"
    }  # fmt: skip


# --- hostile names

HOSTILE = [
    'Quote "q" and \'s\'', "New\nline", "Close ] } ) >", "<b>bold</b> &amp; &bogus; &#60;",
    "# hash ; semi : colon", "dash -- arrow --> end", "%%{init: {'theme':'dark'}}%%",
    "direction LR", "back\\slash \\N \\l", "state", "default", "class", "end", "click", "[*]",
    "{", "}", "ünïcödé ✓", "--", "x\"]; a --> b : y",
]  # fmt: skip


def _hostile_model(tmp_path: Path) -> Path:
    event = 'ev"]}--x'
    kit = ModelKit('Hostile "model"\n<x>')
    kit.hardware("Camera", "Sensor")
    kit.hardware('Sub "cam" }\n<1>', "Sensor", generals=["Camera"])
    kit.behaviour("Look", "SwarmBehavior", requires=["Camera"])
    kit.event(event, sender="station")
    m = kit.machine('Machine "M"\n--> x')
    m.initial(HOSTILE[0])
    for i, name in enumerate(HOSTILE):
        m.state(name, do="Look" if i % 3 == 0 else None)
        if i:
            m.transition(
                HOSTILE[i - 1],
                name,
                event,
                guard='note != "x]\\"}"',
                effect='note = "a\\"b]} <i>#;:"',
            )
    inner = m.composite('Comp "}" {', ['R"1"\n', "R2 -- ]"])
    m.initial('in1 "', inner[0])
    m.state('in1 "', region=inner[0])
    m.initial("in2 ]", inner[1])
    m.state("in2 ]", region=inner[1])
    m.final('Fin "al"\n}')
    m.transition(HOSTILE[-1], 'Comp "}" {', event)
    m.transition('Comp "}" {', 'Fin "al"\n}', event)
    parts: dict[str, str | tuple[str, int]] = {'c"am\n': ('Sub "cam" }\n<1>', 2)}
    kit.member('Mem"ber\n]', machine=m, parts=parts, data={"note": ("String", "n")})
    kit.swarm('Sw"arm }\n', {'Mem"ber\n]': 3})
    path = tmp_path / "hostile.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


@pytest.mark.parametrize("source", ["fixture", "modelkit"])
def test_hostile_names_stay_inside_their_labels(source: str, tmp_path: Path) -> None:
    path = HOSTILE_FIXTURE if source == "fixture" else _hostile_model(tmp_path)
    model = _model(path)
    mermaid_files = graph.files(model, "mermaid")
    dot_files = graph.files(model, "dot")
    for text in mermaid_files.values():
        # every line is one statement of a known form with escaped text: no raw quote, newline,
        # `;`, `:`, `#`, `%%` or brace from a name can open, close or add a statement
        bad = [line for line in text.splitlines() if not _MERMAID_LINE.fullmatch(line)]
        assert not bad, bad
    for machine in model.machines:
        stem = view.machine_stems(model)[machine.id]
        text = mermaid_files[PurePosixPath(f"{stem}.mmd")]
        labels = set(_mermaid_labels(text).values())
        root = _svg(dot_files[PurePosixPath(f"{stem}.dot")])
        assert len(_svg_nodes(root)) == _expected_nodes(model, machine)
        texts = _svg_texts(root)
        for name in _state_names(machine):
            assert name in labels or f"◉ {name}" in labels  # the exact name, unescaped
            for line in name.splitlines():
                assert line.strip() in texts
    swarm = _svg(dot_files[PurePosixPath("swarm.dot")])
    assert len(_svg_nodes(swarm)) == len(model.swarms) + len(model.member_types) + len(
        model.hardware
    )
    if source == "modelkit":
        assert {
            'Comp "}" {',
            "<b>bold</b> &amp; &bogus; &#60;",
            "%%{init: {'theme':'dark'}}%%",
        } <= (_svg_texts(root))
        assert 'note = "a\\"b]} <i>#;:"' in " ".join(_svg_texts(root))


def test_escaping_functions() -> None:
    assert mermaid.text('a"b\n#;:') == "a#34;b#10;#35;#59;#58;"
    assert mermaid.text("Direction TB") == "#68;irection TB"
    assert mermaid.text("\u202e") == "#65533;"
    assert dot.quote('a"b\\c\nd&e') == '"a\\"b\\\\c\\nd&amp;e"'


# --- determinism and the command line


def _cli(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "swarmgen", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
        check=False,
        env={**os.environ, **(env or {})},
    )


def test_output_is_deterministic_across_runs_and_hash_seeds(tmp_path: Path) -> None:
    for fmt in ("mermaid", "dot"):
        runs = {_cli("graph", str(PATROL), "--format", fmt, env={"PYTHONHASHSEED": seed}).stdout
                for seed in ("0", "4242")}  # fmt: skip
        assert len(runs) == 1 and next(iter(runs))
    first, second = tmp_path / "a", tmp_path / "b"
    for out, seed in ((first, "1"), (second, "77")):
        done = _cli(
            "graph", str(SAR), "--format", "svg", "-o", str(out), env={"PYTHONHASHSEED": seed}
        )
        assert done.returncode == 0, done.stderr
    names = sorted(p.name for p in first.iterdir())
    assert names == [
        ".swarmgen.json",
        "SarBehavior.svg",
        "UavMission.svg",
        "UgvRescue.svg",
        "swarm.svg",
    ]
    for name in names:
        assert (first / name).read_bytes() == (second / name).read_bytes()


def test_cli_prints_mermaid_and_writes_files(tmp_path: Path) -> None:
    done = run_cli("graph", str(SAR), "--member", "UGV")
    assert done.returncode == 0, done.stderr
    assert done.stdout.count("stateDiagram-v2") == 1 and "flowchart LR" in done.stdout
    out = tmp_path / "diagrams"
    done = run_cli("graph", str(SAR), "--format", "dot", "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert (out / "UavMission.dot").read_text(encoding="utf-8").startswith('digraph "UavMission"')
    assert run_cli("graph", str(SAR), "-o", str(out)).returncode == 0  # ours: replaced
    assert sorted(p.suffix for p in out.iterdir() if p.name != ".swarmgen.json") == [".mmd"] * 4


@pytest.mark.parametrize(
    ("args", "code", "message"),
    [
        (["--member", "Rover"], 2, "swarmgen: error: no member type 'Rover'"),
        (["--format", "svg"], 2, "--format svg writes files"),
        (["--format", "png"], 2, "Invalid value for '--format'"),
    ],
)
def test_cli_misuse_exits_2(args: list[str], code: int, message: str) -> None:
    done = run_cli("graph", str(SAR), *args)
    assert done.returncode == code and message in done.stderr
    assert done.stdout == ""


def test_cli_model_errors_exit_1_unreadable_2_foreign_dir_2(tmp_path: Path) -> None:
    bad = ROOT / "tests" / "fixtures" / "bad"
    done = run_cli("graph", str(bad / "guard_syntax.xmi"))
    assert done.returncode == 1 and "[SG107]" in done.stderr and "nothing drawn" in done.stderr
    assert done.stdout == ""
    done = run_cli("graph", str(bad / "not_xml.xmi"))
    assert done.returncode == 2 and "[SG002]" in done.stderr
    foreign = tmp_path / "project"
    foreign.mkdir()
    (foreign / "keep.txt").write_text("mine", encoding="utf-8")
    done = run_cli("graph", str(SAR), "-o", str(foreign))
    assert done.returncode == 2 and "was not written by swarmgen" in done.stderr
    assert [p.name for p in foreign.iterdir()] == ["keep.txt"]


def test_cli_without_graphviz_exits_2(tmp_path: Path) -> None:
    empty = tmp_path / "bin"
    empty.mkdir()
    done = _cli("graph", str(SAR), "--format", "svg", "-o", str(tmp_path / "out"),
                env={"PATH": str(empty)})  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "Graphviz `dot` was not found" in done.stderr
    assert not (tmp_path / "out").exists()
