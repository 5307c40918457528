"""`swarmgen verify`: the swarm as a finite transition system, explored breadth first over the
same engine every backend runs, checked against built-in properties, with counterexamples that
`swarmgen replay` runs (docs/verify.md).

`state` snapshots and restores one member's engine, `system` composes the members and computes
the steps, `explore` is the search (symmetry, hashed visited set, budget), `properties` turns what
the search saw into findings, `counterexample` prints and writes the shortest traces.
"""
