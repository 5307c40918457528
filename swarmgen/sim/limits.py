"""The limits of a simulation, checked before anything runs (docs/simulate.md, docs/security.md)."""

# Limits, checked before anything runs (docs/simulate.md): beyond them a sweep would exhaust
# memory (about 10 KB per member and repetition, 1 KB of it the random draws kept ahead, 16
# bytes per patch and repetition) or overflow the world's 32-bit tick arrays, instead of
# failing cleanly.
SCENARIO_BYTES = 1 << 20  # a scenario file
MAX_SIDE = 10_000  # patches along one side of the world
MAX_VIEW = 16  # Chebyshev radius of a member's view
MAX_PATCH_RUNS = 10**8  # patches x repetitions of one configuration
MAX_MEMBERS = 10_000  # members of one configuration
MAX_MEMBER_RUNS = 100_000  # members x repetitions of one configuration
MAX_TARGETS = 100_000  # targets of one configuration (and never more than the patches)
MAX_REPS = 10_000  # repetitions per configuration
MAX_RUNS = 100_000  # configurations x repetitions
MAX_TICKS = 2_000_000_000  # ticks of a repetition (the world stores ticks as int32)
MAX_TICK_MS = 86_400_000  # one day
MAX_SEED = 2**63 - 1
MAX_LIST = 1_000  # counts in a sweep, station events, levels
STAMP_NS = 2**63 - 1  # bag stamps (int64 ns) of the last tick must fit
