"""The root of swarmgen's user errors: the CLI maps every one to its message and exit code.

A user error is something the user can fix (an unreadable scenario, an output directory that
cannot be written, a bag that is not a bag); the CLI prints `swarmgen: error: <message>` and
exits with the class's `exit_code`, in one place (`swarmgen.commands.common.report`: the message
escaped to one line, `verbatim` errors printed as they are). Bugs stay ordinary exceptions (the CLI's exit 3). The
runtime vendored into generated packages (swarmgen/runtime, swarmgen/ros/runtime) does not
import this module: generated code does not depend on swarmgen.
"""

from __future__ import annotations

__all__ = ["SwarmgenError"]


class SwarmgenError(Exception):
    """A user error; its message is one line for the user, `exit_code` the process's exit."""

    exit_code: int = 2  # diagnostics.ExitCode.INPUT_ERROR: the input or the command is at fault
    # Printed as it is rather than escaped to one line: for messages written for the terminal.
    verbatim: bool = False
