"""Reading goal/request fields and writing result/response fields by name, on messages whose
types are known only at run time (imported by name): poses as `PoseStamped`, `Pose` or `Point`,
numbers and strings converted to the field's Python type (rclpy refuses an int for a float)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .geometry import Pose


def _point_of(value: Any) -> Any:
    """The `Point` inside a PoseStamped, a Pose or a Point (None for anything else)."""
    if hasattr(value, "pose") and hasattr(value, "header"):
        value = value.pose
    if hasattr(value, "position"):
        value = value.position
    return value if all(hasattr(value, axis) for axis in ("x", "y", "z")) else None


def read_xy(message: Any, name: str) -> tuple[float, float] | None:
    """(x, y) of the pose-like field `name`, or None when the message has no such field."""
    point = _point_of(getattr(message, name, None))
    return None if point is None else (float(point.x), float(point.y))


def read_number(message: Any, name: str, default: float = 0.0) -> float:
    """The numeric field `name`, or `default` when absent."""
    value = getattr(message, name, None)
    return float(value) if isinstance(value, (int, float)) else default


def pose_of(message: Any) -> Pose:
    """A `geometry_msgs/PoseStamped` (or Pose) as the core's `Pose`."""
    point = _point_of(message)
    return Pose(float(point.x), float(point.y), float(point.z))


def set_pose(target: Any, x: float, y: float, z: float = 0.0) -> None:
    """Fill a PoseStamped (frame `map`, unit quaternion), a Pose or a Point in place."""
    if hasattr(target, "header") and hasattr(target, "pose"):
        target.header.frame_id = "map"
    point = _point_of(target)
    point.x, point.y, point.z = float(x), float(y), float(z)
    holder = target.pose if hasattr(target, "header") and hasattr(target, "pose") else target
    if hasattr(holder, "orientation"):
        holder.orientation.x = holder.orientation.y = holder.orientation.z = 0.0
        holder.orientation.w = 1.0


def pose_dict(x: float, y: float, z: float = 0.0) -> dict[str, Any]:
    """A PoseStamped as the swarm events carry it (the model's PoseStamped data type)."""
    return {
        "header": {"frame_id": "map"},
        "pose": {
            "position": {"x": float(x), "y": float(y), "z": float(z)},
            "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
        },
    }


def write_fields(message: Any, values: Mapping[str, Any]) -> None:
    """Set each field of `message` that `values` names; the others are left as they are.
    A pose value is a mapping with x, y (and z)."""
    for name, value in values.items():
        if value is None or not hasattr(message, name):
            continue
        current = getattr(message, name)
        if isinstance(value, Mapping):
            if _point_of(current) is not None:
                set_pose(current, value.get("x", 0.0), value.get("y", 0.0), value.get("z", 0.0))
        elif isinstance(current, bool):
            setattr(message, name, bool(value))
        elif isinstance(current, int):
            setattr(message, name, int(value))
        elif isinstance(current, float):
            setattr(message, name, float(value))
        elif isinstance(current, str):
            setattr(message, name, str(value))
