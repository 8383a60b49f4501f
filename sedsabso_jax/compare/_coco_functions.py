"""The 24 noiseless bbob functions in JAX: pure arithmetic on one point ``x`` and its
instance's data (:class:`~._coco_instances.Instance` as JAX arrays: ``a.R``, ``a.Q`` are
the matrices as COCO applies them; ``rot1`` is COCO's rotation from ``rseed + 1e6``,
``rot2`` from ``rseed``).

Each function follows its COCO source (coco-experiment 2.8.2, github numbbo/coco
``code-experiments/src/``): the raw function of ``f_<name>.c`` and, from the outside in,
the transformations its ``f_<name>_bbob_problem_allocate`` wraps around it
(``transform_vars_shift``, ``_affine``, ``_oscillate`` (T_osz), ``_asymmetric``
(T_asy^beta), ``_conditioning`` (Lambda^alpha), ``_brs``, ``_scale``, ``_x_hat``,
``_z_hat``; ``transform_obj_oscillate``, ``_power``, ``_shift`` (f_opt), ``_penalize``
(f_pen)). Constants that depend only on the dimension are computed at trace time with the
C library's ``pow``, as COCO computes them; sums run in XLA's order, so values match COCO
to rounding, not bit for bit (tests/test_coco.py).

Hansen et al., "Real-parameter black-box optimization benchmarking 2009: noiseless
functions definitions", INRIA RR-6829 (2009), whose names the comments use.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from ._coco_random import PI, exponents, powers

TWO_PI = 2.0 * PI


def _c(values: Any, x: Any) -> Any:
    """A trace-time constant in ``x``'s dtype."""
    return jnp.asarray(np.asarray(values, dtype=np.float64), dtype=x.dtype)


def _index(x):
    return np.arange(x.shape[-1])


def affine(M, x, b=None):
    """``M x + b`` (``transform_vars_affine``), at full precision on every backend (no
    TF32 / bfloat16 passes for float32 on accelerators). COCO sums in order of ``j``,
    XLA in its own: the last bits differ, as from any other order."""
    y = jnp.matmul(M, x, precision=jax.lax.Precision.HIGHEST)
    return y if b is None else y + b


def t_osz(x):
    """T_osz (``tosz_uv``, ``transform_obj_oscillate``): ``sign(x) exp(x_hat + 0.049 (sin
    c1 x_hat + sin c2 x_hat))``, ``x_hat = log |x|``. COCO writes ``pow(exp(a), 0.1)``
    with ``a = log|x| / 0.1 + 0.49 (...)``; XLA folds that into ``exp(a * 0.1)`` under
    ``jit``, written so here (eager and compiled agree, and float32 stays finite)."""
    t = jnp.log(jnp.where(x == 0, 1.0, jnp.abs(x))) / 0.1
    pos = jnp.exp((t + 0.49 * (jnp.sin(t) + jnp.sin(0.79 * t))) * 0.1)
    neg = -jnp.exp((t + 0.49 * (jnp.sin(0.55 * t) + jnp.sin(0.31 * t))) * 0.1)
    return jnp.where(x > 0, pos, jnp.where(x < 0, neg, jnp.zeros_like(x)))


def t_asy(x, beta: float):
    """T_asy^beta: ``x_i^(1 + beta i / (D - 1) sqrt(x_i))`` where ``x_i > 0``."""
    d = x.shape[-1]
    slope = _c(beta * _index(x) / (d - 1.0), x)
    safe = jnp.where(x > 0, x, 1.0)
    return jnp.where(x > 0, jnp.power(safe, 1.0 + slope * jnp.sqrt(safe)), x)


def f_pen(x):
    """f_pen: ``sum max(0, |x_i| - 5)^2``."""
    over = jnp.maximum(jnp.abs(x) - 5.0, 0.0)
    return jnp.sum(over * over)


def _weights(base: float, x):
    """``pow(base, i / (D - 1))``, a constant."""
    return _c(powers(base, exponents(x.shape[-1])), x)


def _rastrigin(z):
    d = z.shape[-1]
    return 10.0 * (d - jnp.sum(jnp.cos(TWO_PI * z))) + jnp.sum(z * z)


def _ellipsoid(z):
    return jnp.sum(_weights(1.0e6, z) * z * z)


def sphere(x, a):
    """f1, sphere: ``||z||^2``, ``z = x - x_opt``."""
    z = x - a.xopt
    return jnp.sum(z * z) + a.fopt


def ellipsoid(x, a):
    """f2, separable ellipsoid: ``sum 10^(6 i / (D - 1)) z_i^2``, ``z = T_osz(x - x_opt)``."""
    return _ellipsoid(t_osz(x - a.xopt)) + a.fopt


def rastrigin(x, a):
    """f3, separable Rastrigin: ``z = Lambda^10 T_asy^0.2(T_osz(x - x_opt))``."""
    d = x.shape[-1]
    conditioning = _c([math.pow(10.0, 0.5 * i / (d - 1.0)) for i in range(d)], x)
    return _rastrigin(conditioning * t_asy(t_osz(x - a.xopt), 0.2)) + a.fopt


def bueche_rastrigin(x, a):
    """f4, Bueche-Rastrigin: ``z = s T_osz(x - x_opt)`` (``s_i = 10^(i / 2(D - 1))``,
    times 10 for positive ``z_i`` of even ``i``; x_opt positive there), ``+ 100 f_pen``."""
    factor = _weights(math.sqrt(10.0), x)
    even = jnp.asarray(_index(x) % 2 == 0)
    z = t_osz(x - a.xopt)
    z = jnp.where(even & (z > 0), factor * 10.0, factor) * z
    return _rastrigin(z) + a.fopt + 100.0 * f_pen(x)


def linear_slope(x, a):
    """f5, linear slope: ``sum 5 |s_i| - s_i z_i``, ``s_i = sign(x_opt_i) 10^(i / (D - 1))``;
    ``z_i = x_i`` while ``x_i x_opt_i < 25``, else ``x_opt_i`` (``x_opt = +-5``)."""
    s = jnp.where(a.xopt > 0, 1.0, -1.0) * _weights(math.sqrt(100.0), x)
    inside = x * a.xopt < 25.0
    return jnp.sum(5.0 * jnp.abs(s) - s * jnp.where(inside, x, a.xopt)) + a.fopt


def attractive_sector(x, a):
    """f6, attractive sector: ``T_osz(sum (s_i z_i)^2)^0.9``, ``s_i = 100`` where
    ``z_i x_opt_i > 0``, ``z = R (x - x_opt)`` (``R = rot1 Lambda^10 rot2``)."""
    z = affine(a.R, x - a.xopt)
    raw = jnp.sum(jnp.where(a.xopt * z > 0, 100.0 * 100.0 * z * z, z * z))
    return jnp.power(t_osz(raw), 0.9) + a.fopt


def step_ellipsoid(x, a):
    """f7, step ellipsoid: ``0.1 max(|z_1| / 1e4, sum 10^(2 i / (D - 1)) (Q round(z))_i^2)
    + f_pen``, ``z = R (x - x_opt)`` (``R = Lambda^10 rot2``, ``Q = rot1``); ``round`` to
    integers above 0.5, to tenths below (``f_step_ellipsoid_raw``: ``floor(v + 0.5)``)."""
    z = affine(a.R, x - a.xopt)  # R = Lambda^10 rot2, row by row
    rounded = jnp.where(jnp.abs(z) > 0.5, jnp.floor(z + 0.5), jnp.floor(10.0 * z + 0.5) / 10.0)
    zz = affine(a.Q, rounded)
    total = jnp.sum(_weights(100.0, x) * zz * zz)
    small = jnp.abs(z[0]) * 1.0e-4
    return 0.1 * jnp.where(small >= total, small, total) + f_pen(x) + a.fopt


def _rosenbrock(z):
    c = z[:-1] * z[:-1] - z[1:]
    return 100.0 * jnp.sum(c * c) + jnp.sum((z[:-1] - 1.0) ** 2)


def rosenbrock(x, a):
    """f8, Rosenbrock: ``z = max(1, sqrt(D) / 8) (x - x_opt) + 1``, x_opt 3/4 of the draw."""
    factor = max(1.0, math.sqrt(x.shape[-1]) / 8.0)
    return _rosenbrock(factor * (x - a.xopt) + 1.0) + a.fopt


def rosenbrock_rotated(x, a):
    """f9, rotated Rosenbrock: ``z = max(1, sqrt(D) / 8) R x + 1/2``."""
    return _rosenbrock(affine(a.R, x, 0.5)) + a.fopt


def ellipsoid_rotated(x, a):
    """f10, ellipsoid: ``z = T_osz(R (x - x_opt))``."""
    return _ellipsoid(t_osz(affine(a.R, x - a.xopt))) + a.fopt


def discus(x, a):
    """f11, discus: ``10^6 z_1^2 + sum_{i>1} z_i^2``, ``z = T_osz(R (x - x_opt))``."""
    z = t_osz(affine(a.R, x - a.xopt))
    return 1.0e6 * z[0] * z[0] + jnp.sum(z[1:] * z[1:]) + a.fopt


def bent_cigar(x, a):
    """f12, bent cigar: ``z_1^2 + 10^6 sum_{i>1} z_i^2``, ``z = R T_asy^0.5(R (x - x_opt))``
    (x_opt from the seed + 1e6)."""
    z = affine(a.R, t_asy(affine(a.R, x - a.xopt), 0.5))
    return z[0] * z[0] + jnp.sum(1.0e6 * z[1:] * z[1:]) + a.fopt


def sharp_ridge(x, a):
    """f13, sharp ridge: ``z_1^2 + 100 sqrt(sum_{i>1} z_i^2)``, ``z = R (x - x_opt)``
    (``R = rot1 Lambda^10 rot2``)."""
    z = affine(a.R, x - a.xopt)
    return 100.0 * jnp.sqrt(jnp.sum(z[1:] * z[1:])) + z[0] * z[0] + a.fopt


def different_powers(x, a):
    """f14, different powers: ``sqrt(sum |z_i|^(2 + 4 i / (D - 1)))``, ``z = R (x - x_opt)``."""
    z = affine(a.R, x - a.xopt)
    power = _c(2.0 + 4.0 * _index(x) / (x.shape[-1] - 1.0), x)
    return jnp.sqrt(jnp.sum(jnp.power(jnp.abs(z), power))) + a.fopt


def rastrigin_rotated(x, a):
    """f15, Rastrigin: ``z = Q T_asy^0.2(T_osz(R (x - x_opt)))`` (``R = rot1``,
    ``Q = rot1 Lambda^10 rot2``)."""
    return _rastrigin(affine(a.Q, t_asy(t_osz(affine(a.R, x - a.xopt)), 0.2))) + a.fopt


#: Weierstrass' 12 terms: a_k = 0.5^k, b_k = 3^k, and f0 = sum a_k cos(pi b_k).
_AK = np.array([math.pow(0.5, k) for k in range(12)])
_BK = np.array([math.pow(3.0, k) for k in range(12)])
_F0 = float(np.cumsum([_AK[k] * math.cos(2 * PI * _BK[k] * 0.5) for k in range(12)])[-1])


def weierstrass(x, a):
    """f16, Weierstrass: ``10 (1/D sum_i sum_k a_k cos(2 pi b_k (z_i + 1/2)) - f0)^3 +
    10/D f_pen``, ``z = Q T_osz(R (x - x_opt))`` (``Q = rot1 Lambda^(1/100) rot2``)."""
    z = affine(a.Q, t_osz(affine(a.R, x - a.xopt)))
    terms = jnp.cos((TWO_PI * (z + 0.5))[:, None] * _c(_BK, x)) * _c(_AK, x)
    inner = jnp.sum(terms) / x.shape[-1] - _F0
    return 10.0 * inner * inner * inner + a.fopt + 10.0 / x.shape[-1] * f_pen(x)


def schaffers(x, a):
    """f17 (conditioning 10) and f18 (1000), Schaffers F7: ``(1/(D-1) sum sqrt(s_i) (1 +
    sin^2(50 s_i^0.2)))^2 + 10 f_pen``, ``s_i = sqrt(z_i^2 + z_i+1^2)``, ``z = Q
    T_asy^0.5(R (x - x_opt))`` (``Q = Lambda rot2``)."""
    z = affine(a.Q, t_asy(affine(a.R, x - a.xopt), 0.5))
    s = z[:-1] * z[:-1] + z[1:] * z[1:]
    total = jnp.sum(jnp.power(s, 0.25) * (1.0 + jnp.sin(50.0 * jnp.power(s, 0.1)) ** 2))
    mean = total / (x.shape[-1] - 1.0)
    return mean * mean + a.fopt + 10.0 * f_pen(x)


def griewank_rosenbrock(x, a):
    """f19, composite Griewank-Rosenbrock F8F2: ``10 + 10/(D-1) sum (s_i / 4000 -
    cos s_i)``, ``s_i = 100 (z_i^2 - z_i+1)^2 + (z_i - 1)^2``, ``z = max(1, sqrt(D) / 8) R x
    + 1/2``."""
    z = affine(a.R, x) + 0.5
    c1 = z[:-1] * z[:-1] - z[1:]
    c2 = 1.0 - z[:-1]
    s = 100.0 * c1 * c1 + c2 * c2
    return 10.0 + 10.0 * jnp.sum(s / 4000.0 - jnp.cos(s)) / (x.shape[-1] - 1) + a.fopt


def schwefel(x, a):
    """f20, Schwefel x sin(sqrt|x|): ``x_hat = 2 sign(x_opt) x``; ``z_hat_i = x_hat_i + 1/4
    (x_hat_i-1 - 2 |x_opt_i-1|)``; ``z = 100 (Lambda^10 (z_hat - 2 |x_opt|) + 2 |x_opt|)``;
    ``0.01 (418.9828872724339 - 1/D sum z_i sin sqrt|z_i|) + 100 f_pen(z / 100)``."""
    d = x.shape[-1]
    y = 2.0 * jnp.where(a.xopt < 0, -x, x)  # x_hat, then the factor 2
    twice = 2.0 * jnp.abs(a.xopt)
    z = jnp.concatenate([y[:1], y[1:] + 0.25 * (y[:-1] - twice[:-1])])  # z_hat
    conditioning = _c([math.pow(10.0, 0.5 * i / (d - 1.0)) for i in range(d)], x)
    z = 100.0 * (conditioning * (z - twice) - (-twice))
    over = jnp.maximum(jnp.abs(z) - 500.0, 0.0)
    total = jnp.sum(z * jnp.sin(jnp.sqrt(jnp.abs(z))))
    return 0.01 * (jnp.sum(over * over) + 418.9828872724339 - total / d) + a.fopt


def gallagher(x, a):
    """f21 (101 peaks) and f22 (21), Gallagher's Gaussian peaks: ``T_osz(10 - max_i w_i
    exp(-1/(2D) (R x - R y_i)^T C_i (R x - R y_i)))^2 + f_pen``."""
    d = x.shape[-1]
    diff = affine(a.R, x)[None, :] - a.peaks
    height = a.peak_weights * jnp.exp(-0.5 / d * jnp.sum(a.peak_scales * diff * diff, -1))
    g = t_osz(10.0 - jnp.maximum(jnp.max(height), 0.0))
    return g * g + f_pen(x) + a.fopt


def katsuura(x, a):
    """f23, Katsuura: ``10/D^2 (prod_i (1 + i sum_j |2^j z_i - round(2^j z_i)| / 2^j)^(10 /
    D^1.2) - 1) + f_pen``, ``z = R (x - x_opt)`` (``R = rot1 Lambda^100 rot2``)."""
    d = x.shape[-1]
    z = affine(a.R, x - a.xopt)
    two_j = _c([math.pow(2.0, j) for j in range(1, 33)], x)
    v = z[:, None] * two_j
    tmp = jnp.sum(jnp.abs(v - jnp.floor(v + 0.5)) / two_j, -1)
    factors = jnp.power(1.0 + (_c(_index(x), x) + 1.0) * tmp, 10.0 / math.pow(d, 1.2))
    return 10.0 / d / d * (-1.0 + jnp.prod(factors)) + a.fopt + f_pen(x)


def lunacek(x, a):
    """f24, Lunacek bi-Rastrigin: ``x_hat = 2 sign(x_opt) x``; ``min(sum (x_hat_i - mu0)^2,
    D + s sum (x_hat_i - mu1)^2) + 10 (D - sum cos 2 pi z_i) + 10^4 f_pen``, ``z = Q R
    (x_hat - mu0)`` (``Q = rot1``, ``R = Lambda^100 rot2``)."""
    d = x.shape[-1]
    mu0, s = 2.5, 1.0 - 0.5 / (math.sqrt(d + 20.0) - 4.1)
    mu1 = -math.sqrt((mu0 * mu0 - 1.0) / s)
    x_hat = jnp.where(a.xopt < 0.0, -(2.0 * x), 2.0 * x)
    z = affine(a.Q, affine(a.R, x_hat - mu0))
    sum1 = jnp.sum((x_hat - mu0) * (x_hat - mu0))
    sum2 = jnp.sum((x_hat - mu1) * (x_hat - mu1))
    second = 1.0 * d + s * sum2
    rastrigin_part = 10.0 * (d - jnp.sum(jnp.cos(TWO_PI * z)))
    return (jnp.where(sum1 <= second, sum1, second) + rastrigin_part + 1.0e4 * f_pen(x)
            + a.fopt)


#: The functions in COCO's order, f1 first; f17/f18 and f21/f22 share their code (the
#: instance data differ).
FUNCTIONS: tuple[Callable[[Any, Any], Any], ...] = (
    sphere, ellipsoid, rastrigin, bueche_rastrigin, linear_slope, attractive_sector,
    step_ellipsoid, rosenbrock, rosenbrock_rotated, ellipsoid_rotated, discus, bent_cigar,
    sharp_ridge, different_powers, rastrigin_rotated, weierstrass, schaffers, schaffers,
    griewank_rosenbrock, schwefel, gallagher, gallagher, katsuura, lunacek)
