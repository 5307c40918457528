"""The lowered statechart shared by every output, and `lower` (Model -> Charts)."""

from swarmgen.chart.lower import lower
from swarmgen.chart.model import Chart, Node, Transition

__all__ = ["Chart", "Node", "Transition", "lower"]
