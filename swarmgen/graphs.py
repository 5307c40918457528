"""Graph algorithms the compiler's analyses and the verifier share (standard library only)."""

from __future__ import annotations

from collections.abc import Callable, Iterable


def strongly_connected(
    roots: Iterable[int], successors: Callable[[int], Iterable[int]]
) -> list[set[int]]:
    """The strongly connected components reached from `roots` (in that order), in the order
    Tarjan's algorithm closes them; iterative, so a long path cannot exhaust the call stack.

    `successors(node)` gives a node's successors in the order they are to be visited (a caller
    restricting the graph to a subset filters them there). Work is linear in what is reached."""
    index: dict[int, int] = {}
    low: dict[int, int] = {}
    stack: list[int] = []
    on_stack: set[int] = set()
    found: list[set[int]] = []
    for root in roots:
        if root in index:
            continue
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        work = [(root, iter(successors(root)))]
        while work:
            node, pending = work[-1]
            advanced = False
            for successor in pending:
                if successor not in index:
                    index[successor] = low[successor] = len(index)
                    stack.append(successor)
                    on_stack.add(successor)
                    work.append((successor, iter(successors(successor))))
                    advanced = True
                    break
                if successor in on_stack:
                    low[node] = min(low[node], index[successor])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                found.append(_pop_component(stack, on_stack, node))
    return found


def _pop_component(stack: list[int], on_stack: set[int], root: int) -> set[int]:
    component: set[int] = set()
    while True:
        member = stack.pop()
        on_stack.discard(member)
        component.add(member)
        if member == root:
            return component
