"""What building shares: the raw model, diagnostics, stereotypes and reference resolution."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import field
from functools import cached_property

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.diagnostics import Diagnostic
from swarmgen.frontend.raw import RawElement, RawModel, StereotypeApplication
from swarmgen.ir.literals import (
    INTEGER_TEXT,
    BadLiteral,
    literal_text,
    literal_value,
    unrepresentable,
)
from swarmgen.ir.nodes import (
    Behaviour,
    BehaviourKind,
    Enumeration,
    Event,
    HardwareKind,
    Property,
    Value,
)
from swarmgen.names import identifier
from swarmgen.records import dataclass

HARDWARE_KINDS = {k.value: k for k in HardwareKind}
BEHAVIOUR_KINDS = {k.value: k for k in BehaviourKind}
_BEHAVIOUR_TAGS = frozenset({"requires", "outcomes", "emits", "rosKind", "rosName", "rosType"})
KNOWN_STEREOTYPES: dict[str, frozenset[str]] = {
    "Swarm": frozenset(),
    "SwarmMember": frozenset({"role"}),
    "Sensor": frozenset(),
    "Actuator": frozenset(),
    "Controller": frozenset(),
    "CommunicationInterface": frozenset({"communicationType", "communicationParams"}),
    "BehaviorLibrary": frozenset(),
    "SwarmEvent": frozenset({"sender", "scope"}),
    "RosMessage": frozenset({"rosType"}),  # on a DataType: the ROS message it is (profile.md)
    "Property": frozenset(),  # on a Constraint of a swarm class: a user property (verify.md)
    **{k: _BEHAVIOUR_TAGS for k in BEHAVIOUR_KINDS},
}


@dataclass
class Builder:
    """The state of one build: the raw model, the diagnostics so far, stereotypes by base id,
    and the behaviours and events read so far (which later stages resolve against)."""

    raw: RawModel
    diags: list[Diagnostic] = field(default_factory=list)
    stereo: dict[str, list[StereotypeApplication]] = field(default_factory=dict)
    behaviours: dict[str, Behaviour] = field(default_factory=dict)
    events_by_signal: dict[str, Event] = field(default_factory=dict)
    events_by_name: dict[str, Event] = field(default_factory=dict)
    enumerations: dict[str, Enumeration] = field(default_factory=dict)  # by name
    # Parsed texts, enumeration literals resolved: the same guard or effect text recurs on
    # thousands of transitions (10,000 states: 13,700 texts, 330 distinct). The results are
    # frozen and carry no span (a diagnostic's span is the element's), so one serves every
    # occurrence. Filled only after `enumerations` is complete; a text that fails is not kept.
    parsed_exprs: dict[str, expr.Expr] = field(default_factory=dict)
    parsed_actions: dict[str, tuple[expr.Action, ...]] = field(default_factory=dict)
    parsed_bindings: dict[str, tuple[expr.Binding, ...]] = field(default_factory=dict)

    @cached_property
    def declares_events(self) -> bool:
        """Whether the model applies «SwarmEvent» anywhere (then an unknown trigger name is an
        error); once per build, not a scan of every stereotype per trigger."""
        return any(a.name == "SwarmEvent" for a in self.raw.stereotypes)

    # --- helpers

    def expression(self, text: str) -> expr.Expr:
        """`text` parsed as one expression, its enumeration literals resolved; raises ExprError."""
        found = self.parsed_exprs.get(text)
        if found is None:
            found = expr.resolve_enums(expr.parse_expr(text), self.enumerations)
            self.parsed_exprs[text] = found
        return found

    def actions(self, text: str) -> tuple[expr.Action, ...]:
        """`text` parsed as statements, their enumeration literals resolved; raises ExprError."""
        found = self.parsed_actions.get(text)
        if found is None:
            parsed = expr.parse_actions(text)
            found = tuple(expr.resolve_action_enums(a, self.enumerations) for a in parsed)
            self.parsed_actions[text] = found
        return found

    def bindings(self, text: str) -> tuple[expr.Binding, ...]:
        """`text` parsed as argument bindings, enumeration literals resolved; raises ExprError."""
        found = self.parsed_bindings.get(text)
        if found is None:
            found = tuple(_resolved(binding, self) for binding in expr.parse_bindings(text))
            self.parsed_bindings[text] = found
        return found

    def stereotype(self, element: RawElement, names: Iterable[str]) -> StereotypeApplication | None:
        """The first application on `element` of one of the named stereotypes, if any."""
        wanted = set(names)
        apps = [a for a in self.stereo.get(element.id or "", []) if a.name in wanted]
        return apps[0] if apps else None

    def ref(
        self, element: RawElement, feature: str, kinds: set[str] | None = None
    ) -> RawElement | None:
        """Resolve a single-valued reference, reporting dangling and wrong-kind references,
        and several values where UML allows one (`source="_a _b"` used to take `_a`)."""
        values = element.ref_values(feature)
        if len(values) > 1:
            self.several(element, feature, values)
            return None
        return self._resolve(element, feature, values[0], kinds) if values else None

    def several(self, element: RawElement, feature: str, values: list[str]) -> None:
        """Report several values of a single-valued reference."""
        shown = " ".join(values[:3]) + (" ..." if len(values) > 3 else "")
        self.diags.append(
            dg.SEVERAL_REFS.at(
                element.span,
                kind=element.uml_type or element.feature,
                label=label(element),
                feature=feature,
                count=len(values),
                shown=shown,
            )
        )

    def refs(
        self, element: RawElement, feature: str, kinds: set[str] | None = None
    ) -> list[RawElement]:
        """Resolve a multi-valued reference, dropping (and reporting) the bad values."""
        found = (self._resolve(element, feature, v, kinds) for v in element.ref_values(feature))
        return [f for f in found if f is not None]

    def _resolve(
        self, element: RawElement, feature: str, value: str, kinds: set[str] | None
    ) -> RawElement | None:
        target = self.raw.resolve(value)
        if target is None:
            if _is_external(value):
                return None
            self.diags.append(
                dg.DANGLING_REF.at(
                    element.span,
                    kind=element.uml_type or element.feature,
                    name=element.name,
                    feature=feature,
                    value=value,
                )
            )
            return None
        if kinds is not None and target.uml_type not in kinds:
            self.diags.append(
                dg.WRONG_REF_KIND.at(
                    element.span,
                    feature=feature,
                    name=element.name,
                    kind=target.uml_type or target.feature,
                    target=target.name,
                    expected=" or ".join(sorted(kinds)),
                )
            )
            return None
        return target

    def type_name(self, element: RawElement) -> str | None:
        """The name of the element's type: a model type or a primitive-library fragment."""
        values = element.ref_values("type")
        if len(values) > 1:
            self.several(element, "type", values)
            return None
        for value in values:
            target = self.raw.resolve(value)
            if target is not None:
                return target.name or None
            # pathmap://.../UMLPrimitiveTypes.library.uml#Real, OMG uml.xml#Integer
            if "#" in value:
                return value.rsplit("#", 1)[1] or None
            self._resolve(element, "type", value, None)  # reports the dangling reference
        return None

    def prop(self, element: RawElement) -> Property:
        """An attribute or parameter as a Property, with its checked default."""
        type_name = self.type_name(element)
        return Property(
            id=element.id or element.span.path,
            name=element.name,
            ident=identifier(element.name),
            type=type_name,
            default=self._default(element, type_name),
            many=self._many(element),
            span=element.span,
        )

    def _many(self, element: RawElement) -> bool:
        """Whether the upper multiplicity makes a sequence: `*` (or UML's -1) or above 1; a
        text that is no number is a single value (swarm parts report it: SG022)."""
        upper = element.first("upperValue")
        if upper is None:
            return False
        text = upper.attrs.get("value", "1").strip()
        if text in {"*", "-1"}:
            return True
        return INTEGER_TEXT.fullmatch(text) is not None and int(text[:19]) > 1

    def _default(self, element: RawElement, type_name: str | None) -> Value:
        """The default, if generated code can hold it exactly and it is of the declared type
        (an Integer `abc` or `1e3` used to become a string literal, a Boolean `yes` false)."""
        spec = element.first("defaultValue")
        if spec is None:
            return None
        enumeration = self.enumerations.get(type_name or "")
        if enumeration is not None:
            return self._literal_default(element, spec, enumeration)
        value = literal_value(spec)
        if not isinstance(value, BadLiteral):
            bad = unrepresentable(value, type_name)
            if bad is None:
                return value
            value = bad
        self.diags.append(
            dg.BAD_DEFAULT.at(
                element.span,
                value=short(literal_text(spec)),
                name=element.name,
                problem=value.problem,
                hint=value.hint,
            )
        )
        return None

    def _literal_default(
        self, element: RawElement, spec: RawElement, enumeration: Enumeration
    ) -> Value:
        """An enumeration-typed default: a literal by reference (`InstanceValue`, UML2) or by
        name (Modelio's `Expression symbol`, a `LiteralString`)."""
        if spec.uml_type == "InstanceValue":
            target = self.ref(spec, "instance")
            text = target.name if target is not None else ""
        else:
            value = literal_value(spec)
            text = value.strip() if isinstance(value, str) else literal_text(spec)
        if text in enumeration.literals:
            return text
        self.diags.append(
            dg.BAD_DEFAULT.at(
                element.span,
                value=short(text),
                name=element.name,
                problem=f"is not a literal of {enumeration.name}",
                hint=f"write one of {', '.join(enumeration.literals) or '(none)'}",
            )
        )
        return None

    # --- stereotypes

    def index_stereotypes(self) -> None:
        """Index stereotype applications by base id, reporting unknown ones and tags."""
        for app in self.raw.stereotypes:
            known = KNOWN_STEREOTYPES.get(app.name)
            if known is None:
                self.diags.append(dg.UNKNOWN_STEREOTYPE.at(app.span, stereotype=app.name))
                continue
            for tag in sorted(set(app.tags) - known):
                self.diags.append(dg.UNKNOWN_TAG.at(app.span, stereotype=app.name, tag=tag))
            for base in app.base_ids:
                if self.raw.resolve(base) is None:
                    self.diags.append(
                        dg.DANGLING_REF.at(
                            app.span, "stereotype-base", stereotype=app.name, base=base
                        )
                    )
                self.stereo.setdefault(base, []).append(app)

    def tag_choice(
        self, app: StereotypeApplication, tag: str, allowed: tuple[str, ...]
    ) -> str | None:
        """A tag's value if it is one of `allowed` (reported otherwise); None when unset."""
        value = app.tags.get(tag, "").strip()
        if not value:
            return None
        if value not in allowed:
            self.diags.append(
                dg.BAD_TAG_VALUE.at(
                    app.span,
                    stereotype=app.name,
                    tag=tag,
                    value=value,
                    allowed=", ".join(allowed),
                )
            )
            return None
        return value


def label(element: RawElement) -> str:
    """How a message names an element: by name, else (transitions rarely have one) by id."""
    return f"'{element.name}'" if element.name else (element.id or element.span.path)


def _is_external(value: str) -> bool:
    """hrefs into other files (profiles, UML libraries) are not ours to resolve."""
    if "#" not in value:
        return False
    file_part = value.split("#", 1)[0]
    return bool(file_part)


def is_part(attribute: RawElement) -> bool:
    """Whether the attribute is a composite part (hardware of a member, members of a swarm)."""
    return attribute.attrs.get("aggregation") == "composite"


def short(text: str, limit: int = 60) -> str:
    """Model text quoted for a message: whitespace collapsed, clipped at `limit`."""
    flat = " ".join(text.split())
    return f"'{flat[: limit - 3]}...'" if len(flat) > limit else f"'{flat}'"


def _resolved(binding: expr.Binding, b: Builder) -> expr.Binding:
    """The binding with its enumeration literals resolved (itself when it has none)."""
    value = expr.resolve_enums(binding.value, b.enumerations)
    return binding if value is binding.value else expr.Binding(name=binding.name, value=value)
