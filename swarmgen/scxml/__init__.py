"""SCXML output: the emitter and its `swarmgen` extension namespace."""

from swarmgen.scxml.emit import SCXML_NS, SG_NS, ScxmlDocument, emit

__all__ = ["SCXML_NS", "SG_NS", "ScxmlDocument", "emit"]
