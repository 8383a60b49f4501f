"""Identification of a robot's parameters from joint data, and how well the result
predicts torques. Builds on :mod:`sedsabso_jax.dynamics` and :mod:`sedsabso_jax.optim`.

- :mod:`.model`: the torque model (base regressor + friction terms);
- :mod:`.identify`: :func:`identify` (OLS, WLS, L1, LM, the swarms, physical);
- :mod:`.physical`: the physically consistent fit (LMI, Clarabel);
- :mod:`.metrics`: :func:`validation_metrics` (RMS, NRMS over range and limits);
- :mod:`.report`: what ``sedsabso-jax identify`` prints, writes and plots.
"""

from .. import _deprecation
from ..dynamics.inertia import is_physically_consistent as is_physically_consistent
from .identify import METHODS as METHODS
from .identify import Identification as Identification
from .identify import identify as identify
from .metrics import Metrics as Metrics
from .metrics import nrms_over_limits as nrms_over_limits
from .metrics import validation_metrics as validation_metrics
from .model import FRICTION_TERMS as FRICTION_TERMS
from .model import TorqueModel as TorqueModel

__getattr__ = _deprecation.module_getattr(__name__, {
    "Model": ("sedsabso_jax.identification.model", "TorqueModel"),
})
