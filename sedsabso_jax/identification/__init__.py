"""Identification beyond the package root's names (``identify``, ``select_and_identify``,
the estimators ``OLS``, ``WLS``, ``L1``, ``LevenbergMarquardt``, ``BoxSearch``,
``PhysicallyConsistent`` and their base ``Estimator``, ``TorqueModel`` and its terms
``Offset``, ``Quadratic``, ``SmoothCoulomb``, ``Stribeck``, ``LoadFriction``,
``Presliding``, ``Armature``, ``CoupledMotorFriction``, ``Identification``,
``IdentificationReport``, ``cross_validate``, ``select_model``, ``choose_prior_strength``,
``validation_metrics``, ``Metrics``, the validations ``Validation``, ``PhaseFolds``,
``SpeedSplits``, ``RecordingFolds``, ``GivenFolds``, ``Pooled``; ``identify_payload``,
``Payload``; ``identify_drive_gains``, ``DriveGains``).

Here: what writing a torque-model term needs (``AbstractTerm``, ``AbstractScale``,
``Signals``, ``Nonlinear``, ``diagonal``), how a fit searches a model's nonlinear
parameters (``CoordinateSearch``, ``PopulationSearch``, ``LeastSquaresSearch``, their
base ``AbstractSearch``, and the problem they search, ``Projection``), what writing an
estimator needs, the command line's friction text (``parse_friction``), the default
candidates (``candidate_models``, ``estimator_candidates``), the default choice as one
value (``Default``, ``DEFAULT``) and the rules between ``select_and_identify``'s options
(``Choice``), the validation's parts and results,
Dahl's presliding state (``dahl_state``), how far held-out data extrapolate
(``extrapolation``), each held-out recording of a report judged alone (``HeldOut``) and
metrics averaged over recordings (``mean_metrics``), and the identified model in a
simulator: what MuJoCo holds of each term and of a model (``InSimulator``,
``Simulated``, ``simulated``; the candidates it holds in full, ``held_frictions``), its
torques there (``mujoco_torques``), open-loop rollouts in JAX and in MuJoCo
(``rollout_errors``, ``RolloutErrors``), the report's check of both
(``SimulatorCheck``) and the refinement by simulation error (``refine``, ``OutputError``,
``Refined``). Builds on :mod:`sedsabso_jax.dynamics`, :mod:`sedsabso_jax.optim`
and :mod:`sedsabso_jax.measurements`.

The sub-packages answer one question each: ``_model`` (what torque a model predicts: its
terms), ``_search`` (how a few nonlinear parameters are searched), ``_estimators`` (how
the linear values are fitted to rows), ``_fit`` (how a model is fitted: its terms'
stages, the compiled search problem, ``identify``), ``_validation`` (how well a fit
predicts what it was not fitted to, and the choice of a model by it), ``_payload`` (a
body fixed to a link), ``_gains`` (drive gains from a payload of known mass) and
``_default`` (what the command does by default, and its report)."""

from __future__ import annotations

from ._default._choice import Choice as Choice
from ._default._choice import DefaultValidation as DefaultValidation
from ._default._choice import estimator_candidates as estimator_candidates
from ._default._held_out import HeldOut as HeldOut
from ._default._policy import DEFAULT as DEFAULT
from ._default._policy import Default as Default
from ._default._report import figure_torques as figure_torques
from ._default._simulator_check import SimulatorCheck as SimulatorCheck
from ._estimators._box_search import FACE_TOLERANCE as FACE_TOLERANCE
from ._estimators._estimator import EstimatorFit as EstimatorFit
from ._estimators._estimator import FitProblem as FitProblem
from ._estimators._estimator import weigh as weigh
from ._estimators._least_squares import AbstractLeastSquares as AbstractLeastSquares
from ._fit._delay import LARGEST_DELAY_S as LARGEST_DELAY_S
from ._fit._delay import DelayEstimate as DelayEstimate
from ._fit._delay import estimate_delay as estimate_delay
from ._fit._fit import SETTLE_RTOL as SETTLE_RTOL
from ._fit._fit import Fitted as Fitted
from ._fit._output_error import OutputError as OutputError
from ._fit._output_error import Refined as Refined
from ._fit._output_error import refine as refine
from ._fit._projection import Projection as Projection
from ._fit._rollouts import RolloutErrors as RolloutErrors
from ._fit._rollouts import rollout_errors as rollout_errors
from ._fit._simulator import Simulated as Simulated
from ._fit._simulator import held_frictions as held_frictions
from ._fit._simulator import mujoco_torques as mujoco_torques
from ._fit._simulator import simulated as simulated
from ._gains._result import CALIBRATED_STD as CALIBRATED_STD
from ._gains._solvers import GAIN_METHODS as GAIN_METHODS
from ._gains._solvers import AbstractGainMethod as AbstractGainMethod
from ._gains._solvers import LikelihoodGains as LikelihoodGains
from ._gains._solvers import OrdinaryGains as OrdinaryGains
from ._gains._solvers import PhysicalGains as PhysicalGains
from ._gains._solvers import TotalGains as TotalGains
from ._metrics import mean_metrics as mean_metrics
from ._metrics import nrms_over_limits as nrms_over_limits
from ._model._candidates import FRICTION_CANDIDATES as FRICTION_CANDIDATES
from ._model._candidates import candidate_models as candidate_models
from ._model._dahl import dahl_state as dahl_state
from ._model._dahl import increments as increments
from ._model._order import FRICTION_TERMS as FRICTION_TERMS
from ._model._order import TERMS as TERMS
from ._model._order import parse_friction as parse_friction
from ._model._scales import AbstractScale as AbstractScale
from ._model._scales import scale as scale
from ._model._term import AbstractTerm as AbstractTerm
from ._model._term import InSimulator as InSimulator
from ._model._term import Nonlinear as Nonlinear
from ._model._term import Signals as Signals
from ._model._term import diagonal as diagonal
from ._payload._term import PAYLOAD_PARAMETERS as PAYLOAD_PARAMETERS
from ._search._methods import AbstractSearch as AbstractSearch
from ._search._methods import CoordinateSearch as CoordinateSearch
from ._search._methods import Held as Held
from ._search._methods import LeastSquaresSearch as LeastSquaresSearch
from ._search._methods import PopulationSearch as PopulationSearch
from ._validation._cross_validation import CrossValidation as CrossValidation
from ._validation._extrapolation import Extrapolation as Extrapolation
from ._validation._extrapolation import extrapolation as extrapolation
from ._validation._kept_terms import KEPT_TERMS as KEPT_TERMS
from ._validation._kept_terms import KeptTerms as KeptTerms
from ._validation._phase import DEFAULT_FOLDS as DEFAULT_FOLDS
from ._validation._phase import phase_folds as phase_folds
from ._validation._phase import repeat_period as repeat_period
from ._validation._rests import Rests as Rests
from ._validation._rests import rests as rests
from ._validation._screened_terms import SCREENED_TERMS as SCREENED_TERMS
from ._validation._screened_terms import ScreenedTerms as ScreenedTerms
from ._validation._selection import ESTIMATOR_CANDIDATES as ESTIMATOR_CANDIDATES
from ._validation._selection import PRIOR_STRENGTHS as PRIOR_STRENGTHS
from ._validation._selection import PriorSelection as PriorSelection
from ._validation._selection import Selection as Selection
from ._validation._selection import simplest_not_worse as simplest_not_worse
from ._validation._splits import Splits as Splits

__all__ = [
    "FitProblem", "EstimatorFit", "weigh", "AbstractLeastSquares", "FACE_TOLERANCE",
    "CrossValidation", "phase_folds", "repeat_period", "DEFAULT_FOLDS", "Selection",
    "simplest_not_worse", "PriorSelection", "FRICTION_CANDIDATES", "ESTIMATOR_CANDIDATES",
    "PRIOR_STRENGTHS", "estimator_candidates", "candidate_models", "Choice", "Default",
    "DEFAULT",
    "DefaultValidation", "nrms_over_limits", "FRICTION_TERMS", "TERMS", "AbstractTerm",
    "AbstractScale", "scale", "Signals", "Nonlinear", "diagonal", "Fitted", "SETTLE_RTOL",
    "parse_friction", "figure_torques", "extrapolation", "Extrapolation", "Splits",
    "PAYLOAD_PARAMETERS", "Projection", "AbstractSearch", "CoordinateSearch", "Held",
    "PopulationSearch", "LeastSquaresSearch", "dahl_state", "increments", "GAIN_METHODS",
    "AbstractGainMethod", "LikelihoodGains", "TotalGains", "OrdinaryGains", "PhysicalGains",
    "CALIBRATED_STD", "KeptTerms", "KEPT_TERMS", "ScreenedTerms", "SCREENED_TERMS", "rests",
    "Rests", "HeldOut", "mean_metrics",
    "InSimulator", "Simulated", "simulated", "held_frictions", "mujoco_torques",
    "SimulatorCheck", "rollout_errors", "RolloutErrors", "OutputError", "Refined", "refine",
    "estimate_delay", "DelayEstimate", "LARGEST_DELAY_S",
]
