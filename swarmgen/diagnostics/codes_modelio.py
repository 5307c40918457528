"""The registry's codes of the Modelio native reader, .exml and .ramc (SG080-SG089): archive safety and what the native format lacks.

Registered after `codes_ros`, in the same `CODES`, the same way.
"""

from __future__ import annotations

__all__: list[str] = []
