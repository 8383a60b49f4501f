"""Identification by simulation error: an output-error refinement of a physical fit.

DIDIM (Gautier, Janot & Vandanjon, "A new closed-loop output error method for parameter
identification of robot dynamics", IEEE TCST 21(2), 2013) starts from the inverse-dynamics
fit and moves the parameters until the simulated robot follows the measured one. Here the
simulation is open loop over many short windows of the recording, each started from the
measured state and driven by the measured torques (:func:`~sedsabso_jax.dynamics.rollout`,
linearly implicit Euler, all windows in one ``lax.scan``), and the parameters are those a
simulator holds (:func:`~._rollouts.simulated_dynamics`): every link's 10 inertial
parameters through the Cholesky factor of its pseudo-inertia ``J = L L^T`` (Rucker &
Wensing, "Smooth parameterization of rigid-body inertia", IEEE RA-L 7(2), 2022: every
value is a physical body), each joint's viscous and Coulomb friction and armature (as
squares: never negative) and torque offset. Levenberg-Marquardt (optimistix) minimises::

    sum_windows,steps |q_sim - q|^2 / (N_q sigma_q^2)
        + w^2 sum_samples |(tau_hat - tau) / tau_max|^2 / N_tau

(positions in units of ``sigma_q`` = 1 degree, torques in % of the limits, ``w`` the
``torque_weight``: 0 is the pure output error, a positive ``w`` keeps the inverse-dynamics
torque fit in the cost as DIDIM's torque output does), with the exact Jacobian of every
window by forward-mode differentiation (``jax.linearize``), not one perturbed rollout per
parameter.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, ArrayLike, Float

from ... import _x64
from ...dynamics._forward import rollout
from ...dynamics._inertia import pseudo_inertia
from ...dynamics._regressor import inverse_dynamics
from ...dynamics._robot import Robot
from ...measurements._container import Measurements
from .._estimators._programme import inertial_params
from ._rollouts import ModelTorque, simulated_dynamics, starts

#: The position error the cost counts as one unit (rad): 1 degree.
SIGMA_Q = np.pi / 180.0
#: Smallest friction coefficient or armature the refinement starts from (their square
#: roots are searched, and a root of 0 would never move): a zero value starts here, too
#: small to change any torque.
FLOOR = 1e-6


class OutputError(eqx.Module):
    """Options of :func:`refine`: ``windows`` rollout windows of ``length`` seconds evenly
    spaced over the data, ``steps`` Levenberg-Marquardt iterations at most (each one
    Jacobian of every window), stopping earlier at relative / absolute tolerances
    ``rtol`` / ``atol`` of optimistix, the ``torque_weight`` of the inverse-dynamics
    torque error in the cost (0: positions only; needs ``limits``; how the default was
    chosen: docs/explanation/mujoco.md), and the ``longest_step`` of the rollouts'
    integrator (s: a sample period is split into as many substeps as that needs; the
    cost of a Jacobian grows with their number)."""

    length: float = 0.2
    windows: int = 32
    steps: int = 10
    torque_weight: float = 10.0
    longest_step: float = 0.005
    rtol: float = 1e-4
    atol: float = 1e-8

    def __check_init__(self):
        if not self.length > 0:
            raise ValueError(f"length must be a positive number of seconds, got {self.length!r}")
        for name in ("windows", "steps"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"{name} must be a positive integer, got {value!r}")
        if not self.longest_step > 0:
            raise ValueError(f"longest_step must be a positive number of seconds, "
                             f"got {self.longest_step!r}")
        if not self.torque_weight >= 0:
            raise ValueError(f"torque_weight must be >= 0, got {self.torque_weight!r}")


def _cholesky_params(p12: np.ndarray) -> np.ndarray:
    """Each link's lower Cholesky factor of its pseudo-inertia, as 10 numbers: the
    logarithms of the diagonal, then the 6 entries below it."""
    L = np.linalg.cholesky(pseudo_inertia(p12[:, :10]))
    rows, cols = np.tril_indices(4, -1)
    return np.concatenate([np.log(np.diagonal(L, axis1=-2, axis2=-1)), L[:, rows, cols]], 1)


def _inertial(theta: Array) -> Array:
    """The links' 10 inertial parameters ``(n, 10)`` of Cholesky factors ``theta``."""
    rows, cols = np.tril_indices(4, -1)
    L = jnp.zeros(theta.shape[:-1] + (4, 4))
    L = L.at[..., np.arange(4), np.arange(4)].set(jnp.exp(theta[..., :4]))
    L = L.at[..., rows, cols].set(theta[..., 4:])
    J = (L @ jnp.swapaxes(L, -1, -2)).reshape(-1, 4, 4)
    # the physical fit's map from a pseudo-inertia to the 10 parameters, one per link
    p = jax.vmap(lambda Jk: jnp.stack(inertial_params(Jk)))(J)
    return p.reshape(theta.shape[:-1] + (10,))


@dataclasses.dataclass(frozen=True, eq=False)
class Refined:
    """What :func:`refine` returns: the model a simulator holds after the refinement,
    ``params`` (12 per link, their Coulomb friction ``FC`` the whole dry friction, in the
    fit's Coulomb shape), ``armature`` and ``offset`` ``(n,)``; ``start`` the same
    three before it; the ``cost`` before and after (its unit as in the module's note),
    the Levenberg-Marquardt ``steps`` taken, the CPU ``seconds`` (compilation included),
    the ``method`` (:class:`OutputError`) and whether optimistix reported success
    (``converged``; the step limit reached is not)."""

    robot: Robot
    params: np.ndarray
    armature: np.ndarray
    offset: np.ndarray
    start: tuple[np.ndarray, np.ndarray, np.ndarray]
    cost: tuple[float, float]
    steps: int
    seconds: float
    method: OutputError
    converged: bool
    model: Any  # the fit's TorqueModel: its Coulomb shape

    def dynamics(self) -> tuple[Robot, np.ndarray, np.ndarray, ModelTorque]:
        """``(robot, params, armature, extra)`` for :func:`~sedsabso_jax.dynamics.rollout`
        (the Coulomb friction moved to ``extra``, as
        :func:`~._rollouts.simulated_dynamics`)."""
        p = self.params.reshape(-1, 12).copy()
        fc, p[:, 10] = p[:, 10].copy(), 0.0
        return (self.robot, p.ravel(), self.armature,
                ModelTorque(jnp.asarray(fc), jnp.asarray(self.offset), self.model))

    def predict(self, q: Float[ArrayLike, "*batch n"], qd: Float[ArrayLike, "*batch n"],
                qdd: Float[ArrayLike, "*batch n"]) -> Float[np.ndarray, "*batch n"]:
        """The torques ``(..., n)`` the refined model needs for states ``(..., n)``: the
        inverse dynamics, the armature's ``a qdd`` and the friction and offsets of
        ``extra``."""
        robot, p, armature, extra = self.dynamics()
        q, qd, qdd = (jnp.asarray(a, dtype=jnp.float64) for a in (q, qd, qdd))
        return np.asarray(inverse_dynamics(robot, p, q, qd, qdd) + armature * qdd
                          + extra(q, qd))

    def mjcf(self, **options: Any) -> str:
        """The refined model as MJCF (:func:`~sedsabso_jax.dynamics.to_mjcf`, its
        ``limits``, ``timestep``, ``integrator``, ``comment`` as ``options``); the
        default comment names the refinement and what MuJoCo cannot hold of it (a smooth
        Coulomb shape)."""
        from ...dynamics._mjcf_writer import to_mjcf

        m = self.method
        reshaped = bool(self.model.shaping)
        comment = options.pop("comment", (
            f"refined by simulation error ({m.windows} windows of {m.length} s, torque "
            f"weight {m.torque_weight:g}, {self.steps} steps); "
            + ("not held by the simulator (left out): the Coulomb friction's smooth shape "
               "(frictionloss is its level)" if reshaped else
               "every part of the refined model is held")))
        return to_mjcf(self.robot, self.params, armature=self.armature, offset=self.offset,
                       comment=comment, **options)


def refine(ident, data, method: OutputError = OutputError(), *,
           limits: Float[ArrayLike, " n"] | None = None) -> Refined:
    """Refine the physical fit ``ident`` (an :class:`~sedsabso_jax.Identification` of
    ``PhysicallyConsistent(...)``) by simulation error on ``data`` (a
    :class:`~sedsabso_jax.Measurements`, usually the identification data): see the
    module's note. ``limits`` (N m), needed when ``method.torque_weight > 0``.

    Raises ValueError for a fit that is not physical, data shorter than one window, and
    a torque weight without limits; TypeError for data that are not one
    :class:`~sedsabso_jax.Measurements`."""
    _x64.require("refine")
    if not isinstance(data, Measurements):
        raise TypeError(f"data must be one Measurements (the recording the rollouts follow), "
                        f"got {type(data).__name__}")
    if not isinstance(method, OutputError):
        raise TypeError(f"method must be an OutputError(...), got {method!r}")
    robot, p0, armature0, extra0 = simulated_dynamics(ident)
    n = robot.n_joints
    if method.torque_weight > 0:
        if limits is None:
            raise ValueError("a torque_weight > 0 weighs torques by their limits: give limits")
        limits = np.asarray(limits, dtype=float)
        if limits.shape not in ((), (n,)) or not np.all(np.isfinite(limits) & (limits > 0)):
            raise ValueError(f"limits must be positive and finite, a number or one per "
                             f"joint ({n}), got {limits!r}")
        limits = np.broadcast_to(limits, (n,))
    dt = 1.0 / float(data.rate)
    steps = int(round(method.length / dt))
    if steps < 1:
        raise ValueError(f"length {method.length} s is shorter than a sample ({dt} s)")
    first = starts(data.n_samples, steps, method.windows)
    index = first[:, None] + np.arange(steps + 1)
    q, qd, qdd, tau = (np.asarray(a, dtype=float) for a in (data.q, data.qd, data.qdd,
                                                            data.tau))
    q0, qd0, tau_w, measured = (jnp.asarray(a) for a in (q[first], qd[first],
                                                          tau[index[:, :-1]], q[index]))
    substeps = max(1, int(np.ceil(dt / method.longest_step - 1e-9)))

    p0 = np.asarray(p0).reshape(n, 12)
    theta0 = {"links": jnp.asarray(_cholesky_params(p0)),
              "fv": jnp.sqrt(jnp.maximum(p0[:, 11], FLOOR)),
              "fc": jnp.sqrt(jnp.maximum(np.asarray(extra0.fc), FLOOR)),
              "armature": jnp.sqrt(jnp.maximum(np.asarray(armature0), FLOOR)),
              "offset": jnp.asarray(extra0.offset)}
    model = ident.model

    def unpacked(theta):
        p = jnp.concatenate([_inertial(theta["links"]), jnp.zeros((n, 1)),
                             jnp.square(theta["fv"])[:, None]], 1).ravel()
        return p, jnp.square(theta["armature"]), ModelTorque(jnp.square(theta["fc"]),
                                                          theta["offset"], model)

    n_q = measured[:, 1:].size
    states = tuple(jnp.asarray(a) for a in (q, qd, qdd))

    def residuals(theta, _):
        p, armature, extra = unpacked(theta)
        sim, _ = rollout(robot, p, q0, qd0, tau_w, dt, armature=armature, extra=extra,
                         integrator="implicit", substeps=substeps)
        r = (sim - measured)[:, 1:].ravel() / (SIGMA_Q * np.sqrt(n_q))
        r = jnp.where(jnp.isfinite(r), r, 1e3)  # a diverged window: a large, finite error
        if method.torque_weight == 0:
            return r, None
        predicted = (inverse_dynamics(robot, p, *states) + armature * states[2]
                     + extra(states[0], states[1]))
        e = (predicted - tau) / (limits / 100.0) * (method.torque_weight
                                                     / np.sqrt(tau.size))
        return jnp.concatenate([r, e.ravel()]), None

    def cost(theta):
        r, _ = residuals(theta, None)
        return float(0.5 * jnp.sum(r ** 2))

    t0 = time.process_time()
    solver: Any = optx.LevenbergMarquardt(rtol=method.rtol, atol=method.atol)
    solution: Any = optx.least_squares(residuals, solver, theta0, has_aux=True,
                                  max_steps=method.steps, throw=False,
                                  options={"jac": "fwd"})
    theta = jax.block_until_ready(solution.value)
    seconds = time.process_time() - t0
    before, after = cost(theta0), cost(theta)
    if not after <= before:  # never worse than the start
        theta, after = theta0, before
    p, armature, extra = unpacked(theta)
    p = np.array(p).reshape(n, 12)
    p[:, 10] = np.asarray(extra.fc)
    start = p0.copy()
    start[:, 10] = np.asarray(extra0.fc)
    return Refined(robot=robot, params=p.ravel(), armature=np.asarray(armature),
                   offset=np.asarray(extra.offset),
                   start=(start.ravel(), np.asarray(armature0), np.asarray(extra0.offset)),
                   cost=(before, after), steps=int(solution.stats["num_steps"]),
                   seconds=float(seconds), method=method,
                   converged=bool(solution.result == optx.RESULTS.successful), model=model)
