"""How a fit searches the few parameters of a torque model that enter its columns
nonlinearly (:meth:`~sedsabso_jax.identification.AbstractTerm.nonlinear`; in log scale,
within bounds): one object per method, carrying its options.

- :class:`CoordinateSearch` (the default): sweeps of every coordinate on a grid at once,
  a population of ``k x points`` trials in one compiled call, the grid shrinking around
  the best; the trials of one sweep move one coordinate each, and the sweep keeps the
  moves together where they lower the loss together (the coordinates are nearly
  separable: each joint's scale acts on its own rows);
- :class:`PopulationSearch`: any optimiser :func:`~sedsabso_jax.minimise` runs (the
  package's swarms, an evosax strategy) with a budget of evaluations;
- :class:`LeastSquaresSearch`: optimistix's Levenberg-Marquardt on the residual, its
  Jacobian in forward mode through the columns (a local method, from the start).

Which is the default was measured on the shipped robots (docs/how-to/friction-at-rest.md).
"""

from __future__ import annotations

import abc
import time
from typing import Any, ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ...optim._budget import iterations_for_budget
from ...optim._driver import minimise
from ...optim._solver import AbstractSolver
from .._options import as_float, as_int, check_count, check_number
from ._newton import polish
from ._problem import COMPILED, Searched, SearchProblem, fitness, losses, on_bounds


class AbstractSearch(eqx.Module):
    """A method that searches the parameters ``u`` of a :class:`~._problem.SearchProblem`
    within ``[lower, upper]`` from ``start`` (:meth:`search`); ``searches``: False for
    :class:`Held`, which keeps the model's values and needs no problem."""

    label: eqx.AbstractClassVar[str]
    searches: ClassVar[bool] = True

    @abc.abstractmethod
    def search(self, problem: SearchProblem, start: np.ndarray, lower: np.ndarray,
               upper: np.ndarray) -> Searched:
        """The best ``u`` found (module docstring)."""

    def settings(self) -> dict:
        """The method and its options, for the report."""
        import dataclasses

        return {"method": self.label, **{f.name: getattr(self, f.name)
                                         for f in dataclasses.fields(self)}}


class CoordinateSearch(AbstractSearch):
    """Sweeps of every coordinate on a grid of ``points`` values at once (module
    docstring): the first sweep's grid spans the bounds, each later one spans one of the
    last grid's steps either side of the best (``(points - 1) / 2`` times finer: the
    minimum of a function of one variable lies within a step of its best grid point);
    ``sweeps`` sweeps, the last also trying the vertex of the parabola through each
    coordinate's best value and its two neighbours on its grid; then at most ``newton``
    steps of Newton's method to the minimum (:func:`~._newton.polish`; 0: none).

    A trial counts as better only where it lowers the loss by more than ``rtol`` of it
    (the loss's rounding, about 1e-14 of it, never decides), and of trials within that
    of each other the first on the grid wins: the path, and with the polish the end, do
    not turn on the last bits of the loss, which differ between processors."""

    points: int = eqx.field(default=7, converter=as_int)
    sweeps: int = eqx.field(default=3, converter=as_int)
    newton: int = eqx.field(default=10, converter=as_int)
    rtol: float = eqx.field(default=1e-10, converter=as_float)
    label: ClassVar[str] = "coordinate search"

    def __check_init__(self):
        check_count("points", self.points, 5)
        check_count("sweeps", self.sweeps, 1)
        check_count("newton", self.newton, 0)
        check_number("rtol", self.rtol, strict=True)

    def search(self, problem: SearchProblem, start: np.ndarray, lower: np.ndarray,
               upper: np.ndarray) -> Searched:
        t0 = time.perf_counter()
        u = on_bounds(np.asarray(start, dtype=float), lower, upper)
        k, G = u.size, self.points
        best = float(losses(problem, u[None])[0])
        evaluations = 1
        centre, half = (lower + upper) / 2, (upper - lower) / 2
        flat = np.zeros(k, dtype=bool)
        for sweep in range(self.sweeps):
            tol = self.rtol * abs(best)
            grid = on_bounds(centre[:, None] + half[:, None] * np.linspace(-1, 1, G),
                             lower[:, None], upper[:, None])  # (k, G)
            trials = np.repeat(u[None], k * G, 0)
            trials[np.arange(k * G), np.repeat(np.arange(k), G)] = grid.reshape(-1)
            f = np.array(losses(problem, trials)).reshape(k, G)
            evaluations += k * G
            if sweep == 0:  # the grid spans the box: a coordinate it does not feel stays
                flat = f.max(axis=1) - f.min(axis=1) <= tol
            f[flat] = best
            lowest = f.min(axis=1)
            at = np.argmax(f <= lowest[:, None] + tol, axis=1)  # the first within tol
            better = lowest < best - tol
            moved = u.copy()
            moved[better] = grid[better, at[better]]
            candidates = [moved]  # the moves together; in the last sweep, refined too
            if sweep == self.sweeps - 1:
                candidates.append(_parabola(moved, grid, f, at, lower, upper, tol))
            tried = losses(problem, np.stack(candidates))
            evaluations += len(candidates)
            together = float(tried.min())
            single = int(np.argmax(lowest <= lowest.min() + tol))
            if together < best - tol and together <= lowest[single] + tol:
                u, best = candidates[int(np.argmax(tried <= together + tol))], together
            elif lowest[single] < best - tol:
                u = u.copy()
                u[single] = grid[single, at[single]]
                best = float(lowest[single])
            centre, half = u, half * 2 / (G - 1)
        extra: dict = {"held": flat}
        if self.newton:
            p = polish(problem, u, best, lower, upper, self.rtol, self.newton, k * G, flat)
            u, best, evaluations = p.u, p.loss, evaluations + p.evaluations
            extra.update(newton_steps=p.steps, converged=p.converged)
        return Searched(u, best, evaluations, time.perf_counter() - t0, **extra)


class Held(AbstractSearch):
    """No search: the parameters stay at the model's values. A fitted model carries the
    values its search found with this method (:attr:`~sedsabso_jax.Identification.model`),
    so that fitting it again fits the linear values of the same model;
    ``dataclasses.replace(model, search=None)`` searches again from them."""

    label: ClassVar[str] = "held at the values given"
    searches: ClassVar[bool] = False

    def search(self, problem: SearchProblem, start: np.ndarray, lower: np.ndarray,
               upper: np.ndarray) -> Searched:
        return Searched(np.clip(np.asarray(start, dtype=float), lower, upper), float("nan"),
                        0, 0.0)


#: The search method of a fitted model (:class:`Held`).
HELD = Held()


def _parabola(u, grid, f, at, lower, upper, tol):
    """``u`` with each coordinate whose best grid value is inside its grid moved to the
    vertex of the parabola through that value and its two neighbours, where they are
    apart and their losses differ by more than ``tol`` (else the vertex is the
    rounding's)."""
    out = u.copy()
    for j in np.flatnonzero((at > 0) & (at < grid.shape[1] - 1)):
        x, y = grid[j, at[j] - 1:at[j] + 2], f[j, at[j] - 1:at[j] + 2]
        if not np.all(np.diff(x) > 0) or np.ptp(y) <= tol:  # on a bound, or flat
            continue
        d1, d2 = (y[1] - y[0]) / (x[1] - x[0]), (y[2] - y[1]) / (x[2] - x[1])
        curvature = (d2 - d1) / (x[2] - x[0])
        if curvature > 0:
            out[j] = np.clip((x[0] + x[1]) / 2 - d1 / (2 * curvature), x[0], x[2])
    return np.clip(out, lower, upper)


class PopulationSearch(AbstractSearch):
    """Any optimiser :func:`~sedsabso_jax.minimise` runs (``SEDSABSO()``, ``LDWPSO()``,
    ``Evosax("CMA_ES")``, ...) with about ``evaluations`` evaluations of the loss, one
    run from PRNG ``seed``."""

    solver: AbstractSolver
    evaluations: int = eqx.field(default=1200, converter=as_int)
    seed: int = eqx.field(default=0, converter=as_int)
    label: ClassVar[str] = "population search"

    def __check_init__(self):
        if not isinstance(self.solver, AbstractSolver):
            raise ValueError(f"solver must be an optimiser (LDWPSO(), SEDSABSO(), "
                             f"Evosax('CMA_ES'), ...), got {self.solver!r}")
        check_count("evaluations", self.evaluations, 1)
        check_count("seed", self.seed, 0)

    def search(self, problem: SearchProblem, start: np.ndarray, lower: np.ndarray,
               upper: np.ndarray) -> Searched:
        t0 = time.perf_counter()
        iterations = iterations_for_budget(self.solver, self.evaluations, lower.size)
        with COMPILED:
            res = minimise(fitness, self.solver, lower, upper, key=jax.random.key(self.seed),
                           iterations=iterations, args=problem)
            u = np.asarray(res.x, dtype=float).reshape(-1)
            f = float(np.asarray(res.f).reshape(-1)[0])
            count = int(np.asarray(res.n_evaluations).reshape(-1)[0])
        # the start competes: a search never ends worse than where it began
        f_start = float(losses(problem, np.clip(start, lower, upper)[None])[0])
        if f_start < f:
            u, f = np.clip(start, lower, upper), f_start
        return Searched(u, f, count + 1, time.perf_counter() - t0)

    def settings(self) -> dict:
        return {"method": self.label, "solver": self.solver.label,
                "evaluations": self.evaluations, "seed": self.seed}


def _clipped(u, args):
    problem, lower, upper = args
    return problem.residual(jnp.clip(u, lower, upper))


class LeastSquaresSearch(AbstractSearch):
    """optimistix's Levenberg-Marquardt on the problem's residual from the start, at most
    ``max_steps`` steps (each a Jacobian of ``k`` forward directions), the trial clipped
    to the bounds."""

    max_steps: int = eqx.field(default=100, converter=as_int)
    rtol: float = eqx.field(default=1e-8, converter=as_float)
    atol: float = eqx.field(default=1e-8, converter=as_float)
    label: ClassVar[str] = "Levenberg-Marquardt"

    def __check_init__(self):
        check_count("max_steps", self.max_steps, 1)
        check_number("rtol", self.rtol, strict=True)
        check_number("atol", self.atol, strict=True)

    def search(self, problem: SearchProblem, start: np.ndarray, lower: np.ndarray,
               upper: np.ndarray) -> Searched:
        t0 = time.perf_counter()
        with COMPILED:
            u, steps = _levenberg_marquardt(problem, jnp.asarray(np.clip(start, lower, upper)),
                                            jnp.asarray(lower), jnp.asarray(upper),
                                            self.max_steps, self.rtol, self.atol)
            u, steps = np.clip(np.asarray(u, dtype=float), lower, upper), int(steps)
        return Searched(u, float(losses(problem, u[None])[0]),
                        (steps + 1) * (u.size + 1), time.perf_counter() - t0)


@eqx.filter_jit
def _levenberg_marquardt(problem: Any, u, lower, upper, max_steps: int, rtol: float,
                         atol: float):
    import optimistix as optx

    sol: Any = optx.least_squares(_clipped, optx.LevenbergMarquardt(rtol=rtol, atol=atol), u,
                             args=(problem, lower, upper), max_steps=max_steps, throw=False)
    return sol.value, sol.stats["num_steps"]
