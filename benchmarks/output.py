"""The benchmarks' JSON: plain JSON values from numpy and JAX results."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np


def jsonable(value):
    """``value`` as plain JSON values: dicts (keys as strings), lists, str, bool, int,
    float and None. numpy and JAX arrays become (nested) lists, their scalars Python
    numbers; NaN and +-Inf become None (JSON has no such numbers). Anything else is a
    TypeError naming its type."""
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    if hasattr(value, "__array__"):
        arr = np.asarray(value)
        return jsonable(arr.tolist() if arr.ndim else arr.item())
    raise TypeError(f"cannot convert {type(value).__name__} to JSON: {value!r}")


def to_json(value) -> str:
    """Indented JSON text of :func:`jsonable` ``(value)``, with a final newline."""
    return json.dumps(jsonable(value), indent=2) + "\n"


def write_json(path: Path | None, value) -> None:
    """:func:`to_json` ``(value)`` written to ``path`` (its folder made; None: nothing),
    and a line saying so."""
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(to_json(value))
        print(f"written: {path}")
