"""Diagnostics as data: stable codes with their messages, severities, spans and hints, rendered
as text, JSON or SARIF.

Every stage returns its diagnostics instead of raising on model errors. Codes and their message
templates are registered once (`codes`, `codes_checks`, `codes_ros`, `codes_scxml`,
`codes_modelio`, `codes_verify`), so that `docs/diagnostics.md`, the renderers and every stage agree; `model`
holds the data types, `render` the output formats.
"""

from __future__ import annotations

from swarmgen.diagnostics import (
    codes,
    codes_checks,
    codes_modelio,
    codes_network,
    codes_ros,
    codes_scxml,
    codes_verify,  # noqa: F401 (registers the verify codes; `verify` names them as `cv`)
)
from swarmgen.diagnostics.codes import *  # noqa: F403 (the codes are the public API)
from swarmgen.diagnostics.codes import CODES, active_codes, register, retire
from swarmgen.diagnostics.codes_checks import *  # noqa: F403
from swarmgen.diagnostics.codes_modelio import *  # noqa: F403
from swarmgen.diagnostics.codes_network import *  # noqa: F403
from swarmgen.diagnostics.codes_ros import *  # noqa: F403
from swarmgen.diagnostics.codes_scxml import *  # noqa: F403
from swarmgen.diagnostics.model import (
    DEFAULT,
    Code,
    Diagnostic,
    ExitCode,
    Message,
    Severity,
    apply_options,
    diag,
    exit_code_for,
    has_errors,
    normalise,
    template_fields,
)
from swarmgen.diagnostics.render import (
    SARIF_SCHEMA,
    one_line,
    refusal_line,
    render_json,
    render_sarif,
    render_text,
    summary_line,
)

__all__ = [
    "CODES",
    "DEFAULT",
    "SARIF_SCHEMA",
    "Code",
    "Diagnostic",
    "ExitCode",
    "Message",
    "Severity",
    "active_codes",
    "apply_options",
    "diag",
    "exit_code_for",
    "has_errors",
    "normalise",
    "one_line",
    "refusal_line",
    "register",
    "render_json",
    "render_sarif",
    "render_text",
    "retire",
    "summary_line",
    "template_fields",
]
__all__ += codes.__all__
__all__ += codes_checks.__all__
__all__ += codes_ros.__all__
__all__ += codes_scxml.__all__
__all__ += codes_modelio.__all__
__all__ += codes_network.__all__
