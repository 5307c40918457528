"""Front end: readers that turn model files into a `RawModel`."""

from swarmgen.frontend.raw import RawElement, RawModel, StereotypeApplication
from swarmgen.frontend.xmi import load

__all__ = ["RawElement", "RawModel", "StereotypeApplication", "load"]
