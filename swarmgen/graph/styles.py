"""The diagrams' colours: one `Style` per behaviour kind, hardware kind and box, shared by the
Mermaid and DOT renderers so that their legends agree."""

from __future__ import annotations

from swarmgen.ir import nodes as ir
from swarmgen.records import dataclass


@dataclass(frozen=True)
class Style:
    """A fill and a border colour, and the words the legend gives them."""

    fill: str
    stroke: str
    title: str  # the legend's words


# Pastel fills with a darker border of the same hue, readable with black text.
BEHAVIOUR_STYLES: dict[ir.BehaviourKind, Style] = {
    ir.BehaviourKind.COMPLEX: Style("#f8cecc", "#b85450", "complex behaviour"),
    ir.BehaviourKind.SWARM_BEHAVIOR: Style("#d5e8d4", "#82b366", "swarm behaviour"),
    ir.BehaviourKind.SWARM_FUNCTION: Style("#dae8fc", "#6c8ebf", "swarm function"),
    ir.BehaviourKind.HARDWARE_FUNCTION: Style("#fff2cc", "#d6b656", "hardware function"),
}
NEUTRAL = Style("#f5f5f5", "#666666", "no behaviour")
COMPOSITE = Style("#ffffff", "#666666", "composite state")
REGION = Style("#ffffff", "#999999", "region")

HARDWARE_STYLES: dict[ir.HardwareKind, Style] = {
    ir.HardwareKind.SENSOR: Style("#e1d5e7", "#9673a6", "sensor"),
    ir.HardwareKind.ACTUATOR: Style("#ffe6cc", "#d79b00", "actuator"),
    ir.HardwareKind.CONTROLLER: Style("#eeeeee", "#666666", "controller"),
    ir.HardwareKind.COMMUNICATION_INTERFACE: Style("#d0eeee", "#3c8c8c", "communication interface"),
}
SWARM_STYLE = Style("#ffffff", "#333333", "swarm")
MEMBER_STYLE = Style("#ffffff", "#333333", "member type")
CLASS_STYLE = Style("#ffffff", "#999999", "class")
