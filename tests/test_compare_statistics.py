"""The comparison statistics against their definitions computed by brute force or by hand
(never against the module itself): A12 by counting pairs, Holm's adjusted p-values on a
worked example, run lengths on a hand-made history; and against the libraries that could
compute them: A12 from scipy's U against the former rank sums, Holm against statsmodels,
the ECDF against scipy's."""

from __future__ import annotations

import gc

import numpy as np
import pytest
import scipy.stats

from sedsabso_jax.compare import _statistics as S


def test_a12_counts_pairs():
    rng = np.random.default_rng(0)
    a = rng.integers(0, 5, 30).astype(float)  # many ties
    b = rng.integers(1, 6, 20).astype(float)
    lower = sum(x < y for x in a for y in b)
    ties = sum(x == y for x in a for y in b)
    assert S.a12(a, b) == pytest.approx((lower + 0.5 * ties) / (a.size * b.size), abs=1e-12)
    assert S.a12(a, b) + S.a12(b, a) == pytest.approx(1.0)
    assert S.a12([1, 2], [3, 4]) == 1.0 and S.a12([3, 4], [1, 2]) == 0.0


def test_holm_worked_example():
    # p = (0.01, 0.04, 0.03, 0.005), m = 4: sorted 0.005*4, 0.01*3, 0.03*2, 0.04*1,
    # each at least the previous one
    adjusted = S.holm([0.01, 0.04, 0.03, 0.005])
    np.testing.assert_allclose(adjusted, [0.03, 0.06, 0.06, 0.02])
    assert S.holm([0.5, 0.9]).tolist() == [1.0, 1.0]


def test_pairwise_finds_the_real_difference_only():
    rng = np.random.default_rng(1)
    samples = {"good": rng.normal(0, 1, 100), "bad": rng.normal(3, 1, 100),
               "same": rng.normal(0, 1, 100)}
    rows = {(r["a"], r["b"]): r for r in S.pairwise(samples)}
    assert rows["good", "bad"]["significant"] and rows["good", "bad"]["better"] == "good"
    assert rows["bad", "same"]["better"] == "same"
    assert not rows["good", "same"]["significant"]
    raw = scipy.stats.mannwhitneyu(samples["good"], samples["same"]).pvalue
    assert rows["good", "same"]["p"] == pytest.approx(raw)
    assert rows["good", "same"]["p_holm"] >= rows["good", "same"]["p"]
    # identical constant samples: no evidence, no error
    assert S.pairwise({"a": np.zeros(5), "b": np.zeros(5)})[0]["p"] == 1.0


def test_summary_quartiles():
    s = S.summary(np.arange(1.0, 10.0))
    assert (s["median"], s["q1"], s["q3"], s["iqr"]) == (5.0, 3.0, 7.0, 4.0)
    assert S.summary([1.0, np.nan])["worst"] == np.inf  # NaN sorts last


def test_run_lengths_and_ecdf():
    history = np.array([[5.0, 1.0, 0.5, 0.01],    # reaches 1 at 20 evaluations, 0.01 at 40
                        [5.0, 6.0, 2.0, 2.0]])     # never below 2
    evaluations = np.array([10, 20, 30, 40])
    rl = S.run_lengths(history, evaluations, [10.0, 1.0, 0.01])
    np.testing.assert_array_equal(rl, [[10, 20, 40], [10, np.inf, np.inf]])
    np.testing.assert_allclose(S.ecdf(rl, [5, 10, 20, 40]), [0, 2 / 6, 3 / 6, 4 / 6])
    assert S.effect_size_label(0.5) == "negligible" and S.effect_size_label(0.8) == "large"


def _a12_by_ranks(a, b):
    """The package's former A12 (before scipy's U): rank sums of the negated values."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    ranks = scipy.stats.rankdata(np.concatenate([-a, -b]))
    return (ranks[: a.size].sum() - a.size * (a.size + 1) / 2) / (a.size * b.size)


def test_a12_from_mann_whitney_u_matches_rank_sums():
    """A12 read off scipy's U equals the former rank-sum formula and the pair count, on
    continuous, heavily tied and infinite (never finished) values."""
    rng = np.random.default_rng(7)
    worst = 0.0
    for k in range(200):
        n, m = rng.integers(1, 40, 2)
        if k % 3 == 0:
            a, b = rng.normal(0, 1, n), rng.normal(0.3, 1, m)
        elif k % 3 == 1:
            a, b = rng.integers(0, 4, n).astype(float), rng.integers(0, 4, m).astype(float)
        else:
            a, b = rng.choice([0.0, 1.0, np.inf], n), rng.choice([0.5, np.inf], m)
        pairs = (np.sum(a[:, None] < b) + 0.5 * np.sum(a[:, None] == b)) / (n * m)
        worst = max(worst, abs(S.a12(a, b) - _a12_by_ranks(a, b)), abs(S.a12(a, b) - pairs))
    assert worst < 1e-12


def test_holm_matches_statsmodels(monkeypatch):
    """Holm's adjusted p-values equal statsmodels' on random p-vectors with ties, ones and
    values whose products exceed 1."""
    multitest = pytest.importorskip("statsmodels.stats.multitest")
    # ``multipletests`` runs ``gc.collect()`` on every call: seconds each in a test process
    # that holds many compiled programs (100 s of the suite on 2 cores). Not collecting
    # changes none of its numbers.
    monkeypatch.setattr(gc, "collect", lambda generation=2: 0)
    rng = np.random.default_rng(3)
    worst = 0.0
    for k in range(40):
        m = int(rng.integers(1, 30))
        p = rng.uniform(0, 1, m) ** rng.uniform(0.5, 4)
        if k % 2:
            p = rng.choice(np.r_[p[: max(1, m // 3)], 1.0, 0.05], m)  # ties and p = 1
        expected = multitest.multipletests(p, alpha=S.ALPHA, method="holm")[1]
        worst = max(worst, float(np.abs(S.holm(p) - expected).max()))
    assert worst < 1e-15
    assert S.holm([1.0, 1.0, 0.01, 0.01]).tolist() == [1.0, 1.0, 0.04, 0.04]


def test_ecdf_matches_scipy_on_finite_run_lengths():
    """On finite run lengths ``ecdf`` equals ``scipy.stats.ecdf``; with targets never
    reached (``inf``), which scipy refuses, it is scipy's ECDF of the finite ones times
    their share: the unreached pairs stay in the denominator."""
    rng = np.random.default_rng(5)
    lengths = rng.choice([10.0, 20.0, 35.0, 40.0, 100.0], (6, 5))  # many ties
    grid = np.array([1.0, 10.0, 15.0, 20.0, 40.0, 99.0, 100.0, 1e3])
    scipy_ecdf = scipy.stats.ecdf(lengths.ravel()).cdf.evaluate(grid)
    assert np.abs(S.ecdf(lengths, grid) - scipy_ecdf).max() < 1e-15
    lengths[rng.uniform(size=lengths.shape) < 0.4] = np.inf
    finite = lengths[np.isfinite(lengths)]
    share = finite.size / lengths.size
    expected = share * scipy.stats.ecdf(finite).cdf.evaluate(grid)
    np.testing.assert_allclose(S.ecdf(lengths, grid), expected, rtol=0, atol=1e-15)
    assert S.ecdf(lengths, [np.inf])[0] == 1.0 and S.ecdf([np.inf], [1e9])[0] == 0.0
