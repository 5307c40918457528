"""swarmgen: a model-to-code compiler for swarms of cyber-physical systems."""

__version__ = "0.1.0"
