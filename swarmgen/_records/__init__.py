"""Compiled dataclass methods: see swarmgen/records.py."""
