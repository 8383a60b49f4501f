"""The model simulated: mass matrix, forward dynamics and open-loop rollouts, in JAX.

The joint-space equation of motion (Featherstone, *Rigid Body Dynamics Algorithms*, 2008,
Ch. 6; Lynch & Park, *Modern Robotics*, 2017, Sec. 8.1)::

    M(q) qdd + diag(armature) qdd + h(q, qd) = tau - extra(q, qd)

with ``h(q, qd)`` the inverse dynamics at ``qdd = 0`` (Coriolis, centrifugal, gravity and
the parameters' friction ``Fc sign(qd) + Fv qd``) and ``M(q)`` its exact derivative with
respect to ``qdd`` (the inverse dynamics is linear in ``qdd``): both come from the exact
regressor (:mod:`._regressor`), in one forward-mode linearisation, so ``M`` needs no
composite-rigid-body code of its own. ``M + diag(armature)`` is solved by Cholesky.

Rollouts use the parameters as given: a non-zero Coulomb friction ``Fc sign(qd)`` is
discontinuous at ``qd = 0`` and makes a rollout stiff (it chatters about rest with any
step). To simulate a smoothed Coulomb friction, zero the ``FC`` entries of ``params`` and
give the smooth law through ``extra``, e.g.
``extra=lambda q, qd: fc * jnp.tanh(qd / 0.01)``.

Everything is float64, batched over leading axes and jit-compatible.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _x64
from ._regressor import chunk_size, unchecked_regressor
from ._robot import Robot, joint_arrays

#: ``extra(q, qd) -> torques (..., n)`` the model adds to the inverse dynamics.
Extra = Callable[[Array, Array], Array]
#: The integrators :func:`rollout` knows.
INTEGRATORS = ("rk4", "euler", "implicit")


def _params(robot: Robot, params) -> Array:
    params = jnp.asarray(robot.params if params is None else params, dtype=jnp.float64)
    if params.shape != (robot.n_params,):
        raise ValueError(f"params must have shape ({robot.n_params},) for robot "
                         f"{robot.name!r} (12 per joint), got {params.shape}")
    return params


def _armature(robot: Robot, armature) -> Array:
    n = robot.n_joints
    if armature is None:
        return jnp.zeros(n)
    armature = jnp.asarray(armature, dtype=jnp.float64)
    if armature.shape not in ((), (n,)):
        raise ValueError(f"armature must be a number or have shape ({n},) for robot "
                         f"{robot.name!r}, got {armature.shape}")
    return jnp.broadcast_to(armature, (n,))


def _id(robot: Robot, params: Array, q, qd, qdd) -> Array:
    Y = unchecked_regressor(robot, q, qd, qdd)
    return jnp.matmul(Y, params, precision=jax.lax.Precision.HIGHEST)


def _mass_and_bias(robot: Robot, params: Array, q: Array, qd: Array) -> tuple[Array, Array]:
    """``(M(q), h(q, qd))`` of one sample ``(n,)``: the inverse dynamics linearised in
    ``qdd`` at 0 (its value is ``h``, its Jacobian ``M``; the kinematics are shared).
    Measured on a 2-core CPU (KUKA, 10,000 samples, jit): 2-3x faster than ``n``
    inverse dynamics at unit accelerations minus the bias, for ``M`` alone and with ``h``."""
    def f(qdd):
        tau = _id(robot, params, q, qd, qdd)
        return tau, tau

    M, h = jax.jacfwd(f, has_aux=True)(jnp.zeros_like(q))
    return M, h


def _map(fn, flat):
    """``fn`` of one sample over the first axis of the arrays ``flat``: in chunks under
    ``lax.map`` on a CPU (as the regressor, :func:`chunk_size`; 2-3x faster than one
    ``vmap`` for 10,000 KUKA samples), all at once elsewhere."""
    n, samples = flat[0].shape[-1], flat[0].shape[0]
    chunk = chunk_size(n, samples, memory_budget=None)
    if chunk is None or chunk >= samples:
        return jax.vmap(fn)(*flat)
    return jax.lax.map(lambda s: fn(*s), tuple(flat), batch_size=chunk)


def _batched(fn, *arrays):
    """``fn`` of one sample mapped over the (broadcast) leading axes of ``arrays``."""
    batch = arrays[0].shape[:-1]
    out = _map(fn, [a.reshape((-1, a.shape[-1])) for a in arrays])
    return jax.tree.map(lambda o: o.reshape(batch + o.shape[1:]), out)


def _qdd(robot, params, armature, extra, q, qd, tau) -> Array:
    """Forward dynamics of one sample ``(n,)`` (no checks)."""
    M, h = _mass_and_bias(robot, params, q, qd)
    rhs = tau - h
    if extra is not None:
        rhs = rhs - extra(q, qd)
    chol = jax.scipy.linalg.cho_factor(M + jnp.diag(armature), lower=True)
    return jax.scipy.linalg.cho_solve(chol, rhs)


def mass_matrix(robot: Robot, params: Float[ArrayLike, " p"] | None,
                q: Float[ArrayLike, "*batch n"], *,
                armature: Float[ArrayLike, " n"] | float | None = None
                ) -> Float[Array, "*batch n n"]:
    """The joint-space mass matrix ``M(q) + diag(armature)``, ``(..., n, n)``, float64.

    Exact: the Jacobian of :func:`~sedsabso_jax.inverse_dynamics` with respect to ``qdd``
    (which it is linear in), with ``params`` (None: ``robot.params``). ``armature``
    (reflected rotor inertia, MuJoCo's ``dof_armature``): a number or one per joint,
    default none. Jit-compatible; batched over the leading axes of ``q``."""
    params, armature = _params(robot, params), _armature(robot, armature)
    (q,) = joint_arrays(robot, ("q", q))
    return _mass_jit(robot, params, armature, q)


@eqx.filter_jit
def _mass_jit(robot, params, armature, q):
    M = _batched(lambda x: _mass_and_bias(robot, params, x, jnp.zeros_like(x))[0], q)
    return M + jnp.diag(armature)


def forward_dynamics(robot: Robot, params: Float[ArrayLike, " p"] | None,
                     q: Float[ArrayLike, "*batch n"], qd: Float[ArrayLike, "*batch n"],
                     tau: Float[ArrayLike, "*batch n"], *,
                     armature: Float[ArrayLike, " n"] | float | None = None,
                     extra: Extra | None = None) -> Float[Array, "*batch n"]:
    """Joint accelerations ``qdd`` solving
    ``(M(q) + diag(armature)) qdd + h(q, qd) = tau - extra(q, qd)`` (Featherstone 2008,
    Sec. 6.1; Lynch & Park 2017, Sec. 8.1), ``(..., n)``, float64.

    ``h`` is the inverse dynamics at ``qdd = 0`` with ``params`` (None: ``robot.params``):
    gravity, Coriolis and the parameters' friction ``Fc sign(qd) + Fv qd`` as given.
    ``extra(q, qd)``, optional: further torques of the state that the model adds to the
    inverse dynamics (an identified model's offsets, a smooth friction law), called on
    one sample ``(n,)`` at a time and returning ``(n,)``. Solved by Cholesky
    (``M + diag(armature)`` must be positive definite). Leading axes broadcast."""
    params, armature = _params(robot, params), _armature(robot, armature)
    q, qd, tau = joint_arrays(robot, ("q", q), ("qd", qd), ("tau", tau))
    return _fd_jit(robot, params, armature, extra, q, qd, tau)


@eqx.filter_jit
def _fd_jit(robot, params, armature, extra, q, qd, tau):
    return _batched(partial(_qdd, robot, params, armature, extra), q, qd, tau)


def _rk4(f, q, qd, tau, h):
    """Classic fourth-order Runge-Kutta on ``(q, qd)``, as MuJoCo's ``RK4``; stages 2-4
    under one ``lax.scan`` (one copy of the dynamics to compile, not four)."""
    a1 = f(q, qd, tau)

    def stage(carry, c):
        v, a, sum_v, sum_a = carry  # the previous stage's velocity and acceleration
        v_next = qd + c * h * a
        a_next = f(q + c * h * v, v_next, tau)
        w = jnp.where(c == 1.0, 1.0, 2.0)
        return (v_next, a_next, sum_v + w * v_next, sum_a + w * a_next), None

    (_, _, sum_v, sum_a), _ = jax.lax.scan(stage, (qd, a1, qd, a1),
                                           jnp.array([0.5, 0.5, 1.0], q.dtype))
    return q + h / 6.0 * sum_v, qd + h / 6.0 * sum_a


def _euler(f, q, qd, tau, h):
    """Semi-implicit Euler: ``qd += h qdd; q += h qd`` (MuJoCo's ``Euler`` with
    ``eulerdamp`` disabled)."""
    qd = qd + h * f(q, qd, tau)
    return q + h * qd, qd


def _implicit_qdd(robot, params, armature, extra, h, q, qd, tau) -> Array:
    """The accelerations of one linearly implicit Euler step of one sample: the torques'
    velocity derivative ``D`` taken implicitly, ``(M + diag(armature) + h D) qdd = tau -
    h(q, qd) - extra(q, qd)`` (MuJoCo's ``implicit`` integrator; stable under stiff
    friction such as a smooth Coulomb law near rest)."""
    def torque(v, a):
        out = _id(robot, params, q, v, a)
        return out if extra is None else out + extra(q, v)

    a0 = jnp.zeros_like(q)
    M = jax.jacfwd(torque, argnums=1)(qd, a0)
    D, b = jax.jacfwd(lambda v: (torque(v, a0),) * 2, has_aux=True)(qd)
    return jnp.linalg.solve(M + jnp.diag(armature) + h * D, tau - b)


def _implicit(f, q, qd, tau, h):
    """Linearly implicit Euler: ``qd += h qdd`` (velocity derivatives implicit), then
    ``q += h qd``."""
    qd = qd + h * f(q, qd, tau)
    return q + h * qd, qd


@eqx.filter_jit
def _rollout(robot, params, armature, extra, q0, qd0, tau, dt, integrator, substeps):
    step = {"rk4": _rk4, "euler": _euler, "implicit": _implicit}[integrator]
    h = dt / substeps  # substeps traced: one compilation serves every count
    one = (partial(_implicit_qdd, robot, params, armature, extra, h)
           if integrator == "implicit" else partial(_qdd, robot, params, armature, extra))

    def f(q, qd, tau):
        return _map(one, [q, qd, tau])

    def advance(state, tau_k):
        state = jax.lax.fori_loop(0, substeps, lambda _, s: step(f, *s, tau_k, h), state)
        return state, state

    # time-major: every window advances together, one step per scan iteration
    _, (q, qd) = jax.lax.scan(advance, (q0, qd0), jnp.swapaxes(tau, 0, 1))
    q = jnp.concatenate([q0[None], q], 0)
    qd = jnp.concatenate([qd0[None], qd], 0)
    return jnp.swapaxes(q, 0, 1), jnp.swapaxes(qd, 0, 1)


def rollout(robot: Robot, params: Float[ArrayLike, " p"] | None,
            q0: Float[ArrayLike, "*batch n"], qd0: Float[ArrayLike, "*batch n"],
            tau: Float[ArrayLike, "*batch steps n"], dt: float, *,
            armature: Float[ArrayLike, " n"] | float | None = None,
            extra: Extra | None = None, integrator: str = "rk4", substeps: int = 1
            ) -> tuple[Float[Array, "*batch steps+1 n"], Float[Array, "*batch steps+1 n"]]:
    """Open-loop simulation of the model from ``(q0, qd0)`` driven by ``tau``.

    ``tau[..., k, :]`` is held constant over step ``k`` of ``dt`` seconds (zero-order hold,
    as MuJoCo's controls and ``qfrc_applied``); the step is split into ``substeps`` equal
    integrator steps. Returns ``(q, qd)`` of shape ``(..., steps + 1, n)``, index 0 the
    initial state and index ``k`` the state at time ``k dt``. ``integrator``: ``"rk4"``
    (classic Runge-Kutta, MuJoCo's ``integrator="RK4"``), ``"euler"`` (semi-implicit:
    ``qd += dt qdd; q += dt qd``, MuJoCo's ``Euler`` with ``<flag eulerdamp="disable"/>``)
    or ``"implicit"`` (the same with every velocity derivative of the torques taken
    implicitly, as MuJoCo's ``implicit``: for stiff friction laws).
    Accelerations from :func:`forward_dynamics` (``params``, ``armature``, ``extra`` as
    there; the parameters' Coulomb friction as given, see the module's note). All leading
    axes (windows) are simulated at once in one ``lax.scan`` over steps, compiled once per
    robot structure, shapes, integrator and ``extra`` (a new lambda each call compiles
    again: pass the same function)."""
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
        raise ValueError(f"substeps must be a positive integer, got {substeps!r}")
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating, np.integer)) \
            or not dt > 0:
        raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
    _x64.require("rollout")
    params, armature = _params(robot, params), _armature(robot, armature)
    q0, qd0 = joint_arrays(robot, ("q0", q0), ("qd0", qd0))
    (tau,) = joint_arrays(robot, ("tau", tau))
    if tau.ndim < 2:
        raise ValueError(f"tau must have shape (..., steps, {robot.n_joints}), "
                         f"got shape {tau.shape}")
    try:
        batch = jnp.broadcast_shapes(q0.shape[:-1], tau.shape[:-2])
    except ValueError as err:
        raise ValueError(f"batch shapes do not broadcast: q0 {q0.shape}, "
                         f"tau {tau.shape} (steps on its second-to-last axis)") from err
    n, steps = robot.n_joints, tau.shape[-2]
    q0, qd0 = (jnp.broadcast_to(a, batch + (n,)).reshape(-1, n) for a in (q0, qd0))
    tau = jnp.broadcast_to(tau, batch + (steps, n)).reshape(-1, steps, n)
    q, qd = _rollout(robot, params, armature, extra, q0, qd0, tau,
                     jnp.asarray(dt, jnp.float64), integrator, jnp.asarray(substeps))
    return q.reshape(batch + q.shape[1:]), qd.reshape(batch + qd.shape[1:])


def windows(q: Float[ArrayLike, "T n"], qd: Float[ArrayLike, "T n"],
            tau: Float[ArrayLike, "T n"], dt: float, length: float,
            stride: float | None = None
            ) -> tuple[Array, Array, Array, Array]:
    """Cut a recording sampled every ``dt`` seconds into rollout windows.

    A window of ``length`` seconds is ``steps = round(length / dt)`` steps starting at
    sample ``s``: it starts from ``(q[s], qd[s])``, is driven by ``tau[s : s + steps]``
    (held over each step) and is measured as ``q[s : s + steps + 1]``; windows start every
    ``stride`` seconds (default ``length``: back to back). Returns
    ``(q0, qd0, tau_windows, q_measured)`` of shapes ``(w, n)``, ``(w, n)``,
    ``(w, steps, n)`` and ``(w, steps + 1, n)``, ready for :func:`rollout`."""
    q, qd, tau = (np.asarray(a, dtype=float) for a in (q, qd, tau))
    if q.ndim != 2 or qd.shape != q.shape or tau.shape != q.shape:
        raise ValueError(f"q, qd and tau must have one shape (T, n), got {q.shape}, "
                         f"{qd.shape}, {tau.shape}")
    if not dt > 0 or not length > 0 or (stride is not None and not stride > 0):
        raise ValueError(f"dt, length and stride must be positive, got {dt}, {length}, {stride}")
    steps = int(round(length / dt))
    every = steps if stride is None else int(round(stride / dt))
    if steps < 1 or every < 1:
        raise ValueError(f"length and stride must be at least one sample period ({dt} s), "
                         f"got {length} and {stride}")
    starts = np.arange(0, q.shape[0] - steps, every)
    if starts.size == 0:
        raise ValueError(f"a recording of {q.shape[0]} samples holds no window of "
                         f"{steps} steps ({length} s at {dt} s)")
    idx = starts[:, None] + np.arange(steps + 1)
    return (jnp.asarray(q[starts]), jnp.asarray(qd[starts]), jnp.asarray(tau[idx[:, :-1]]),
            jnp.asarray(q[idx]))


def end_errors(robot: Robot, q_sim: Float[ArrayLike, "*batch steps n"],
               q_measured: Float[ArrayLike, "*batch steps n"]) -> Float[Array, "*batch n"]:
    """Each window's end error ``|q_sim[..., -1, :] - q_measured[..., -1, :]|`` per joint,
    in degrees for revolute joints and metres for prismatic ones. The median over windows
    (``jnp.median(err, 0)``) is the usual summary."""
    q_sim, q_measured = (jnp.asarray(a, jnp.float64) for a in (q_sim, q_measured))
    if q_sim.shape != q_measured.shape or q_sim.ndim < 2 or q_sim.shape[-1] != robot.n_joints:
        raise ValueError(f"q_sim and q_measured must have one shape (..., steps, "
                         f"{robot.n_joints}), got {q_sim.shape} and {q_measured.shape}")
    scale = jnp.array([180.0 / np.pi if t == "revolute" else 1.0 for t in robot.joint_types])
    return jnp.abs(q_sim[..., -1, :] - q_measured[..., -1, :]) * scale
