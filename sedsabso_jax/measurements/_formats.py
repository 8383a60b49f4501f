"""The measurement file formats: reading and writing ``.npz`` and ``.csv``.

Read by :func:`~sedsabso_jax.load_measurements`, written by
:meth:`~sedsabso_jax.Measurements.save`:

- ``.npz`` (the format of FloBaRoID's KUKA files, ``data/kuka_lwr4/``): float arrays
  ``times (T,)``, ``positions, torques (T, n)``, optional ``velocities, accelerations
  (T, n)``. Other keys (FloBaRoID's ``target_positions`` ...) are ignored. Read with
  ``allow_pickle=False``: an archive holding Python objects is refused, never unpickled.
- ``.csv``: one header line, then one line per sample, separated by commas (or by
  semicolons or tabs, as the header is, with decimal points or commas). Columns
  ``time, q1..qn, qd1..qdn, qdd1..qddn, tau1..taun`` (1-based joint numbers; ``qd`` and
  ``qdd`` optional, column order free). Also accepted, case-insensitive, with or without
  ``_`` before the number: ``times``/``t``; ``pos``/``position``/``positions``;
  ``dq``/``qdot``/``vel``/``velocity``/``velocities``; ``ddq``/``qddot``/``acc``/
  ``acceleration``/``accelerations``; ``torque``/``torques``/``effort``. Other columns
  are ignored (listed in ``info["ignored_columns"]``). A unit may follow a name in
  brackets or parentheses (``time [s]``, ``q1 [rad]``, ``qd1 (rad/s)``); one the package
  does not read (``deg``, ``ms``) is refused, the torques' is free (they may hold
  currents). A ``#`` before the header is allowed; later lines starting with ``#`` are
  comments.

Readers return the raw fields (checked later by :func:`._container.check_fields`); every
problem is a ValueError naming the file, the field or line, what was expected and found.
"""

from __future__ import annotations

import io
import re
import zipfile
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from .._output import PathLike, atomic_write

#: .npz keys, in the order written; times, positions and torques are required to read.
NPZ_KEYS = ("times", "positions", "velocities", "accelerations", "torques")
REQUIRED = ("times", "positions", "torques")
#: CSV column prefixes written by :func:`write` (joint number appended, from 1).
CSV_PREFIXES = {"positions": "q", "velocities": "qd", "accelerations": "qdd", "torques": "tau"}
_CSV_TIME = ("time", "times", "t")
_CSV_ALIASES = {
    "positions": ("q", "pos", "position", "positions"),
    "velocities": ("qd", "dq", "qdot", "vel", "velocity", "velocities"),
    "accelerations": ("qdd", "ddq", "qddot", "acc", "acceleration", "accelerations"),
    "torques": ("tau", "torque", "torques", "effort"),
}
_CSV_FIELD = {alias: field for field, names in _CSV_ALIASES.items() for alias in names}
_JOINT_COLUMN = re.compile(r"^([a-z_]+?)_?(\d+)$")
#: The separators a CSV file's header may use, tried in this order.
CSV_DELIMITERS = (",", ";", "\t")
#: A unit after a column's name, in brackets or parentheses: ``q1 [rad]``, ``time (s)``.
_UNIT = re.compile(r"^(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]$")
#: The units each field may state (lower case, spaces removed); torques may state any
#: (their columns may hold currents, see ``identify --drive-gains``).
CSV_UNITS = {
    "times": ("s", "sec", "second", "seconds"),
    "positions": ("rad", "m"),
    "velocities": ("rad/s", "m/s"),
    "accelerations": ("rad/s^2", "rad/s2", "rad/s\u00b2", "rad/s/s", "m/s^2", "m/s2",
                      "m/s\u00b2", "m/s/s"),
}


def _unit_checked(source: str, name: str, field: str, unit: str | None) -> None:
    """A column's stated unit must be what the package reads (SI, radians)."""
    if unit is None or field not in CSV_UNITS:
        return
    if unit.replace(" ", "").lower() not in CSV_UNITS[field]:
        si = CSV_UNITS[field][0]
        expected = si if field == "times" else (f"{si} ({si.replace('rad', 'm', 1)} on a "
                                                f"prismatic joint)")
        raise ValueError(f"{source}: column {name!r}: {field} in {unit!r}; expected "
                         f"{expected}: convert the column (degrees: x pi/180)")


def _delimiter(header: str) -> str:
    """The header's separator: the first of :data:`CSV_DELIMITERS` it holds (else ',')."""
    return next((d for d in CSV_DELIMITERS if d in header), ",")


def read_npz(path: Path, source: str) -> tuple[dict, dict]:
    if not zipfile.is_zipfile(path):
        raise ValueError(
            f"{source}: not an .npz archive (expected a zip of .npy arrays with keys "
            f"{', '.join(NPZ_KEYS)}; the file has no zip structure)"
        )
    fields: dict[str, Any] = {}
    try:
        with np.load(path, allow_pickle=False) as archive:
            present = set(archive.files)
            missing = [k for k in REQUIRED if k not in present]
            if missing:
                raise ValueError(
                    f"{source}: missing key(s) {', '.join(map(repr, missing))}; expected "
                    f"'times', 'positions', 'torques' (and optionally 'velocities', "
                    f"'accelerations'), got {sorted(present)}"
                )
            for key in NPZ_KEYS:
                if key not in present:
                    continue
                try:
                    value = archive[key]
                except ValueError as err:
                    if "allow_pickle" in str(err):
                        raise ValueError(
                            f"{source}: field {key!r}: holds Python objects (an object "
                            f"array needing pickle); refused, expected real numbers"
                        ) from err
                    raise ValueError(f"{source}: field {key!r}: unreadable ({err})") from err
                if not isinstance(value, np.ndarray):
                    raise ValueError(f"{source}: field {key!r}: not a .npy array")
                fields[key] = value
    except (zipfile.BadZipFile, OSError, EOFError, KeyError) as err:
        raise ValueError(f"{source}: corrupt .npz archive ({err})") from err
    return fields, {}


def read_csv(path: Path, source: str, n_joints: int | None) -> tuple[dict, dict]:
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise ValueError(f"{source}: not a UTF-8 text CSV file ({err})") from err
    lines = [(i + 1, line) for i, line in enumerate(text.splitlines()) if line.strip()]
    if not lines:
        raise ValueError(f"{source}: no header line (the file is blank)")
    header_no, header = lines[0]
    delimiter = _delimiter(header)
    names = [c.strip() for c in header.lstrip().removeprefix("#").split(delimiter)]
    rows = [(no, line) for no, line in lines[1:] if not line.lstrip().startswith("#")]
    columns: dict[str, dict[int, int]] = {k: {} for k in _CSV_ALIASES}
    time_col, ignored = None, []
    seen: dict[str, int] = {}
    for c, name in enumerate(names):
        stated = _UNIT.match(name)
        key = (stated.group(1) if stated else name).lower()
        unit = stated.group(2) if stated else None
        if key in seen:
            raise ValueError(
                f"{source}: column {name!r}: appears twice in the header (columns "
                f"{seen[key] + 1} and {c + 1})"
            )
        seen[key] = c
        match = _JOINT_COLUMN.match(key)
        if key in _CSV_TIME:
            if time_col is not None:
                raise ValueError(f"{source}: column {name!r}: a second time column "
                                 f"(already {names[time_col]!r})")
            _unit_checked(source, name, "times", unit)
            time_col = c
        elif match and match.group(1) in _CSV_FIELD:
            field = _CSV_FIELD[match.group(1)]
            _unit_checked(source, name, field, unit)
            j = int(match.group(2))
            if j in columns[field]:
                raise ValueError(f"{source}: column {name!r}: a second column for joint {j} "
                                 f"of {field!r}")
            columns[field][j] = c
        else:
            ignored.append(name)
    if time_col is None:
        raise ValueError(
            f"{source}: column 'time': missing; expected a header like "
            f"time,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun (separated by commas, semicolons "
            f"or tabs; units in brackets allowed: time [s]), got {len(names)} column(s) "
            f"{delimiter.join(names)!r}"
        )
    counts = {}
    for field, cols in columns.items():
        if not cols:
            continue
        prefix = CSV_PREFIXES[field]
        top = n_joints if n_joints is not None else max(cols)
        missing = [f"{prefix}{j}" for j in range(1, top + 1) if j not in cols]
        if missing:
            raise ValueError(
                f"{source}: field {field!r}: missing columns {', '.join(missing)} (expected "
                f"{prefix}1..{prefix}{top}, joints numbered from 1), got joint numbers "
                f"{sorted(cols)}"
            )
        counts[field] = len(cols)
    for field in ("positions", "torques"):
        if field not in counts:
            p = CSV_PREFIXES[field]
            raise ValueError(
                f"{source}: field {field!r}: missing columns {p}1..{p}n; header is "
                f"{','.join(names)}"
            )
    n = n_joints if n_joints is not None else counts["positions"]
    for field, count in counts.items():
        if count != n:
            p = CSV_PREFIXES[field]
            origin = f"n_joints={n_joints}" if n_joints is not None else "as 'positions'"
            raise ValueError(
                f"{source}: field {field!r}: expected {n} joints ({origin}), got {count} "
                f"columns {p}1..{p}{count}"
            )
    if not rows:
        raise ValueError(f"{source}: field 'times': expected at least 2 samples, got 0 "
                         f"(no data lines after the header)")
    cells = []
    for no, line in rows:
        parts = line.split(delimiter)
        if len(parts) != len(names):
            raise ValueError(
                f"{source}: line {no}: expected {len(names)} fields (as the header), got "
                f"{len(parts)} (ragged rows)"
            )
        if delimiter != ",":  # a decimal comma, where commas do not separate
            parts = [p.replace(",", ".") for p in parts]
        cells.append(parts)
    used = [time_col] + [columns[f][j] for f in counts for j in range(1, n + 1)]
    table = np.array(cells, dtype=object)[:, used]
    try:
        data = table.astype(float)
    except ValueError:
        for r, (no, _) in enumerate(rows):
            for k, c in enumerate(used):
                try:
                    float(table[r, k])
                except ValueError:
                    raise ValueError(
                        f"{source}: line {no}, column {names[c]!r}: expected a number, got "
                        f"{table[r, k].strip()!r}"
                    ) from None
        raise
    fields = {"times": data[:, 0]}
    for i, field in enumerate(counts):
        fields[field] = data[:, 1 + i * n: 1 + (i + 1) * n]
    return fields, ({"ignored_columns": ignored} if ignored else {})


def write(path: PathLike, arrays: dict[str, np.ndarray]) -> Path:
    """Write ``arrays`` (keys :data:`NPZ_KEYS`) to ``path`` atomically: ``.npz``, or
    ``.csv`` with a header ``time,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun`` and 17
    significant digits (what :func:`read_csv` reads back exactly)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        atomic_write(path, lambda f: np.savez(f, **arrays))  # type: ignore[arg-type]
    elif suffix == ".csv":
        n = arrays["positions"].shape[1]
        header = ["time"] + [f"{CSV_PREFIXES[k]}{j + 1}" for k in NPZ_KEYS[1:] for j in range(n)]
        data = np.column_stack([arrays[k] for k in NPZ_KEYS])

        def write_csv(f: BinaryIO) -> None:
            text = io.StringIO()
            np.savetxt(text, data, delimiter=",", header=",".join(header), comments="",
                       fmt="%.17g")
            f.write(text.getvalue().encode("utf-8"))

        atomic_write(path, write_csv)
    else:
        raise ValueError(f"{path}: unsupported file type {path.suffix!r}; use .npz or .csv")
    return path
