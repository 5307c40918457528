"""A raw model written as EMF XMI with the swarm profile applied: the XMI reader's inverse, used
by `swarmgen convert` to bring SCXML, CPSwarm and Modelio-native inputs into the supported flow.

The document has the shape Modelio's XMI export gives and its import reads (docs/convert.md):
`xmi:XMI` (XMI 2.1) holding the `uml:Model` (UML2 3.0.0 namespace) and, after it, one element
per stereotype application in the profile's namespace, `base_<Metaclass>` naming the extended
element. Every element carries its `xmi:type` explicitly (EMF may omit it; Modelio's importer
is happier with it); references given as child elements keep their form (`xmi:idref` for an id,
`href` for a `file#id` or `pathmap://` reference). Deterministic: elements, attributes and
stereotype applications in the raw model's order, nothing dated.
"""

from __future__ import annotations

from lxml import etree

from swarmgen.frontend.raw import RawElement, RawModel, StereotypeApplication

XMI_URI = "http://schema.omg.org/spec/XMI/2.1"
UML_URI = "http://www.eclipse.org/uml2/3.0.0/UML"
# The CPSwarm profile's namespace in Modelio's exports (sample_models/*): used for stereotype
# applications whose own namespace is not known (a reader that makes them up, such as SCXML's).
CPSWARM_URI = "http:///schemas/CPSwarm/_L1oOEIo-Ee-0HcfyqRPQXg/0"
CPSWARM_PREFIX = "CPSwarm"
_XMI = f"{{{XMI_URI}}}"
_ROOT_FEATURES = {"Model", "Package", "Profile"}  # the tag of a root element is its type
# Types that are not UML metaclasses (Ecore's annotations): written without `xmi:type`, as EMF
# writes them; the reader infers them from the feature.
_UNTYPED = {"EAnnotation"}


def write_xmi(model: RawModel) -> bytes:
    """The XMI document of `model`, UTF-8, with an XML declaration and a final newline."""
    namespaces = _namespaces(model.stereotypes)
    root = etree.Element(f"{_XMI}XMI", nsmap=namespaces)
    root.set(f"{_XMI}version", "2.1")
    for element in model.roots:
        root.append(_element(element, top=True))
    prefixes = {uri: prefix for prefix, uri in namespaces.items()}
    for application in model.stereotypes:
        root.append(_stereotype(application, model, prefixes))
    etree.indent(root, space="  ")
    text: bytes = etree.tostring(root, xml_declaration=True, encoding="UTF-8")
    return text + b"\n"


def _namespaces(stereotypes: list[StereotypeApplication]) -> dict[str, str]:
    """xmi, uml, then one prefix per profile namespace in order of first use (the CPSwarm
    profile as `CPSwarm`, others `profile1`, `profile2`, ...)."""
    namespaces = {"xmi": XMI_URI, "uml": UML_URI}
    for application in stereotypes:
        uri = application.profile_uri or CPSWARM_URI
        if uri in namespaces.values():
            continue
        taken = CPSWARM_PREFIX in namespaces
        prefix = CPSWARM_PREFIX if not taken else f"profile{len(namespaces) - 2}"
        namespaces[prefix] = uri
    return namespaces


def _element(raw: RawElement, *, top: bool = False) -> etree._Element:
    """One raw element and its subtree (iteratively: a model may be deep)."""
    node = _node(raw, top)
    stack = [(raw, node)]
    while stack:
        parent_raw, parent_node = stack.pop()
        for child in parent_raw.children:
            child_node = _node(child, False)
            parent_node.append(child_node)
            stack.append((child, child_node))
        for feature, values in parent_raw.child_refs.items():
            for value in values:
                ref = etree.SubElement(parent_node, feature)
                ref.set("href" if _is_href(value) else f"{_XMI}idref", value)
    return node


def _node(raw: RawElement, top: bool) -> etree._Element:
    """The element itself: tag, `xmi:type`, `xmi:id`, the attributes in order, the text."""
    if top and raw.feature in _ROOT_FEATURES:
        node = etree.Element(f"{{{UML_URI}}}{raw.feature}")
    else:
        node = etree.Element(raw.feature)
        if raw.uml_type and raw.uml_type not in _UNTYPED:
            node.set(f"{_XMI}type", f"uml:{raw.uml_type}")
    if raw.id:
        node.set(f"{_XMI}id", raw.id)
    for key, value in raw.attrs.items():
        node.set(key, value)
    if raw.text:
        node.text = raw.text
    return node


def _is_href(value: str) -> bool:
    """A reference to another file or a library (`file.xmi#_id`, `pathmap://...#Real`)."""
    return "#" in value or "://" in value


def _stereotype(
    application: StereotypeApplication, model: RawModel, prefixes: dict[str, str]
) -> etree._Element:
    uri = application.profile_uri or CPSWARM_URI
    node = etree.Element(f"{{{uri}}}{application.name}")
    if application.span.xmi_id:
        node.set(f"{_XMI}id", application.span.xmi_id)
    for metaclass, ids in _bases(application, model).items():
        node.set(f"base_{metaclass}", " ".join(ids))
    for key, value in application.tags.items():
        node.set(key, value)
    assert uri in prefixes  # _namespaces saw every application
    return node


def _bases(application: StereotypeApplication, model: RawModel) -> dict[str, list[str]]:
    """The extended elements by metaclass: `base_Class`, `base_Operation`, ... (the element's
    own UML type; `Element` for an id the model does not hold)."""
    bases: dict[str, list[str]] = {}
    for base in application.base_ids:
        element = model.resolve(base)
        metaclass = element.uml_type if element is not None and element.uml_type else "Element"
        bases.setdefault(metaclass, []).append(base)
    return bases
