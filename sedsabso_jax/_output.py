"""Writing results: atomic files, plain JSON values, markdown tables and their notes, PNG
figures.

Every file goes to a temporary file in the target's directory and is then renamed over the
target. ``os.replace`` is atomic on POSIX and Windows within one file system, so a reader
sees either the old file or the complete new one, never a half-written file, and a failure
while writing leaves the old file (or no file) and no temporary file behind.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import tempfile
import textwrap
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, BinaryIO

import numpy as np
from tabulate import tabulate

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: A file path: a string or a path object.
PathLike = str | os.PathLike[str]


def atomic_write(path: PathLike, write: Callable[[BinaryIO], None]) -> Path:
    """Call ``write(f)`` on a binary file object opened on a temporary file beside
    ``path``; flush and fsync it, give it the permissions of the file it replaces (0644
    for a new one), then move it over ``path``. On any failure the temporary file is
    removed and an existing ``path`` is left as it was."""
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise FileNotFoundError(f"{path}: directory {directory} does not exist")
    mode = (path.stat().st_mode & 0o777) if path.is_file() else 0o644
    try:
        fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as err:
        raise _named(err, path) from None
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except OSError as err:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise _named(err, path) from None
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path


def _named(err: OSError, path: Path) -> OSError:
    """``err`` naming the target ``path``, not the temporary file beside it."""
    if err.errno is None:
        return err
    return type(err)(err.errno, err.strerror, str(path))


def write_text(path: PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    def write(f: BinaryIO) -> None:
        f.write(text.encode("utf-8"))

    return atomic_write(path, write)


def jsonable(value: Any) -> Any:
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


def to_json(value: Any) -> str:
    """Indented JSON text of :func:`jsonable` ``(value)``, with a final newline."""
    return json.dumps(jsonable(value), indent=2, allow_nan=False) + "\n"


def write_json(path: PathLike, value: Any) -> Path:
    """Write :func:`to_json` ``(value)`` to ``path`` atomically."""
    return write_text(path, to_json(value))


#: A cell holding one real number (``"1.5"``, ``"-2e-06"``, ``"inf"``); integers are apart.
_REAL = re.compile(r"[-+]?(\d+\.\d*(e[-+]?\d+)?|\.\d+(e[-+]?\d+)?|\d+e[-+]?\d+|inf|nan)",
                   re.IGNORECASE)
_INTEGER = re.compile(r"[-+]?\d+")


def _alignment(column: Sequence[str]) -> str:
    """``"right"`` for a column of real numbers (digits line up), else ``"left"``: text,
    and integers such as row numbers and counts."""
    cells = [c for c in column if c]
    numeric = all(_REAL.fullmatch(c) or _INTEGER.fullmatch(c) for c in cells)
    return "right" if cells and numeric and any(_REAL.fullmatch(c) for c in cells) else "left"


def markdown_table(head: Sequence[str], rows: Sequence[Sequence[str]],
                   align: Sequence[str] | None = None) -> str:
    """A GitHub (pipe) markdown table, rendered by ``tabulate``. Cells are printed as given
    (no number parsing: ``"0.0000"`` stays); ``align`` per column ``"left"``, ``"right"``
    or ``"center"``, by default right for columns of real numbers and left for the rest."""
    if align is None:
        align = [_alignment([r[k] for r in rows]) for k in range(len(head))]
    return tabulate([list(r) for r in rows], headers=list(head), tablefmt="pipe",
                    disable_numparse=True, colalign=list(align))


def to_its_std(value: float, std: float) -> str:
    """``value`` as a table prints it: rounded to the second significant digit of its
    standard deviation ``std`` (``0.129`` for 0.128649 +- 0.0202, ``0.000`` for 7.5e-06 +-
    0.017), so that the digits printed are those the data determine and the same on every
    processor; in exponent form where that digit lies below 1e-6 and the value below
    1e-3; every digit of a double where that digit is finer; to 6 significant digits
    where ``std`` is not a positive finite number (``inf``: not determined)."""
    if not (math.isfinite(value) and math.isfinite(std) and std > 0):
        return f"{value:.6g}"
    step = math.floor(math.log10(std)) - 1  # the std's second significant digit
    if value != 0 and math.log10(abs(value)) - step > 16:  # finer than a double's digits
        return f"{value:.17g}"
    rounded = round(value / 10.0 ** step) * 10.0 ** step  # round(): an int, never -0
    if step >= -6 or abs(rounded) >= 1e-3:
        return f"{rounded:.{max(-step, 0)}f}"
    if rounded == 0:
        return "0"
    return f"{rounded:.{math.floor(math.log10(abs(rounded))) - step}e}"


def columns_note(*definitions: tuple[str | Sequence[str], str], width: int = 90) -> str:
    """The note under a table that defines its columns: ``"Columns: `a`: what a is; `b`,
    `c`: what b and c are."``, wrapped to ``width``. Each definition is ``(header or
    headers, text)``; every header is written exactly as in the table, in backticks."""
    parts = []
    for names, text in definitions:
        names = [names] if isinstance(names, str) else list(names)
        parts.append(", ".join(f"`{n}`" for n in names) + ": " + text)
    return textwrap.fill("Columns: " + "; ".join(parts) + ".", width=width,
                         break_long_words=False, break_on_hyphens=False)


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the non-interactive Agg backend unless one is chosen
    already (imported here: most runs draw nothing)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Figure, path: PathLike) -> None:
    """Save ``fig`` as PNG atomically and close it."""
    try:
        atomic_write(path, lambda f: fig.savefig(f, format="png", dpi=120))
    finally:
        pyplot().close(fig)
