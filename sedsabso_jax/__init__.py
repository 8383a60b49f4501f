"""sedsabso-jax: identify the dynamic parameters of serial robots with JAX.

The common names are here; specialised ones live in the namespaces ``robots`` (the
built-in robots and constructors), ``baselines``, ``paper`` (the published numbers),
``dynamics``, ``optim``, ``measurements``, ``excitation``, ``identification``,
``compare`` and ``reproduce`` (each with its ``__all__``; no name is in two places).
Each name's module is imported when the name is first used: ``import sedsabso_jax``
itself imports neither JAX nor SciPy.

Importing the package changes nothing in JAX's configuration. Robots, the regressor, base
parameters, identification and excitation design need float64: turn JAX's 64-bit mode on
first (``jax.config.update("jax_enable_x64", True)``), or they stop with one line saying
so (:class:`Float64Required`). The optimisers run in the mode you chose (float32 when it
is off) and compose under ``jax.jit`` and ``jax.vmap``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._version import __version__ as __version__

# imported when first used (._lazy): `import sedsabso_jax` imports no JAX
if TYPE_CHECKING:
    from . import baselines as baselines
    from . import compare as compare
    from . import dynamics as dynamics
    from . import excitation as excitation
    from . import identification as identification
    from . import measurements as measurements
    from . import optim as optim
    from . import paper as paper
    from . import reproduce as reproduce
    from . import robots as robots
    from ._x64 import Float64Required as Float64Required
    from .dynamics._base_parameters import BaseParameters as BaseParameters
    from .dynamics._base_parameters import base_parameters as base_parameters
    from .dynamics._inertia import is_physically_consistent as is_physically_consistent
    from .dynamics._kinematics import forward_kinematics as forward_kinematics
    from .dynamics._limits import JointLimits as JointLimits
    from .dynamics._limits import joint_limits_from_mjcf as joint_limits_from_mjcf
    from .dynamics._limits import joint_limits_from_urdf as joint_limits_from_urdf
    from .dynamics._regressor import inverse_dynamics as inverse_dynamics
    from .dynamics._regressor import regressor as regressor
    from .dynamics._robot import Robot as Robot
    from .excitation._design import design_excitation as design_excitation
    from .excitation._trajectory import FourierTrajectory as FourierTrajectory
    from .identification._default._report import IdentificationReport as IdentificationReport
    from .identification._default._select_and_identify import (
        select_and_identify as select_and_identify,
    )
    from .identification._estimators._box_search import BoxSearch as BoxSearch
    from .identification._estimators._estimator import Estimator as Estimator
    from .identification._estimators._least_squares import OLS as OLS
    from .identification._estimators._least_squares import WLS as WLS
    from .identification._estimators._least_squares import (
        PhysicallyConsistent as PhysicallyConsistent,
    )
    from .identification._estimators._row_fits import L1 as L1
    from .identification._estimators._row_fits import LevenbergMarquardt as LevenbergMarquardt
    from .identification._fit._identify import Identification as Identification
    from .identification._fit._identify import identify as identify
    from .identification._gains._identify_gains import identify_drive_gains as identify_drive_gains
    from .identification._gains._result import DriveGains as DriveGains
    from .identification._metrics import Metrics as Metrics
    from .identification._metrics import validation_metrics as validation_metrics
    from .identification._model._actuators import Armature as Armature
    from .identification._model._actuators import CoupledMotorFriction as CoupledMotorFriction
    from .identification._model._friction import Quadratic as Quadratic
    from .identification._model._friction import SmoothCoulomb as SmoothCoulomb
    from .identification._model._friction import Stribeck as Stribeck
    from .identification._model._load import LoadFriction as LoadFriction
    from .identification._model._offset import Offset as Offset
    from .identification._model._presliding import Presliding as Presliding
    from .identification._model._torque_model import TorqueModel as TorqueModel
    from .identification._payload._identify_payload import identify_payload as identify_payload
    from .identification._payload._result import Payload as Payload
    from .identification._validation._selection import (
        choose_prior_strength as choose_prior_strength,
    )
    from .identification._validation._selection import cross_validate as cross_validate
    from .identification._validation._selection import select_model as select_model
    from .identification._validation._splits import GivenFolds as GivenFolds
    from .identification._validation._splits import PhaseFolds as PhaseFolds
    from .identification._validation._splits import Pooled as Pooled
    from .identification._validation._splits import RecordingFolds as RecordingFolds
    from .identification._validation._splits import SpeedSplits as SpeedSplits
    from .identification._validation._splits import Validation as Validation
    from .measurements._container import Measurements as Measurements
    from .measurements._load import load_kuka_lwr4 as load_kuka_lwr4
    from .measurements._load import load_measurements as load_measurements
    from .measurements._simulate import simulate_measurements as simulate_measurements
    from .measurements._simulate import simulate_measurements_along as simulate_measurements_along
    from .measurements._transmission import Transmission as Transmission
    from .optim._box import box_around as box_around
    from .optim._bso import BSO as BSO
    from .optim._budget import evaluation_counts as evaluation_counts
    from .optim._budget import iterations_for_budget as iterations_for_budget
    from .optim._driver import minimise as minimise
    from .optim._external import Evosax as Evosax
    from .optim._fitness import BlackBox as BlackBox
    from .optim._fitness import L1Residual as L1Residual
    from .optim._ldwpso import LDWPSO as LDWPSO
    from .optim._result import Result as Result
    from .optim._sedsabso import SEDSABSO as SEDSABSO
    from .optim._solver import AbstractSolver as AbstractSolver
else:
    from ._lazy import attach

    __getattr__, __dir__ = attach(__name__)
    del attach
del TYPE_CHECKING

__all__ = [
    "__version__", "Float64Required", "baselines", "compare", "dynamics", "excitation",
    "identification", "measurements", "optim", "paper", "reproduce", "robots", "Robot",
    "regressor", "inverse_dynamics", "forward_kinematics", "base_parameters",
    "BaseParameters", "JointLimits", "joint_limits_from_urdf", "joint_limits_from_mjcf",
    "is_physically_consistent",
    "Measurements", "load_measurements", "load_kuka_lwr4", "simulate_measurements",
    "simulate_measurements_along", "Transmission", "FourierTrajectory", "design_excitation",
    "minimise", "AbstractSolver", "SEDSABSO", "BSO", "LDWPSO", "Evosax", "BlackBox",
    "L1Residual", "Result", "box_around", "iterations_for_budget", "evaluation_counts",
    "identify", "Identification", "select_and_identify", "IdentificationReport",
    "TorqueModel", "Offset", "Quadratic", "SmoothCoulomb", "Stribeck", "LoadFriction",
    "Presliding", "Armature",
    "CoupledMotorFriction", "Estimator", "OLS", "WLS", "L1", "LevenbergMarquardt", "BoxSearch",
    "PhysicallyConsistent", "validation_metrics", "Metrics", "cross_validate",
    "select_model", "choose_prior_strength", "Validation", "PhaseFolds", "SpeedSplits",
    "RecordingFolds", "GivenFolds", "Pooled", "identify_payload", "Payload",
    "identify_drive_gains", "DriveGains",
]
