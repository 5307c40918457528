"""Front end: readers that turn model files into a `RawModel`; `load` picks one by content."""

from swarmgen.frontend.formats import load
from swarmgen.frontend.raw import RawElement, RawModel, StereotypeApplication

__all__ = ["RawElement", "RawModel", "StereotypeApplication", "load"]
