"""The identification estimators, one class each (interface: :mod:`._fitting`).

- :class:`OLS`: least squares by column-pivoted QR (:mod:`sedsabso_jax.optim._linear`);
- :class:`WLS`: the same on rows divided by each joint's sigma, by default Gautier's
  two-step estimate from an OLS pass's residuals;
- :class:`L1`: the exact minimiser of the summed absolute residual (the paper's Eq. 17)
  as the dual linear programme (HiGHS);
- :class:`LevenbergMarquardt`: optimistix's Levenberg-Marquardt on the L2 problem;
- :class:`BoxSearch`: any optimiser :func:`~sedsabso_jax.minimise` runs (the paper's
  swarms SEDSABSO, BSO, LDWPSO, or an evosax strategy) on the weighted L1 objective, in a
  box around the a-priori parameters;
- :class:`PhysicallyConsistent`: least squares over full link parameters a real body can
  have (:mod:`._physical`; Clarabel through cvxpy), optionally pulled toward a prior.

Every one takes ``sigma`` (:func:`~._fitting.weigh`); L1 and the box searches then minimise
the weighted L1 norm. Each is built with its options, checked there::

    WLS("limits"), BoxSearch(SEDSABSO.paper(), runs=3), PhysicallyConsistent(OLS(),
    prior_strength=1e-4)
"""

from __future__ import annotations

import dataclasses
import numbers
from collections.abc import Sequence
from typing import Any, ClassVar

import equinox as eqx
import jax
import numpy as np
from jaxtyping import ArrayLike, Float

from ..optim._baselines import least_squares
from ..optim._box import box_around, check_bounds
from ..optim._driver import minimise
from ..optim._fitness import L1Residual
from ..optim._linear import l1_solve
from ..optim._registry import SWARMS
from ._fitting import Estimator, EstimatorFit, FitProblem, Limits, Sigma, check_sigma, weigh
from ._model import TorqueModel
from ._physical import PSD_MARGIN, fit_physical


def _count(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _non_negative(name: str, value, strict: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a number {'>' if strict else '>='} 0, got {value!r}")
    v = float(value)
    if not (np.isfinite(v) and (v > 0 if strict else v >= 0)):
        raise ValueError(f"{name} must be a number {'>' if strict else '>='} 0, got {value!r}")
    return v


def _prior(value) -> tuple[float, ...] | None:
    """A full a-priori parameter vector (12 per link; its length is checked against the
    robot), kept as a tuple, or None (the robot's own parameters)."""
    if value is None:
        return None
    v = np.asarray(value, dtype=float)
    if v.ndim != 1 or not np.all(np.isfinite(v)):
        raise ValueError(f"prior must be finite full parameters (12 per link), got shape "
                         f"{v.shape}")
    return tuple(float(x) for x in v)


def prior_of(prior: Float[ArrayLike, " p"] | Sequence[float] | None, model: TorqueModel
             ) -> Float[np.ndarray, " p"]:
    """The full a-priori parameters: ``prior``, or the robot's own; checked."""
    robot = model.robot
    p = np.asarray(robot.params if prior is None else prior, dtype=float)
    if p.shape != (robot.n_params,) or not np.all(np.isfinite(p)):
        raise ValueError(f"prior must be {robot.n_params} finite full parameters (12 per "
                         f"link), got shape {p.shape}")
    return p


@dataclasses.dataclass(frozen=True)
class OLS(Estimator):
    """Ordinary least squares (column-pivoted QR; the minimum-norm solution when the rows
    leave columns unidentifiable). ``sigma`` weights the rows (:func:`~._fitting.weigh`)."""

    sigma: Any = None
    registered_as: ClassVar[tuple[str, ...]] = ("OLS",)
    name: ClassVar[str] = "OLS"
    normal_equations: ClassVar[bool] = True

    def __post_init__(self):
        object.__setattr__(self, "sigma", check_sigma(self.sigma))

    def fit(self, problem: FitProblem) -> EstimatorFit:
        rows = weigh(problem, self.sigma, default=self.default_weighting, factor=True)
        return EstimatorFit(rows.weighted_factor.solve(), None, rows.sigma, rows.factor0, rows.W,
                            rows.b, None, {})


@dataclasses.dataclass(frozen=True)
class WLS(OLS):
    """Weighted least squares: :class:`OLS` on rows divided by each joint's ``sigma``;
    ``"residual"`` (the default, also for None) is Gautier's two-step estimate."""

    sigma: Any = "residual"
    registered_as: ClassVar[tuple[str, ...]] = ("WLS",)
    name: ClassVar[str] = "WLS"
    default_weighting: ClassVar[str] = "residual"


@dataclasses.dataclass(frozen=True)
class L1(Estimator):
    """The exact minimiser of the (weighted) summed absolute residual, Eq. 17, as the dual
    linear programme (HiGHS); its iteration count goes to the settings."""

    sigma: Any = None
    registered_as: ClassVar[tuple[str, ...]] = ("L1",)
    name: ClassVar[str] = "L1"

    def __post_init__(self):
        object.__setattr__(self, "sigma", check_sigma(self.sigma))

    def fit(self, problem: FitProblem) -> EstimatorFit:
        rows = weigh(problem, self.sigma)
        x, iterations = l1_solve(rows.W, rows.b)
        return EstimatorFit(np.asarray(x, dtype=float), None, rows.sigma, rows.factor0, rows.W,
                            rows.b, None, {"lp_iterations": iterations})


@dataclasses.dataclass(frozen=True)
class LevenbergMarquardt(Estimator):
    """optimistix's Levenberg-Marquardt on the (weighted) L2 problem, columns scaled to unit
    norm, from zero (:func:`sedsabso_jax.baselines.least_squares`)."""

    sigma: Any = None
    max_steps: int = 256
    rtol: float = 1e-10
    atol: float = 1e-10
    registered_as: ClassVar[tuple[str, ...]] = ("LM",)
    name: ClassVar[str] = "LM"

    def __post_init__(self):
        object.__setattr__(self, "sigma", check_sigma(self.sigma))
        object.__setattr__(self, "max_steps", _count("max_steps", self.max_steps, 1))
        object.__setattr__(self, "rtol", _non_negative("rtol", self.rtol, strict=True))
        object.__setattr__(self, "atol", _non_negative("atol", self.atol, strict=True))

    def fit(self, problem: FitProblem) -> EstimatorFit:
        rows = weigh(problem, self.sigma)
        norms = np.linalg.norm(rows.W, axis=0)
        scale = np.where(norms > 0, norms, 1.0)
        result = least_squares(L1Residual(rows.W / scale, rows.b), "LM",
                               max_steps=self.max_steps, rtol=self.rtol, atol=self.atol)
        x = np.asarray(result.x, dtype=float) / scale
        extra = {"steps": int(result.n_evaluations), "compile_s": float(result.compile_s or 0.0),
                 "run_s": float(result.run_s or 0.0)}
        return EstimatorFit(x, None, rows.sigma, rows.factor0, rows.W, rows.b, result, extra)


def _solver_name(solver) -> str:
    label = getattr(solver, "label", None)
    if isinstance(label, str):
        return label
    if type(solver).__name__ == "Evosax":
        return f"evosax {solver.name}"
    return type(solver).__name__


def _box(box):
    """``box`` as kept: ``(fraction, floor)`` floats, or explicit ``(lower, upper)`` tuples,
    checked (finite; lower < upper)."""
    try:
        a, b = box
    except (TypeError, ValueError):
        raise ValueError(f"box must be (fraction, floor) or (lower, upper) arrays, got "
                         f"{box!r}") from None
    if np.ndim(a) == 0 and np.ndim(b) == 0:
        box_around(np.zeros(1), a, b)  # checks (fraction, floor)
        return float(a), float(b)
    try:
        lower, upper = check_bounds(a, b)
    except ValueError as err:
        raise ValueError(f"box: {err}") from None
    return tuple(lower.tolist()), tuple(upper.tolist())


@dataclasses.dataclass(frozen=True)
class BoxSearch(Estimator):
    """A box optimiser on the (weighted) L1 objective, Eq. 17: ``solver`` is anything
    :func:`~sedsabso_jax.minimise` runs (``SEDSABSO.paper()``, ``BSO()``, ``LDWPSO()``,
    ``Evosax("CMA_ES")``), ``runs`` independent runs of ``iterations`` from PRNG ``seed``,
    the best kept.

    ``box``: ``(fraction, floor)`` searches ``centre +- max(fraction |centre|, floor)``
    around the ``prior`` (full parameters, default the robot's own) projected on the base
    parameters, the extra columns centred on 0; or explicit ``(lower, upper)`` arrays, one
    entry per model column."""

    solver: Any
    box: Any = (0.5, 0.5)
    runs: int = 1
    iterations: int = 600
    seed: int = 0
    sigma: Any = None
    prior: Any = None
    registered_as: ClassVar[tuple[str, ...]] = tuple(SWARMS)

    def __post_init__(self):
        if not isinstance(self.solver, eqx.Module):  # a solver checks itself when built
            raise ValueError(f"solver must be an optimiser instance (e.g. SEDSABSO.paper(), "
                             f"Evosax('CMA_ES')), got {self.solver!r}")
        object.__setattr__(self, "box", _box(self.box))
        object.__setattr__(self, "runs", _count("runs", self.runs, 1))
        object.__setattr__(self, "iterations", _count("iterations", self.iterations, 1))
        object.__setattr__(self, "seed", _count("seed", self.seed, 0))
        object.__setattr__(self, "sigma", check_sigma(self.sigma))
        object.__setattr__(self, "prior", _prior(self.prior))

    @classmethod
    def from_name(cls, name: str, **options: Any) -> BoxSearch:
        """The swarm ``name`` with the paper's settings (Sec. 5.2) in a box search."""
        out = super().from_name(name, solver=SWARMS[name].paper(), **options)
        assert isinstance(out, BoxSearch)
        return out

    @property
    def name(self) -> str:
        return _solver_name(self.solver)

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
        fraction, floor = self.box
        lower, upper = box_around(centre, fraction, floor)
        return lower, upper, {"fraction": fraction, "floor": floor, "centre": "prior"}

    def check(self, model: TorqueModel, limits: Limits) -> None:
        super().check(model, limits)
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
        hyper = solver.hyperparameters()
        extra = {"box": box_setting, "runs": self.runs, "iterations": self.iterations,
                 "seed": self.seed, "solver": hyper, "best_run": best,
                 "f_runs": [float(v) for v in f], "compile_s": float(res.compile_s or 0.0),
                 "run_s": float(res.run_s or 0.0)}
        return EstimatorFit(np.asarray(X[best], dtype=float), None, rows.sigma, rows.factor0,
                            rows.W, rows.b, res, extra)


@dataclasses.dataclass(frozen=True)
class PhysicallyConsistent(Estimator):
    """Least squares (``least_squares``: :class:`OLS` or :class:`WLS`, whose weighting and
    name it takes) over full link parameters a real body can have: every link's
    pseudo-inertia positive definite, friction and armature coefficients >= 0
    (:mod:`._physical`; a semidefinite programme solved by Clarabel). It returns the full
    parameters too (:meth:`~._identify.Identification.urdf`).

    ``prior`` (full parameters, default the robot's own) is pulled toward with weight
    ``prior_weight`` plus ``prior_strength`` times the data term's mean curvature (the
    scale-free form; :func:`~._validation.choose_prior_strength` chooses it)."""

    least_squares: Any = OLS()
    prior: Any = None
    prior_weight: float = 0.0
    prior_strength: float = 0.0
    normal_equations: ClassVar[bool] = True

    def __post_init__(self):
        if not isinstance(self.least_squares, OLS):
            raise ValueError(f"least_squares must be OLS(...) or WLS(...): a physically "
                             f"consistent fit is a least-squares fit, got {self.least_squares!r}")
        object.__setattr__(self, "prior", _prior(self.prior))
        for name in ("prior_weight", "prior_strength"):
            object.__setattr__(self, name, _non_negative(name, getattr(self, name)))

    @property
    def name(self) -> str:
        return self.least_squares.name

    @property
    def sigma(self) -> Sigma:
        return self.least_squares.sigma

    @property
    def weights(self) -> str:
        return self.least_squares.weights

    @property
    def physical(self) -> bool:
        return True

    def settings(self) -> dict:
        return {**super().settings(), "prior_weight": self.prior_weight,
                "prior_strength": self.prior_strength, "psd_margin": PSD_MARGIN}

    def check(self, model: TorqueModel, limits: Limits) -> None:
        super().check(model, limits)
        prior_of(self.prior, model)

    def fit(self, problem: FitProblem) -> EstimatorFit:
        ls = self.least_squares
        rows = weigh(problem, ls.sigma, default=ls.default_weighting, factor=True)
        fit = fit_physical(problem.model, rows.weighted_factor, prior_of(self.prior, problem.model),
                           self.prior_weight, self.prior_strength)
        extra = {"physical_fit": {"solver": fit.solver, "status": fit.status,
                                  "iterations": fit.iterations, "seconds": fit.seconds}}
        return EstimatorFit(np.asarray(fit.values, dtype=float), fit.full_params, rows.sigma,
                            rows.factor0, rows.W, rows.b, None, extra)
