"""Validation metrics against numbers worked out by hand, and their input checks."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sedsabso_jax.identification._metrics import Metrics, validation_metrics

# 4 samples, 2 joints; errors +-0.1 on joint 1 and +-1 on joint 2.
MEASURED = np.array([[1.0, 10.0], [-1.0, 20.0], [3.0, 30.0], [1.0, 20.0]])
ERRORS = np.array([[0.1, 1.0], [-0.1, -1.0], [0.1, 1.0], [-0.1, -1.0]])
PREDICTED = MEASURED - ERRORS
LIMITS = (10.0, 50.0)


def test_hand_computed_example():
    m = validation_metrics(MEASURED, PREDICTED, LIMITS)
    assert isinstance(m, Metrics)
    # RMS of the errors: 0.1 and 1.0 exactly.
    np.testing.assert_allclose(m.rms, [0.1, 1.0], rtol=1e-14)
    # RMS measured: sqrt((1 + 1 + 9 + 1) / 4) = sqrt(3); sqrt((100+400+900+400)/4) = sqrt(450).
    np.testing.assert_allclose(m.relative_rms_percent,
                               [10.0 / math.sqrt(3.0), 100.0 / math.sqrt(450.0)], rtol=1e-14)
    # ranges: 3 - (-1) = 4 and 30 - 10 = 20 -> 2.5 % and 5 %, mean 3.75 %.
    np.testing.assert_allclose(m.nrms_range_percent, [2.5, 5.0], rtol=1e-14)
    assert m.nrms_range_percent_mean == pytest.approx(3.75, rel=1e-14)
    # limits 10 and 50: 0.1 / 20 = 0.5 %, 1 / 100 = 1 %, mean 0.75 %.
    np.testing.assert_allclose(m.nrms_limits_percent_per_joint, [0.5, 1.0], rtol=1e-14)
    assert m.nrms_limits_percent == pytest.approx(0.75, rel=1e-14)
    # overall: ||e|| = sqrt(4 * 0.01 + 4 * 1) = sqrt(4.04); ||tau|| = sqrt(12 + 1800).
    assert m.relative_rms_percent_overall == pytest.approx(
        100.0 * math.sqrt(4.04) / math.sqrt(1812.0), rel=1e-14)
    assert m.rms_overall == pytest.approx(math.sqrt(4.04 / 8.0), rel=1e-14)
    assert (m.n_samples, m.n_joints) == (4, 2)
    assert m["nrms_limits_percent"] == m.nrms_limits_percent
    with pytest.raises(KeyError):
        m["no such metric"]


def test_without_limits_and_json():
    m = validation_metrics(MEASURED, PREDICTED)
    assert m.nrms_limits_percent is None and m.nrms_limits_percent_per_joint is None
    d = json.loads(json.dumps(m.as_dict()))
    assert d["nrms_limits_percent"] is None
    assert d["nrms_range_percent"] == pytest.approx([2.5, 5.0], rel=1e-14)
    assert set(d) == set(m.keys())
    assert "overall" in m.table(["a1", "a2"])


def test_zero_measured_joint_gives_nan_and_null():
    measured = MEASURED.copy()
    measured[:, 1] = 0.0
    m = validation_metrics(measured, measured + 0.5)
    assert np.isnan(m.relative_rms_percent[1]) and np.isnan(m.nrms_range_percent[1])
    assert m.relative_rms_percent[0] > 0
    d = m.as_dict()
    assert d["relative_rms_percent"][1] is None
    json.dumps(d, allow_nan=False)


def test_one_joint_and_jax_input():
    import jax.numpy as jnp

    m = validation_metrics(jnp.asarray(MEASURED[:, 0]), PREDICTED[:, 0], [10.0])
    assert m.n_joints == 1
    assert m.nrms_limits_percent == pytest.approx(0.5)


@pytest.mark.parametrize(
    "measured, predicted, limits, match",
    [
        (MEASURED, PREDICTED[:3], None, r"tau_predicted: expected the shape .*\(4, 2\).*\(3, 2\)"),
        (np.where(np.eye(4, 2) > 0, np.nan, MEASURED), PREDICTED, None,
         r"tau_measured: expected finite.*2 NaN/Inf.*sample 1 of \d+, joint 1"),
        (MEASURED, np.full((4, 2), np.inf), None, r"tau_predicted: expected finite"),
        (MEASURED, PREDICTED, (1.0,), r"torque_limits: expected 2 numbers"),
        (MEASURED, PREDICTED, (1.0, 0.0), r"torque_limits: expected finite positive"),
        (MEASURED, PREDICTED, (1.0, np.nan), r"torque_limits: expected finite positive"),
        (np.zeros((0, 2)), np.zeros((0, 2)), None, r"tau_measured: expected shape \(T, n"),
        (np.zeros((2, 2, 2)), np.zeros((2, 2, 2)), None, r"tau_measured: expected shape"),
        (np.array([["a", "b"]]), np.zeros((1, 2)), None, r"tau_measured: expected real"),
    ],
)
def test_bad_input(measured, predicted, limits, match):
    with pytest.raises(ValueError, match=match):
        validation_metrics(measured, predicted, limits)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(1e-3, 1e3))
def test_scale_invariance_and_perfect_fit(seed, scale):
    rng = np.random.default_rng(seed)
    tau = rng.normal(size=(20, 3))
    pred = tau + 0.1 * rng.normal(size=(20, 3))
    limits = rng.uniform(1.0, 5.0, 3)
    a = validation_metrics(tau, pred, limits)
    b = validation_metrics(scale * tau, scale * pred, scale * limits)
    for key in ("relative_rms_percent", "nrms_range_percent", "nrms_limits_percent_per_joint"):
        np.testing.assert_allclose(a[key], b[key], rtol=1e-10)
    assert a.relative_rms_percent_overall == pytest.approx(b.relative_rms_percent_overall)
    np.testing.assert_allclose(b.rms, scale * a.rms, rtol=1e-10)
    perfect = validation_metrics(tau, tau, limits)
    assert perfect.nrms_limits_percent == 0.0 and perfect.relative_rms_percent_overall == 0.0
