"""`swarmgen simulate`: the paper's abstract simulation, running the compiled behaviours.

Every swarm member is its compiled state machine (the chart the asyncio backend generates, run by
`swarmgen.runtime.engine.Engine`); the simulator is the engine's host: it advances a numpy world
in discrete ticks and supplies the simulated Abstraction Library (`library.py`). See
docs/simulate.md. numpy and matplotlib are imported only here, never by the compiler.
"""
