"""What generated code imports: the statechart engine (SCXML semantics), members on asyncio,
the swarm bus, the behaviour protocol and simulated behaviours. Standard library only: this
package never imports the compiler, and backends copy it into their output."""
