"""Baselines for the identification problem of the paper's Eq. 17, ``f(p) = sum |W p - tau|``.

* :func:`ols`: ordinary least squares, ``min ||W p - tau||_2`` by a column-pivoted QR
  factorisation (the classical identification estimate; :mod:`._linear`).
* :func:`least_squares`: the same L2 problem solved iteratively with optimistix
  (Levenberg-Marquardt or Gauss-Newton), the gradient-based counterpart of the swarms.
* :func:`l1_optimum`: the exact minimiser of Eq. 17 itself, as a linear programme
  (HiGHS, :func:`._linear.l1_solve`). Eq. 17 is convex and piecewise linear, so its minimum
  is global and the LP reaches it up to the solver's tolerances: no optimiser of Eq. 17
  (swarm or otherwise) can return a lower ``f``. It is the floor against which
  :func:`gap_to_optimum` measures the others.

Every baseline returns a :class:`~sedsabso_jax.Result` whose ``f`` is the Eq. 17
value at its ``x``, with empty histories.
"""

from __future__ import annotations

import functools
import time
import warnings
from typing import Any, TypeAlias

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, ArrayLike, Float, Int

from .. import _x64
from ._fitness import L1Residual
from ._linear import factorize, l1_solve
from ._result import Result

#: An identification problem: Eq. 17 as an :class:`~sedsabso_jax.L1Residual` or ``(W, tau)``.
L1Problem: TypeAlias = L1Residual | tuple[ArrayLike, ArrayLike]

_SOLVERS = {"LM": optx.LevenbergMarquardt, "GN": optx.GaussNewton}


def _as_problem(problem) -> L1Residual:
    if isinstance(problem, L1Residual):
        return problem
    if isinstance(problem, tuple) and len(problem) == 2:
        return L1Residual(*problem)
    raise TypeError(f"problem must be an L1Residual or a tuple (W, tau), got {type(problem)}")


def _result(method, problem, x, n_evaluations=0, compile_s=0.0, run_s=0.0) -> Result:
    x = np.asarray(x, dtype=float)
    f = np.sum(np.abs(np.asarray(problem.W, float) @ x - np.asarray(problem.tau, float)))
    return Result(
        method=method, x=jnp.asarray(x), f=jnp.asarray(f),
        history_f=jnp.zeros((0,), dtype=float), history_n=jnp.zeros((0,), dtype=int),
        sa_accepted=jnp.asarray(0), n_evaluations=jnp.asarray(int(n_evaluations)),
        n_nonfinite=jnp.asarray(0), compile_s=float(compile_s), run_s=float(run_s),
    )


def ols(problem: L1Problem) -> Result:
    """Ordinary least squares ``argmin ||W x - tau||_2`` (method ``"OLS"``), by the
    column-pivoted QR of :func:`._linear.factorize`. If ``W`` is rank deficient or poorly
    conditioned (judged on unit-norm columns), warns with the condition number and the
    columns concerned; a rank-deficient ``W`` gets the minimum-norm solution."""
    problem = _as_problem(problem)
    W, tau = np.asarray(problem.W, float), np.asarray(problem.tau, float)
    t0 = time.perf_counter()
    factor = factorize(W, tau)
    factor.warn("ols: W")
    x = factor.solve()
    return _result("OLS", problem, x, run_s=time.perf_counter() - t0)


def _residual(x, args):
    W, tau = args
    return W @ x - tau


@functools.lru_cache(maxsize=16)
def _compiled(method, rtol, atol, max_steps, shape):
    """The compiled solve for one configuration and problem shape; cached, so a second call
    with the same configuration reports ``compile_s = 0``."""
    solver = _SOLVERS[method](rtol=rtol, atol=atol)

    def solve(W: Float[Array, "m d"], tau: Float[Array, " m"], x0: Float[Array, " d"]
              ) -> tuple[Float[Array, " d"], Any, Int[Array, ""]]:
        sol: optx.Solution = optx.least_squares(_residual, solver, x0, (W, tau),
                                                max_steps=max_steps, throw=False)
        return sol.value, sol.result, sol.stats["num_steps"]

    m, d = shape
    W, tau, x0 = (jax.ShapeDtypeStruct(s, jnp.float64) for s in ((m, d), (m,), (d,)))
    return jax.jit(solve).lower(W, tau, x0).compile()


def least_squares(problem: L1Problem, method: str = "LM", x0: Float[ArrayLike, " d"] | None = None,
                  max_steps: int = 256,
                  rtol: float = 1e-10, atol: float = 1e-10) -> Result:
    """``argmin ||W x - tau||_2`` by optimistix's Levenberg-Marquardt (``method="LM"``) or
    Gauss-Newton (``"GN"``) from ``x0`` (default zeros). Warns if the solver stops without
    success (e.g. ``max_steps`` reached). ``n_evaluations`` is the number of steps taken.
    Always solved in float64: a float32 problem is promoted (optimistix 0.1.0's
    Levenberg-Marquardt fails on float32 input under JAX's x64 mode), which needs JAX's
    64-bit mode on.
    """
    _x64.require(f"least_squares ({method})")
    if method not in _SOLVERS:
        raise ValueError(f"method must be one of {sorted(_SOLVERS)}, got {method!r}")
    problem = _as_problem(problem)
    d = problem.dim
    x0 = np.zeros(d) if x0 is None else np.asarray(x0, dtype=float)
    if x0.shape != (d,):
        raise ValueError(f"x0 must have shape ({d},) to match W's {d} columns, got {x0.shape}")
    if not (isinstance(max_steps, int) and max_steps > 0):
        raise ValueError(f"max_steps must be a positive int, got {max_steps!r}")
    W, tau = jnp.asarray(problem.W, jnp.float64), jnp.asarray(problem.tau, jnp.float64)
    hits, t0 = _compiled.cache_info().hits, time.perf_counter()
    compiled = _compiled(method, float(rtol), float(atol), max_steps, W.shape)
    reused = _compiled.cache_info().hits > hits
    compile_s = 0.0 if reused else time.perf_counter() - t0
    t0 = time.perf_counter()
    x, result, n_steps = compiled(W, tau, jnp.asarray(x0, jnp.float64))
    x = jax.block_until_ready(x)
    run_s = time.perf_counter() - t0
    if not bool(result == optx.RESULTS.successful):
        why = optx.RESULTS[result]  # type: ignore[misc, type-arg, valid-type]
        warnings.warn(f"least_squares ({method}): optimistix did not succeed after "
                      f"{int(n_steps)} steps: {why}", stacklevel=2)
    return _result(method, problem, x, int(n_steps), compile_s, run_s)


def l1_optimum(problem: L1Problem) -> Result:
    """The exact minimiser of Eq. 17 (method ``"L1-LP"``) by linear programming
    (:func:`._linear.l1_solve`: the dual LP with HiGHS, polished at its vertex).
    ``n_evaluations`` is HiGHS's iteration count. Raises ``RuntimeError`` with HiGHS's
    message if the LP fails."""
    problem = _as_problem(problem)
    W, tau = np.asarray(problem.W, float), np.asarray(problem.tau, float)
    t0 = time.perf_counter()
    x, nit = l1_solve(W, tau)
    return _result("L1-LP", problem, x, nit, run_s=time.perf_counter() - t0)


#: Below this fraction of the data's size (``sum |tau|``) a fitness is rounding: on
#: noise-free data the L1 optimum and a least-squares fit's are ~1e-9 of it.
ROUNDING = 1e-9


def gap_to_optimum(result_f: Float[ArrayLike, "*shape"], l1_f: Float[ArrayLike, "*shape"],
                   scale: float = 0.0) -> float | Float[np.ndarray, "*shape"]:
    """Relative gap ``(f - f_opt) / max(f_opt, 1e-9 scale)`` of a fitness ``result_f``
    above the L1 optimum ``l1_f`` (from :func:`l1_optimum`); 0 at the optimum. ``scale``:
    the size of the data, e.g. ``sum |tau|``: on noise-free data ``f_opt`` is rounding
    noise (~1e-9) and a least-squares fit can land a little below it, which without a
    scale reads as a gap near -1; with it such gaps are ~0. Scalars give a float, arrays an
    array (broadcast)."""
    f, f_opt = np.asarray(result_f, float), np.asarray(l1_f, float)
    floor = np.maximum(f_opt, max(ROUNDING * float(scale), np.finfo(float).tiny))
    gap = (f - f_opt) / floor
    return float(gap) if gap.ndim == 0 else gap
