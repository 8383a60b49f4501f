"""A box optimiser on the (weighted) L1 objective, the paper's Eq. 17, as an estimator
(:class:`BoxSearch`): a swarm (SEDSABSO, BSO, LDWPSO) or an evosax strategy searches a box
around the a-priori parameters.

A box that is too small holds the fit back: parameters end on its faces and the fit is
worse than least squares, with nothing else to say so. The fit reports the parameters on
a face (``at_bounds`` in its settings) and warns when there are any. How the swarms fare
against least squares: docs/explanation/identification-defaults.md ("Not a swarm").
"""

from __future__ import annotations

import warnings
from typing import Any, ClassVar, cast

import equinox as eqx
import jax
import numpy as np

from ..._deprecation import caller_stacklevel
from ...optim._box import box_around, check_bounds
from ...optim._driver import minimise
from ...optim._fitness import L1Residual
from ...optim._registry import SWARMS, paper_solver
from ...optim._solver import AbstractSolver
from .._model._torque_model import TorqueModel
from .._options import as_float, as_floats, as_int, check_count
from ._estimator import EstimatorFit, FitProblem, Limits, check_sigma, check_weighting, weigh
from ._least_squares import SigmaOption, check_prior, prior_of
from ._row_fits import AbstractRowFit

#: A parameter within this fraction of the box's width of a face is on that face.
FACE_TOLERANCE = 1e-3

Box = tuple[float, float] | tuple[tuple[float, ...], tuple[float, ...]]


def _as_solver(solver: object) -> object:
    """A registered swarm's name as that swarm with the paper's settings (Sec. 5.2)."""
    return paper_solver(solver) if isinstance(solver, str) and solver in SWARMS else solver


def _pair(box: object) -> tuple[Any, Any] | None:
    """``box``'s two entries, or None if it has not two."""
    if not isinstance(box, (tuple, list, np.ndarray)) or len(box) != 2:
        return None
    return box[0], box[1]


def _as_box(box: object) -> object:
    """``(fraction, floor)`` as floats, ``(lower, upper)`` as tuples of floats; anything
    else as given, for the check."""
    pair = _pair(box)
    if pair is None:
        return box
    a, b = pair
    if np.ndim(a) == 0 and np.ndim(b) == 0:
        return as_float(a), as_float(b)
    return as_floats(a), as_floats(b)


def _check_box(box: object) -> None:
    """``box`` is ``(fraction, floor)`` (checked by :func:`~sedsabso_jax.box_around`) or
    ``(lower, upper)``, finite, ``lower < upper``."""
    pair = _pair(box)
    if pair is None:
        raise ValueError(f"box must be (fraction, floor) or (lower, upper) arrays, got "
                         f"{box!r}")
    a, b = pair
    if np.ndim(a) == 0 and np.ndim(b) == 0:
        box_around(np.zeros(1), a, b)
        return
    try:
        check_bounds(a, b)
    except ValueError as err:
        raise ValueError(f"box: {err}") from None


def on_faces(x: np.ndarray, lower: np.ndarray, upper: np.ndarray,
             rtol: float = FACE_TOLERANCE) -> np.ndarray:
    """Which entries of ``x`` lie on a face of the box ``[lower, upper]``: within ``rtol``
    of the box's width in that coordinate from its lower or upper bound."""
    margin = rtol * (upper - lower)
    return (x - lower <= margin) | (upper - x <= margin)


class BoxSearch(AbstractRowFit):
    """A box optimiser on the (weighted) L1 objective, Eq. 17: ``solver`` is anything
    :func:`~sedsabso_jax.minimise` runs (``SEDSABSO.paper()``, ``BSO()``, ``LDWPSO()``,
    ``Evosax("CMA_ES")``; a swarm's name: its paper settings), ``runs`` independent runs
    of ``iterations`` from PRNG ``seed``, the best kept.

    ``box``: ``(fraction, floor)`` searches ``centre +- max(fraction |centre|, floor)``
    around the ``prior`` (full parameters, default the robot's own) projected on the base
    parameters, the extra columns centred on 0; or explicit ``(lower, upper)`` arrays, one
    entry per model column.

    A parameter is on the box's face when it ends within :data:`FACE_TOLERANCE` (0.1 %)
    of the box's width in its coordinate from a bound: the fit's settings say how many
    and which (``at_bounds``), and a fit on all the data warns when any are: the box holds
    the fit back (widen it), or the search has not converged (a swarm clips its points to
    the box, and one stopped early leaves some on the faces even of a wide box)."""

    solver: AbstractSolver = eqx.field(converter=_as_solver)
    box: Box = eqx.field(default=(0.5, 0.5), converter=_as_box)
    runs: int = eqx.field(default=1, converter=as_int)
    iterations: int = eqx.field(default=600, converter=as_int)
    seed: int = eqx.field(default=0, converter=as_int)
    sigma: SigmaOption = eqx.field(default=None, converter=as_floats)
    prior: tuple[float, ...] | None = eqx.field(default=None, converter=as_floats)
    default_weighting: ClassVar[str] = "equal"
    costly: ClassVar[bool] = True
    norm: ClassVar[int] = 1
    registered_as: ClassVar[dict[str, dict[str, Any]]] = {
        name: {"solver": name} for name in SWARMS}

    def __check_init__(self):
        if not isinstance(self.solver, AbstractSolver):
            raise ValueError(f"solver must be an optimiser instance (e.g. SEDSABSO.paper(), "
                             f"Evosax('CMA_ES')), got {self.solver!r}")
        _check_box(self.box)
        check_count("runs", self.runs, 1)
        check_count("iterations", self.iterations, 1)
        check_count("seed", self.seed, 0)
        check_sigma(self.sigma)
        check_prior(self.prior)

    @property
    def name(self) -> str:
        return self.solver.label

    def bounds(self, model: TorqueModel) -> tuple[np.ndarray, np.ndarray, Any]:
        """``(lower, upper, setting)``: the box for ``model``'s columns (class docstring)."""
        d = model.dim
        if np.ndim(self.box[0]) == 1:
            lower, upper = (np.asarray(v, dtype=float) for v in self.box)
            if lower.shape != (d,):
                raise ValueError(f"box bounds must both have shape ({d},) (one per model "
                                 f"column), got {lower.shape} and {upper.shape}")
            return lower, upper, "explicit"
        centre = np.concatenate([np.asarray(model.base.project(prior_of(self.prior, model))),
                                 np.zeros(d - model.base.rank)])
        fraction, floor = cast(tuple[float, float], self.box)
        lower, upper = box_around(centre, fraction, floor)
        return lower, upper, {"fraction": fraction, "floor": floor, "centre": "prior"}

    def check(self, model: TorqueModel, limits: Limits) -> None:
        check_weighting(self, model, limits)
        self.bounds(model)

    def fit(self, problem: FitProblem) -> EstimatorFit:
        rows = weigh(problem, self.sigma)
        lower, upper, box_setting = self.bounds(problem.model)
        solver = self.solver
        res = minimise(L1Residual(rows.W, rows.b), solver, lower, upper,
                       key=jax.random.key(self.seed), iterations=self.iterations,
                       runs=self.runs)
        X, f = np.atleast_2d(np.asarray(res.x)), np.atleast_1d(np.asarray(res.f))
        best = int(np.argmin(f))
        x = np.asarray(X[best], dtype=float)
        faces = [problem.model.names[i] for i in np.flatnonzero(on_faces(x, lower, upper))]
        if faces and problem.warn:
            warnings.warn(f"{self.name}: {len(faces)} of {len(x)} parameters ended on the "
                          f"box's faces ({', '.join(faces)}): the box may hold the fit back "
                          f"(widen it: BoxSearch(..., box=(fraction, floor)) with a larger "
                          f"fraction or floor, or wider bounds), or the search stopped short "
                          f"of the optimum (more iterations)", UserWarning,
                          stacklevel=caller_stacklevel())
        hyper = solver.hyperparameters()
        extra = {"box": box_setting, "runs": self.runs, "iterations": self.iterations,
                 "seed": self.seed, "solver": hyper, "best_run": best,
                 "f_runs": [float(v) for v in f], "compile_s": float(res.compile_s or 0.0),
                 "run_s": float(res.run_s or 0.0),
                 "at_bounds": {"count": len(faces), "names": faces,
                               "tolerance": FACE_TOLERANCE}}
        return EstimatorFit(x, None, rows.sigma, rows.factor0, rows.W, rows.b, res, extra)
