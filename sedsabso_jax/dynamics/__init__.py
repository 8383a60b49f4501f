"""Robot dynamics beyond the package root's names: the first foundation (robot models, the
exact regressor, base parameters), which knows nothing of optimisers, measurements or
identification. The common names (``Robot``, ``regressor``, ``inverse_dynamics``,
``forward_kinematics``, ``base_parameters``, ``BaseParameters``, ``JointLimits``,
``joint_limits_from_urdf``, ``joint_limits_from_mjcf``, ``is_physically_consistent``)
are ``sedsabso_jax``'s; the built-in robots are :mod:`sedsabso_jax.robots`."""

from __future__ import annotations

from ._base_parameters import random_states as random_states
from ._forward import end_errors as end_errors
from ._forward import forward_dynamics as forward_dynamics
from ._forward import mass_matrix as mass_matrix
from ._forward import rollout as rollout
from ._forward import windows as windows
from ._inertia import from_pseudo_inertia as from_pseudo_inertia
from ._inertia import params_from_com as params_from_com
from ._inertia import pseudo_inertia as pseudo_inertia
from ._kinematics import link_poses as link_poses
from ._limits import joint_limits as joint_limits
from ._mjcf import MJCFError as MJCFError
from ._mjcf_update import update_mjcf as update_mjcf
from ._mjcf_writer import to_mjcf as to_mjcf
from ._regressor import chunk_size as chunk_size
from ._regressor import unchecked_regressor as unchecked_regressor
from ._robot import LINK_PARAMETERS as LINK_PARAMETERS
from ._robot import N_LINK_PARAMETERS as N_LINK_PARAMETERS
from ._urdf import URDFError as URDFError
from ._urdf import fixed_link_pose as fixed_link_pose
from ._urdf_writer import to_urdf as to_urdf
from ._urdf_writer import update_urdf as update_urdf

__all__ = [
    "URDFError", "MJCFError", "unchecked_regressor", "chunk_size", "random_states",
    "joint_limits",
    "pseudo_inertia", "from_pseudo_inertia", "params_from_com", "to_urdf", "to_mjcf",
    "update_urdf", "update_mjcf",
    "link_poses", "fixed_link_pose",
    "LINK_PARAMETERS", "N_LINK_PARAMETERS",
    "mass_matrix", "forward_dynamics", "rollout", "windows", "end_errors",
]
