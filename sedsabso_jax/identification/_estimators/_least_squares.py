"""Least squares on the (weighted) rows and its physically consistent form, the
identification's estimators of normal equations (interface: :mod:`._estimator`).

- :class:`OLS`: least squares by column-pivoted QR (:mod:`sedsabso_jax.optim._linear`);
- :class:`WLS`: the same on rows divided by each joint's sigma, by default Gautier's
  two-step estimate from an OLS pass's residuals;
- :class:`PhysicallyConsistent`: least squares over full link parameters a real body can
  have (:mod:`._physical`; Clarabel through cvxpy), optionally pulled toward a prior.

Each is built with its options, converted and checked there::

    WLS("limits"), PhysicallyConsistent(OLS(), prior_strength=1e-4)

OLS and WLS are the two final forms of :class:`AbstractLeastSquares` (they differ in the
default weighting only).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import equinox as eqx
import numpy as np
from jaxtyping import ArrayLike, Float

from .._model._torque_model import TorqueModel
from .._options import as_float, as_floats, as_int, check_count, check_number
from ._estimator import (
    Estimator,
    EstimatorFit,
    FitProblem,
    Limits,
    check_sigma,
    check_weighting,
    weigh,
    weighting_settings,
)
from ._physical import fit_bodies, fit_physical
from ._programme import PSD_MARGIN

#: An estimator's ``sigma`` as kept: None, a weighting's name, or one number per joint.
SigmaOption = str | tuple[float, ...] | None


def check_prior(prior: object) -> None:
    """That a prior (as :func:`~.._options.as_floats` converted it) is None (the robot's
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
        rows = weigh(problem, self.sigma, default=self.default_weighting, factor=True,
                     passes=self.passes_of_weights)
        return EstimatorFit(rows.weighted_factor.solve(), None, rows.sigma, rows.factor0, rows.W,
                            rows.b, None, {})

    def check(self, model: TorqueModel, limits: Limits) -> None:
        check_weighting(self, model, limits)

    def settings(self) -> dict:
        out = weighting_settings(self)
        passes = self.passes_of_weights
        return out if passes == 1 else {**out, "passes": passes}

    def physically_consistent(self) -> PhysicallyConsistent:
        return PhysicallyConsistent(self)

    @property
    def passes_of_weights(self) -> int:
        """How many times Gautier's weights are made (each final class's ``passes``, a
        field after its ``sigma``)."""
        return getattr(self, "passes")

    def __check_init__(self):
        check_sigma(self.sigma)
        check_count("passes", self.passes_of_weights, 1)


class OLS(AbstractLeastSquares):
    """Ordinary least squares; ``sigma`` weights the rows (:func:`~._estimator.weigh`;
    None: equal weights); ``passes``: of Gautier's weights (``sigma="residual"``)."""

    sigma: SigmaOption = eqx.field(default=None, converter=as_floats)
    passes: int = eqx.field(default=1, converter=as_int)
    name: ClassVar[str] = "OLS"
    default_weighting: ClassVar[str] = "equal"
    registered_as: ClassVar[dict[str, dict[str, Any]]] = {"OLS": {}}


class WLS(AbstractLeastSquares):
    """Weighted least squares: rows divided by each joint's ``sigma``; ``"residual"``
    (the default, also for None) is Gautier's two-step estimate, made again from the
    weighted fit's residual ``passes - 1`` times (:func:`~._estimator.weigh`)."""

    sigma: SigmaOption = eqx.field(default="residual", converter=as_floats)
    passes: int = eqx.field(default=1, converter=as_int)
    name: ClassVar[str] = "WLS"
    default_weighting: ClassVar[str] = "residual"
    registered_as: ClassVar[dict[str, dict[str, Any]]] = {"WLS": {}}


class PhysicallyConsistent(Estimator):
    """Least squares (``least_squares``: :class:`OLS` or :class:`WLS`, whose weighting and
    name it takes) over full link parameters a real body can have: every link's
    pseudo-inertia positive definite, friction and armature coefficients >= 0
    (:mod:`._physical`; a semidefinite programme solved by Clarabel). It returns the full
    parameters too (:meth:`~sedsabso_jax.Identification.urdf`).

    ``prior`` (full parameters, default the robot's own) is pulled toward with weight
    ``prior_weight`` plus ``prior_strength`` times the data term's mean curvature (the
    scale-free form; :func:`~sedsabso_jax.choose_prior_strength` chooses it).

    ``links=False`` leaves the robot's links (the base values) free and constrains only
    the model's terms: coefficients ``>= 0`` and terms that are bodies (a payload) with a
    positive semidefinite pseudo-inertia (:func:`~._physical.fit_bodies`; no full
    parameters, no prior): a payload then cannot take up what an inconsistent robot
    model leaves."""

    least_squares: AbstractLeastSquares = OLS()
    prior: tuple[float, ...] | None = eqx.field(default=None, converter=as_floats)
    prior_weight: float = eqx.field(default=0.0, converter=as_float)
    prior_strength: float = eqx.field(default=0.0, converter=as_float)
    links: bool = True
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
        if not isinstance(self.links, bool):
            raise ValueError(f"links must be True or False, got {self.links!r}")
        if not self.links and (self.prior is not None or self.prior_weight
                               or self.prior_strength):
            raise ValueError("a prior pulls the links' full parameters: links=False has "
                             "none (give no prior, prior_weight or prior_strength)")

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
        out = {**weighting_settings(self), "prior_weight": self.prior_weight,
               "prior_strength": self.prior_strength, "psd_margin": PSD_MARGIN}
        if self.least_squares.passes_of_weights != 1:
            out["passes"] = self.least_squares.passes_of_weights
        return out if self.links else {**out, "links": False}

    def check(self, model: TorqueModel, limits: Limits) -> None:
        check_weighting(self, model, limits)
        prior_of(self.prior, model)

    def physically_consistent(self) -> PhysicallyConsistent:
        return self

    def fit(self, problem: FitProblem) -> EstimatorFit:
        ls = self.least_squares
        rows = weigh(problem, ls.sigma, default=ls.default_weighting, factor=True,
                     passes=ls.passes_of_weights)
        if self.links:
            fit = fit_physical(problem.model, rows.weighted_factor,
                               prior_of(self.prior, problem.model), self.prior_weight,
                               self.prior_strength)
        else:
            fit = fit_bodies(problem.model, rows.weighted_factor)
        extra = {"physical_fit": fit.report}
        return EstimatorFit(np.asarray(fit.values, dtype=float), fit.full_params, rows.sigma,
                            rows.factor0, rows.W, rows.b, None, extra)
