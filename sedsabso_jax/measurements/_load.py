"""Loading measurements from files: read, check, derive what is missing, filter, downsample."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from .._output import PathLike
from . import _formats as formats
from ._container import Measurements, check_fields, positive_int
from ._signal import (
    BUTTERWORTH_ORDER,
    DEFAULT_CUTOFF_HZ,
    differentiate,
    edge_seconds,
    lowpass,
    median_rate,
)


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
            file has them (see :func:`differentiate`); missing ones are always derived.
        resample_hz: interpolate every recorded signal linearly onto a uniform grid at
            this rate first (before any derivation or filtering): for logs whose time
            stamps are far from uniform.
        trim_edges: when anything was derived or filtered, drop the first and last
            :func:`edge_seconds` (``2 / cutoff_hz``) of the recording, where the
            zero-phase filter rings (spikes in the derived accelerations at the ends), so
            they never enter a fit.

    Positions are kept as recorded. ``info`` records, for velocities, accelerations and
    torques, ``"recorded"`` or how they were obtained, the cutoff used and the seconds
    trimmed at each end (``"trimmed_s"``).
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
    times = fields["times"]
    rate = median_rate(times)
    cutoff = DEFAULT_CUTOFF_HZ if cutoff_hz is None else cutoff_hz
    info.update({"format": suffix[1:], "rate_hz": rate, "cutoff_hz": None,
                 "resampled_hz": None if resample_hz is None else float(resample_hz),
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
    first, last = 0, len(times)
    info["trimmed_s"] = 0.0
    if trim_edges and info["cutoff_hz"] is not None:
        edge = edge_seconds(cutoff)
        first = int(np.searchsorted(times, times[0] + edge, side="left"))
        last = int(np.searchsorted(times, times[-1] - edge, side="right"))
        if last - first < 2:
            raise ValueError(
                f"{source}: the recording ({times[-1] - times[0]:.3g} s) is too short to drop "
                f"the filter's {edge:.3g} s edge transients at both ends; raise the cutoff "
                f"(now {float(cutoff):g} Hz) or keep the edges (trim_edges=False)")
        info["trimmed_s"] = edge
    index = slice(first, last, downsample)
    return Measurements(times[index], fields["positions"][index], fields["velocities"][index],
                        fields["accelerations"][index], fields["torques"][index],
                        source=source, info=info)


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
