"""The raw model: the XMI element tree with types inferred, ids indexed and spans attached.

It is deliberately generic (no UML semantics beyond type inference): `ir.build` gives it meaning.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import field

from swarmgen.records import dataclass
from swarmgen.span import Span


@dataclass(eq=False)
class RawElement:
    """One XMI element. `uml_type` is the `xmi:type` suffix, or inferred from the feature name."""

    feature: str  # the element's local tag name: packagedElement, subvertex, region, ...
    uml_type: str  # State, Transition, ... ('' when unknown)
    id: str | None
    attrs: dict[str, str]  # by local name, without the xmi: bookkeeping attributes
    file: str
    line: int
    col: int
    path: str  # `Model::Package::Class::Machine::State`
    text: str = ""  # stripped text content (bodies, languages)
    children: list[RawElement] = field(default_factory=list)
    parent: RawElement | None = None
    # References given as child elements: feature -> ids (xmi:idref) or hrefs (file#id, pathmap://...).
    child_refs: dict[str, list[str]] = field(default_factory=dict)

    _span: Span | None = None
    # Children by feature, built on the first `kids(feature)` (the builder asks each element
    # for a few features; filtering every child per question was a tenth of the build).
    _by_feature: dict[str, list[RawElement]] | None = field(default=None, repr=False)
    _indexed: int = field(default=-1, repr=False)  # len(children) when _by_feature was built

    @property
    def span(self) -> Span:
        """Built on first use: most raw elements never need one."""
        if self._span is None:
            self._span = Span(
                file=self.file, line=self.line, col=self.col, xmi_id=self.id, path=self.path
            )
        return self._span

    @property
    def name(self) -> str:
        """The element's `name` attribute ('' when unnamed)."""
        return self.attrs.get("name", "")

    def kids(self, feature: str | None = None, uml_type: str | None = None) -> Iterator[RawElement]:
        """Direct children, optionally only those of one feature and/or UML type."""
        found = self.children if feature is None else self._of_feature(feature)
        if uml_type is None:
            return iter(found)
        return iter([child for child in found if child.uml_type == uml_type])

    def first(self, feature: str) -> RawElement | None:
        """The first child of a feature, or None."""
        found = self._of_feature(feature)
        return found[0] if found else None

    def _of_feature(self, feature: str) -> list[RawElement]:
        """The children of one feature, in document order (re-indexed if children grew)."""
        if self._by_feature is None or self._indexed != len(self.children):
            index: dict[str, list[RawElement]] = {}
            for child in self.children:
                index.setdefault(child.feature, []).append(child)
            self._by_feature, self._indexed = index, len(self.children)
        return self._by_feature.get(feature, _NONE)

    def walk(self) -> Iterator[RawElement]:
        """This element and all its descendants, depth first in document order."""
        stack: list[RawElement] = [self]
        while stack:
            element = stack.pop()
            yield element
            stack.extend(reversed(element.children))

    def ref_values(self, feature: str) -> list[str]:
        """References of one feature in any of XMI's three forms (attribute list, idref, href)."""
        values = self.attrs.get(feature, "").split()
        return values + self.child_refs.get(feature, [])


_NONE: list[RawElement] = []  # shared and never mutated: the children of an absent feature


@dataclass(frozen=True)
class StereotypeApplication:
    """A root-level `<Profile:Stereotype base_X="id" tag="..."/>` element."""

    name: str  # local name of the stereotype (package-qualified names keep their last segment)
    profile_uri: str
    base_ids: tuple[str, ...]
    tags: dict[str, str]
    span: Span


@dataclass
class RawModel:
    """A parsed XMI file: its root elements, the id index and the stereotype applications."""

    file: str
    roots: list[RawElement]
    index: dict[str, RawElement]
    stereotypes: list[StereotypeApplication]
    exporter: str  # "modelio", "eclipse-uml2", "papyrus", ... (informative)
    # the documents of the SCXML `<invoke>`s, by the `session` attribute of their element
    sessions: dict[str, RawModel] = field(default_factory=dict)

    def elements(self) -> Iterator[RawElement]:
        """Every element of every root, depth first in document order."""
        for root in self.roots:
            yield from root.walk()

    def resolve(self, ref: str) -> RawElement | None:
        """An element by id, or by the fragment of a same-file href (`model.xmi#_id`)."""
        element = self.index.get(ref)
        if element is None and "#" in ref:
            element = self.index.get(ref.rsplit("#", 1)[1])
        return element
