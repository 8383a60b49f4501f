"""COCO's legacy random generator of the BBOB testbed, bit for bit, in NumPy float64.

What COCO's ``suite_bbob_legacy_code.c`` (coco-experiment 2.8.2, github numbbo/coco
``code-experiments/src/``) draws an instance from: ``bbob2009_unif`` (a Park-Miller
"minimal standard" LCG, 16807 mod 2^31 - 1 by Schrage's method, shuffled through a
32-entry Bays-Durham table), ``bbob2009_gauss`` (Box-Muller from ``2 N`` uniforms),
``bbob2009_compute_xopt``, ``bbob2009_compute_fopt`` and ``bbob2009_compute_rotation``
(Gram-Schmidt on a Gaussian matrix). The generator runs on Python integers and the C
library's ``log``, ``cos`` and ``pow`` (``math``, the same libm as COCO's C), and every
sum is taken in COCO's order (``np.cumsum``, sequential), so the instance data equal
COCO's to the last bit.

Hansen et al., "Real-parameter black-box optimization benchmarking 2009: noiseless
functions definitions", INRIA RR-6829 (2009), section 2 for the instance construction.
"""

from __future__ import annotations

import functools
import math

import numpy as np

#: COCO's ``coco_pi``.
PI = 3.14159265358979323846
#: bbob2009_compute_rotation fills a ``double gvect[2000]``: at most 44 x 44.
MAX_DIMENSION = 44


def _lcg(seed: int) -> int:
    """One step of the minimal standard generator (Schrage's factorisation)."""
    tmp = math.floor(seed / 127773.0)
    seed = 16807 * (seed - tmp * 127773) - 2836 * tmp
    return seed + 2147483647 if seed < 0 else seed


def unif(n: int, seed: int) -> np.ndarray:
    """``bbob2009_unif``: ``n`` uniforms in (0, 1] from ``seed``."""
    seed = max(abs(int(seed)), 1)
    table = [0] * 32
    for i in range(39, -1, -1):  # warm-up: 8 steps discarded, then the shuffle table
        seed = _lcg(seed)
        if i < 32:
            table[i] = seed
    out = []
    current = table[0]
    for _ in range(n):
        seed = _lcg(seed)
        slot = math.floor(current / 67108865.0)
        current = table[slot]
        table[slot] = seed
        out.append(current / 2.147483647e9)
    r = np.array(out, dtype=np.float64)
    r[r == 0.0] = 1e-99
    return r


def gauss(n: int, seed: int) -> np.ndarray:
    """``bbob2009_gauss``: ``n`` standard normals (Box-Muller from ``unif(2 n, seed)``)."""
    u = unif(2 * n, seed).tolist()
    g = np.array([math.sqrt(-2 * math.log(a)) * math.cos(2 * PI * b)
                  for a, b in zip(u[:n], u[n:])])
    g[g == 0.0] = 1e-99
    return g


def compute_xopt(seed: int, dimension: int) -> np.ndarray:
    """``bbob2009_compute_xopt``: the optimum, uniform on a 1e-4 grid of [-4, 4)."""
    x = 8 * np.floor(1e4 * unif(dimension, seed)) / 1e4 - 4
    x[x == 0.0] = -1e-5
    return x


def fopt_seed(function: int) -> int:
    """The seed ``bbob2009_compute_fopt`` uses for a noiseless function: its number, but
    3 for f4 and 17 for f18 (they share f3's and f17's draws)."""
    return {4: 3, 18: 17}.get(function, function)


def compute_fopt(function: int, instance: int) -> float:
    """``bbob2009_compute_fopt``: the optimal value, a Cauchy-like draw rounded to 0.01
    and clipped to [-1000, 1000]."""
    seed = fopt_seed(function) + 10000 * instance
    ratio = gauss(1, seed)[0] / gauss(1, seed + 1)[0]
    return min(1000.0, max(-1000.0, math.floor(100.0 * 100.0 * ratio + 0.5) / 100.0))


def seq_sum(a: np.ndarray, axis: int = -1) -> np.ndarray:
    """Sum along ``axis`` from the first element to the last, one addition at a time, as
    a C loop does (NumPy's ``sum`` adds pairwise: its last bit may differ)."""
    return np.take(np.cumsum(a, axis=axis), -1, axis=axis)


@functools.lru_cache(maxsize=16)
def compute_rotation(seed: int, dimension: int) -> np.ndarray:
    """``bbob2009_compute_rotation``: a random orthogonal matrix, Gram-Schmidt on the
    columns of a Gaussian matrix filled column by column (read-only; the last few kept,
    as several functions take the same one twice)."""
    B = gauss(dimension * dimension, seed).reshape(dimension, dimension)  # row i: column i
    for i in range(dimension):
        for j in range(i):
            B[i] -= np.cumsum(B[i] * B[j])[-1] * B[j]
        B[i] /= math.sqrt(np.cumsum(B[i] * B[i])[-1])
    B = B.T
    B.flags.writeable = False
    return B


def exponents(dimension: int) -> np.ndarray:
    """``i / (D - 1)`` for ``i = 0 .. D - 1``, the exponent of every conditioning."""
    return np.arange(dimension) / (dimension - 1.0)


def powers(base: float, exponent: np.ndarray) -> np.ndarray:
    """``pow(base, e)`` for each ``e`` with the C library's ``pow``."""
    return np.array([math.pow(base, float(e)) for e in exponent])


def rotated_conditioning(rot1: np.ndarray, diagonal: np.ndarray, rot2: np.ndarray
                         ) -> np.ndarray:
    """``M = rot1 diag(diagonal) rot2`` summed as COCO's allocators sum it
    (``M[i, j] += rot1[i, k] * diagonal[k] * rot2[k, j]`` over ``k`` in order)."""
    terms = (rot1 * diagonal)[:, None, :] * rot2.T[None, :, :]
    return seq_sum(terms)
