"""Compiled templates: see swarmgen/precompiled.py."""
