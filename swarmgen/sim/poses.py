"""Positions inside values of the model's pose types, whatever their shape.

The library moves bodies in the plane; the model decides how a pose is written: a data type
`{x, y, z}`, a «RosMessage» `PoseStamped {header, pose {position {x, y, z}, orientation}}`, or
untyped. The position of a value is the first mapping, breadth first, with numeric `x` and `y`,
never inside an `orientation` (a quaternion has an `x` and a `y` too); the library reads goals
there and writes finds into a copy of the output's or event field's initial value (its model
defaults kept: a frame id, a unit quaternion). An untyped or unknown template gets `{x, y, z}`.
"""

from __future__ import annotations

import copy
from collections import deque
from collections.abc import Mapping, MutableMapping
from typing import Any

SKIPPED = frozenset({"orientation"})  # keys whose insides are never a position


def _is_position(value: Any) -> bool:
    """A mapping with numeric (not Boolean) `x` and `y`."""
    if not isinstance(value, Mapping):
        return False
    return all(
        isinstance(value.get(k), int | float) and not isinstance(value.get(k), bool)
        for k in ("x", "y")
    )


def _position_mapping(value: Any) -> Mapping[str, Any] | None:
    """The mapping holding the position of `value` (breadth first), if any."""
    queue: deque[Any] = deque([value])
    while queue:
        item = queue.popleft()
        if _is_position(item):
            return item  # type: ignore[no-any-return]
        if isinstance(item, Mapping):
            queue.extend(v for k, v in item.items() if k not in SKIPPED)
    return None


def position_of(value: Any) -> tuple[float, float] | None:
    """The (x, y) a pose value holds, or None."""
    found = _position_mapping(value)
    return None if found is None else (float(found["x"]), float(found["y"]))


def placed(template: Any, x: float, y: float) -> Any:
    """A copy of `template` (a pose value of the model's type) at (x, y); z is 0."""
    value = copy.deepcopy(template)
    found = _position_mapping(value)
    if not isinstance(found, MutableMapping):
        return {"x": float(x), "y": float(y), "z": 0.0}
    found["x"], found["y"] = float(x), float(y)
    if "z" in found:
        found["z"] = 0.0
    return value
