"""sedsabso-jax: identify the dynamic parameters of serial robots with JAX.

Importing the package changes nothing in JAX's configuration. Robots, the regressor, base
parameters, identification and excitation design need float64: turn JAX's 64-bit mode on
first (``jax.config.update("jax_enable_x64", True)``), or they stop with one line saying
so. The optimisers run in the mode you chose (float32 when it is off).

Layers (each imports only from the ones above it; see the README's "Layout"):
``paper`` (the published numbers) and the private helpers; the two foundations
``dynamics`` (robots, regressor, base parameters) and ``optim`` (swarms, baselines);
``measurements`` and ``excitation``; ``identification``; ``reproduce``; ``cli``.
"""

from . import excitation as excitation
from . import identification as identification
from . import measurements as measurements
from . import paper as paper
from ._version import __version__ as __version__
from .dynamics import BaseParameters as BaseParameters
from .dynamics import JointLimits as JointLimits
from .dynamics import Robot as Robot
from .dynamics import base_parameters as base_parameters
from .dynamics import forward_kinematics as forward_kinematics
from .dynamics import inverse_dynamics as inverse_dynamics
from .dynamics import is_physically_consistent as is_physically_consistent
from .dynamics import joint_limits_from_urdf as joint_limits_from_urdf
from .dynamics import regressor as regressor
from .dynamics import robots as robots
from .excitation import FourierTrajectory as FourierTrajectory
from .excitation import design_excitation as design_excitation
from .identification import L1 as L1
from .identification import OLS as OLS
from .identification import WLS as WLS
from .identification import BoxSearch as BoxSearch
from .identification import Estimator as Estimator
from .identification import Identification as Identification
from .identification import IdentificationReport as IdentificationReport
from .identification import LevenbergMarquardt as LevenbergMarquardt
from .identification import Metrics as Metrics
from .identification import PhysicallyConsistent as PhysicallyConsistent
from .identification import TorqueModel as TorqueModel
from .identification import identify as identify
from .identification import metrics as metrics
from .identification import select_and_identify as select_and_identify
from .identification import validation_metrics as validation_metrics
from .measurements import Measurements as Measurements
from .measurements import load_kuka_lwr4 as load_kuka_lwr4
from .measurements import load_measurements as load_measurements
from .measurements import simulate_measurements as simulate_measurements
from .measurements import simulate_measurements_along as simulate_measurements_along  # noqa: E501
from .optim import BSO as BSO
from .optim import LDWPSO as LDWPSO
from .optim import SEDSABSO as SEDSABSO
from .optim import BlackBox as BlackBox
from .optim import Evosax as Evosax
from .optim import L1Residual as L1Residual
from .optim import Result as Result
from .optim import baselines as baselines
from .optim import box_around as box_around
from .optim import iterations_for_budget as iterations_for_budget
from .optim import minimise as minimise
