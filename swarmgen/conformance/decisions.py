"""docs/conformance.md's decisions on the mandatory tests swarmgen's typed datamodel does not run,
per test, and on how confSwarmgen.xsl writes the IRP's vocabulary for that datamodel."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

_SCRIPT = (
    '`<script>`: the test is "valid only for datamodels that support scripting" (its own '
    "comment); swarmgen's datamodel is typed data and an expression language, with no scripts: "
    "ECMAScript source would run only in the SCXML output, nothing runs it in Python"
)
TYPED = {
    "152": "`<foreach>` over a number (the IRP's illegalArray, 7) is SG208 when the document is "
    "compiled, where W3C raises error.execution when it runs: a datum's type is what the checker "
    "infers from its `<data expr>`, after the reader, and a loop over a value known not to be a "
    "sequence stays a type error as in a UML model (an undeclared location, by contrast, is read "
    "as `invalid(...)`, which fails when it runs: docs/scxml-input.md); the loop's item "
    "`'continue'` is no identifier, SG060",
    "525": "the loop's body extends the array it iterates (`[].concat(Var1, [4])`); swarmgen's "
    '`for` iterates a copy as W3C wants (docs/semantics.md, "Loops"), but the language has no '
    "calls and no sequence concatenation: `+` on sequences cannot be written in ECMAScript "
    'without their types (`[1] + [4]` is the string "14")',
    "329": "it assigns `_event` and `_ioprocessors` whole to data and compares them "
    "(`Var2 == _event`): the typed datamodel reads `_event` field by field and `_ioprocessors` "
    "as `_ioprocessors.scxml.location`, and records do not compare (ECMAScript compares objects "
    "by identity, Python by value: SG208); its read-only `_sessionid` and `_name` swarmgen does "
    "(tests/test_system_assign.py)",
    "330": "`'name' in _event`: every event of the typed datamodel has all of W3C's fields "
    '(blank ones ""), so there is nothing to test, and the language has no `in`',
    "216": "`<invoke srcexpr>`: the child document is named by a value computed when the "
    "state is entered; swarmgen reads, checks and compiles every invoked document when the "
    "parent is compiled (a generated package carries no SCXML reader or compiler, and a "
    "document it never checked would run unchecked), so only `src` and inline `<content>` "
    "are read",
    "530": "the child document is the value of a datum (`<content expr>`), assigned an XML "
    "document by `<assign>` with inline content: the typed datamodel holds no XML values, "
    "and a document computed at run time is not compiled (as 216)",
    "245": "it tests that a name the child never declares stays unbound (`conf:isBound`, "
    "`typeof` in ECMAScript): the typed datamodel has no unbound names (as the `undefined` "
    "tests above); what it tests first, that a namelist value for a name the child does not "
    'declare sets nothing, swarmgen does (docs/semantics.md, "Invoked sessions")',
    "302": _SCRIPT,
    "303": _SCRIPT,
    "304": _SCRIPT,
}
CONVERSIONS = [
    "`invalidSessionID` is the string `'27'` (confEcma.xsl's number 27 would make the datum a "
    "number, which test 173 then assigns a target string: SG208); `invalidSendTypeExpr` the "
    "same way",
    "`systemVarIsBound` (test 319, of `_event`) is `_event.name != ''`: reading `_event` fails "
    "(error.execution, the cond is false) until the first event, and every event has a name "
    "(W3C 5.10.1)",
    "`<data src>` reads the IRP's `.txt` files, copied beside the converted documents "
    "(docs/scxml-input.md: a file in the document's directory, read when it is compiled)",
]


def typed_section(rows: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """The mandatory tests the typed datamodel does not run and why, and the conversions."""
    found = [t for t in TYPED if rows.get(t, {}).get("swarmgen") == "not-run"]
    lines = ["## Tests the typed datamodel does not express", ""]
    lines += [f"- {t}: {TYPED[t]}." for t in found]
    lines += ["", "confSwarmgen.xsl writes for the typed datamodel:", ""]
    return [*lines, *(f"- {c}." for c in CONVERSIONS), ""]
