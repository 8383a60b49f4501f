"""Identification beyond the package root's names (``identify``, ``select_and_identify``,
the estimators ``OLS``, ``WLS``, ``L1``, ``LevenbergMarquardt``, ``BoxSearch``,
``PhysicallyConsistent`` and their base ``Estimator``, ``TorqueModel`` and its terms
``Offset``, ``Quadratic``, ``SmoothCoulomb``, ``Stribeck``, ``LoadFriction``, ``Armature``,
``CoupledMotorFriction``,
``Identification``, ``IdentificationReport``, ``cross_validate``, ``select_model``,
``choose_prior_strength``, ``validation_metrics``, ``Metrics``, and the validations
``Validation``, ``PhaseFolds``, ``SpeedSplits``, ``RecordingFolds``, ``GivenFolds``,
``Pooled``; ``identify_payload``, ``Payload``): what writing a new estimator or
torque-model term needs, the command line's
friction text (``parse_friction``), the default candidates (``candidate_models``,
``estimator_candidates``) and the rules between ``select_and_identify``'s options
(``Choice``), the validation's parts and results, and how far held-out data extrapolate
(``extrapolation``). Builds on :mod:`sedsabso_jax.dynamics`, :mod:`sedsabso_jax.optim`
and :mod:`sedsabso_jax.measurements`."""

from __future__ import annotations

from ._auto import Choice as Choice
from ._auto import DefaultValidation as DefaultValidation
from ._auto import Names as Names
from ._auto import estimator_candidates as estimator_candidates
from ._box_search import FACE_TOLERANCE as FACE_TOLERANCE
from ._estimators import AbstractLeastSquares as AbstractLeastSquares
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
from ._friction_state import dahl_state as dahl_state
from ._friction_state import increments as increments
from ._metrics import nrms_over_limits as nrms_over_limits
from ._model import FRICTION_CANDIDATES as FRICTION_CANDIDATES
from ._model import candidate_models as candidate_models
from ._payload import PAYLOAD_PARAMETERS as PAYLOAD_PARAMETERS
from ._report import figure_torques as figure_torques
from ._shapes import LOAD_RTOL as LOAD_RTOL
from ._shapes import Fitted as Fitted
from ._state_search import PreslidingProblem as PreslidingProblem
from ._term_base import AbstractTerm as AbstractTerm
from ._term_base import Shapes as Shapes
from ._term_base import Signals as Signals
from ._terms import FRICTION_TERMS as FRICTION_TERMS
from ._terms import parse_friction as parse_friction
from ._validation import ESTIMATOR_CANDIDATES as ESTIMATOR_CANDIDATES
from ._validation import PRIOR_STRENGTHS as PRIOR_STRENGTHS
from ._validation import PriorSelection as PriorSelection
from ._validation import Selection as Selection
from ._validation import simplest_not_worse as simplest_not_worse

__all__ = [
    "FitProblem", "EstimatorFit", "weigh", "AbstractLeastSquares", "FACE_TOLERANCE",
    "CrossValidation", "phase_folds", "repeat_period", "DEFAULT_FOLDS", "Selection",
    "simplest_not_worse",
    "PriorSelection", "FRICTION_CANDIDATES", "ESTIMATOR_CANDIDATES", "PRIOR_STRENGTHS",
    "estimator_candidates", "candidate_models", "Choice", "Names", "DefaultValidation",
    "nrms_over_limits", "FRICTION_TERMS", "AbstractTerm", "Signals", "Shapes", "Fitted",
    "LOAD_RTOL", "parse_friction", "figure_torques", "extrapolation", "Extrapolation",
    "Splits", "PAYLOAD_PARAMETERS", "PreslidingProblem", "dahl_state", "increments",
]
