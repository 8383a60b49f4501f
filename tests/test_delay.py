"""The delay of the torques behind the motion (``sj.identification.estimate_delay``,
``Measurements.delayed``): on simulated plants whose torques answer the motion a known
time earlier or later, at 1 kHz and at 100 Hz, with noise, the delay is recovered within
the issue's figures (1 ms at 1 kHz, a sample at 100 Hz); the delayed recording's torques
are the plant's at the shifted times; bad input is refused by name."""

from __future__ import annotations

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.identification import estimate_delay


def _plant(rate: float, delay: float, seconds: float = 12.0, seed: int = 0):
    """RS010N on a 5-harmonic Fourier motion sampled at ``rate``; the torques the motion
    at ``t`` causes recorded at ``t + delay`` (the motion evaluated at ``t - delay``,
    exactly), with 1 % noise and a constant offset."""
    robot = sj.robots.rs010n()
    rng = np.random.default_rng(seed)
    w = 2 * np.pi * 0.1 * np.arange(1, 6)
    a, b = rng.normal(0, 0.3, (2, 5, robot.n_joints)) / np.arange(1, 6)[:, None]

    def motion(t):
        s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
        return (s @ a + c @ b, (c * w) @ a - (s * w) @ b, -(s * w ** 2) @ a - (c * w ** 2) @ b)

    t = np.arange(0.0, seconds, 1.0 / rate)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, *motion(t - delay)))
    tau = tau + 0.01 * np.sqrt(np.mean(tau ** 2, 0)) * rng.standard_normal(tau.shape) + 0.3
    return robot, sj.Measurements(t, *motion(t), tau)


@pytest.mark.parametrize("rate, delay", [(1000.0, 0.0073), (1000.0, -0.0041), (100.0, 0.023),
                                         (100.0, -0.012)])
def test_the_delay_of_a_simulated_plant_is_recovered(rate, delay):
    """Within a quarter of a sample (measured 0.05-0.11 samples): the parabola's vertex,
    not the nearest whole sample (0.1-0.3 samples off here)."""
    robot, data = _plant(rate, delay)
    found = estimate_delay(robot, data, largest_s=0.03)
    assert abs(found.seconds - delay) < 0.25 / rate, found.seconds
    weighed = estimate_delay(robot, data, largest_s=0.03, limits=(50.0, 100.0, 200.0))
    assert abs(weighed.seconds - delay) < 0.25 / rate and weighed.seconds != found.seconds
    assert found.samples == pytest.approx(found.seconds * rate)
    # every sample with its shifted neighbours inside the recording, no more dropped
    m = found.shifts.max()
    assert found.residuals == (data.n_samples - 2 * (m + 1)) * 3
    assert found.rate == pytest.approx(rate) and m >= 0.03 * rate
    assert not found.at_bound and found.losses.argmin() in (
        np.abs(found.shifts - delay * rate).argsort()[:2])
    # the recording re-timed by the delay found fits better than as recorded
    model = sj.TorqueModel.of(robot, [sj.Offset()])
    before = np.mean(sj.identify(robot, data, sj.OLS(), model).fit["rms"])
    after = sj.identify(robot, data.delayed(found.seconds), sj.OLS(), model)
    assert np.mean(after.fit["rms"]) < before


def test_delayed_takes_the_torques_at_the_shifted_times():
    robot, data = _plant(200.0, 0.0, seconds=2.0)
    later = data.delayed(0.0125)  # 2.5 samples: between samples, interpolated
    assert later.n_samples == data.n_samples - 3 and later.info["delay_s"] == 0.0125
    np.testing.assert_array_equal(later.q, data.q[:-3])
    np.testing.assert_allclose(later.tau, 0.5 * (data.tau[2:-1] + data.tau[3:]))
    back = later.delayed(-0.0125)
    assert back.info["delay_s"] == 0.0
    np.testing.assert_allclose(data.delayed(-0.01).tau, data.tau[:-2])
    for bad in (np.nan, "soon", None):
        with pytest.raises(ValueError, match="the delay must be a finite number"):
            data.delayed(bad)
    with pytest.raises(ValueError, match="leaves fewer than 2 samples"):
        data.delayed(5.0)
    with pytest.raises(ValueError, match="largest_s must be a number of seconds > 0"):
        estimate_delay(robot, data, largest_s=0.0)
    with pytest.raises(ValueError, match="needs recordings of more than"):
        estimate_delay(robot, data.slice(0, 20), largest_s=0.05)
