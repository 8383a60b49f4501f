"""Statistics for comparing optimisers over independent seeded runs (minimisation: smaller
is better), as reviewers of optimisation papers expect them.

- location and spread: median and interquartile range (no normality assumed);
- pairwise two-sided Mann-Whitney U tests (``scipy.stats.mannwhitneyu``; the runs of two
  algorithms are independent samples, not pairs), their p-values corrected for the
  multiple comparisons of one problem by Holm's step-down method (S. Holm, "A simple
  sequentially rejective multiple test procedure", Scand. J. Statist. 6, 1979);
- effect size: Vargha and Delaney's A12 (J. Educ. Behav. Stat. 25(2), 2000), here the
  probability that a run of A ends BELOW a run of B, ties counting half (read off scipy's
  Mann-Whitney U): 0.5 is no effect, 0.56 / 0.64 / 0.71 small / medium / large (their
  thresholds);
- run length: evaluations a run needs to reach a target precision, and their empirical
  cumulative distribution over (run, target) pairs (COCO's ECDF of run lengths:
  N. Hansen et al., "COCO: performance assessment", arXiv:1605.03560);
- average runtime (aRT, formerly ERT) to reach a target: the evaluations of all runs
  until each reached it or ran out, over the number of runs that reached it (same
  paper; Price 1997).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np
import scipy.stats
from jaxtyping import ArrayLike, Float

ALPHA = 0.05
#: COCO's 51 targets on ``f - f_opt``, 1e2 .. 1e-8, five per decade: the values cocopp
#: aligns its data on (``numpy.power(10, i / 5)``), so a target is one of its rows exactly
COCO_TARGETS = np.power(10.0, np.arange(10, -41, -1) / 5)


def summary(values: Float[ArrayLike, " runs"] | Sequence[float]) -> dict:
    """Median, quartiles and IQR of ``values`` (non-finite values sort last)."""
    v = np.asarray(values, dtype=float)
    v = np.where(np.isnan(v), np.inf, v)
    with np.errstate(invalid="ignore"):  # inf - inf between two infinite values
        q1, med, q3 = np.quantile(v, [0.25, 0.5, 0.75], method="linear")
    return {"median": float(med), "q1": float(q1), "q3": float(q3),
            "iqr": float(q3 - q1), "best": float(v.min()), "worst": float(v.max()),
            "runs": int(v.size)}


def a12(a: Float[ArrayLike, " runs_a"] | Sequence[float],
        b: Float[ArrayLike, " runs_b"] | Sequence[float]) -> float:
    """Vargha-Delaney A12: ``P(a < b) + P(a == b) / 2`` over all pairs of a run of ``a``
    and a run of ``b`` (minimisation: above 0.5 means ``a`` tends to end lower).

    Read off the Mann-Whitney U of ``(b, a)``: scipy's U of ``(x, y)`` counts the pairs
    with ``x > y``, ties half, so ``U(b, a) / (n_a n_b)`` is this A12."""
    a, b = np.asarray(a, dtype=float).ravel(), np.asarray(b, dtype=float).ravel()
    u = scipy.stats.mannwhitneyu(b, a, alternative="two-sided").statistic
    return float(u / (a.size * b.size))


def holm(p_values: Float[ArrayLike, " m"] | Sequence[float]) -> Float[np.ndarray, " m"]:
    """Holm's step-down adjusted p-values (reject where adjusted p <= alpha); they control
    the family-wise error rate over the family of tests given.

    Kept here rather than statsmodels' ``multipletests(p, method="holm")``, which gives the
    same values (tests/test_compare_statistics.py compares them): statsmodels is a large
    dependency for these few lines, and scipy has no Holm correction."""
    p = np.asarray(p_values, dtype=float)
    order = np.argsort(p, kind="stable")
    m = p.size
    adjusted = np.empty(m)
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (m - rank) * p[i]))
        adjusted[i] = running
    return adjusted


def pairwise(samples: dict[str, np.ndarray], alpha: float = ALPHA) -> list[dict]:
    """Every pair of algorithms in ``samples`` (name -> final values of its runs): the
    two-sided Mann-Whitney U p-value, its Holm-adjusted value over all pairs, A12 and
    which one is better where the difference is significant at ``alpha``."""
    pairs = list(itertools.combinations(samples, 2))
    rows, p = [], []
    for a, b in pairs:
        x = np.nan_to_num(np.asarray(samples[a], float), nan=np.inf)
        y = np.nan_to_num(np.asarray(samples[b], float), nan=np.inf)
        if np.all(x == x[0]) and np.all(y == x[0]):
            pv = 1.0  # every value identical: no evidence either way
        else:
            pv = float(scipy.stats.mannwhitneyu(x, y, alternative="two-sided").pvalue)
        rows.append({"a": a, "b": b, "p": pv, "a12": a12(x, y)})
        p.append(pv)
    for row, adj in zip(rows, holm(p) if rows else []):
        row["p_holm"] = float(adj)
        row["significant"] = bool(adj <= alpha)
        row["better"] = (None if not row["significant"]
                         else row["a"] if float(row["a12"]) > 0.5  # type: ignore[arg-type]
                         else row["b"])
    return rows


def effect_size_label(a: float) -> str:
    """Vargha and Delaney's words for an A12 (symmetric around 0.5)."""
    d = abs(a - 0.5)
    return ("negligible" if d < 0.06 else "small" if d < 0.14 else
            "medium" if d < 0.21 else "large")


def run_lengths(precision_history: Float[ArrayLike, "runs iterations"],
                evaluations: Float[ArrayLike, " iterations"],
                targets: Float[np.ndarray, " targets"] | Sequence[float]
                ) -> Float[np.ndarray, "runs targets"]:
    """Evaluations each run needs to reach each target: ``precision_history (runs,
    iterations)`` the best precision after each iteration, ``evaluations (iterations,)``
    the cumulative evaluations then; returns ``(runs, targets)``, ``inf`` where a target
    is never reached."""
    h = np.minimum.accumulate(np.asarray(precision_history, dtype=float), axis=-1)
    evaluations = np.asarray(evaluations, dtype=float)
    out = np.full((h.shape[0], len(targets)), np.inf)
    for j, target in enumerate(targets):
        hit = h <= target
        first = np.argmax(hit, axis=-1)
        out[:, j] = np.where(hit.any(axis=-1), evaluations[first], np.inf)
    return out


def ecdf(run_lengths_: Float[ArrayLike, "*shape"], grid: Float[ArrayLike, " g"]
         ) -> Float[np.ndarray, " g"]:
    """Share of (run, target) pairs reached within each evaluation count of ``grid``.

    Not ``scipy.stats.ecdf``: it refuses the ``inf`` of a target never reached, and those
    pairs belong in the denominator (COCO's convention); as right-censored data it would
    be a Kaplan-Meier estimate, another quantity. On finite run lengths the two agree
    (tests/test_compare_statistics.py)."""
    r = np.asarray(run_lengths_, dtype=float).ravel()
    return np.array([np.mean(r <= g) for g in np.asarray(grid, dtype=float)])


def average_runtime(run_lengths_: Float[ArrayLike, "runs targets"],
                    evaluations: Float[ArrayLike, " runs"]) -> Float[np.ndarray, " targets"]:
    """Average runtime (aRT) per target: the evaluations each run spent until it reached
    the target, or all of its ``evaluations`` where it did not (``inf`` in
    ``run_lengths_``), summed over the runs and divided by the number of runs that
    reached it; ``inf`` where none did. cocopp's ``DataSet.detERT`` on the same runs."""
    rl = np.asarray(run_lengths_, dtype=float)
    spent = np.asarray(evaluations, dtype=float)
    if rl.ndim != 2 or spent.shape != rl.shape[:1]:
        raise ValueError(f"expected run lengths (runs, targets) and one evaluation count "
                         f"per run, got {rl.shape} and {spent.shape}")
    hit = np.isfinite(rl)
    successes = hit.sum(axis=0)
    total = np.where(hit, rl, 0.0).sum(axis=0) + np.where(hit, 0.0, spent[:, None]).sum(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(successes > 0, total / successes, np.inf)

