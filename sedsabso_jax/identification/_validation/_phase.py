"""Folds of a motion's phase (:func:`phase_folds`): a recording of an excitation
trajectory usually repeats its motion, so folds are stretches of its phase, found from
the period after which the positions repeat (:func:`repeat_period`)."""

from __future__ import annotations

import numpy as np
from jaxtyping import ArrayLike, Float, Int

from .._default._policy import DEFAULT

#: Folds of :func:`~._selection.cross_validate` unless told otherwise, and the
#: autocorrelation of a repeat of the motion (the default's,
#: :class:`~.._default._policy.Default`).
DEFAULT_FOLDS = DEFAULT.folds
REPEAT_CORRELATION = DEFAULT.repeat_correlation


def repeat_period(times: Float[ArrayLike, " T"], q: Float[ArrayLike, "T n"], *,
                  correlation: float = REPEAT_CORRELATION) -> float | None:
    """The period [s] after which the positions ``q (T, n)`` repeat (the lag of highest
    normalised autocorrelation between 10 % and 90 % of the recording, if it reaches
    ``correlation``), or None when the motion does not repeat."""
    times, q = np.asarray(times, dtype=float), np.asarray(q, dtype=float)
    step = max(1, len(times) // 1500)  # the motion is slow: a coarse grid finds the period
    t, x = times[::step], q[::step]
    x = (x - x.mean(0)) / np.where(x.std(0) > 0, x.std(0), 1.0)
    T = len(t)
    best, lag_best = -np.inf, None
    for lag in range(max(1, T // 10), max(2, 9 * T // 10)):
        a, b = x[:-lag], x[lag:]
        r = np.sum(a * b) / np.sqrt(np.sum(a * a) * np.sum(b * b))
        if r > best:
            best, lag_best = r, lag
    if lag_best is None or best < correlation:
        return None
    return float(t[lag_best] - t[0])


def phase_folds(times: Float[ArrayLike, " T"], q: Float[ArrayLike, "T n"],
                folds: int = DEFAULT_FOLDS) -> tuple[Int[np.ndarray, " T"], float | None]:
    """``(fold of each sample, period)``: folds of the trajectory's phase (module
    docstring); contiguous blocks when the motion does not repeat (period None)."""
    times = np.asarray(times, dtype=float)
    if not isinstance(folds, (int, np.integer)) or isinstance(folds, bool) or folds < 2:
        raise ValueError(f"folds must be an integer >= 2, got {folds!r}")
    period = repeat_period(times, q)
    span = period if period is not None else (times[-1] - times[0]) * (1 + 1e-12)
    phase = np.mod((times - times[0]) / span, 1.0)
    return np.minimum((phase * folds).astype(int), folds - 1), period
