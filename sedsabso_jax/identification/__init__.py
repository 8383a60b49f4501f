"""Identification of a robot's parameters from joint data, and how well the result
predicts torques. Builds on :mod:`sedsabso_jax.dynamics` and :mod:`sedsabso_jax.optim`.

- :mod:`.model`: the torque model (base regressor + friction terms), ``TorqueModel.of``;
- :mod:`.fitting`: what every estimator shares (the rows, the weighting, the interface);
- :mod:`.estimators`: OLS, WLS, L1, LevenbergMarquardt, BoxSearch, PhysicallyConsistent;
- :mod:`.identify`: :func:`identify` (robot, data, estimator, model);
- :mod:`.physical`: the physically consistent fit (LMI, Clarabel);
- :mod:`.metrics`: :func:`validation_metrics` (RMS, NRMS over range and limits);
- :mod:`.folds`, :mod:`.validation`: cross-validation over the motion's phase, the
  choice of a model and of the pull to the prior;
- :mod:`.auto`: :func:`select_and_identify`, the command's default as one call;
- :mod:`.report`: what ``sedsabso-jax identify`` prints, writes and plots;
- :mod:`.legacy`: 0.2's keyword forms.
"""

from .. import _deprecation
from ..dynamics.inertia import is_physically_consistent as is_physically_consistent
from .auto import estimator_candidates as estimator_candidates
from .auto import select_and_identify as select_and_identify
from .estimators import L1 as L1
from .estimators import OLS as OLS
from .estimators import WLS as WLS
from .estimators import BoxSearch as BoxSearch
from .estimators import LevenbergMarquardt as LevenbergMarquardt
from .estimators import PhysicallyConsistent as PhysicallyConsistent
from .fitting import Estimator as Estimator
from .fitting import EstimatorFit as EstimatorFit
from .fitting import FitProblem as FitProblem
from .identify import METHODS as METHODS
from .identify import Identification as Identification
from .identify import identify as identify
from .metrics import Metrics as Metrics
from .metrics import nrms_over_limits as nrms_over_limits
from .metrics import validation_metrics as validation_metrics
from .model import FRICTION_TERMS as FRICTION_TERMS
from .model import TorqueModel as TorqueModel
from .report import IdentificationReport as IdentificationReport
from .validation import choose_prior_strength as choose_prior_strength
from .validation import cross_validate as cross_validate
from .validation import select_model as select_model

__getattr__ = _deprecation.module_getattr(__name__, {
    "Model": ("sedsabso_jax.identification.model", "TorqueModel"),
})
