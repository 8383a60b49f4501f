"""Identification beyond the package root's names (``identify``, ``select_and_identify``,
the estimators ``OLS``, ``WLS``, ``L1``, ``LevenbergMarquardt``, ``BoxSearch``,
``PhysicallyConsistent`` and their base ``Estimator``, ``TorqueModel``,
``Identification``, ``IdentificationReport``, ``cross_validate``, ``select_model``,
``choose_prior_strength``, ``validation_metrics``, ``Metrics``, and the validations
``Validation``, ``PhaseFolds``, ``SpeedSplits``, ``RecordingFolds``, ``GivenFolds``,
``Pooled``): what
writing a new estimator needs, the validation's parts and results, the default
candidates, and how far held-out data extrapolate (``extrapolation``).
Builds on :mod:`sedsabso_jax.dynamics`, :mod:`sedsabso_jax.optim` and
:mod:`sedsabso_jax.measurements`."""

from __future__ import annotations

from .. import _deprecation
from ._auto import estimator_candidates as estimator_candidates
from ._extrapolation import Extrapolation as Extrapolation
from ._extrapolation import extrapolation as extrapolation
from ._fitting import EstimatorFit as EstimatorFit
from ._fitting import FitProblem as FitProblem
from ._fitting import weigh as weigh
from ._folds import DEFAULT_FOLDS as DEFAULT_FOLDS
from ._folds import CrossValidation as CrossValidation
from ._folds import Splits as Splits
from ._folds import phase_folds as phase_folds
from ._folds import repeat_period as repeat_period
from ._metrics import nrms_over_limits as nrms_over_limits
from ._model import FRICTION_TERMS as FRICTION_TERMS
from ._report import figure_torques as figure_torques
from ._validation import ESTIMATOR_CANDIDATES as ESTIMATOR_CANDIDATES
from ._validation import FRICTION_CANDIDATES as FRICTION_CANDIDATES
from ._validation import PRIOR_STRENGTHS as PRIOR_STRENGTHS
from ._validation import PriorSelection as PriorSelection
from ._validation import Selection as Selection

__all__ = [
    "FitProblem", "EstimatorFit", "weigh", "CrossValidation", "phase_folds",
    "repeat_period", "DEFAULT_FOLDS", "Selection", "PriorSelection", "FRICTION_CANDIDATES",
    "ESTIMATOR_CANDIDATES", "PRIOR_STRENGTHS", "estimator_candidates", "nrms_over_limits",
    "FRICTION_TERMS", "figure_torques", "extrapolation", "Extrapolation", "Splits",
]

#: Names that moved to the package root (0.3), kept with a warning through 0.3.x.
__getattr__ = _deprecation.moved(__name__, {
    "identify": "sedsabso_jax.identify",
    "select_and_identify": "sedsabso_jax.select_and_identify",
    "Identification": "sedsabso_jax.Identification",
    "IdentificationReport": "sedsabso_jax.IdentificationReport",
    "TorqueModel": "sedsabso_jax.TorqueModel",
    "Estimator": "sedsabso_jax.Estimator",
    "OLS": "sedsabso_jax.OLS",
    "WLS": "sedsabso_jax.WLS",
    "L1": "sedsabso_jax.L1",
    "LevenbergMarquardt": "sedsabso_jax.LevenbergMarquardt",
    "BoxSearch": "sedsabso_jax.BoxSearch",
    "PhysicallyConsistent": "sedsabso_jax.PhysicallyConsistent",
    "validation_metrics": "sedsabso_jax.validation_metrics",
    "Metrics": "sedsabso_jax.Metrics",
    "cross_validate": "sedsabso_jax.cross_validate",
    "select_model": "sedsabso_jax.select_model",
    "choose_prior_strength": "sedsabso_jax.choose_prior_strength",
    "is_physically_consistent": "sedsabso_jax.is_physically_consistent",
    "Model": "sedsabso_jax.TorqueModel",
    "METHODS": ("sedsabso_jax.identification._legacy.METHODS",
                "sedsabso_jax.Estimator.registered()"),
})
