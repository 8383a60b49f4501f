"""Signal processing for joint measurements: zero-phase low-pass filtering and the
derivation of velocities and accelerations from positions.

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
"""

from __future__ import annotations

import numpy as np
from jaxtyping import ArrayLike, Float

#: Default low-pass cutoff [Hz] for deriving velocities/accelerations and filtering torques.
DEFAULT_CUTOFF_HZ = 10.0
#: Order of the Butterworth low-pass (applied forwards and backwards: zero phase).
BUTTERWORTH_ORDER = 4


def median_rate(times: Float[ArrayLike, " T"]) -> float:
    """Median sample rate [Hz] of strictly increasing time stamps ``(T,)``."""
    times = np.asarray(times, dtype=float)
    return float(1.0 / np.median(np.diff(times)))


def check_cutoff(cutoff_hz: float, rate: float, source: str) -> float:
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


def lowpass(x: Float[ArrayLike, "T ..."], rate: float,
            cutoff_hz: float = DEFAULT_CUTOFF_HZ, *, order: int = BUTTERWORTH_ORDER,
            source: str = "lowpass") -> Float[np.ndarray, "T ..."]:
    """Zero-phase Butterworth low-pass of ``x`` along axis 0 (``scipy.signal.sosfiltfilt``).

    ``rate`` is the sample rate [Hz] the filter is designed for; ``cutoff_hz`` must lie
    below ``rate / 2``. The forward-backward pass has no phase lag and squares the
    magnitude response (gain 1/2 at the cutoff). The ends are padded by odd reflection over
    ``5 rate / cutoff_hz`` samples (fewer if the signal is shorter), so straight lines pass
    unchanged. Needs more than ``3 (2 ceil(order/2) + 1)`` samples (15 for order 4).
    """
    x = np.asarray(x, dtype=float)
    cutoff = check_cutoff(cutoff_hz, float(rate), source)
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


def edge_seconds(cutoff_hz: float) -> float:
    """How long the zero-phase low-pass rings at each end of a recording: ``2 /
    cutoff_hz`` seconds (0.2 s at 10 Hz), where derived accelerations show the filter's
    edge transients."""
    return 2.0 / float(cutoff_hz)


def differentiate(times: Float[ArrayLike, " T"], q: Float[ArrayLike, "T n"],
                  cutoff_hz: float | None = DEFAULT_CUTOFF_HZ, *, source: str = "differentiate"
                  ) -> tuple[Float[np.ndarray, "T n"], Float[np.ndarray, "T n"]]:
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


def position_noise(q: Float[ArrayLike, "T n"],
                   times: Float[ArrayLike, " T"] | None = None) -> Float[np.ndarray, " n"]:
    """Each joint's white noise on positions ``q (T, n)`` (a robust standard deviation):
    the fourth differences of a smooth motion nearly vanish while white noise's have 70
    times its variance, so the noise is ``1.4826 MAD(d4 q) / sqrt(70)`` (the median
    absolute deviation's consistency factor for a normal distribution). With ``times``,
    differences only within stretches without a gap (a step above 1.5 median steps: a
    split's samples). A ValueError names positions that are not ``(T, n)`` finite numbers,
    or times that are not ``(T,)`` increasing."""
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or not np.all(np.isfinite(q)):
        raise ValueError(f"position_noise: q must be (T, n) finite positions, got shape "
                         f"{q.shape}" + ("" if q.ndim != 2 else " with NaN or inf"))
    if times is None:
        d4 = np.diff(q, 4, axis=0)
    else:
        step = np.diff(np.asarray(times, dtype=float))
        if np.shape(times) != q.shape[:1] or not np.all(step > 0):
            raise ValueError(f"position_noise: times must be {q.shape[:1]} increasing time "
                             f"stamps, one per position, got shape {np.shape(times)}")
        cuts = np.flatnonzero(step > 1.5 * np.median(step)) + 1
        d4 = np.concatenate([np.diff(part, 4, axis=0) for part in np.split(q, cuts)
                             if len(part) > 4] or [np.zeros((0, q.shape[1]))])
    if not d4.shape[0]:
        raise ValueError("position_noise: no stretch of 5 samples without a gap")
    return 1.4826 * np.median(np.abs(d4 - np.median(d4, axis=0)), axis=0) / np.sqrt(70.0)


def velocity_noise(times: Float[ArrayLike, " T"], q: Float[ArrayLike, "T n"],
                   cutoff_hz: float = DEFAULT_CUTOFF_HZ) -> Float[np.ndarray, " n"]:
    """Each joint's noise on velocities derived from positions ``q (T, n)`` at ``times``
    (:func:`differentiate` at ``cutoff_hz``) by their white noise (:func:`position_noise`,
    within stretches without a gap): that noise times the derivation's gain on white
    noise at the same median rate (a fixed draw of at least 4000 samples or 50 cutoff
    periods, its middle half: the filter's ends ring). A ValueError where the cutoff is
    not below half the rate, as :func:`differentiate`'s."""
    noise = position_noise(q, times)  # checks the positions and times first
    rate = median_rate(times)
    n = int(max(4000, 50 * rate / check_cutoff(cutoff_hz, rate, "velocity_noise")))
    white = np.random.default_rng(0).standard_normal((n, 1))
    qd, _ = differentiate(np.arange(n) / rate, white, cutoff_hz, source="velocity_noise")
    return noise * float(np.std(qd[n // 4:3 * n // 4]))


def describe_signals(info: dict | None) -> str:
    """How a recording's signals were obtained, in words, from its
    :attr:`~sedsabso_jax.Measurements.info` (:func:`~._load.load_measurements`'s record;
    several recordings joined: each one's, the same said once): which signals were
    recorded and which derived, the low-pass and its cutoff, the seconds trimmed at each
    end, the resampling and downsampling, and a delay of the torques behind the positions
    where one was applied (a :class:`~._chain.SignalChain`'s ``delay_s``, or
    :meth:`~sedsabso_jax.Measurements.delayed`)."""
    info = info or {}
    top = float(info.get("delay_s", 0.0))  # joined recordings re-timed together, or one
    delays = {top + float(r.get("delay_s", 0.0)) for r in info.get("recordings", [])} or {top}
    if delays == {0.0}:
        return _chain(info) + "; torques and positions taken as simultaneous (no delay)"
    said = ", ".join(f"{1e3 * d:.3g} ms" for d in sorted(delays))
    return _chain(info) + f"; torques taken {said} after the positions they answer"


def _chain(info: dict | None) -> str:
    if not info:
        return "as given (no record of how they were obtained)"
    if "recordings" in info:
        said = [_chain(r) for r in info["recordings"]]
        return said[0] if len(set(said)) == 1 else "; ".join(
            f"recording {k + 1} ({s})" for k, s in enumerate(said))
    derived = [k for k in ("velocities", "accelerations")
               if str(info.get(k, "recorded")).startswith("derived")]
    filtered = "low-passed" in str(info.get("torques", ""))
    recorded = ["positions", *(k for k in ("velocities", "accelerations") if k not in derived),
                *([] if filtered else ["torques"])]
    parts = [", ".join(recorded[:-1]) + f" and {recorded[-1]} as recorded"
             if len(recorded) > 1 else "positions as recorded"]
    cutoff = info.get("cutoff_hz")
    at = "" if cutoff is None else f", at {cutoff:g} Hz"
    if derived:
        parts.append(f"{' and '.join(derived)} derived from the positions (zero-phase "
                     f"Butterworth low-pass, order {BUTTERWORTH_ORDER}{at}, then central "
                     f"differences)")
    if filtered:
        parts.append(f"torques low-passed alike{at}")
    if info.get("trimmed_s"):
        parts.append(f"{info['trimmed_s']:g} s trimmed at each end (the filter's ringing)")
    if info.get("resampled_hz"):
        parts.append(f"resampled to {info['resampled_hz']:g} Hz")
    if (info.get("downsample") or 1) > 1:
        parts.append(f"downsampled {info['downsample']}x")
    if info.get("transmission"):
        parts.append("converted to the joint side through the transmission")
    return "; ".join(parts)
