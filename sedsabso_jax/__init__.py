"""sedsabso-jax: identify the dynamic parameters of serial robots with JAX.

Importing the package turns on JAX's 64-bit mode (``jax_enable_x64``): the regressor and
the base-parameter reduction need float64, and float32 stays available to any code that
asks for it explicitly (the swarms can run in float32).

Layers (each imports only from the ones above it; see the README's "Layout"):
``paper`` (the published numbers) and the private helpers; the two foundations
``dynamics`` (robots, regressor, base parameters) and ``optim`` (swarms, baselines);
``measurements`` and ``excitation``; ``identification``; ``reproduce``; ``cli``.
"""

import jax as _jax

_jax.config.update("jax_enable_x64", True)

from . import excitation as excitation  # noqa: E402
from . import identification as identification  # noqa: E402
from . import measurements as measurements  # noqa: E402
from . import paper as paper  # noqa: E402
from ._version import __version__ as __version__  # noqa: E402
from .dynamics import BaseParameters as BaseParameters  # noqa: E402
from .dynamics import JointLimits as JointLimits  # noqa: E402
from .dynamics import Robot as Robot  # noqa: E402
from .dynamics import base_parameters as base_parameters  # noqa: E402
from .dynamics import forward_kinematics as forward_kinematics  # noqa: E402
from .dynamics import inverse_dynamics as inverse_dynamics  # noqa: E402
from .dynamics import is_physically_consistent as is_physically_consistent  # noqa: E402
from .dynamics import joint_limits_from_urdf as joint_limits_from_urdf  # noqa: E402
from .dynamics import regressor as regressor  # noqa: E402
from .dynamics import robots as robots  # noqa: E402
from .excitation import FourierTrajectory as FourierTrajectory  # noqa: E402
from .excitation import design_excitation as design_excitation  # noqa: E402
from .identification import Identification as Identification  # noqa: E402
from .identification import Metrics as Metrics  # noqa: E402
from .identification import identify as identify  # noqa: E402
from .identification import metrics as metrics  # noqa: E402
from .identification import validation_metrics as validation_metrics  # noqa: E402
from .measurements import Measurements as Measurements  # noqa: E402
from .measurements import load_kuka_lwr4 as load_kuka_lwr4  # noqa: E402
from .measurements import load_measurements as load_measurements  # noqa: E402
from .measurements import simulate_measurements as simulate_measurements  # noqa: E402
from .measurements import simulate_measurements_along as simulate_measurements_along  # noqa: E402,E501
from .optim import BSO as BSO  # noqa: E402
from .optim import LDWPSO as LDWPSO  # noqa: E402
from .optim import SEDSABSO as SEDSABSO  # noqa: E402
from .optim import BlackBox as BlackBox  # noqa: E402
from .optim import Evosax as Evosax  # noqa: E402
from .optim import L1Residual as L1Residual  # noqa: E402
from .optim import Result as Result  # noqa: E402
from .optim import baselines as baselines  # noqa: E402
from .optim import box_around as box_around  # noqa: E402
from .optim import iterations_for_budget as iterations_for_budget  # noqa: E402
from .optim import minimise as minimise  # noqa: E402
