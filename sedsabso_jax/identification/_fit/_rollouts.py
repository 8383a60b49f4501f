"""An identification simulated: open-loop rollouts from measured states, driven by the
measured torques, in JAX (:func:`~sedsabso_jax.dynamics.rollout`) and in MuJoCo (the
written MJCF), and their end errors after a few tenths of a second."""

from __future__ import annotations

import dataclasses
from typing import Any

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from ...dynamics._forward import rollout
from ...dynamics._robot import Robot
from ._simulator import import_mujoco, simulated

#: The rollout windows' lengths the report gives (s).
LENGTHS = (0.2, 0.5)
#: Windows per recording, evenly spaced over it.
WINDOWS = 64
#: The velocity scale (rad/s or m/s) of the JAX rollouts' ``sign(qd)``: ``tanh(qd / v)``,
#: stiff, which the linearly implicit Euler holds (an explicit ``sign`` chatters about
#: rest and never sticks).
STICKING_VELOCITY = 1e-3
#: The longest integrator step of the JAX rollouts (s): a sample period is split into
#: as many substeps as that needs (linearly implicit Euler is first order).
LONGEST_STEP = 0.001


class ModelTorque(eqx.Module):
    """The torques an identified model adds to its rigid body as a function of the state:
    its Coulomb friction ``fc`` in the model's own shape (a smooth Coulomb's ``tanh``, else
    ``sign``, regularised as ``tanh(qd /`` :data:`STICKING_VELOCITY` ``)`` so that a joint
    sticks as its friction makes it) and its torque offsets (``extra`` of
    :func:`~sedsabso_jax.dynamics.rollout`)."""

    fc: Array
    offset: Array
    model: Any  # the TorqueModel (its Coulomb shape)

    def __call__(self, q: Array, qd: Array) -> Array:
        shape, reshaped = self.model.coulomb(qd)
        if not reshaped:  # sign(qd), regularised: stiff, held by the implicit integrator
            shape = jnp.tanh(qd / STICKING_VELOCITY)
        return self.fc * shape + self.offset


def simulated_dynamics(ident) -> tuple[Robot, np.ndarray, np.ndarray, ModelTorque]:
    """``(robot, params, armature, extra)`` of a physical fit for
    :func:`~sedsabso_jax.dynamics.rollout`: the links and viscous friction (Coulomb's,
    with its terms' dry friction, moved to ``extra`` in the model's shape), the armature
    and offsets of its terms (:func:`~._simulator.simulated`; what no simulator holds is
    left out here too, as from the MJCF)."""
    if ident.full_params is None:
        raise ValueError("a rollout needs the full link parameters of a physically "
                         "consistent fit: identify with PhysicallyConsistent(...) "
                         "(--physical)")
    p = np.asarray(ident.full_params, dtype=float).reshape(-1, 12).copy()
    held = simulated(ident.model, ident.values)
    fc = p[:, 10] + held.frictionloss  # as the MJCF: a term's dry friction joins it
    p[:, 10] = 0.0
    return (ident.model.robot, p.ravel(), held.armature,
            ModelTorque(jnp.asarray(fc), jnp.asarray(held.offset), ident.model))


def starts(samples: int, steps: int, count: int = WINDOWS) -> np.ndarray:
    """``count`` window starts evenly spaced over a recording of ``samples`` (fewer where
    it is short), each followed by ``steps`` samples."""
    last = samples - steps - 1
    if last < 0:
        raise ValueError(f"a recording of {samples} samples is shorter than one rollout "
                         f"window ({steps} steps)")
    return np.unique(np.linspace(0, last, min(count, last + 1)).round().astype(int))


def mujoco_rollouts(xml: str, q0: np.ndarray, qd0: np.ndarray, tau: np.ndarray
                    ) -> np.ndarray:
    """MuJoCo's own rollouts of the MJCF ``xml`` (its integrator and timestep) from each
    window's ``(q0, qd0)`` (``(w, n)``), ``ctrl`` the measured torques ``tau`` (``(w, steps,
    n)``) held over each step: positions ``(w, steps + 1, n)``, ``inf`` from where MuJoCo
    found the simulation unstable (it then resets the state; its warning is not printed)."""
    mujoco = import_mujoco()
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    w, steps, n = tau.shape
    out = np.empty((w, steps + 1, n))
    bad = [mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQVEL,
           mujoco.mjtWarning.mjWARN_BADQPOS]
    printed = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda text: None)
    try:
        for k in range(w):
            mujoco.mj_resetData(m, d)
            d.qpos[:], d.qvel[:] = q0[k], qd0[k]
            out[k, 0] = d.qpos
            for i in range(steps):
                d.ctrl[:] = tau[k, i]
                mujoco.mj_step(m, d)
                if any(d.warning[b].number for b in bad):
                    out[k, i + 1:] = np.inf
                    break
                out[k, i + 1] = d.qpos
    finally:
        mujoco.set_mju_user_warning(printed)
    return out


@dataclasses.dataclass(frozen=True, eq=False)
class RolloutErrors:
    """End errors of open-loop rollouts: ``own`` (the package's model in JAX) and
    ``mujoco`` (the written MJCF in MuJoCo, or None), each ``(len(lengths), windows, n)``
    in degrees (metres for a prismatic joint) after each of ``lengths`` seconds; the
    windows' ``times`` ``(w, steps + 1)`` (s from the recording's start), the
    ``measured`` positions there and the simulated ones, ``q_own`` and ``q_mujoco``
    (None without MuJoCo), each ``(w, steps + 1, n)``."""

    lengths: tuple[float, ...]
    own: np.ndarray
    mujoco: np.ndarray | None
    times: np.ndarray
    measured: np.ndarray
    q_own: np.ndarray
    q_mujoco: np.ndarray | None

    def medians(self) -> dict[str, list[float | None]]:
        """The median end error over windows and joints, per length."""
        def median(e):
            return None if e is None else [float(np.median(x)) for x in e]
        return {"own": median(self.own), "mujoco": median(self.mujoco)}


def rollout_errors(ident, data, xml: str | None = None, lengths=LENGTHS,
                   count: int = WINDOWS) -> RolloutErrors:
    """Open-loop rollouts of a physical fit ``ident`` (or a
    :class:`~._output_error.Refined`: anything with ``dynamics()``) from ``count``
    measured states of ``data`` (a :class:`~sedsabso_jax.Measurements`), driven by its
    measured torques held over each sample period, for the longest of ``lengths`` (s);
    each length's error is the rollout's at that time: in JAX (linearly implicit Euler,
    steps of at most :data:`LONGEST_STEP`), and in MuJoCo when the MJCF ``xml`` is given
    (its own integrator; its timestep must be the sample period)."""
    dt = 1.0 / float(data.rate)
    steps = [int(round(length / dt)) for length in lengths]
    if min(steps) < 1:
        raise ValueError(f"rollout lengths {lengths} s are shorter than a sample ({dt} s)")
    first = starts(data.n_samples, max(steps), count)
    index = first[:, None] + np.arange(max(steps) + 1)
    q, qd, tau = (np.asarray(a, dtype=float) for a in (data.q, data.qd, data.tau))
    robot, params, armature, extra = ident.dynamics()
    own, _ = rollout(robot, params, q[first], qd[first], tau[index[:, :-1]], dt,
                     armature=armature, extra=extra, integrator="implicit",
                     substeps=max(1, int(np.ceil(dt / LONGEST_STEP - 1e-9))))
    measured = q[index]
    scale = np.array([180.0 / np.pi if t == "revolute" else 1.0 for t in robot.joint_types])

    def errors(sim):  # a diverged window's error is inf
        e = np.stack([np.abs(np.asarray(sim)[:, k] - measured[:, k]) * scale for k in steps])
        return np.where(np.isfinite(e), e, np.inf)

    q_mujoco = None if xml is None else mujoco_rollouts(xml, q[first], qd[first],
                                                        tau[index[:, :-1]])
    times = (np.asarray(data.times, dtype=float) - float(data.times[0]))[index]
    return RolloutErrors(tuple(float(x) for x in lengths), errors(own),
                         None if q_mujoco is None else errors(q_mujoco), times, measured,
                         np.asarray(own), q_mujoco)


def figure_rollouts(r: RolloutErrors, robot: Robot, title: str, windows: int = 6):
    """The first ``windows`` rollout windows against the measured positions, one panel a
    joint (degrees for a revolute joint)."""
    from ..._output import pyplot

    plt = pyplot()
    n = robot.n_joints
    scale = np.array([180.0 / np.pi if t == "revolute" else 1.0 for t in robot.joint_types])
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.5 * n + 0.8), sharex=True,
                             constrained_layout=True, squeeze=False)
    for j, ax in enumerate(axes[:, 0]):
        for k in range(min(windows, len(r.times))):
            first = k == 0
            ax.plot(r.times[k], r.measured[k, :, j] * scale[j], color="0.3", lw=1.2,
                    label="measured" if first else None)
            ax.plot(r.times[k], r.q_own[k, :, j] * scale[j], color="tab:red", lw=1,
                    ls="--", label="the package's model (JAX)" if first else None)
            if r.q_mujoco is not None:
                ax.plot(r.times[k], np.where(np.isfinite(r.q_mujoco[k, :, j]),
                                             r.q_mujoco[k, :, j], np.nan) * scale[j],
                        color="tab:blue", lw=1, ls=":",
                        label="written MJCF (MuJoCo)" if first else None)
        unit = "deg" if robot.joint_types[j] == "revolute" else "m"
        ax.set_ylabel(f"{robot.joint_names[j]}\n[{unit}]")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(loc="best", fontsize="small")
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title)
    return fig
