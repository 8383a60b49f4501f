"""The measurements container: times, ``q, qd, qdd, tau`` along one trajectory, checked.

A :class:`Measurements` holds, on numpy arrays, ``times (T,)`` in seconds and ``q, qd,
qdd, tau (T, n)``: joint positions [rad or m], velocities, accelerations and torques
[N m or N], with the file it came from (``source``) and a record of what was derived or
filtered (``info``). It is immutable (read-only arrays); :meth:`Measurements.slice`,
:meth:`Measurements.downsample` return new ones.

Every problem with a file or an array (NaN/Inf, missing key or column, joint count,
ragged lengths, non-increasing times, empty file, not a data file) is a ValueError that
names the source and the field, with what was expected and what was found; a file that
does not exist is a FileNotFoundError.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import equinox as eqx
import numpy as np
from jaxtyping import ArrayLike

from .._output import PathLike
from . import _formats as formats
from ._chain import Recorded, SignalChain
from ._signal import median_rate

#: Field name (as in the files) -> attribute of :class:`Measurements`.
ATTRIBUTES = {"positions": "q", "velocities": "qd", "accelerations": "qdd", "torques": "tau"}


def as_float(source: str, field: str, value: ArrayLike, ndim: int) -> np.ndarray:
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
        at = f"sample {where[0] + 1} of {arr.shape[0]}" + (f", joint {where[1] + 1}"
                                                         if ndim == 2 else "")
        raise ValueError(
            f"{source}: field {field!r}: expected finite numbers, got {int(bad.sum())} "
            f"NaN/Inf value(s), the first at {at}"
        )
    return arr


def check_fields(source: str, fields: Mapping[str, Any], n_joints: int | None = None,
                  ) -> dict[str, np.ndarray]:
    """Check times/positions/torques (+ optional velocities/accelerations) belong together.

    Returns float64 copies. Missing optional fields are returned as None.
    """
    times = as_float(source, "times", fields["times"], 1)
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
    out: dict[str, np.ndarray | None] = {"times": times}
    q = as_float(source, "positions", fields["positions"], 2)
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
        arr = q if field == "positions" else as_float(source, field, value, 2)
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
    return out  # type: ignore[return-value]  # velocities, accelerations may be None


class Measurements(eqx.Module):
    """Joint measurements along one trajectory (numpy, float64, read-only).

    Attributes:
        times: ``(T,)`` strictly increasing time stamps [s].
        q, qd, qdd: ``(T, n)`` joint positions, velocities, accelerations.
        tau: ``(T, n)`` joint torques.
        source: the file read, ``"simulated"``, or ``"arrays"``.
        info: what was derived, filtered, sliced (JSON-friendly values).
        recorded: the signals as recorded, where a :class:`~._chain.SignalChain` made
            these (:func:`~sedsabso_jax.load_measurements`); None: given as they are.

    Construction checks shapes, finiteness and times (ValueError naming the field).
    """

    times: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    source: str = "arrays"
    info: dict = eqx.field(default_factory=dict)
    recorded: Recorded | None = None

    def __init__(self, times: ArrayLike, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike,
                 tau: ArrayLike, source: str = "arrays", info: dict | None = None,
                 recorded: Recorded | None = None):
        source = str(source)
        checked = check_fields(source, {"times": times, "positions": q, "velocities": qd,
                                        "accelerations": qdd, "torques": tau})
        arrays = {}
        for field, attr in (("times", "times"), *ATTRIBUTES.items()):
            arr = checked[field]
            if arr is None:
                raise ValueError(f"{source}: field {field!r}: missing ({attr}=None)")
            arr.flags.writeable = False
            arrays[attr] = arr
        self.times, self.q, self.qd = arrays["times"], arrays["q"], arrays["qd"]
        self.qdd, self.tau = arrays["qdd"], arrays["tau"]
        self.source, self.info = source, dict(info or {})
        if recorded is not None and not isinstance(recorded, Recorded):
            raise TypeError(f"{source}: recorded must be a Recorded or None, got "
                            f"{type(recorded).__name__}")
        self.recorded = recorded

    @property
    def n_joints(self) -> int:
        """Joints of the recording (columns of ``q``)."""
        return self.q.shape[1]

    @property
    def n_samples(self) -> int:
        """Samples of the recording (rows of ``q``)."""
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
                            self.tau[index], source=self.source, info=info,
                            recorded=self.recorded)

    def subset(self, mask: ArrayLike) -> Measurements:
        """The samples where ``mask`` (``(T,)`` booleans) is True; at least 2 must remain.
        Like :meth:`slice`, it keeps :attr:`recorded`: :meth:`with_chain` makes the same
        samples by another chain."""
        keep = np.asarray(mask)
        if keep.dtype != bool or keep.shape != self.times.shape:
            raise ValueError(f"{self.source}: mask must be {self.times.shape} booleans, got "
                             f"{keep.dtype} {keep.shape}")
        if keep.sum() < 2:
            raise ValueError(f"{self.source}: the mask keeps {int(keep.sum())} samples; at "
                             f"least 2 must remain")
        return self._with(keep, f"subset of {int(keep.sum())} samples")

    def slice(self, start: int | None = None, stop: int | None = None,
              step: int = 1) -> Measurements:
        """Samples ``start:stop:step`` (Python slice rules); at least 2 must remain."""
        step = positive_int("step", step)
        return self._with(slice(start, stop, step), f"slice {start}:{stop}:{step}")

    def downsample(self, k: int) -> Measurements:
        """Every ``k``-th sample, starting with the first. No anti-alias filter: load with
        a cutoff below the new Nyquist frequency first if the signals need one."""
        k = positive_int("downsample factor k", k)
        return self._with(slice(None, None, k), f"downsample {k}")

    def delayed(self, seconds: float) -> Measurements:
        """The torques taken ``seconds`` later than the motion they answer: ``tau'(t) =
        tau(t + seconds)`` (linear interpolation between samples), at the samples whose
        ``t + seconds`` lies within the recording (the others dropped). Positive: the
        torque signal lags the positions (a bus, a filter, a current loop on the torques);
        negative: the positions lag. ``info["delay_s"]`` adds it up
        (:func:`~sedsabso_jax.identification.estimate_delay` finds it)."""
        try:
            d = float(seconds)
        except (TypeError, ValueError):
            d = float("nan")
        if not np.isfinite(d):
            raise ValueError(f"{self.source}: the delay must be a finite number of seconds, "
                             f"got {seconds!r}")
        t = self.times
        keep = (t + d >= t[0]) & (t + d <= t[-1])
        if keep.sum() < 2:
            raise ValueError(f"{self.source}: a delay of {d:g} s leaves fewer than 2 samples "
                             f"of the {self.duration:g} s recording")
        tau = np.column_stack([np.interp(t[keep] + d, t, self.tau[:, j])
                               for j in range(self.n_joints)])
        info = dict(self.info, delay_s=float(self.info.get("delay_s", 0.0)) + d)
        return Measurements(t[keep], self.q[keep], self.qd[keep], self.qdd[keep], tau,
                            source=self.source, info=info)

    @property
    def chain(self) -> SignalChain | None:
        """The :class:`~._chain.SignalChain` that made these from :attr:`recorded` (None:
        given as they are)."""
        said = self.info.get("chain")
        return None if self.recorded is None or said is None else SignalChain(
            said["cutoff_hz"], said["derive"], said["filter_torques"], said.get("delay_s", 0.0))

    def with_chain(self, chain: SignalChain, *, trim_s: float | None = None,
                   given: bool = True) -> Measurements:
        """These measurements made again from :attr:`recorded` by ``chain``
        (:meth:`made_by`; ``trim_s``: the seconds dropped at each end, None: the filter's
        ringing); where these were sliced, downsampled or a subset, the same samples, of
        those the chain keeps. A ValueError where nothing was recorded (built from
        arrays, or delayed)."""
        if not isinstance(chain, SignalChain):
            raise TypeError(f"chain must be a SignalChain, got {type(chain).__name__}")
        if self.recorded is None:
            raise ValueError(f"{self.source}: these measurements keep no recorded signals "
                             f"(built from arrays, or delayed after loading): load them "
                             f"with load_measurements or recorded_signals to apply another "
                             f"signal chain")
        made = Measurements.made_by(chain, self.recorded, trim_s=trim_s, given=given)
        if "operations" not in self.info:
            return made
        # sliced, downsampled or a subset: the same samples (those the chain keeps)
        keep = np.isin(made.times, self.times)
        return Measurements(made.times[keep], made.q[keep], made.qd[keep], made.qdd[keep],
                            made.tau[keep], source=made.source,
                            info=dict(made.info, operations=self.info["operations"]),
                            recorded=self.recorded)

    @classmethod
    def made_by(cls, chain: SignalChain, recorded: Recorded, *, trim_s: float | None = None,
                given: bool = True) -> Measurements:
        """The measurements ``chain`` makes of ``recorded``
        (:meth:`~._chain.SignalChain.made`), keeping ``recorded``."""
        (times, q, qd, qdd, tau), info = chain.made(recorded, trim_s=trim_s, given=given)
        return cls(times, q, qd, qdd, tau, source=recorded.source, info=info,
                   recorded=recorded)

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays under the ``.npz`` key names (:data:`._formats.NPZ_KEYS`)."""
        return {"times": self.times, "positions": self.q, "velocities": self.qd,
                "accelerations": self.qdd, "torques": self.tau}

    def save(self, path: PathLike) -> Path:
        """Write to ``path``: ``.npz`` (keys :data:`._formats.NPZ_KEYS`) or ``.csv``
        (header ``time,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun``, 17 significant digits).

        Atomic: written to a temporary file in the same directory, flushed, then moved
        over ``path`` with ``os.replace``; on any failure the temporary file is removed
        and an existing ``path`` is left as it was. ``source`` and ``info`` are not saved.
        """
        return formats.write(path, self.arrays())


def positive_int(label: str, value: object) -> int:
    """``value`` as an int, or a ValueError naming ``label`` unless it is an integer >= 1."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ValueError(f"{label} must be an integer >= 1, got {value!r}")
    return int(value)
