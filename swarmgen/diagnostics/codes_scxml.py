"""The registry's codes of the SCXML reader (SG060-SG079): documents swarmgen cannot read, or reads with a caveat.

Registered after `codes_ros`, in the same `CODES`, the same way.
"""

from __future__ import annotations

__all__: list[str] = []
