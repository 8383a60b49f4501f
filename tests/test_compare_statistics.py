"""The comparison statistics against their definitions computed by brute force or by hand
(never against the module itself): A12 by counting pairs, Holm's adjusted p-values on a
worked example, run lengths on a hand-made history."""

from __future__ import annotations

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
