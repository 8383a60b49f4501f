"""0.2's keyword forms, kept working through 0.3.x: ``identify(robot, q, qd, qdd, tau,
method=..., friction=..., sigma=..., physical=..., prior=..., box=..., runs=..., ...)`` and
the same keywords in :mod:`._validation`, turned into an estimator object and a torque
model (:func:`from_keywords`); and the helpers built on them (:func:`prepare`,
:func:`fit_regressor`, :func:`swarm_box`), which ``compare`` still uses."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
from jaxtyping import ArrayLike, Float

from .. import _deprecation
from ..dynamics._base_parameters import BaseParameters
from ..dynamics._robot import Robot
from ..measurements._transmission import TransmissionLike
from ..optim._registry import SWARMS
from ..optim._solver import AbstractSolver
from ._estimators import OLS, BoxSearch, PhysicallyConsistent
from ._fitting import Estimator, EstimatorFit, FitProblem, Limits, Sigma, describe, per_joint
from ._model import SMOOTH_VELOCITY, TorqueModel

#: The names :meth:`~._fitting.Estimator.named` knows (and the command's ``--method``).
METHODS = Estimator.registered()
#: 0.2's name of :class:`~._fitting.EstimatorFit`.
RegressorFit = EstimatorFit
#: 0.2's keyword settings of an estimator, with their defaults.
SETTINGS = {"method": "OLS", "sigma": None, "physical": False, "prior": None,
            "prior_weight": 0.0, "prior_strength": 0.0, "box": (0.5, 0.5), "runs": 1,
            "iterations": 600, "seed": 0, "solver": None}


def estimator_from(robot: Robot, *, method: str = "OLS", sigma: Sigma = None,
                   physical: bool = False,
                   prior: Float[ArrayLike, " p"] | Sequence[float] | None = None,
                   prior_weight: float = 0.0, prior_strength: float = 0.0,
                   box: tuple[Any, Any] = (0.5, 0.5), runs: int = 1, iterations: int = 600,
                   seed: int = 0, solver: AbstractSolver | None = None) -> Estimator:
    """The estimator 0.2's keyword settings describe: ``method`` a registered name,
    ``physical`` wraps OLS / WLS in :class:`~._estimators.PhysicallyConsistent`, a swarm
    name becomes a :class:`~._estimators.BoxSearch` with ``solver`` (default its
    ``.paper()`` settings), ``box``, ``runs``, ``iterations``, ``seed`` and ``prior``."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if physical and method not in ("OLS", "WLS"):
        raise ValueError(f"physical=True is a least-squares fit: use method 'OLS' or 'WLS', "
                         f"not {method!r}")
    if prior is not None:
        p = np.asarray(prior, dtype=float)
        if p.shape != (robot.n_params,) or not np.all(np.isfinite(p)):
            raise ValueError(f"prior must be {robot.n_params} finite full parameters (12 per "
                             f"link), got shape {p.shape}")
    if method in SWARMS:
        if solver is None:
            solver = SWARMS[method].paper()
        elif type(solver) is not SWARMS[method]:
            raise ValueError(f"solver must be a {method} instance for method {method!r}, got "
                             f"{type(solver).__name__}")
        return BoxSearch(solver, box=box, runs=runs, iterations=iterations, seed=seed,
                         sigma=sigma, prior=prior)
    estimator = Estimator.named(method, sigma=sigma)
    # the pull's settings are checked whether used or not, as 0.2 did
    physical_fit = PhysicallyConsistent(estimator if isinstance(estimator, OLS) else OLS(),
                                        prior=prior, prior_weight=prior_weight,
                                        prior_strength=prior_strength)
    return physical_fit if physical else estimator


def from_keywords(robot: Robot, keywords: dict, *, transmission: TransmissionLike = None,
                  base: BaseParameters | None = None,
                  smooth_velocity: float = SMOOTH_VELOCITY) -> tuple[Estimator, TorqueModel]:
    """``(estimator, model)`` for 0.2's keywords (:data:`SETTINGS`, ``friction``, and the
    deprecated ``weights`` for ``sigma``)."""
    keywords = dict(keywords)
    if "weights" in keywords:
        if "sigma" in keywords:
            raise TypeError("got both weights= (deprecated) and sigma=")
        _deprecation.warn("identify(weights=...)", "sigma=...")
        keywords["sigma"] = keywords.pop("weights")
    friction = keywords.pop("friction", "viscous-coulomb")
    unknown = sorted(set(keywords) - set(SETTINGS))
    if unknown:
        raise TypeError(f"unexpected keyword argument {unknown[0]!r}")
    model = TorqueModel.of(robot, friction, transmission=transmission,
                           smooth_velocity=smooth_velocity, base=base)
    return estimator_from(robot, **keywords), model


@dataclasses.dataclass(frozen=True, eq=False)
class Setup:
    """0.2's checked identification problem: a torque ``model``, an ``estimator`` and the
    torque ``limits``, built by :func:`prepare`."""

    model: TorqueModel
    estimator: Estimator
    limits: np.ndarray | None

    @property
    def method(self) -> str:
        return self.estimator.name

    def settings(self) -> dict:
        """The settings that do not depend on the data."""
        return describe(self.estimator, self.model, self.limits)


def prepare(robot: Robot, *, friction: str = "viscous-coulomb", limits: Limits = None,
            smooth_velocity: float = SMOOTH_VELOCITY, base: BaseParameters | None = None,
            transmission: TransmissionLike = None, warn: bool = True, **settings: Any
            ) -> Setup:
    """0.2's form: check ``identify``'s keyword settings and build the model; nothing is
    fitted. New code builds an estimator and :meth:`TorqueModel.of
    <.model.TorqueModel.of>` instead."""
    model = TorqueModel.of(robot, friction, transmission=transmission,
                           smooth_velocity=smooth_velocity, base=base)
    estimator = estimator_from(robot, **settings)
    limits = per_joint("limits", limits, robot.n_joints)
    estimator.check(model, limits)
    if warn and model.regrouped:
        warnings.warn(regrouped_message(model), stacklevel=2)
    return Setup(model, estimator, limits)


def regrouped_message(model: TorqueModel) -> str:
    """The warning that extra columns of ``model`` were left out."""
    return (f"identify: {', '.join(model.regrouped)} cannot be identified apart from the base "
            f"parameters (their columns are in the base regressor's span); left out of the "
            f"model")


def fit_regressor(setup: Setup, Y: Float[np.ndarray, "samples n d"],
                  tau: Float[np.ndarray, "samples n"], *, warn: bool = True) -> EstimatorFit:
    """0.2's form of ``setup.estimator.fit(FitProblem(setup.model, Y, tau, ...))``."""
    return setup.estimator.fit(FitProblem(setup.model, Y, tau, setup.limits, warn))


def swarm_box(setup: Setup) -> tuple[np.ndarray, np.ndarray, object]:
    """0.2's form of ``setup.estimator.bounds(setup.model)`` (a box search's box)."""
    if not isinstance(setup.estimator, BoxSearch):
        raise ValueError(f"{setup.method} searches no box")
    return setup.estimator.bounds(setup.model)
