"""The `swarmgen` commands, one module each (the group that holds them is `swarmgen.cli`)."""
