"""Fits of the weighted rows themselves, not of their normal equations
(:class:`AbstractRowFit`): :class:`L1`, the exact minimiser of the summed absolute
residual (the paper's Eq. 17) as the dual linear programme (HiGHS), and
:class:`LevenbergMarquardt`, optimistix's on the L2 problem; the box search
(:mod:`._box_search`) is the third. None has a physically consistent form.
"""

from __future__ import annotations

from typing import Any, ClassVar

import equinox as eqx
import numpy as np

from ...optim._baselines import least_squares
from ...optim._fitness import L1Residual
from ...optim._linear import l1_solve
from .._model._torque_model import TorqueModel
from .._options import as_float, as_floats, as_int, check_count, check_number
from ._estimator import (
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
from ._least_squares import PhysicallyConsistent, SigmaOption


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


