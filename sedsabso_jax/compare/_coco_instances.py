"""The instance data of COCO's 24 noiseless bbob functions, drawn once per (function,
instance, dimension) in NumPy float64 exactly as COCO's allocators draw them.

Each function's ``f_<name>_bbob_problem_allocate`` in COCO's ``f_*.c`` (coco-experiment
2.8.2, github numbbo/coco ``code-experiments/src/``), with ``coco_get_bbob_problem``'s
seeds (``suite_bbob.c``): ``rseed = function + 10000 instance``, but f4 takes f3's seed
and f18 f17's. What an evaluation needs (:class:`Instance`), in one structure for every
function (the fields a function does not use are zeros):

- ``xopt``: the vector the allocator names ``xopt`` (the shift of most functions; f5's
  corner; f20's and f24's signs; not used by f9, f19, f21, f22);
- ``fopt``: ``bbob2009_compute_fopt`` (COCO's optimal value ``best_value``, all 24);
- ``R``, ``Q``: the first and the second linear map (rotations, with the conditioning
  ``Lambda`` folded in where COCO folds it into the matrix);
- ``peaks``, ``peak_scales``, ``peak_weights``: Gallagher's local optima ``R y_i``, the
  diagonals ``C_i`` and the heights ``w_i``, padded to 101 peaks with zero heights;
- ``x_opt``, ``f_opt``: COCO's ``best_parameter`` and ``best_value`` (the optimum and
  its value; not used by the evaluation). ``f_opt`` is ``fopt`` but for f20, whose raw
  function COCO evaluates at 420.96874633 (about 2e-15, not 0) before adding ``fopt``.

Hansen et al., "Real-parameter black-box optimization benchmarking 2009: noiseless
functions definitions", INRIA RR-6829 (2009).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from ._coco_random import (
    compute_fopt,
    compute_rotation,
    compute_xopt,
    exponents,
    gauss,
    powers,
    rotated_conditioning,
    seq_sum,
    unif,
)

#: f21's peaks; f22's 21 are padded to as many (zero heights).
PEAKS = 101


class Instance(NamedTuple):
    """One instance's data (see the module's docstring), NumPy float64, read-only."""

    xopt: np.ndarray
    fopt: float
    R: np.ndarray
    Q: np.ndarray
    peaks: np.ndarray
    peak_scales: np.ndarray
    peak_weights: np.ndarray
    x_opt: np.ndarray
    f_opt: float


def rseed(function: int, instance: int) -> int:
    """``coco_get_bbob_problem``'s seed: f4 uses ``rseed_3``, f18 ``rseed_17``."""
    return {4: 3, 18: 17}.get(function, function) + 10000 * instance


def _rot_lambda(seed: int, d: int, base: float) -> np.ndarray:
    """``rot1 diag(base^(k / (D - 1))) rot2`` with rot1 from ``seed + 1e6`` and rot2
    from ``seed``: Lambda^alpha (``base = sqrt(alpha)``) between two rotations (f6, f13,
    f15, f16, f23)."""
    diagonal = powers(base, exponents(d))
    return rotated_conditioning(compute_rotation(seed + 1000000, d), diagonal,
                                compute_rotation(seed, d))


def _rows_scaled(seed: int, d: int, diagonal: np.ndarray) -> np.ndarray:
    """``diag(diagonal) rot(seed)``, row by row as COCO multiplies (f7, f17, f18, f24)."""
    return diagonal[:, None] * compute_rotation(seed, d)


def _gallagher(seed: int, d: int, n: int):
    """f21 (``n = 101``) and f22 (``n = 21``): ``f_gallagher_bbob_problem_allocate``."""
    rotation = compute_rotation(seed, d)
    first, b, c = (math.sqrt(1000.0), 10.0, 5.0) if n == 101 else (1000.0, 9.8, 4.9)
    order = np.argsort(unif(n - 1, seed), kind="stable")  # COCO: qsort of (value, index)
    condition = np.concatenate([[first], powers(1000.0, order / (n - 2.0))])
    weights = np.zeros(PEAKS)
    weights[0] = 10.0
    weights[1:n] = np.arange(n - 1) / (n - 2.0) * (9.1 - 1.1) + 1.1
    scales = np.ones((PEAKS, d))
    for i in range(n):
        rank = np.argsort(unif(d, seed + 1000 * i), kind="stable") / (d - 1.0) - 0.5
        scales[i] = [math.pow(condition[i], float(e)) for e in rank]
    u = unif(d * n, seed)
    y = b * u.reshape(n, d) - c
    peaks = np.zeros((PEAKS, d))
    peaks[:n] = seq_sum(rotation[None, :, :] * y[:, None, :])  # R y_i, summed in order
    peaks[0] *= 0.8
    xopt = 0.8 * (b * u[:d] - c)
    return xopt, rotation, peaks, scales, weights


def _schwefel(seed: int, d: int):
    """f20: ``xopt = +-4.2096874637 / 2`` (signs from ``unif``), and COCO's
    ``best_parameter``: 420.96874633 carried back through the transformations."""
    xopt = np.where(unif(d, seed) < 0.5, -1.0, 1.0) * 0.5 * 4.2096874637
    best = (420.96874633 / 100 + -2 * np.abs(xopt) + 2 * np.abs(xopt)) / 2
    return xopt, np.where(xopt < 0, -best, best)


def _schwefel_best_value(d: int) -> float:
    """f_schwefel_raw at its ``best_parameter``, 420.96874633 in every coordinate."""
    v = 420.96874633
    total = float(seq_sum(np.full(d, v * math.sin(math.sqrt(abs(v))))))
    return 0.01 * (0.0 + 418.9828872724339 - total / d)


def _draw(function: int, seed: int, d: int):
    """``(xopt, R, Q, x_opt)`` of a function other than f20-f22 (None: unused)."""
    R = Q = None
    if function == 12:  # bent cigar: its optimum from seed + 1e6
        xopt = compute_xopt(seed + 1000000, d)
    else:
        xopt = compute_xopt(seed, d)
    x_opt = xopt
    if function == 4:
        xopt = xopt.copy()
        xopt[::2] = np.abs(xopt[::2])
        x_opt = xopt
    elif function == 5:  # linear slope: the corner in the orthant of xopt
        xopt = x_opt = np.where(xopt < 0.0, -5.0, 5.0)
    elif function == 8:
        xopt = x_opt = 0.75 * xopt
    elif function in (9, 19):  # z = max(1, sqrt(D) / 8) R x + 1/2, no shift
        factor = max(1.0, math.sqrt(d) / 8.0)
        rotation = compute_rotation(seed, d)
        R = factor * rotation
        # best_parameter: f9 sums the rotation's columns, f19 the scaled matrix's
        x_opt = seq_sum((rotation if function == 9 else R).T) / (2.0 * factor)
        xopt = np.zeros(d)
    elif function in (6, 13):
        R = _rot_lambda(seed, d, math.sqrt(10.0))
    elif function in (10, 11, 12, 14):
        R = compute_rotation(seed + 1000000, d)
    elif function in (15, 16, 23):
        R = compute_rotation(seed + 1000000, d)
        base = {15: math.sqrt(10.0), 16: 1.0 / math.sqrt(100.0), 23: math.sqrt(100.0)}
        Q = _rot_lambda(seed, d, base[function])
        if function == 23:  # one map: R is Lambda^100 between the rotations
            R, Q = Q, None
    elif function == 7:
        # c_i = sqrt(pow(100 / 10, i / (D - 1))), as f_step_ellipsoid_raw computes it
        c = np.sqrt(powers(10.0, exponents(d)))
        R = _rows_scaled(seed, d, c)
        Q = compute_rotation(seed + 1000000, d)
    elif function in (17, 18):
        R = compute_rotation(seed + 1000000, d)
        conditioning = 10.0 if function == 17 else 1000.0
        Q = _rows_scaled(seed, d, powers(math.sqrt(conditioning), exponents(d)))
    elif function == 24:
        xopt = x_opt = np.where(gauss(d, seed) < 0.0, -1.25, 1.25)
        R = _rows_scaled(seed, d, powers(math.sqrt(100.0), exponents(d)))
        Q = compute_rotation(seed + 1000000, d)
    return xopt, R, Q, x_opt


def _frozen(a: np.ndarray) -> np.ndarray:
    if not a.flags.writeable:  # already kept
        return a
    a = np.array(a, dtype=np.float64)
    a.flags.writeable = False
    return a


@functools.cache
def _unused(d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The fields a function does not use (one read-only copy per dimension): a zero
    matrix, zero peaks, unit scales and zero heights."""
    return (_frozen(np.zeros((d, d))), _frozen(np.zeros((PEAKS, d))),
            _frozen(np.ones((PEAKS, d))), _frozen(np.zeros(PEAKS)))


@functools.cache
def instance_data(function: int, instance: int, dimension: int) -> Instance:
    """The data of ``function`` (1-24), ``instance`` (COCO's number) in ``dimension``
    dimensions, drawn once and kept (arguments checked by the caller)."""
    d = dimension
    seed = rseed(function, instance)
    zeros, peaks, scales, weights = _unused(d)
    if function in (21, 22):
        xopt, R, peaks, scales, weights = _gallagher(seed, d, 101 if function == 21 else 21)
        Q, x_opt = None, xopt
    elif function == 20:
        xopt, x_opt = _schwefel(seed, d)
        R = Q = None
    else:
        xopt, R, Q, x_opt = _draw(function, seed, d)
    fopt = compute_fopt(function, instance)
    f_opt = fopt + _schwefel_best_value(d) if function == 20 else fopt
    return Instance(_frozen(xopt), fopt, _frozen(zeros if R is None else R),
                    _frozen(zeros if Q is None else Q), _frozen(peaks), _frozen(scales),
                    _frozen(weights), _frozen(x_opt), f_opt)
