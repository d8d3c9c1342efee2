"""Checks shared by the sections of a mission's waypoints (scout stops, navigate_to legs), ROS-free: each
problem appended to the caller's list, naming the key and its value."""
import math
from typing import Any, List, Sequence


def is_number(v: Any) -> bool:
    """A finite int or float (bool is not a number here)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def keyed_mapping(raw: Any, where: str, keys: Sequence[str], problems: List[str]) -> bool:
    """Whether `raw` is a mapping; a problem for it when not, and one for each key it has outside `keys`."""
    if not isinstance(raw, dict):
        problems.append(f"{where}: expected a mapping with keys {', '.join(keys)}, got {raw!r}")
        return False
    for key in raw:
        if key not in keys:
            problems.append(f"{where}.{key}: unknown key (value {raw[key]!r}); known: {', '.join(keys)}")
    return True
