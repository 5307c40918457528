"""W3C's transition domain against the reader's regions (docs/scxml-input.md, "A transition out
of a `<parallel>` child").

The reader gives a `<parallel>` one UML region per child, and a child with behaviour of its own
(`onentry`, a transition, ...) becomes a state *inside* its region. W3C has no such region: a
transition's domain is its least common *compound* ancestor, and a `<parallel>` never is one. So
`<parallel id="p"><state id="a"><transition event="reset" target="a1"/>...` leaves the whole of
`p` in SCXML (every sibling region is exited and entered again), but only `a`'s region in the
reader's UML. `reentered` finds the state such a transition must exit and enter as a whole for
the two to agree (IR `Transition.reenters`: the lowering adds it to the transition's targets,
after the real one, which is what `target="a1 p"` means in SCXML).
"""

from __future__ import annotations

from collections.abc import Sequence

from lxml import etree

from swarmgen.frontend.scxml_raw import STATE_TAGS, children, local, sg

_CHILD_STATES = ("state", "parallel", "final")  # what makes a <state> compound (W3C)


def is_own_region(node: etree._Element) -> bool:
    """Whether a child of `<parallel>` is read as a region itself (its children are the region's
    vertices) rather than as a state the reader puts in a region of its own: a plain `<state>`
    with children and no behaviour, or a region swarmgen wrote (`sg:region`)."""
    plain = local(node) == "state" and not children(
        node, "onentry", "onexit", "transition", "invoke"
    )
    return sg(node, "region") is not None or (plain and bool(children(node, *STATE_TAGS)))


class _Wrapper:
    """The region the reader makes to hold a `<parallel>` child that is not its own region."""

    def __init__(self, child: etree._Element) -> None:
        self.child = child

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Wrapper) and other.child is self.child

    def __hash__(self) -> int:
        return id(self.child)


_Level = etree._Element | _Wrapper


def _w3c_compound(node: etree._Element) -> bool:
    return local(node) == "scxml" or (
        local(node) == "state" and bool(children(node, *_CHILD_STATES))
    )


def _proper_ancestors(node: etree._Element) -> list[etree._Element]:
    found = []
    parent = node.getparent()
    while parent is not None and local(parent) in (*STATE_TAGS, "scxml"):
        found.append(parent)
        parent = parent.getparent()
    return found


def _w3c_domain(source: etree._Element, others: Sequence[etree._Element]) -> etree._Element | None:
    """W3C `findLCCA([source, *others])`."""
    holders = [_proper_ancestors(o) for o in others]
    for ancestor in _proper_ancestors(source):
        if _w3c_compound(ancestor) and all(ancestor in held for held in holders):
            return ancestor
    return None


def _as_named(node: etree._Element) -> etree._Element:
    """What naming `node` names in the reader's UML: a child of `<parallel>` that is its own
    region stands for the `<parallel>` (entering it enters the other regions by default)."""
    parent = node.getparent()
    if parent is not None and local(parent) == "parallel" and is_own_region(node):
        return parent
    return node


def _region_levels(node: etree._Element) -> list[_Level]:
    """The proper ancestors of `node` in the reader's UML, innermost first, with the regions it
    adds around `<parallel>` children."""
    found: list[_Level] = []
    current = node
    for parent in _proper_ancestors(node):
        if local(parent) == "parallel" and not is_own_region(current):
            found.append(_Wrapper(current))
        found.append(parent)
        current = parent
    return found


def _region_compound(level: _Level) -> bool:
    return isinstance(level, _Wrapper) or _w3c_compound(level)


def _region_domain(source: etree._Element, others: Sequence[etree._Element]) -> _Level | None:
    """The same least common compound ancestor in the reader's UML (its regions count)."""
    named = [_region_levels(_as_named(o)) for o in others]
    for level in _region_levels(_as_named(source)):
        if _region_compound(level) and all(level in levels for levels in named):
            return level
    return None


def reentered(
    source: etree._Element,
    target: etree._Element,
    extra: Sequence[etree._Element],
    internal: bool,
) -> etree._Element | None:
    """The state a transition from `source` to `target` (with `extra` further targets, each a
    `<parallel>` holding `target`) must exit and enter again so that the reader's UML leaves
    what W3C leaves, or None when the two domains agree.

    W3C computes a history target's domain from the states it holds when the transition is
    taken, all inside the history's parent: from a source outside that parent (or the parent
    itself) the domain is the one the history's own place gives, so it is decided here; from a
    source inside it, it depends on the run, and the reader's domain is kept (as for a history
    directly in a `<parallel>`, which the reader holds in a region of its own)."""
    if not any(local(a) == "parallel" for a in _proper_ancestors(source)):
        return None  # no region the reader adds holds the source: the domains are W3C's
    if local(target) == "history" and not _history_decided(source, target):
        return None
    if internal and _w3c_compound(source) and source in _proper_ancestors(target):
        return None  # W3C's internal transition stays in its source, as the reader's does
    w3c = _w3c_domain(source, [target, *extra])
    if w3c is None or _region_domain(source, [target]) is w3c:
        return None
    below = [a for a in (source, *_proper_ancestors(source)) if a.getparent() is w3c]
    return below[0] if below else None


def _history_decided(source: etree._Element, history: etree._Element) -> bool:
    """Whether the domain of a transition into `history` is the same whatever it holds."""
    parent = history.getparent()
    if parent is None or local(parent) == "parallel":
        return False
    return parent not in _proper_ancestors(source)


def split_reentry(
    targets: list[str], by_id: dict[str, etree._Element]
) -> tuple[list[str], list[etree._Element]]:
    """`target="a1 p"` with `p` a `<parallel>` holding `a1`: the one target and the `<parallel>`
    states it names besides (swarmgen writes this for a transition that `reentered` gives a
    state, and W3C reads it so); any other list is returned whole (UML has one target)."""
    if len(targets) < 2 or targets[0] not in by_id:
        return targets, []
    first = by_id[targets[0]]
    holders = _proper_ancestors(first)
    extra = [by_id.get(t) for t in targets[1:]]
    if all(e is not None and local(e) == "parallel" and e in holders for e in extra):
        return targets[:1], [e for e in extra if e is not None]
    return targets, []
