"""sedsabso-jax: identify the dynamic parameters of serial robots with JAX.

Importing the package turns on JAX's 64-bit mode (``jax_enable_x64``): the regressor and
the base-parameter reduction need float64, and float32 stays available to any code that
asks for it explicitly (the swarms can run in float32).
"""

import jax as _jax

_jax.config.update("jax_enable_x64", True)

from importlib.metadata import PackageNotFoundError as _NotFound  # noqa: E402
from importlib.metadata import version as _version  # noqa: E402

from . import baselines as baselines  # noqa: E402
from . import excitation as excitation  # noqa: E402
from . import measurements as measurements  # noqa: E402
from . import metrics as metrics  # noqa: E402
from . import robots as robots  # noqa: E402
from .base_parameters import BaseParameters as BaseParameters  # noqa: E402
from .base_parameters import base_parameters as base_parameters  # noqa: E402
from .bso import BSO as BSO  # noqa: E402
from .excitation import FourierTrajectory as FourierTrajectory  # noqa: E402
from .excitation import JointLimits as JointLimits  # noqa: E402
from .excitation import design_excitation as design_excitation  # noqa: E402
from .excitation import joint_limits_from_urdf as joint_limits_from_urdf  # noqa: E402
from .fitness import BlackBox as BlackBox  # noqa: E402
from .fitness import L1Residual as L1Residual  # noqa: E402
from .identification import Identification as Identification  # noqa: E402
from .identification import identify as identify  # noqa: E402
from .kinematics import forward_kinematics as forward_kinematics  # noqa: E402
from .ldwpso import LDWPSO as LDWPSO  # noqa: E402
from .measurements import Measurements as Measurements  # noqa: E402
from .measurements import load_kuka_lwr4 as load_kuka_lwr4  # noqa: E402
from .measurements import load_measurements as load_measurements  # noqa: E402
from .measurements import simulate_measurements as simulate_measurements  # noqa: E402
from .measurements import simulate_measurements_along as simulate_measurements_along  # noqa: E402,E501
from .metrics import Metrics as Metrics  # noqa: E402
from .metrics import validation_metrics as validation_metrics  # noqa: E402
from .regressor import inverse_dynamics as inverse_dynamics  # noqa: E402
from .regressor import regressor as regressor  # noqa: E402
from .result import Result as Result  # noqa: E402
from .robot import Robot as Robot  # noqa: E402
from .sedsabso import SEDSABSO as SEDSABSO  # noqa: E402
from .swarm import minimise as minimise  # noqa: E402

try:
    __version__ = _version("sedsabso-jax")
except _NotFound:  # running from a source tree that is not installed
    __version__ = "0+unknown"
