"""The problems the speed benchmarks share."""

from __future__ import annotations

import jax
import numpy as np

import sedsabso_jax as sj


def rs010n_problem(samples: int = 1000, seed: int = 0, box: float = 0.1):
    """The paper's identification problem on the RS010N: Eq. 17 over ``samples`` random
    states (seeded), noise-free torques from Table 2, the box ``true +- max(box |true|,
    box)``. Returns ``(L1Residual, lower, upper, true base parameters)``."""
    jax.config.update("jax_enable_x64", True)
    base = sj.base_parameters(sj.robots.rs010n())
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (samples, 3))
    qd, qdd = rng.standard_normal((2, samples, 3))
    true = np.asarray(base.values)
    tau = np.asarray(base.regressor(q, qd, qdd)) @ true
    half = np.maximum(box * np.abs(true), box)
    return sj.L1Residual.from_base(base, q, qd, qdd, tau), true - half, true + half, true
