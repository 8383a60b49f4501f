"""Robot dynamics, the first foundation: robot models, the exact regressor, base parameters.

Nothing here knows about optimisers, measurements or identification.

- :mod:`.robot`: the :class:`Robot` pytree (geometry, parameters, gravity);
- :mod:`.robots`: constructors (RS010N, modified and standard DH, URDF, KUKA LWR4+);
- :mod:`.urdf`: reading a URDF into a serial chain;
- :mod:`.limits`: joint limits (Table 3, URDF ``<limit>``);
- :mod:`.spatial`, :mod:`.inertia`: rigid transforms; inertial parameters, pseudo-inertia;
- :mod:`.kinematics`: forward kinematics;
- :mod:`.regressor`: ``tau = Y(q, qd, qdd) P`` (Eq. 2), inverse dynamics;
- :mod:`.base_parameters`: the identifiable combinations (Eq. 3-4).
"""

from . import robots as robots
from .base_parameters import BaseParameters as BaseParameters
from .base_parameters import base_parameters as base_parameters
from .inertia import is_physically_consistent as is_physically_consistent
from .kinematics import forward_kinematics as forward_kinematics
from .limits import JointLimits as JointLimits
from .limits import joint_limits_from_urdf as joint_limits_from_urdf
from .regressor import inverse_dynamics as inverse_dynamics
from .regressor import regressor as regressor
from .robot import Robot as Robot
from .urdf import URDFError as URDFError
