"""The signal chain: how the signals a fit uses are obtained from the recorded ones.

A :class:`Recorded` holds the signals as recorded (after any resampling): times,
positions and torques, and the velocities and accelerations where the file has them. A
:class:`SignalChain` turns it into :class:`~._container.Measurements`: velocities and
accelerations derived from the positions (zero-phase low-pass at ``cutoff_hz``, then
central differences, :func:`~._signal.differentiate`) where missing or where ``derive``
asks, torques low-passed alike if ``filter_torques``, the motion taken ``delay_s``
earlier than the torques (cubic interpolation; the torques stay as recorded), the
filter's ringing and the delay trimmed at the ends, every ``downsample``-th sample
kept. :func:`~._load.load_measurements` is a chain applied to a file; Measurements a
chain makes keep their :class:`Recorded`, so that
:meth:`~._container.Measurements.with_chain` can derive them again by another chain (the
default's choice of the chain by validation, :mod:`sedsabso_jax.identification`).
"""

from __future__ import annotations

import equinox as eqx
import numpy as np
import scipy.interpolate

from ._signal import (
    BUTTERWORTH_ORDER,
    DEFAULT_CUTOFF_HZ,
    check_cutoff,
    differentiate,
    edge_seconds,
    lowpass,
    median_rate,
)


class Recorded(eqx.Module):
    """Signals as recorded: ``times (T,)``, ``q, tau (T, n)``, ``qd, qdd (T, n)`` or None
    where not recorded; ``info`` the loader's record of the file (format, rate,
    resampling); ``downsample`` and ``trim_edges`` how every chain applied to it keeps
    samples (:meth:`SignalChain.made`). Arrays are checked by the
    :class:`~._container.Measurements` a chain makes of them."""

    times: np.ndarray
    q: np.ndarray
    tau: np.ndarray
    qd: np.ndarray | None = None
    qdd: np.ndarray | None = None
    source: str = "arrays"
    info: dict = eqx.field(default_factory=dict)
    downsample: int = 1
    trim_edges: bool = True

    @property
    def complete(self) -> bool:
        """Whether velocities and accelerations are both recorded."""
        return self.qd is not None and self.qdd is not None

    def linear(self, motion: np.ndarray, offset: np.ndarray, torque: np.ndarray,
               info: dict) -> Recorded:
        """The signals through constant matrices: ``q @ motion - offset``, ``qd @
        motion``, ``qdd @ motion``, ``tau @ torque`` (a transmission to the joint side, or
        gains on currents); ``info`` the new record. Filters and differences are linear
        and act per column, so a chain commutes with this."""
        def m(x):
            return None if x is None else x @ motion
        return Recorded(self.times, self.q @ motion - offset, self.tau @ torque, m(self.qd),
                        m(self.qdd), self.source, info, self.downsample, self.trim_edges)


def _cutoff(value: object) -> float:
    try:
        cutoff = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        cutoff = float("nan")
    if not (np.isfinite(cutoff) and cutoff > 0.0):
        raise ValueError(f"cutoff_hz must be a positive number of Hz, got {value!r}")
    return cutoff


def _delay(value: object) -> float:
    try:
        delay = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        delay = float("nan")
    if not np.isfinite(delay):
        raise ValueError(f"delay_s must be a finite number of seconds, got {value!r}")
    return delay


class SignalChain(eqx.Module):
    """How velocities, accelerations and torques are obtained from a :class:`Recorded`
    (module docstring): ``cutoff_hz`` the zero-phase low-pass's cutoff [Hz] (below half
    the rate), ``derive`` velocities and accelerations from the positions even where
    recorded, ``filter_torques`` low-pass the torques too, ``delay_s`` the torques'
    delay behind the motion [s]: the torque recorded at ``t`` paired with the motion at
    ``t - delay_s`` (``q, qd, qdd`` by a cubic spline through their samples; the torques
    untouched, so chains with different delays are scored against the same
    measurements). Positive: the torque signal lags (a bus, a filter, a current loop);
    :func:`~sedsabso_jax.identification.estimate_delay` finds it. ``SignalChain()`` is
    what :func:`~._load.load_measurements` does unless told: recorded signals where there
    are, derived at 10 Hz where not, torques as recorded, no delay."""

    cutoff_hz: float = eqx.field(default=DEFAULT_CUTOFF_HZ, converter=_cutoff)
    derive: bool = eqx.field(default=False, converter=bool)
    filter_torques: bool = eqx.field(default=False, converter=bool)
    delay_s: float = eqx.field(default=0.0, converter=_delay)

    def filters(self, recorded: Recorded) -> bool:
        """Whether anything of ``recorded`` is low-passed (the cutoff matters)."""
        return self.derive or self.filter_torques or not recorded.complete

    def label(self, recorded: Recorded | None = None) -> str:
        """A short name: which velocities and accelerations, the cutoff where it matters
        (for ``recorded``; None: always), the torques' filter and delay."""
        delay = f", torques {1e3 * self.delay_s:+.3g} ms" if self.delay_s else ""
        if recorded is not None and not self.filters(recorded):
            return "recorded" + delay
        if self.derive or (recorded is not None and recorded.qd is None):
            which = "derived"
        elif recorded is None:
            which = "recorded where there are"
        else:  # recorded velocities; accelerations derived, or only the torques filtered
            which = "recorded qd" if recorded.qdd is None else "recorded"
        return (f"{which}, {self.cutoff_hz:g} Hz" + ", torques low-passed"
                * self.filter_torques + delay)

    def made(self, recorded: Recorded, *, trim_s: float | None = None,
             given: bool = True
             ) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
                        dict]:
        """What this chain makes of ``recorded``: ``(times, q, qd, qdd, tau)`` and their
        ``info``, for :meth:`~._container.Measurements.made_by`: derived, filtered and
        delayed, the first and last ``trim_s`` seconds dropped (None: the filter's
        ringing, :func:`~._signal.edge_seconds`, where anything is filtered and
        ``recorded.trim_edges``; at least the delay), then every
        ``recorded.downsample``-th sample of the recording kept. ``info`` records what was
        done, with ``chain`` (this chain's fields, and ``given``: whether the user chose
        it, rather than the loader's default)."""
        times, source = recorded.times, recorded.source
        rate = median_rate(times)
        cutoff = (check_cutoff(self.cutoff_hz, rate, source) if self.filters(recorded)
                  else self.cutoff_hz)
        info = dict(recorded.info)
        info.update({"rate_hz": rate, "cutoff_hz": None, "filter": None,
                     "velocities": "recorded", "accelerations": "recorded",
                     "torques": "recorded", "downsample": recorded.downsample,
                     "chain": {"cutoff_hz": cutoff, "derive": self.derive,
                               "filter_torques": self.filter_torques,
                               "delay_s": self.delay_s, "given": bool(given)}})
        filt = (f"Butterworth low-pass, order {BUTTERWORTH_ORDER}, zero phase (sosfiltfilt), "
                f"{cutoff:g} Hz at the median rate {rate:.6g} Hz")
        qd, qdd, tau = recorded.qd, recorded.qdd, recorded.tau
        need = [k for k, v in (("velocities", qd), ("accelerations", qdd))
                if self.derive or v is None]
        if need:
            derived = dict(zip(("velocities", "accelerations"),
                               differentiate(times, recorded.q, cutoff, source=source)))
            qd = derived["velocities"] if "velocities" in need else qd
            qdd = derived["accelerations"] if "accelerations" in need else qdd
            for key in need:
                info[key] = "derived from positions: low-pass, then np.gradient on times"
            info["cutoff_hz"], info["filter"] = cutoff, filt
        if self.filter_torques:
            tau = lowpass(tau, rate, cutoff, source=source)
            info["torques"] = "recorded, low-passed"
            info["cutoff_hz"], info["filter"] = cutoff, filt
        q = recorded.q
        if self.delay_s:  # the motion at t - delay_s, paired with the torque at t
            assert qd is not None and qdd is not None
            q, qd, qdd = (scipy.interpolate.CubicSpline(times, x, axis=0)(
                times - self.delay_s) for x in (q, qd, qdd))
            info["delay_s"] = float(info.get("delay_s", 0.0)) + self.delay_s
        if trim_s is None:
            trim_s = edge_seconds(cutoff) if (recorded.trim_edges
                                              and info["cutoff_hz"] is not None) else 0.0
        trim_s = max(float(trim_s), abs(self.delay_s))  # no torque from beyond the ends
        first, last = 0, len(times)
        if trim_s > 0.0:
            first = int(np.searchsorted(times, times[0] + trim_s, side="left"))
            last = int(np.searchsorted(times, times[-1] - trim_s, side="right"))
            if last - first < 2 and abs(self.delay_s) >= trim_s:
                raise ValueError(
                    f"{source}: the recording ({times[-1] - times[0]:.3g} s) is too short for "
                    f"a delay of {self.delay_s:g} s: no sample keeps a torque and the motion "
                    f"{self.delay_s:g} s before it")
            if last - first < 2:
                raise ValueError(
                    f"{source}: the recording ({times[-1] - times[0]:.3g} s) is too short to "
                    f"drop the filter's {trim_s:.3g} s edge transients at both ends; raise "
                    f"the cutoff (now {cutoff:g} Hz) or keep the edges (trim_edges=False)")
        info["trimmed_s"] = float(trim_s)
        # every downsample-th sample of the recording's own grid, whatever the trim: two
        # chains keep the same samples where both keep them
        k = recorded.downsample
        index = slice(first + (-first) % k, last, k)
        assert qd is not None and qdd is not None  # derived where missing
        return (times[index], q[index], qd[index], qdd[index], tau[index]), info

