"""What lever 1 of issue 17 would buy, measured without building it: the SAR swarm explored
with chains of ample deliveries folded into one edge (docs/verify.md, "Not reached").

This is a measurement, not a verifier: it checks no property and records no graph. It runs the
verifier's own successor function (`System.apply`), reductions (`ample`, symmetry, decoupled
states after the abort) and budget, but stores a state only when no single delivery forms a
persistent set in it: from each stored state, every step is followed by the chain of ample
deliveries it leads into, and only the chain's last state is stored. So it gives the number of
states a folded search would store, the steps it would still compute, and the time and memory
of the search itself (the properties' bookkeeping left out), for compositions the unfolded
search cannot finish.

    .venv/bin/python benchmarks/fold_size.py UAVS UGVS [--max-states N] [--no-symmetry] [--unfolded]

Prints one JSON line. `--unfolded` runs the verifier's search (`explore`, no property
observer) on the same composition instead, for a same-run comparison of the search alone. Without symmetry and with the same budget, the stored states equal the
unfolded search's states minus its `expanded_by_ample_set` (every state an ample set expands is
folded away, every other one stored): `bench_verify.py`'s rows check it.
"""

from __future__ import annotations

import argparse
import json
import resource
import sys
import time
from collections import deque
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from swarmgen.verify.ample import ample  # noqa: E402
from swarmgen.verify.decouple import decoupled  # noqa: E402
from swarmgen.verify.explore import Budget, explore  # noqa: E402
from swarmgen.verify.load import load  # noqa: E402
from swarmgen.verify.system import SwarmState, System, canonical_state  # noqa: E402

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"


def folded(system: System, max_states: int, symmetry: bool) -> dict[str, int | bool]:
    """Breadth-first over chain ends (see the module docstring): stored states, the steps
    computed inside chains, the longest chain, and whether the budget stopped it."""

    def key(state: SwarmState) -> SwarmState:
        return canonical_state(system, state) if symmetry else state

    first = key(system.initial())
    seen = {first.key(): 0}
    frontier = deque([(first, 0)])
    chained = longest = depth = 0
    bounded = False
    while frontier:
        state, depth = frontier.popleft()
        if len(seen) >= max_states:
            bounded = True
            break
        if state.aborted and decoupled(system, state.members) is not None:
            continue
        for step in ample(system, state, None) or system.steps(state):
            after = key(system.apply(state, step)[0])
            length = 0
            while not (after.aborted and decoupled(system, after.members) is not None):
                reduced = ample(system, after, None)
                if reduced is None:
                    break
                after = key(system.apply(after, reduced[0])[0])
                length += 1
            chained += length
            longest = max(longest, length)
            code = after.key()
            if code not in seen:
                seen[code] = len(seen)
                frontier.append((after, depth + 1))
    return {
        "stored": len(seen),
        "chain_steps": chained,
        "longest_chain": longest,
        "edge_depth": depth,
        "bounded": bounded,
    }


def main() -> None:
    """Measure one composition and print it as JSON."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("uavs", type=int)
    parser.add_argument("ugvs", type=int)
    parser.add_argument("--max-states", type=int, default=20_000_000)
    parser.add_argument("--no-symmetry", action="store_true")
    parser.add_argument("--unfolded", action="store_true", help="the verifier's search instead")
    args = parser.parse_args()
    loaded = load(SAR, {"UAV": args.uavs, "UGV": args.ugvs}, ())
    assert loaded.system is not None
    started = time.perf_counter()
    if args.unfolded:
        budget = Budget(max_states=args.max_states, symmetry=not args.no_symmetry)
        search = explore(loaded.system, budget)
        row = {"stored": search.states, "expanded_by_ample_set": search.reduced}
        row |= {"depth": search.max_depth, "bounded": search.bounded}
    else:
        row = folded(loaded.system, args.max_states, not args.no_symmetry)
    seconds = time.perf_counter() - started
    members = {"UAV": args.uavs, "UGV": args.ugvs}
    peak = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)
    result = {"members": members, "symmetry": not args.no_symmetry, "folded": not args.unfolded}
    result |= row
    print(json.dumps({**result, "seconds": round(seconds, 2), "peak_rss_mb": peak}))


if __name__ == "__main__":
    main()
