"""The identification estimators, one final class each (interface: :mod:`._fitting`).

- :class:`OLS`: least squares by column-pivoted QR (:mod:`sedsabso_jax.optim._linear`);
- :class:`WLS`: the same on rows divided by each joint's sigma, by default Gautier's
  two-step estimate from an OLS pass's residuals;
- :class:`L1`: the exact minimiser of the summed absolute residual (the paper's Eq. 17)
  as the dual linear programme (HiGHS);
- :class:`LevenbergMarquardt`: optimistix's Levenberg-Marquardt on the L2 problem;
- :class:`~._box_search.BoxSearch`: any optimiser :func:`~sedsabso_jax.minimise` runs (the
  paper's swarms SEDSABSO, BSO, LDWPSO, or an evosax strategy) on the weighted L1
  objective, in a box around the a-priori parameters;
- :class:`PhysicallyConsistent`: least squares over full link parameters a real body can
  have (:mod:`._physical`; Clarabel through cvxpy), optionally pulled toward a prior.

Every one takes ``sigma`` (:func:`~._fitting.weigh`); L1 and the box searches then minimise
the weighted L1 norm. Each is built with its options, converted and checked there::

    WLS("limits"), BoxSearch(SEDSABSO.paper(), runs=3), PhysicallyConsistent(OLS(),
    prior_strength=1e-4)

Abstract or final: OLS and WLS are the two final forms of :class:`AbstractLeastSquares`
(they differ in the default weighting only); L1, Levenberg-Marquardt and the box search
those of :class:`AbstractRowFit`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import equinox as eqx
import numpy as np
from jaxtyping import ArrayLike, Float

from ..optim._baselines import least_squares
from ..optim._fitness import L1Residual
from ..optim._linear import l1_solve
from ._fitting import (
    Estimator,
    EstimatorFit,
    FitProblem,
    Limits,
    check_sigma,
    check_weighting,
    no_physical_form,
    weigh,
    weighting_settings,
)
from ._model import TorqueModel
from ._options import as_float, as_floats, as_int, check_count, check_number
from ._physical import PSD_MARGIN, fit_physical

#: An estimator's ``sigma`` as kept: None, a weighting's name, or one number per joint.
SigmaOption = str | tuple[float, ...] | None


def check_prior(prior: object) -> None:
    """That a prior (as :func:`~._options.as_floats` converted it) is None (the robot's
    own parameters) or finite full parameters (12 per link; the count is checked against
    the robot)."""
    if prior is not None and not (isinstance(prior, tuple) and np.all(np.isfinite(prior))):
        raise ValueError(f"prior must be finite full parameters (12 per link), got shape "
                         f"{np.shape(prior)}")  # type: ignore[call-overload]


def prior_of(prior: Float[ArrayLike, " p"] | Sequence[float] | None, model: TorqueModel
             ) -> Float[np.ndarray, " p"]:
    """The full a-priori parameters: ``prior``, or the robot's own; checked."""
    robot = model.robot
    p = np.asarray(robot.params if prior is None else prior, dtype=float)
    if p.shape != (robot.n_params,) or not np.all(np.isfinite(p)):
        raise ValueError(f"prior must be {robot.n_params} finite full parameters (12 per "
                         f"link), got shape {p.shape}")
    return p


class AbstractLeastSquares(Estimator):
    """Least squares on the (weighted) rows by column-pivoted QR, the minimum-norm
    solution when the rows leave columns unidentifiable: :class:`OLS` and :class:`WLS`."""

    physical: ClassVar[bool] = False
    costly: ClassVar[bool] = False
    normal_equations: ClassVar[bool] = True
    norm: ClassVar[int] = 2

    def fit(self, problem: FitProblem) -> EstimatorFit:
        rows = weigh(problem, self.sigma, default=self.default_weighting, factor=True)
        return EstimatorFit(rows.weighted_factor.solve(), None, rows.sigma, rows.factor0, rows.W,
                            rows.b, None, {})

    def check(self, model: TorqueModel, limits: Limits) -> None:
        check_weighting(self, model, limits)

    def settings(self) -> dict:
        return weighting_settings(self)

    def physically_consistent(self) -> PhysicallyConsistent:
        return PhysicallyConsistent(self)

    def __check_init__(self):
        check_sigma(self.sigma)


class AbstractRowFit(Estimator):
    """An unconstrained fit of the weighted rows themselves, not of their normal
    equations: :class:`L1`, :class:`LevenbergMarquardt`,
    :class:`~._box_search.BoxSearch`. None has a physically consistent form."""

    physical: ClassVar[bool] = False
    normal_equations: ClassVar[bool] = False

    def settings(self) -> dict:
        return weighting_settings(self)

    def physically_consistent(self) -> PhysicallyConsistent:
        raise no_physical_form(self)


class OLS(AbstractLeastSquares):
    """Ordinary least squares; ``sigma`` weights the rows (:func:`~._fitting.weigh`;
    None: equal weights)."""

    sigma: SigmaOption = eqx.field(default=None, converter=as_floats)
    name: ClassVar[str] = "OLS"
    default_weighting: ClassVar[str] = "equal"
    registered_as: ClassVar[dict[str, dict[str, Any]]] = {"OLS": {}}


class WLS(AbstractLeastSquares):
    """Weighted least squares: rows divided by each joint's ``sigma``; ``"residual"``
    (the default, also for None) is Gautier's two-step estimate."""

    sigma: SigmaOption = eqx.field(default="residual", converter=as_floats)
    name: ClassVar[str] = "WLS"
    default_weighting: ClassVar[str] = "residual"
    registered_as: ClassVar[dict[str, dict[str, Any]]] = {"WLS": {}}


class L1(AbstractRowFit):
    """The exact minimiser of the (weighted) summed absolute residual, Eq. 17, as the dual
    linear programme (HiGHS); its iteration count goes to the settings."""

    sigma: SigmaOption = eqx.field(default=None, converter=as_floats)
    name: ClassVar[str] = "L1"
    default_weighting: ClassVar[str] = "equal"
    costly: ClassVar[bool] = False
    norm: ClassVar[int] = 1
    registered_as: ClassVar[dict[str, dict[str, Any]]] = {"L1": {}}

    def __check_init__(self):
        check_sigma(self.sigma)

    def fit(self, problem: FitProblem) -> EstimatorFit:
        rows = weigh(problem, self.sigma)
        x, iterations = l1_solve(rows.W, rows.b)
        return EstimatorFit(np.asarray(x, dtype=float), None, rows.sigma, rows.factor0, rows.W,
                            rows.b, None, {"lp_iterations": iterations})

    def check(self, model: TorqueModel, limits: Limits) -> None:
        check_weighting(self, model, limits)


class LevenbergMarquardt(AbstractRowFit):
    """optimistix's Levenberg-Marquardt on the (weighted) L2 problem, columns scaled to unit
    norm, from zero (:func:`sedsabso_jax.baselines.least_squares`)."""

    sigma: SigmaOption = eqx.field(default=None, converter=as_floats)
    max_steps: int = eqx.field(default=256, converter=as_int)
    rtol: float = eqx.field(default=1e-10, converter=as_float)
    atol: float = eqx.field(default=1e-10, converter=as_float)
    name: ClassVar[str] = "LM"
    default_weighting: ClassVar[str] = "equal"
    costly: ClassVar[bool] = False
    norm: ClassVar[int] = 2
    registered_as: ClassVar[dict[str, dict[str, Any]]] = {"LM": {}}

    def __check_init__(self):
        check_sigma(self.sigma)
        check_count("max_steps", self.max_steps, 1)
        check_number("rtol", self.rtol, strict=True)
        check_number("atol", self.atol, strict=True)

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

    def check(self, model: TorqueModel, limits: Limits) -> None:
        check_weighting(self, model, limits)


class PhysicallyConsistent(Estimator):
    """Least squares (``least_squares``: :class:`OLS` or :class:`WLS`, whose weighting and
    name it takes) over full link parameters a real body can have: every link's
    pseudo-inertia positive definite, friction and armature coefficients >= 0
    (:mod:`._physical`; a semidefinite programme solved by Clarabel). It returns the full
    parameters too (:meth:`~._identify.Identification.urdf`).

    ``prior`` (full parameters, default the robot's own) is pulled toward with weight
    ``prior_weight`` plus ``prior_strength`` times the data term's mean curvature (the
    scale-free form; :func:`~._validation.choose_prior_strength` chooses it)."""

    least_squares: AbstractLeastSquares = OLS()
    prior: tuple[float, ...] | None = eqx.field(default=None, converter=as_floats)
    prior_weight: float = eqx.field(default=0.0, converter=as_float)
    prior_strength: float = eqx.field(default=0.0, converter=as_float)
    physical: ClassVar[bool] = True
    costly: ClassVar[bool] = False
    normal_equations: ClassVar[bool] = True
    norm: ClassVar[int] = 2

    def __check_init__(self):
        if not isinstance(self.least_squares, AbstractLeastSquares):
            raise ValueError(f"least_squares must be OLS(...) or WLS(...): a physically "
                             f"consistent fit is a least-squares fit, got {self.least_squares!r}")
        check_prior(self.prior)
        check_number("prior_weight", self.prior_weight)
        check_number("prior_strength", self.prior_strength)

    @property
    def name(self) -> str:
        return self.least_squares.name

    @property
    def sigma(self) -> SigmaOption:
        return self.least_squares.sigma

    @property
    def default_weighting(self) -> str:
        return self.least_squares.default_weighting

    def settings(self) -> dict:
        return {**weighting_settings(self), "prior_weight": self.prior_weight,
                "prior_strength": self.prior_strength, "psd_margin": PSD_MARGIN}

    def check(self, model: TorqueModel, limits: Limits) -> None:
        check_weighting(self, model, limits)
        prior_of(self.prior, model)

    def physically_consistent(self) -> PhysicallyConsistent:
        return self

    def fit(self, problem: FitProblem) -> EstimatorFit:
        ls = self.least_squares
        rows = weigh(problem, ls.sigma, default=ls.default_weighting, factor=True)
        fit = fit_physical(problem.model, rows.weighted_factor, prior_of(self.prior, problem.model),
                           self.prior_weight, self.prior_strength)
        extra = {"physical_fit": {"solver": fit.solver, "status": fit.status,
                                  "iterations": fit.iterations, "seconds": fit.seconds}}
        return EstimatorFit(np.asarray(fit.values, dtype=float), fit.full_params, rows.sigma,
                            rows.factor0, rows.W, rows.b, None, extra)
