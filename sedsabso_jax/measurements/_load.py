"""Loading measurements from files: read, check, derive what is missing, filter, downsample."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from jaxtyping import ArrayLike

from .._output import PathLike
from . import _formats as formats
from ._chain import Recorded, SignalChain
from ._container import Measurements, check_fields, positive_int
from ._signal import DEFAULT_CUTOFF_HZ


def load_measurements(path: PathLike, *, n_joints: int | None = None,
                      cutoff_hz: float | None = None, filter_torques: bool = False,
                      downsample: int = 1,
                      derive: bool = False, trim_edges: bool = True,
                      resample_hz: float | None = None) -> Measurements:
    """Read measurements from a ``.npz`` or ``.csv`` file (formats: :mod:`._formats`).

    Args:
        path: the file; its suffix (``.npz`` or ``.csv``, any case) picks the format.
        n_joints: if given, the file must have this many joints (e.g. ``robot.n_joints``).
        cutoff_hz: low-pass cutoff for what is filtered (default
            :data:`DEFAULT_CUTOFF_HZ`); must lie below half the median sample rate.
            Unused when nothing is derived or filtered.
        filter_torques: low-pass the torques too (same zero-phase filter).
        downsample: keep every ``downsample``-th sample, after derivation and filtering.
        derive: derive velocities and accelerations from the positions even where the
            file has them (see :func:`~._signal.differentiate`); missing ones are always derived.
        resample_hz: interpolate every recorded signal linearly onto a uniform grid at
            this rate first (before any derivation or filtering): for logs whose time
            stamps are far from uniform.
        trim_edges: when anything was derived or filtered, drop the first and last
            :func:`~._signal.edge_seconds` (``2 / cutoff_hz``) of the recording, where the
            zero-phase filter rings (spikes in the derived accelerations at the ends), so
            they never enter a fit.

    Positions are kept as recorded. ``info`` records, for velocities, accelerations and
    torques, ``"recorded"`` or how they were obtained, the cutoff used, the seconds
    trimmed at each end (``"trimmed_s"``) and the ``chain`` (``given``: whether
    ``cutoff_hz``, ``derive`` or ``filter_torques`` chose it; if not, the default may
    choose another, :func:`~sedsabso_jax.select_and_identify`). This is the
    :class:`~._chain.SignalChain` of those options applied to the file's
    :class:`~._chain.Recorded` signals, which the result keeps (``recorded``).
    """
    path = Path(path)
    source = str(path)
    if not path.is_file():
        raise FileNotFoundError(f"{source}: no such file")
    if n_joints is not None:
        n_joints = positive_int("n_joints", n_joints)
    downsample = positive_int("downsample", downsample)
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".csv"):
        raise ValueError(f"{source}: unsupported file type {path.suffix!r}; expected .npz "
                         f"or .csv")
    if path.stat().st_size == 0:
        raise ValueError(f"{source}: the file is empty (0 bytes); expected "
                         f"{'an .npz archive' if suffix == '.npz' else 'a CSV header and data'}")
    if suffix == ".npz":
        raw, info = formats.read_npz(path, source)
    else:
        raw, info = formats.read_csv(path, source, n_joints)
    fields = check_fields(source, raw, n_joints)
    if resample_hz is not None:
        fields = _resample(fields, resample_hz, source)
    info.update({"format": suffix[1:],
                 "resampled_hz": None if resample_hz is None else float(resample_hz)})
    recorded = Recorded(fields["times"], fields["positions"], fields["torques"],
                        fields["velocities"], fields["accelerations"], source, info,
                        downsample, bool(trim_edges))
    chain = SignalChain(DEFAULT_CUTOFF_HZ if cutoff_hz is None else cutoff_hz, derive,
                        filter_torques)
    return Measurements.made_by(chain, recorded,
                                given=cutoff_hz is not None or derive or filter_torques)


def recorded_signals(times: ArrayLike, q: ArrayLike, tau: ArrayLike,
                     qd: ArrayLike | None = None, qdd: ArrayLike | None = None, *,
                     chain: SignalChain | None = None, source: str = "arrays",
                     trim_edges: bool = True) -> Measurements:
    """Measurements from recorded arrays by ``chain`` (None: :class:`SignalChain`'s
    defaults, derive what is missing at 10 Hz, left to the default to choose), keeping
    the recording so that another chain can be applied
    (:meth:`~._container.Measurements.with_chain`) or chosen
    (:func:`~sedsabso_jax.select_and_identify`). ``qd``, ``qdd``: None where not
    recorded."""
    fields = check_fields(str(source), {"times": times, "positions": q, "velocities": qd,
                                        "accelerations": qdd, "torques": tau})
    recorded = Recorded(fields["times"], fields["positions"], fields["torques"],
                        fields["velocities"], fields["accelerations"], str(source),
                        trim_edges=trim_edges)
    return Measurements.made_by(chain or SignalChain(), recorded, given=chain is not None)


def _resample(fields: dict, rate_hz, source: str) -> dict:
    """Every recorded field linearly interpolated onto ``t0 + k / rate_hz``."""
    try:
        rate = float(rate_hz)
    except (TypeError, ValueError):
        rate = float("nan")
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"{source}: resample_hz must be a positive number, got {rate_hz!r}")
    times = fields["times"]
    grid = times[0] + np.arange(int(np.floor((times[-1] - times[0]) * rate)) + 1) / rate
    if grid.size < 2:
        raise ValueError(f"{source}: resample_hz={rate:g} leaves fewer than 2 samples")
    out = {"times": grid}
    for key, value in fields.items():
        if key != "times":
            out[key] = None if value is None else np.column_stack(
                [np.interp(grid, times, value[:, j]) for j in range(value.shape[1])])
    return out


def load_kuka_lwr4(run: int = 1, **kwargs: Any) -> Measurements:
    """FloBaRoID's real KUKA LWR4+ recording ``run`` (1 or 2), shipped with the package
    (``data/kuka_lwr4/measurements_<run>.npz``, LGPL-3.0; see its SOURCE.md). Keyword
    arguments go to :func:`load_measurements`."""
    if run not in (1, 2):
        raise ValueError(f"run must be 1 or 2 (measurements_1.npz, measurements_2.npz), "
                         f"got {run!r}")
    resource = resources.files("sedsabso_jax") / "data" / "kuka_lwr4" / f"measurements_{run}.npz"
    with resources.as_file(resource) as path:
        return load_measurements(path, **kwargs)
