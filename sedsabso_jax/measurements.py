"""Joint measurements: load recorded data, simulate it, derive velocities and accelerations.

A :class:`Measurements` holds, on numpy arrays, ``times (T,)`` in seconds and ``q, qd,
qdd, tau (T, n)``: joint positions [rad or m], velocities, accelerations and torques
[N m or N], with the file it came from (``source``) and a record of what was derived or
filtered (``info``). It is immutable (read-only arrays); :meth:`Measurements.slice`,
:meth:`Measurements.downsample` return new ones.

Files (:func:`load_measurements`, :meth:`Measurements.save`):

- ``.npz`` (the format of FloBaRoID's KUKA files, ``data/kuka_lwr4/``): float arrays
  ``times (T,)``, ``positions, torques (T, n)``, optional ``velocities, accelerations
  (T, n)``. Other keys (FloBaRoID's ``target_positions`` ...) are ignored. Read with
  ``allow_pickle=False``: an archive holding Python objects is refused, never unpickled.
- ``.csv``: one header line, then one line per sample, comma separated. Columns
  ``time, q1..qn, qd1..qdn, qdd1..qddn, tau1..taun`` (1-based joint numbers; ``qd`` and
  ``qdd`` optional, column order free). Also accepted, case-insensitive, with or without
  ``_`` before the number: ``times``/``t``; ``pos``/``position``/``positions``;
  ``dq``/``qdot``/``vel``/``velocity``/``velocities``; ``ddq``/``qddot``/``acc``/
  ``acceleration``/``accelerations``; ``torque``/``torques``/``effort``. Other columns
  are ignored (listed in ``info["ignored_columns"]``). A ``#`` before the header is
  allowed; later lines starting with ``#`` are comments.

Missing velocities or accelerations (or ``derive=True``) are derived from the positions:
a zero-phase low-pass (Butterworth of order :data:`BUTTERWORTH_ORDER` = 4, run forwards
and backwards with ``scipy.signal.sosfiltfilt``, so no lag and an overall gain of
1/2 (-6 dB) at the cutoff), then central differences on the actual time stamps,
themselves passed through the same filter so that uneven samples stay paired with their
times (``np.gradient(x, t_f)``, second order in the interior), twice. The filter is designed
for the median sample rate. Default cutoff :data:`DEFAULT_CUTOFF_HZ` = 10 Hz: excitation
trajectories of industrial and collaborative arms live below a few Hz (99.9 % of the
position signal power of FloBaRoID's KUKA runs lies below 2 Hz) while sensor noise is
broadband, and 10 Hz stays well below the Nyquist frequency of the usual 100 Hz to 1 kHz
recordings. The cutoff must lie below the Nyquist frequency (half the median rate),
otherwise a ValueError says so. Like any filter, it is less exact near the two ends: the
derived accelerations ring for about ``2 / cutoff_hz`` seconds there (0.2 s at 10 Hz).

Every problem with a file or an array (NaN/Inf, missing key or column, joint count,
ragged lengths, non-increasing times, empty file, not a data file) is a ValueError that
names the source and the field, with what was expected and what was found; a file that
does not exist is a FileNotFoundError.
"""

from __future__ import annotations

import dataclasses
import io
import re
import zipfile
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from ._io import atomic_write

#: Default low-pass cutoff [Hz] for deriving velocities/accelerations and filtering torques.
DEFAULT_CUTOFF_HZ = 10.0
#: Order of the Butterworth low-pass (applied forwards and backwards: zero phase).
BUTTERWORTH_ORDER = 4
#: Default size of a simulated outlier, in multiples of the joint's RMS torque.
DEFAULT_OUTLIER_SCALE = 10.0
#: Torque (effort) limits of the KUKA LWR4+ in its URDF [N m], joint 1 to 7.
KUKA_LWR4_TORQUE_LIMITS = (176.0, 176.0, 100.0, 100.0, 100.0, 38.0, 38.0)

#: .npz keys, in the order written; times, positions and torques are required to read.
NPZ_KEYS = ("times", "positions", "velocities", "accelerations", "torques")
_REQUIRED = ("times", "positions", "torques")
_ATTRIBUTE = {"positions": "q", "velocities": "qd", "accelerations": "qdd", "torques": "tau"}
#: CSV column prefixes written by :meth:`Measurements.save` (joint number appended, from 1).
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


# --------------------------------------------------------------------------------------
# validation


def _as_float(source: str, field: str, value, ndim: int) -> np.ndarray:
    """``value`` as a float64 array of ``ndim`` dimensions, or a ValueError naming it."""
    try:
        arr = np.asarray(value)
    except Exception as err:  # any conversion failure is bad input
        raise ValueError(f"{source}: field {field!r}: not an array ({err})") from err
    if arr.dtype.kind not in "biuf":
        raise ValueError(
            f"{source}: field {field!r}: expected real numbers, got dtype {arr.dtype}"
        )
    if arr.ndim != ndim:
        want = "(T,)" if ndim == 1 else "(T, n_joints)"
        raise ValueError(
            f"{source}: field {field!r}: expected a {ndim}-D array {want}, got shape {arr.shape}"
        )
    arr = np.array(arr, dtype=np.float64)  # a copy: the caller's array stays its own
    bad = ~np.isfinite(arr)
    if bad.any():
        where = np.argwhere(bad)[0]
        at = f"sample {where[0]}" + (f", joint {where[1] + 1}" if ndim == 2 else "")
        raise ValueError(
            f"{source}: field {field!r}: expected finite numbers, got {int(bad.sum())} "
            f"NaN/Inf value(s), the first at {at}"
        )
    return arr


def _check_fields(source: str, fields: Mapping[str, Any], n_joints: int | None = None,
                  ) -> dict[str, np.ndarray]:
    """Check times/positions/torques (+ optional velocities/accelerations) belong together.

    Returns float64 copies. Missing optional fields are returned as None.
    """
    times = _as_float(source, "times", fields["times"], 1)
    T = times.shape[0]
    if T < 2:
        raise ValueError(f"{source}: field 'times': expected at least 2 samples, got {T}")
    steps = np.diff(times)
    bad = np.flatnonzero(steps <= 0.0)
    if bad.size:
        k = int(bad[0])
        raise ValueError(
            f"{source}: field 'times': expected strictly increasing time stamps, got "
            f"times[{k + 1}] = {float(times[k + 1])!r} after times[{k}] = {float(times[k])!r} "
            f"({bad.size} non-increasing step(s))"
        )
    out = {"times": times}
    q = _as_float(source, "positions", fields["positions"], 2)
    n = q.shape[1]
    if n_joints is not None and n != n_joints:
        raise ValueError(
            f"{source}: field 'positions': expected {n_joints} joints (n_joints={n_joints}), "
            f"got {n} columns, shape {q.shape}"
        )
    if n < 1:
        raise ValueError(f"{source}: field 'positions': expected at least 1 joint, got 0")
    for field in ("positions", "velocities", "accelerations", "torques"):
        value = fields.get(field)
        if value is None:
            out[field] = None
            continue
        arr = q if field == "positions" else _as_float(source, field, value, 2)
        if arr.shape[0] != T:
            raise ValueError(
                f"{source}: field {field!r}: expected {T} samples (as 'times'), got "
                f"{arr.shape[0]} (ragged lengths)"
            )
        if arr.shape[1] != n:
            raise ValueError(
                f"{source}: field {field!r}: expected {n} joints (as 'positions'), got "
                f"{arr.shape[1]} columns, shape {arr.shape}"
            )
        out[field] = arr
    if out["torques"] is None:
        raise ValueError(f"{source}: field 'torques': missing")
    return out


# --------------------------------------------------------------------------------------
# filtering and differentiation


def median_rate(times) -> float:
    """Median sample rate [Hz] of strictly increasing time stamps ``(T,)``."""
    times = np.asarray(times, dtype=float)
    return float(1.0 / np.median(np.diff(times)))


def _check_cutoff(cutoff_hz: float, rate: float, source: str) -> float:
    try:
        cutoff = float(cutoff_hz)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{source}: cutoff_hz must be a number, got {cutoff_hz!r}") from err
    nyquist = rate / 2.0
    if not (np.isfinite(cutoff) and 0.0 < cutoff < nyquist):
        raise ValueError(
            f"{source}: cutoff_hz must lie in (0, {nyquist:g}) Hz, below the Nyquist "
            f"frequency of the median sample rate {rate:g} Hz; got {cutoff_hz!r}"
        )
    return cutoff


def lowpass(x, rate: float, cutoff_hz: float = DEFAULT_CUTOFF_HZ, *,
            order: int = BUTTERWORTH_ORDER, source: str = "lowpass") -> np.ndarray:
    """Zero-phase Butterworth low-pass of ``x`` along axis 0 (``scipy.signal.sosfiltfilt``).

    ``rate`` is the sample rate [Hz] the filter is designed for; ``cutoff_hz`` must lie
    below ``rate / 2``. The forward-backward pass has no phase lag and squares the
    magnitude response (gain 1/2 at the cutoff). The ends are padded by odd reflection over
    ``5 rate / cutoff_hz`` samples (fewer if the signal is shorter), so straight lines pass
    unchanged. Needs more than ``3 (2 ceil(order/2) + 1)`` samples (15 for order 4).
    """
    x = np.asarray(x, dtype=float)
    cutoff = _check_cutoff(cutoff_hz, float(rate), source)
    import scipy.signal  # here: importing it costs ~1 s, and most runs never filter

    sos = scipy.signal.butter(int(order), cutoff, btype="low", output="sos", fs=float(rate))
    minimum = 3 * (2 * len(sos) + 1)  # scipy's default pad length
    if x.shape[0] <= minimum:
        raise ValueError(
            f"{source}: the order-{order} low-pass needs more than {minimum} samples, "
            f"got {x.shape[0]}"
        )
    # Odd extension over 5 cutoff periods lets the start-up transient die out in the pad:
    # a straight line comes out unchanged up to the ends (scipy's 15 samples bend it).
    padlen = min(x.shape[0] - 1, max(minimum, int(np.ceil(5.0 * rate / cutoff))))
    return scipy.signal.sosfiltfilt(sos, x, axis=0, padtype="odd", padlen=padlen)


def differentiate(times, q, cutoff_hz: float | None = DEFAULT_CUTOFF_HZ, *,
                  source: str = "differentiate") -> tuple[np.ndarray, np.ndarray]:
    """Velocities and accelerations ``(qd, qdd)`` from positions ``q (T, n)``.

    ``q`` is low-passed with :func:`lowpass` at ``cutoff_hz`` (``None``: not filtered),
    for the median rate of ``times``; then ``qd = np.gradient(q_f, t_f)`` and
    ``qdd = np.gradient(qd, t_f)`` (central differences on the actual time stamps,
    second order inside, first order at the two ends). ``t_f`` are the time stamps passed
    through the same low-pass: a linear filter keeps a straight line ``q = a + b t`` on
    it, so unevenly spaced samples stay paired with their times (with the raw stamps a
    +-0.5 ms jitter at 200 Hz puts 12 % errors on the velocity of a 0.5 Hz sine, with the
    filtered ones 0.3 %). Only the stamps' deviation from their least-squares straight line
    is filtered, so evenly spaced stamps are kept exactly.
    """
    times = np.asarray(times, dtype=float)
    q = np.asarray(q, dtype=float)
    if cutoff_hz is not None:
        rate = median_rate(times)
        q = lowpass(q, rate, cutoff_hz, source=source)
        # The filter sees samples, not times: with uneven sampling it smooths q(t_k) into
        # q at smoothed times. Filtering the time stamps alike keeps (t, q) paired.
        # Only the deviation from the straight line through the stamps is filtered, so
        # evenly spaced stamps come out exactly as they went in (filtfilt's edge
        # transients would bend even a straight line at the two ends).
        k = np.arange(times.size, dtype=float)
        line = np.polyval(np.polyfit(k, times - times[0], 1), k) + times[0]
        times = line + lowpass(times - line, rate, cutoff_hz, source=source)
        if np.any(np.diff(times) <= 0.0):
            raise ValueError(f"{source}: field 'times': too irregular to differentiate "
                             f"(the low-passed time stamps are not increasing)")
    qd = np.gradient(q, times, axis=0)
    return qd, np.gradient(qd, times, axis=0)


# --------------------------------------------------------------------------------------
# the container


@dataclasses.dataclass(frozen=True, eq=False)
class Measurements:
    """Joint measurements along one trajectory (numpy, float64, read-only).

    Attributes:
        times: ``(T,)`` strictly increasing time stamps [s].
        q, qd, qdd: ``(T, n)`` joint positions, velocities, accelerations.
        tau: ``(T, n)`` joint torques.
        source: the file read, ``"simulated"``, or ``"arrays"``.
        info: what was derived, filtered, sliced (JSON-friendly values).

    Construction checks shapes, finiteness and times (ValueError naming the field).
    """

    times: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    source: str = "arrays"
    info: dict = dataclasses.field(default_factory=dict)

    def __post_init__(self):
        source = str(self.source)
        checked = _check_fields(source, {
            "times": self.times, "positions": self.q, "velocities": self.qd,
            "accelerations": self.qdd, "torques": self.tau,
        })
        for field, attr in (("times", "times"), *_ATTRIBUTE.items()):
            arr = checked[field]
            if arr is None:
                raise ValueError(f"{source}: field {field!r}: missing ({attr}=None)")
            arr.flags.writeable = False
            object.__setattr__(self, attr, arr)
        object.__setattr__(self, "source", source)
        object.__setattr__(self, "info", dict(self.info))

    @property
    def n_joints(self) -> int:
        return self.q.shape[1]

    @property
    def n_samples(self) -> int:
        return self.times.shape[0]

    @property
    def rate(self) -> float:
        """Median sample rate [Hz]."""
        return median_rate(self.times)

    @property
    def duration(self) -> float:
        """``times[-1] - times[0]`` [s]."""
        return float(self.times[-1] - self.times[0])

    def __repr__(self) -> str:
        return (f"Measurements({self.source!r}, {self.n_samples} samples x {self.n_joints} "
                f"joints, {self.rate:.4g} Hz)")

    def _with(self, index, note: str) -> Measurements:
        info = dict(self.info)
        info["operations"] = [*info.get("operations", []), note]
        return Measurements(self.times[index], self.q[index], self.qd[index], self.qdd[index],
                            self.tau[index], source=self.source, info=info)

    def slice(self, start: int | None = None, stop: int | None = None,
              step: int = 1) -> Measurements:
        """Samples ``start:stop:step`` (Python slice rules); at least 2 must remain."""
        step = _positive_int("step", step)
        return self._with(slice(start, stop, step), f"slice {start}:{stop}:{step}")

    def downsample(self, k: int) -> Measurements:
        """Every ``k``-th sample, starting with the first. No anti-alias filter: load with
        a cutoff below the new Nyquist frequency first if the signals need one."""
        k = _positive_int("downsample factor k", k)
        return self._with(slice(None, None, k), f"downsample {k}")

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays under the ``.npz`` key names (:data:`NPZ_KEYS`)."""
        return {"times": self.times, "positions": self.q, "velocities": self.qd,
                "accelerations": self.qdd, "torques": self.tau}

    def save(self, path) -> Path:
        """Write to ``path``: ``.npz`` (keys :data:`NPZ_KEYS`) or ``.csv`` (header
        ``time,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun``, 17 significant digits).

        Atomic: written to a temporary file in the same directory, flushed, then moved
        over ``path`` with ``os.replace``; on any failure the temporary file is removed
        and an existing ``path`` is left as it was. ``source`` and ``info`` are not saved.
        """
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix == ".npz":
            arrays = self.arrays()
            atomic_write(path, lambda f: np.savez(f, **arrays))
        elif suffix == ".csv":
            atomic_write(path, self._write_csv)
        else:
            raise ValueError(f"{path}: unsupported file type {path.suffix!r}; use .npz or .csv")
        return path

    def _write_csv(self, f) -> None:
        n = self.n_joints
        header = ["time"] + [f"{CSV_PREFIXES[k]}{j + 1}" for k in _ATTRIBUTE for j in range(n)]
        data = np.column_stack([self.times, self.q, self.qd, self.qdd, self.tau])
        text = io.StringIO()
        np.savetxt(text, data, delimiter=",", header=",".join(header), comments="",
                   fmt="%.17g")
        f.write(text.getvalue().encode("utf-8"))


def _positive_int(label: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ValueError(f"{label} must be an integer >= 1, got {value!r}")
    return int(value)


# --------------------------------------------------------------------------------------
# reading


def _read_npz(path: Path, source: str) -> tuple[dict, dict]:
    if not zipfile.is_zipfile(path):
        raise ValueError(
            f"{source}: not an .npz archive (expected a zip of .npy arrays with keys "
            f"{', '.join(NPZ_KEYS)}; the file has no zip structure)"
        )
    fields: dict[str, Any] = {}
    try:
        with np.load(path, allow_pickle=False) as archive:
            present = set(archive.files)
            missing = [k for k in _REQUIRED if k not in present]
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


def _read_csv(path: Path, source: str, n_joints: int | None) -> tuple[dict, dict]:
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise ValueError(f"{source}: not a UTF-8 text CSV file ({err})") from err
    lines = [(i + 1, line) for i, line in enumerate(text.splitlines()) if line.strip()]
    if not lines:
        raise ValueError(f"{source}: no header line (the file is blank)")
    header_no, header = lines[0]
    names = [c.strip() for c in header.lstrip().removeprefix("#").split(",")]
    rows = [(no, line) for no, line in lines[1:] if not line.lstrip().startswith("#")]
    columns: dict[str, dict[int, int]] = {k: {} for k in _CSV_ALIASES}
    time_col, ignored, seen = None, [], {}
    for c, name in enumerate(names):
        key = name.lower()
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
            time_col = c
        elif match and match.group(1) in _CSV_FIELD:
            field = _CSV_FIELD[match.group(1)]
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
            f"time,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun, got {','.join(names)}"
        )
    counts = {}
    for field, cols in columns.items():
        if not cols:
            continue
        n = len(cols)
        prefix = CSV_PREFIXES[field]
        if sorted(cols) != list(range(1, n + 1)):
            raise ValueError(
                f"{source}: field {field!r}: expected columns {prefix}1..{prefix}{n} "
                f"(joints numbered from 1, no gaps), got joint numbers {sorted(cols)}"
            )
        counts[field] = n
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
        parts = line.split(",")
        if len(parts) != len(names):
            raise ValueError(
                f"{source}: line {no}: expected {len(names)} fields (as the header), got "
                f"{len(parts)} (ragged rows)"
            )
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


def load_measurements(path, *, n_joints: int | None = None, cutoff_hz: float | None = None,
                      filter_torques: bool = False, downsample: int = 1,
                      derive: bool = False) -> Measurements:
    """Read measurements from a ``.npz`` or ``.csv`` file (formats: module docstring).

    Args:
        path: the file; its suffix (``.npz`` or ``.csv``, any case) picks the format.
        n_joints: if given, the file must have this many joints (e.g. ``robot.n_joints``).
        cutoff_hz: low-pass cutoff for what is filtered (default
            :data:`DEFAULT_CUTOFF_HZ`); must lie below half the median sample rate.
            Unused when nothing is derived or filtered.
        filter_torques: low-pass the torques too (same zero-phase filter).
        downsample: keep every ``downsample``-th sample, after derivation and filtering.
        derive: derive velocities and accelerations from the positions even where the
            file has them (see :func:`differentiate`); missing ones are always derived.

    Positions are kept as recorded. ``info`` records, for velocities, accelerations and
    torques, ``"recorded"`` or how they were obtained, and the cutoff used.
    """
    path = Path(path)
    source = str(path)
    if not path.is_file():
        raise FileNotFoundError(f"{source}: no such file")
    if n_joints is not None:
        n_joints = _positive_int("n_joints", n_joints)
    downsample = _positive_int("downsample", downsample)
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".csv"):
        raise ValueError(f"{source}: unsupported file type {path.suffix!r}; expected .npz "
                         f"or .csv")
    if path.stat().st_size == 0:
        raise ValueError(f"{source}: the file is empty (0 bytes); expected "
                         f"{'an .npz archive' if suffix == '.npz' else 'a CSV header and data'}")
    if suffix == ".npz":
        raw, info = _read_npz(path, source)
    else:
        raw, info = _read_csv(path, source, n_joints)
    fields = _check_fields(source, raw, n_joints)
    times = fields["times"]
    rate = median_rate(times)
    cutoff = DEFAULT_CUTOFF_HZ if cutoff_hz is None else cutoff_hz
    info.update({"format": suffix[1:], "rate_hz": rate, "cutoff_hz": None,
                 "filter": None, "velocities": "recorded", "accelerations": "recorded",
                 "torques": "recorded", "downsample": downsample})
    filt = (f"Butterworth low-pass, order {BUTTERWORTH_ORDER}, zero phase (sosfiltfilt), "
            f"{float(cutoff):g} Hz at the median rate {rate:.6g} Hz")
    need = [k for k in ("velocities", "accelerations") if derive or fields[k] is None]
    if need:
        qd, qdd = differentiate(times, fields["positions"], cutoff, source=source)
        for key, value in (("velocities", qd), ("accelerations", qdd)):
            if key in need:
                fields[key] = value
                info[key] = "derived from positions: low-pass, then np.gradient on times"
        info["cutoff_hz"], info["filter"] = float(cutoff), filt
    if filter_torques:
        fields["torques"] = lowpass(fields["torques"], rate, cutoff, source=source)
        info["torques"] = "recorded, low-passed"
        info["cutoff_hz"], info["filter"] = float(cutoff), filt
    index = slice(None, None, downsample)
    return Measurements(times[index], fields["positions"][index], fields["velocities"][index],
                        fields["accelerations"][index], fields["torques"][index],
                        source=source, info=info)


def load_kuka_lwr4(run: int = 1, **kwargs) -> Measurements:
    """FloBaRoID's real KUKA LWR4+ recording ``run`` (1 or 2), shipped with the package
    (``data/kuka_lwr4/measurements_<run>.npz``, LGPL-3.0; see its SOURCE.md). Keyword
    arguments go to :func:`load_measurements`."""
    if run not in (1, 2):
        raise ValueError(f"run must be 1 or 2 (measurements_1.npz, measurements_2.npz), "
                         f"got {run!r}")
    resource = resources.files("sedsabso_jax") / "data" / "kuka_lwr4" / f"measurements_{run}.npz"
    with resources.as_file(resource) as path:
        return load_measurements(path, **kwargs)


# --------------------------------------------------------------------------------------
# simulation


def _nonnegative(label: str, value, upper: float | None = None) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{label} must be a number, got {value!r}") from err
    if not np.isfinite(value) or value < 0.0 or (upper is not None and value > upper):
        span = f"[0, {upper:g}]" if upper is not None else ">= 0"
        raise ValueError(f"{label} must be finite and in {span}, got {value!r}")
    return value


def simulate_measurements(robot, q, qd, qdd, times, *, params=None, torque_noise: float = 0.0,
                          position_noise: float = 0.0, outlier_fraction: float = 0.0,
                          outlier_scale: float = DEFAULT_OUTLIER_SCALE,
                          seed: int | None = 0) -> Measurements:
    """Measurements of ``robot`` moving along ``q, qd, qdd (T, n)`` at ``times (T,)``.

    Torques ``inverse_dynamics(robot, params, q, qd, qdd)`` (``params`` default
    ``robot.params``), then, with ``numpy.random.default_rng`` streams spawned from
    ``seed`` (one each, so turning one kind of noise on does not change the others):

    - ``torque_noise``: Gaussian, standard deviation ``torque_noise`` times each joint's
      RMS noise-free torque (0.02 = 2 %);
    - ``position_noise``: Gaussian, standard deviation in rad (m for prismatic joints),
      added to the recorded ``q`` only; torques, ``qd`` and ``qdd`` stay those of the
      true motion;
    - ``outlier_fraction``: that fraction of the ``T n`` torque samples (rounded) get
      ``+-outlier_scale`` times the joint's RMS torque added, sign at random, on top of
      the Gaussian noise.

    The same seed gives identical data; ``seed=None`` draws fresh entropy.
    """
    from .regressor import inverse_dynamics

    torque_noise = _nonnegative("torque_noise", torque_noise)
    position_noise = _nonnegative("position_noise", position_noise)
    outlier_fraction = _nonnegative("outlier_fraction", outlier_fraction, 1.0)
    outlier_scale = _nonnegative("outlier_scale", outlier_scale)
    n = robot.n_joints
    source = "simulated"
    # torques are computed below; the positions stand in for them in the shape check
    fields = _check_fields(source, {"times": times, "positions": q, "velocities": qd,
                                    "accelerations": qdd, "torques": q}, n)
    for key in ("velocities", "accelerations"):
        if fields[key] is None:
            raise ValueError(f"{source}: field {key!r}: missing")
    q, qd, qdd = fields["positions"], fields["velocities"], fields["accelerations"]
    params = robot.params if params is None else params
    tau = np.array(inverse_dynamics(robot, params, q, qd, qdd), dtype=np.float64)
    rms = np.sqrt(np.mean(tau**2, axis=0))
    T = tau.shape[0]
    rng_tau, rng_q, rng_out = (np.random.default_rng(s)
                               for s in np.random.SeedSequence(seed).spawn(3))
    if torque_noise > 0.0:
        tau = tau + rng_tau.standard_normal(tau.shape) * (torque_noise * rms)
    q_recorded = q + rng_q.standard_normal(q.shape) * position_noise if position_noise else q
    n_outliers = int(round(outlier_fraction * T * n))
    if n_outliers:
        flat = rng_out.choice(T * n, size=n_outliers, replace=False)
        sign = rng_out.choice(np.array([-1.0, 1.0]), size=n_outliers)
        rows, cols = np.unravel_index(flat, (T, n))
        tau[rows, cols] += sign * outlier_scale * rms[cols]
    info = {"params": "robot.params" if params is robot.params else "given",
            "torque_noise": torque_noise, "position_noise": position_noise,
            "outlier_fraction": outlier_fraction, "outlier_scale": outlier_scale,
            "n_outliers": n_outliers, "seed": seed,
            "torque_rms": [float(r) for r in rms]}
    return Measurements(fields["times"], q_recorded, qd, qdd, tau, source=source, info=info)


def simulate_measurements_along(robot, trajectory, times, **kwargs) -> Measurements:
    """:func:`simulate_measurements` along ``trajectory``, a callable called once with the
    whole ``times`` array and returning ``(q, qd, qdd)``, each ``(T, n)``."""
    times = np.asarray(times, dtype=float)
    try:
        q, qd, qdd = trajectory(times)
    except (TypeError, ValueError) as err:
        raise ValueError(
            f"trajectory {trajectory!r}: calling it with times of shape {times.shape} must "
            f"return (q, qd, qdd), each (T, n); got the error {err}"
        ) from err
    return simulate_measurements(robot, np.asarray(q), np.asarray(qd), np.asarray(qdd), times,
                                 **kwargs)
