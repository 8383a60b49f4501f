"""Excitation trajectories and their design (the paper's Eq. 5-9). Builds on
:mod:`sedsabso_jax.dynamics` (regressor, limits) and :mod:`sedsabso_jax.optim` (swarms).

- :mod:`.trajectory`: :class:`FourierTrajectory` (Eq. 5-7) and its file format;
- :mod:`.checks`: :func:`violations`, :func:`check_trajectory` against joint limits;
- :mod:`.fitness`: Eq. 9 (:func:`design_fitness`), :func:`condition_number`;
- :mod:`.design`: :func:`design_excitation`, :func:`coefficient_box`, the random baseline.
"""

from .. import _deprecation
from ..dynamics.limits import JointLimits as JointLimits
from ..dynamics.limits import joint_limits_from_urdf as joint_limits_from_urdf
from .checks import check_trajectory as check_trajectory
from .checks import violations as violations
from .design import ExcitationDesign as ExcitationDesign
from .design import coefficient_box as coefficient_box
from .design import default_solver as default_solver
from .design import design_excitation as design_excitation
from .fitness import PENALTY as PENALTY
from .fitness import DesignProblem as DesignProblem
from .fitness import condition_number as condition_number
from .fitness import design_fitness as design_fitness
from .fitness import sampling_margin as sampling_margin
from .trajectory import FourierTrajectory as FourierTrajectory

__getattr__ = _deprecation.module_getattr(__name__, {
    "search_box": ("sedsabso_jax.excitation.design", "coefficient_box"),
})
