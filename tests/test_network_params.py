"""The model's CommunicationInterface parameters reach the generated package (issue 18 item 1):
`communicationParams` checked at validate time (SG230, SG231, located at the stereotype
application), the swarm's transport keys as the package's NETWORK, the defaults of the
`--transport udp` options, which the command line overrides. Real model files, real compiles,
real processes on loopback."""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
from pathlib import Path

import pytest

from swarmgen import pipeline
from swarmgen.ir.network import swarm_network
from swarmgen.runtime.netoptions import (
    ANNOUNCE_EVERY,
    DEFAULT_GROUP,
    BadItem,
    Options,
    param_items,
    resolve_options,
)
from tests.udpkit import RUN_TIMEOUT, SAR, network, python

SAR_TEXT = SAR.read_text(encoding="utf-8")
PARAMS = 'communicationParams="ifname=wlan0 port=5670"'
# the line of the SAR model's «CommunicationInterface» application (where the tags are)
TAG_LINE = next(
    n for n, line in enumerate(SAR_TEXT.splitlines(), 1) if "CPSwarm:CommunicationInterface" in line
)


def sar_with(tmp_path: Path, params: str, text: str = SAR_TEXT) -> Path:
    """The SAR model with other `communicationParams` on its wireless interface."""
    assert PARAMS in text
    if not (tmp_path / "interfaces").exists():  # the declared ROS types beside the model
        shutil.copytree(SAR.parent / "interfaces", tmp_path / "interfaces")
    path = tmp_path / "sar.xmi"
    path.write_text(text.replace(PARAMS, f'communicationParams="{params}"'), encoding="utf-8")
    return path


BAD = {
    "port": ("ifname=wlan0 port=70000", "SG230", "port 70000 is not in 1-65535"),
    "ttl": ("ttl=abc", "SG230", "ttl 'abc' is not an integer"),
    "group": ("group=10.1.2.3", "SG230", "not a multicast group"),
    "short_group": ("group=239.1", "SG230", "not a multicast group"),
    "item": ("port5670", "SG230", "'port5670' is not key=value"),
    "twice": ("port=5670;port=5671", "SG230", "gives 'port' twice ('5670', '5671')"),
    "misspelt": ("prot=5670", "SG231", "has 'prot', which the network transport does not read"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_communication_params_are_located_diagnostics(tmp_path: Path, case: str) -> None:
    params, code, says = BAD[case]
    found = pipeline.validate(sar_with(tmp_path, params)).diagnostics
    assert [d.code.id for d in found] == [code], pipeline.dg.render_text(found)
    (diagnostic,) = found
    assert says in diagnostic.message and diagnostic.hint
    assert diagnostic.span.line == TAG_LINE
    assert "WirelessInterface" in diagnostic.message
    if case == "misspelt":
        assert "did you mean 'port'?" in diagnostic.hint


def test_other_software_keys_are_not_reported(tmp_path: Path) -> None:
    """Keys far from the transport's own (a radio's channel) are another stack's business."""
    path = sar_with(tmp_path, "ifname=wlan0 channel=5 panId=0xCA5E")
    assert pipeline.validate(path).diagnostics == []


def test_member_types_must_agree_on_the_network(tmp_path: Path) -> None:
    """The UGVs get their own radio (a WirelessInterface) on another port: the swarm would be
    split in two, an error at the radio's stereotype application."""
    radio = '_L3CHq4o-Ee-0HcfyqRPQXg" name="WirelessInterface">'
    ugv_wifi = 'xmi:id="_L20E74o-Ee-0HcfyqRPQXg" name="wifi" type="_L3CHq4o-Ee-0HcfyqRPQXg"'
    tag = SAR_TEXT.splitlines()[TAG_LINE - 1]
    text = SAR_TEXT.replace(
        f'<packagedElement xmi:type="uml:Class" xmi:id="{radio}',
        '<packagedElement xmi:type="uml:Class" xmi:id="_GroundRadio0000000000" name="GroundRadio">'
        '<generalization xmi:id="_GroundRadioGen00000000" general="_L3CHq4o-Ee-0HcfyqRPQXg"/>'
        f'</packagedElement>\n      <packagedElement xmi:type="uml:Class" xmi:id="{radio}',
    )
    text = text.replace(
        ugv_wifi, ugv_wifi.replace("_L3CHq4o-Ee-0HcfyqRPQXg", "_GroundRadio0000000000")
    )
    text = text.replace(
        tag,
        f'{tag}\n  <CPSwarm:CommunicationInterface xmi:id="_GroundRadioApp00000000" '
        'base_Class="_GroundRadio0000000000" communicationParams="port=6000"/>',
    )
    path = sar_with(tmp_path, "port=5670", text)
    found = pipeline.validate(path).diagnostics
    assert [d.code.id for d in found] == ["SG230"], pipeline.dg.render_text(found)
    assert "'UAV' and 'UGV' would use different ports: 5670 and 6000" in found[0].message
    # at the second radio's application
    assert found[0].span.xmi_id == "_GroundRadioApp00000000"
    assert found[0].span.line == text[: text.index("_GroundRadioApp")].count("\n") + 1


def test_the_network_is_read_once_for_check_and_backends(tmp_path: Path) -> None:
    model = pipeline.validate(sar_with(tmp_path, "ttl=0 ifname=wlan0 group=239.1.2.3 port=7")).model
    assert model is not None
    read = swarm_network(model)
    assert read.values == {"group": "239.1.2.3", "port": 7, "ttl": 0}
    assert read.sources == ("WirelessInterface",) and read.problems == ()
    with pytest.raises(BadItem):
        param_items("port=1 =2")


def _args(**given: object) -> argparse.Namespace:
    fields = {"group": None, "port": None, "ttl": None, "interface": None, "announce": 0.25}
    return argparse.Namespace(**{**fields, **given})


def test_the_command_line_overrides_the_model() -> None:
    model = {"group": "239.9.9.9", "port": 6000, "ttl": 0}
    assert resolve_options(_args(), model) == Options("239.9.9.9", 6000, 0)
    assert resolve_options(_args(port=7000, ttl=3), model) == Options("239.9.9.9", 7000, 3)
    assert resolve_options(_args(), None) == Options(DEFAULT_GROUP, announce_every=ANNOUNCE_EVERY)
    with pytest.raises(ValueError, match="expected a port"):
        resolve_options(_args(), {"port": 0})


def test_the_package_runs_on_the_models_network(tmp_path: Path) -> None:
    """The model's group and port (this test's own) are in the package's NETWORK; a member
    started without --group/--port meets a station given them on its command line, and takes
    its events to the end."""
    net = network()
    group, port = net[3], net[5]
    model = sar_with(tmp_path, f"ifname=wlan0 group={group} port={port}")
    pipeline.write_tree(pipeline.compile_model(model).files, tmp_path / "out")
    package = tmp_path / "out" / "asyncio"
    init = (package / "search_and_rescue_swarm" / "__init__.py").read_text(encoding="utf-8")
    assert f'NETWORK: dict[str, str | int] = {{"group": "{group}", "port": {port}}}' in init
    member = subprocess.Popen(
        python("--member", "UGV", "--id", "ugv_1", "--transport", "udp", "--duration", "5"),
        cwd=package,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        station = subprocess.run(
            python(
                "--station-only",
                *net,
                "--expect",
                "1",
                "--duration",
                "5",
                "--events",
                "launch,missionAbort@0.1",
            ),
            cwd=package,
            capture_output=True,
            text=True,
            timeout=RUN_TIMEOUT,
            check=False,
        )
        out, err = member.communicate(timeout=RUN_TIMEOUT)
    finally:
        if member.poll() is None:
            member.kill()
            member.wait(timeout=10)
    assert station.returncode == 0 and member.returncode == 0, station.stdout + err
    record = [json.loads(line) for line in station.stdout.splitlines()]
    assert [r["event"] for r in record if r["station"] == "delivered"] == ["launch", "missionAbort"]
    steps = [json.loads(line)["event"] for line in out.splitlines()]
    assert steps == [None, "launch", "missionAbort"], out
