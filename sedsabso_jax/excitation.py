"""Excitation trajectories: finite Fourier series (the paper's Eq. 5-7) designed by Eq. 9.

Per joint (NOTES_ON_THE_PAPER.md Sec. 2; Eq. 5's printed signs are garbled, so ``q`` is
the integral and ``qdd`` the derivative of Eq. 6)::

    qd(t)  = sum_k  a_k cos(k wf t) - b_k sin(k wf t)                        (Eq. 6)
    q(t)   = q0 + sum_k  a_k / (k wf) sin(k wf t) + b_k / (k wf) cos(k wf t) (Eq. 7)
    qdd(t) = sum_k -a_k k wf sin(k wf t) - b_k k wf cos(k wf t)              (Eq. 5)

``q0`` is the OFFSET of Eq. 7, not the start position: it is the mean position over a
period, so the design can centre the motion inside the position limits, and
``q(0) = q0 + sum_k b_k / (k wf)``. (Eq. 7 prints ``- b_k / (k wf) cos``, which is not an
integral of Eq. 6.) The series is periodic with period ``2 pi / wf``.

Design (:func:`design_excitation`): minimise over ``x = [a, b, q0]`` (``n (2N + 1)``
numbers, :meth:`FourierTrajectory.to_vector`) Eq. 9,
``cond(W_b) + 1e8 [a limit is violated]``, ``W_b`` the base regressor stacked over the
samples (Eq. 8) and ``cond = sigma_max / sigma_min``, with one of the package's swarms
(the paper used MATLAB's GA) through :func:`~sedsabso_jax.swarm.minimise`, which evaluates
the population (regressor and condition number of every member) under ``vmap``. The
paper gives no N, wf, duration or rate; the choices here:

- ``N = 5``, ``wf = 2 pi 0.1`` rad/s: the 10 s experiment is exactly one period, and the
  highest harmonic (0.5 Hz) still moves visibly under Table 3's acceleration limits (45
  deg/s^2 allow a velocity amplitude of 72 deg/s at the fundamental, 14 deg/s at k = 5).
- 10 s at 100 Hz: ``times = arange(1000) / 100`` (the end point is the start again).
- The swarm's condition number is taken on ``design_samples = 100`` equally spaced times
  over the duration (the regressor's cost grows with the samples); the reported one is
  recomputed by an SVD on the 1000 samples. They agree to about 1 % (69.0 vs 68.7 for the
  default RS010N design), the regressor's harmonics being far below the 100-sample grid's
  Nyquist rate. In the fitness the condition number comes from the eigenvalues of
  ``W^T W`` (21 x 21 for RS010N), several times faster under ``vmap`` than an SVD of ``W``.
- The limits are checked at ``design_samples`` times over one period, each limit tightened
  by :func:`sampling_margin` (1.2 % for N = 5 and 100 samples). By Bernstein's inequality
  a design that passes holds its limits at EVERY time, not only at the samples, so the
  final :func:`check_trajectory` on the 100 Hz grid (or any finer one) passes.
- Penalty: a feasible trajectory scores exactly Eq. 9. An infeasible one scores at least
  ``1e8`` (``1e8 + cond``), plus (``graded_penalty=True``, the default) ``1e8`` times its
  summed relative excess over the limits, so that the swarm is drawn back to feasibility;
  with the constant penalty alone, the infeasible majority of a swarm is ranked by its
  condition number, which rewards larger motions, and a run can end with no feasible
  member (seen with LDWPSO in a box 1.4 times wider than :func:`search_box`'s).
  ``graded_penalty=False`` gives the paper's constant ``P``.
- Search box: :func:`search_box`.
- Solver: :func:`default_solver`, LDWPSO with 40 particles for 100 iterations (4040
  evaluations). On RS010N with Table 3, seeds 0, 1, 2, about 4000 evaluations each, this
  box: LDWPSO(40) x 100 gave cond 69.0, 64.8, 72.9; BSO(20) x 67: 74.9, 70.1, 81.4;
  SEDSABSO(n_start=40, one phase) x 60: 89.7, 75.5, 85.0. The best random feasible draw
  of the default's budget (4040): 150.0, 141.7, 181.9. LDWPSO also compiles fastest: every place a
  swarm evaluates the fitness inlines the regressor into the compiled loop, twice for
  LDWPSO (initial population, step), five times for SEDSABSO (initial population, two
  antennae, new positions, SA candidates), and compilation dominates a design's time on
  a CPU.
  Measured on the shared 2-core CPU (load about 3.5): the default RS010N design takes
  18.6 s from a fresh process, base parameters included (swarm compile 5.4 s, swarm run
  2.0 s, random baseline 6.1 s with its own compilation), 4-5 s when called again.

:func:`design_excitation` also runs the random baseline: as many uniform draws from the
same box as the swarm made evaluations, scored by the same fitness; its best feasible
draw's condition number on the full grid is ``ExcitationDesign.random_cond``.
"""

from __future__ import annotations

import math
import os
import time
import zipfile
import zlib
from dataclasses import dataclass

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._io import atomic_write
from .base_parameters import BaseParameters
from .base_parameters import base_parameters as _base_parameters
from .paper import TABLE3_DEG
from .regressor import _regressor
from .result import Result
from .robot import Robot
from .swarm import AbstractSwarm, check_bounds, minimise

#: Eq. 9's penalty when a trajectory violates a limit.
PENALTY = 1e8
#: The fitness tightens every limit by this fraction, so that a design that touches a limit
#: still passes :func:`check_trajectory` after round-off (the optimum sits on the limits).
LIMIT_MARGIN = 1e-9
#: Defaults of :func:`design_excitation` (see the module docstring).
DEFAULT_HARMONICS = 5
DEFAULT_WF = 2 * math.pi * 0.1
DEFAULT_DURATION = 10.0
DEFAULT_RATE = 100.0
DEFAULT_DESIGN_SAMPLES = 100
DEFAULT_ITERATIONS = 100
#: Random draws per compiled batch of the random baseline: small batches stay in cache
#: (4040 draws on the 2-core CPU: 1.8 s in batches of 40, 2.5 s of 128, 3.2 s of 256).
RANDOM_BATCH = 40
#: RS010N joint limits, the paper's Table 3: (min, max) deg, deg/s, deg/s^2.
_FORMAT = "sedsabso-jax FourierTrajectory 1"
_KEYS = ("format", "a", "b", "q0", "wf")


def _concrete(x) -> bool:
    return not isinstance(x, jax.core.Tracer)


def _float_array(name: str, value, ndim: int) -> Array:
    if isinstance(value, jax.core.Tracer):
        arr = value.astype(jnp.float64) if jnp.issubdtype(value.dtype, jnp.number) else value
    else:
        arr = np.asarray(value)
        if arr.dtype.kind not in "biuf":
            raise ValueError(f"{name} must be a real numeric array, got dtype {arr.dtype}")
        arr = arr.astype(np.float64)
    if arr.ndim != ndim:
        raise ValueError(f"{name} must be {ndim}-D, got shape {arr.shape}")
    if _concrete(arr) and not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or Inf")
    return jnp.asarray(arr, dtype=jnp.float64)


def _check_wf(wf) -> float:
    try:
        wf = float(wf)
    except (TypeError, ValueError):
        raise ValueError(f"wf must be a positive number (rad/s), got {wf!r}") from None
    if not (math.isfinite(wf) and wf > 0):
        raise ValueError(f"wf must be a positive finite number (rad/s), got {wf}")
    return wf


def _evaluate(a, b, q0, kw, c, s):
    """``(q, qd, qdd)`` from coefficients ``(n, N)`` and ``c = cos(k wf t)``,
    ``s = sin(k wf t)`` of shape ``(..., N)``; ``kw = k wf``. Returns ``(..., n)`` each."""
    qd = c @ a.T - s @ b.T
    q = q0 + s @ (a / kw).T + c @ (b / kw).T
    qdd = -(s @ (a * kw).T) - c @ (b * kw).T
    return q, qd, qdd


def _sample(traj, times: np.ndarray):
    """``traj(times)`` in numpy (no JAX dispatch or compilation), ``(T, n)`` each."""
    kw = traj.wf * np.arange(1, traj.n_harmonics + 1)
    phase = np.asarray(times, dtype=float)[:, None] * kw
    return _evaluate(np.asarray(traj.a), np.asarray(traj.b), np.asarray(traj.q0), kw,
                     np.cos(phase), np.sin(phase))


def _basis(times, n_harmonics: int, wf: float):
    kw = wf * jnp.arange(1, n_harmonics + 1, dtype=jnp.float64)
    phase = jnp.asarray(times, jnp.float64)[..., None] * kw
    return kw, jnp.cos(phase), jnp.sin(phase)


class FourierTrajectory(eqx.Module):
    """A finite Fourier series per joint (Eq. 5-7), a pytree; see the module docstring.

    Attributes:
        a: ``(n, N)`` cosine coefficients of the velocity (rad/s or m/s).
        b: ``(n, N)`` sine coefficients of the velocity.
        q0: ``(n,)`` position offset, the mean position over a period (NOT ``q(0)``).
        wf: fundamental angular frequency ``wf`` in rad/s (static).
    """

    a: Float[Array, "n N"]
    b: Float[Array, "n N"]
    q0: Float[Array, " n"]
    wf: float = eqx.field(static=True)

    def __init__(self, a, b, q0, wf: float = DEFAULT_WF):
        a = _float_array("a", a, 2)
        b = _float_array("b", b, 2)
        q0 = _float_array("q0", q0, 1)
        if a.shape[0] < 1 or a.shape[1] < 1:
            raise ValueError(f"a must have shape (n_joints, n_harmonics), both >= 1, "
                             f"got {a.shape}")
        if b.shape != a.shape:
            raise ValueError(f"b must have the shape of a, {a.shape}, got {b.shape}")
        if q0.shape != (a.shape[0],):
            raise ValueError(f"q0 must have shape ({a.shape[0]},) (one per joint), "
                             f"got {q0.shape}")
        self.a, self.b, self.q0 = a, b, q0
        self.wf = _check_wf(wf)

    @property
    def n_joints(self) -> int:
        return self.a.shape[0]

    @property
    def n_harmonics(self) -> int:
        return self.a.shape[1]

    @property
    def period(self) -> float:
        """``2 pi / wf`` in seconds."""
        return 2 * math.pi / self.wf

    def __call__(self, t) -> tuple[Array, Array, Array]:
        """``(q, qd, qdd)`` at times ``t`` (seconds, any shape), each ``t.shape + (n,)``."""
        t = jnp.asarray(t)
        if not (jnp.issubdtype(t.dtype, jnp.floating) or jnp.issubdtype(t.dtype, jnp.integer)):
            raise ValueError(f"t must be real times in seconds, got dtype {t.dtype}")
        return _evaluate(self.a, self.b, self.q0, *_basis(t, self.n_harmonics, self.wf))

    def to_vector(self) -> Float[Array, " d"]:
        """Flat ``[a.ravel(), b.ravel(), q0]``, length ``n (2N + 1)`` (joint-major)."""
        return jnp.concatenate([self.a.ravel(), self.b.ravel(), self.q0])

    @classmethod
    def from_vector(cls, x, n_joints: int, n_harmonics: int,
                    wf: float = DEFAULT_WF) -> FourierTrajectory:
        """Inverse of :meth:`to_vector`."""
        n, N = int(n_joints), int(n_harmonics)
        if n < 1 or N < 1:
            raise ValueError(f"n_joints and n_harmonics must be >= 1, got {n}, {N}")
        x = jnp.asarray(x)
        if x.shape != (n * (2 * N + 1),):
            raise ValueError(f"x must have shape ({n * (2 * N + 1)},) = n_joints * (2 "
                             f"n_harmonics + 1) for {n} joints and {N} harmonics, "
                             f"got {x.shape}")
        return cls(x[: n * N].reshape(n, N), x[n * N: 2 * n * N].reshape(n, N),
                   x[2 * n * N:], wf)

    def save(self, path) -> None:
        """Write ``.npz`` (keys ``format a b q0 wf``) atomically: a temporary file in the
        same directory, then ``os.replace``. The path is used as given."""
        arrays = {"format": np.array(_FORMAT), "a": np.asarray(self.a),
                  "b": np.asarray(self.b), "q0": np.asarray(self.q0),
                  "wf": np.array(self.wf, dtype=np.float64)}
        atomic_write(path, lambda fh: np.savez(fh, **arrays))

    @classmethod
    def load(cls, path) -> FourierTrajectory:
        """Read a file written by :meth:`save` (``np.load(allow_pickle=False)``: object
        arrays are refused, nothing is unpickled)."""
        path = os.fspath(path)
        try:
            data = np.load(path, allow_pickle=False)
        except OSError as err:
            raise ValueError(f"cannot read trajectory file {path!r}: {err}") from None
        except (ValueError, EOFError, zipfile.BadZipFile) as err:  # pickled data, bad zip
            raise ValueError(f"trajectory file {path!r} is not a valid .npz: {err}") from None
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ValueError(f"trajectory file {path!r} is a single .npy array, expected an "
                             f".npz with keys {list(_KEYS)}")
        with data:
            keys = set(data.files)
            missing = [k for k in _KEYS if k not in keys]
            unknown = sorted(keys - set(_KEYS))
            if missing or unknown:
                raise ValueError(f"trajectory file {path!r}: missing keys {missing}, unknown "
                                 f"keys {unknown}; expected exactly {list(_KEYS)}")
            arrays = {}
            for k in _KEYS:
                try:
                    arrays[k] = data[k]
                except ValueError as err:  # object arrays need pickle
                    raise ValueError(f"trajectory file {path!r}: key {k!r} cannot be loaded "
                                     f"without pickle ({err})") from None
                except (OSError, EOFError, zipfile.BadZipFile, zlib.error) as err:
                    raise ValueError(f"trajectory file {path!r}: key {k!r} is corrupt "
                                     f"({type(err).__name__}: {err})") from None
        fmt = arrays["format"]
        if fmt.shape != () or fmt.dtype.kind != "U" or str(fmt) != _FORMAT:
            raise ValueError(f"trajectory file {path!r}: key 'format' must be {_FORMAT!r}, "
                             f"got {fmt!r}")
        for k, ndim in (("a", 2), ("b", 2), ("q0", 1), ("wf", 0)):
            arr = arrays[k]
            if arr.dtype.kind not in "iuf":
                raise ValueError(f"trajectory file {path!r}: key {k!r} must be real numbers, "
                                 f"got dtype {arr.dtype}")
            if arr.ndim != ndim:
                raise ValueError(f"trajectory file {path!r}: key {k!r} must be {ndim}-D, got "
                                 f"shape {arr.shape}")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"trajectory file {path!r}: key {k!r} contains NaN or Inf")
        try:
            return cls(arrays["a"], arrays["b"], arrays["q0"], float(arrays["wf"]))
        except ValueError as err:
            raise ValueError(f"trajectory file {path!r}: {err}") from None

    def __repr__(self) -> str:
        return (f"FourierTrajectory(n_joints={self.n_joints}, n_harmonics={self.n_harmonics}, "
                f"wf={self.wf:.6g} rad/s, period={self.period:.6g} s)")


class JointLimits(eqx.Module):
    """Joint limits in SI units: positions ``q_min, q_max`` (rad or m), speeds ``qd_max``
    (rad/s, m/s), accelerations ``qdd_max`` (``inf`` when unknown) and efforts ``tau_max``
    (N m or N; ``nan`` when unknown, informative only: trajectories are not checked
    against it). ``angular[j]`` says joint ``j`` is revolute (messages add degrees)."""

    q_min: Float[Array, " n"]
    q_max: Float[Array, " n"]
    qd_max: Float[Array, " n"]
    qdd_max: Float[Array, " n"]
    tau_max: Float[Array, " n"]
    names: tuple[str, ...] = eqx.field(static=True)
    angular: tuple[bool, ...] = eqx.field(static=True)

    def __init__(self, q_min, q_max, qd_max, qdd_max=None, tau_max=None, *, names=None,
                 angular=None):
        q_min = np.asarray(q_min, dtype=float)
        n = q_min.shape[0] if q_min.ndim == 1 else None
        if n is None or n < 1:
            raise ValueError(f"q_min must be 1-D with one entry per joint, got shape "
                             f"{q_min.shape}")
        qdd_max = np.full(n, np.inf) if qdd_max is None else qdd_max
        tau_max = np.full(n, np.nan) if tau_max is None else tau_max
        arrays = {}
        for name, value in (("q_min", q_min), ("q_max", q_max), ("qd_max", qd_max),
                            ("qdd_max", qdd_max), ("tau_max", tau_max)):
            arr = np.asarray(value, dtype=float)
            if arr.shape != (n,):
                raise ValueError(f"{name} must have shape ({n},) like q_min, got {arr.shape}")
            if name != "tau_max" and np.any(np.isnan(arr)):
                raise ValueError(f"{name} contains NaN (use inf for an unknown limit)")
            arrays[name] = arr
        half_open = np.isfinite(arrays["q_min"]) != np.isfinite(arrays["q_max"])
        if np.any(half_open):
            j = int(np.flatnonzero(half_open)[0])
            raise ValueError(f"joint {j + 1}: position limits must be both finite or both "
                             f"infinite, got q_min {arrays['q_min'][j]}, q_max "
                             f"{arrays['q_max'][j]}")
        bad = np.flatnonzero(~(arrays["q_min"] < arrays["q_max"]))
        if bad.size:
            j = int(bad[0])
            raise ValueError(f"joint {j + 1}: q_min {arrays['q_min'][j]} must be below q_max "
                             f"{arrays['q_max'][j]}")
        for name in ("qd_max", "qdd_max", "tau_max"):
            bad = np.flatnonzero(arrays[name] <= 0)
            if bad.size:
                j = int(bad[0])
                raise ValueError(f"joint {j + 1}: {name} must be > 0, got {arrays[name][j]}")
        self.q_min, self.q_max, self.qd_max, self.qdd_max, self.tau_max = (
            jnp.asarray(arrays[k]) for k in ("q_min", "q_max", "qd_max", "qdd_max", "tau_max"))
        names = tuple(f"J{j + 1}" for j in range(n)) if names is None else tuple(map(str, names))
        if len(names) != n:
            raise ValueError(f"names must have {n} entries, got {len(names)}: {names}")
        angular = (True,) * n if angular is None else tuple(bool(x) for x in angular)
        if len(angular) != n:
            raise ValueError(f"angular must have {n} entries, got {len(angular)}")
        self.names, self.angular = names, angular

    @property
    def n_joints(self) -> int:
        return self.q_min.shape[0]

    @classmethod
    def rs010n(cls) -> JointLimits:
        """The paper's Table 3 for the RS010N's first three joints, converted from deg,
        deg/s and deg/s^2. Joint 2's range (-60, 140) and joint 3's (-180, 80) are not
        symmetric. No torque limits are given (``tau_max`` is nan)."""
        deg = {key: np.array(value) * (math.pi / 180) for key, value in TABLE3_DEG.items()}
        return cls(deg["q_min"], deg["q_max"], deg["qd_max"], deg["qdd_max"],
                   names=("J1", "J2", "J3"))

    def __repr__(self) -> str:
        return f"JointLimits({self.n_joints} joints: {', '.join(self.names)})"


def joint_limits_from_urdf(path, robot: Robot, *, qdd_max=None) -> JointLimits:
    """Limits of ``robot``'s joints from the ``<limit>`` tags of its URDF: ``lower,
    upper`` (a continuous joint or one without ``<limit>``: unbounded), ``velocity``
    (missing or 0: unbounded) and ``effort`` as ``tau_max`` (missing or 0: nan). URDF has
    no acceleration limit: ``qdd_max`` (scalar or ``(n,)``) is taken from the argument,
    ``inf`` by default. The joints are found by ``robot.joint_names``."""
    from ._urdf import joint_limits

    rows = joint_limits(path, robot.joint_names)
    n = robot.n_joints
    qdd = np.full(n, np.inf) if qdd_max is None else np.asarray(qdd_max, dtype=float)
    if qdd.shape not in ((), (n,)):
        raise ValueError(f"qdd_max must be a scalar or have shape ({n},) for robot "
                         f"{robot.name!r}, got {qdd.shape}")
    qdd = np.broadcast_to(qdd, (n,))
    return JointLimits(rows[:, 0], rows[:, 1], rows[:, 2], qdd, rows[:, 3],
                       names=robot.joint_names,
                       angular=[t == "revolute" for t in robot.joint_types])


# --- limit checks -------------------------------------------------------------------------

def _fmt(value: float, angular: bool, suffix: str) -> str:
    if angular:
        return f"{value:.6g} rad{suffix} ({math.degrees(value):.6g} deg{suffix})"
    return f"{value:.6g} m{suffix}"


def violations(limits: JointLimits, q, qd, qdd, times=None) -> list[str]:
    """One readable line per (joint, limit) that ``q, qd, qdd`` (each ``(..., n)``)
    violate, with the worst sample, e.g. ``"joint 2 (J2) velocity: |qd| reaches 2.1 rad/s
    (120.3 deg/s) at t = 3.2 s, above the limit 1.745 rad/s (100 deg/s); 17 of 1000
    samples"``. Empty when all samples are inside the limits (limits included)."""
    n = limits.n_joints
    arrays = []
    for name, value in (("q", q), ("qd", qd), ("qdd", qdd)):
        arr = np.asarray(value, dtype=float)
        if arr.ndim == 0 or arr.shape[-1] != n:
            raise ValueError(f"{name} must have shape (..., {n}) for {n} joint limits, "
                             f"got {arr.shape}")
        if np.any(np.isnan(arr)):
            raise ValueError(f"{name} contains NaN")
        arrays.append(arr.reshape(-1, n))
    q, qd, qdd = arrays
    if not q.shape == qd.shape == qdd.shape:
        raise ValueError(f"q, qd, qdd must have one shape, got {q.shape}, {qd.shape}, "
                         f"{qdd.shape}")
    t = None
    if times is not None:
        t = np.asarray(times, dtype=float).reshape(-1)
        if t.shape != (q.shape[0],):
            raise ValueError(f"times must have one entry per sample ({q.shape[0]}), got "
                             f"{t.shape[0]}")
    lim = {k: np.asarray(getattr(limits, k)) for k in ("q_min", "q_max", "qd_max", "qdd_max")}
    out = []
    for j in range(n):
        label = f"joint {j + 1} ({limits.names[j]})"
        ang = limits.angular[j]
        checks = (
            ("position", "", "q", q[:, j], -q[:, j] > -lim["q_min"][j], lim["q_min"][j],
             "below the minimum", np.argmin),
            ("position", "", "q", q[:, j], q[:, j] > lim["q_max"][j], lim["q_max"][j],
             "above the maximum", np.argmax),
            ("velocity", "/s", "|qd|", np.abs(qd[:, j]), np.abs(qd[:, j]) > lim["qd_max"][j],
             lim["qd_max"][j], "above the limit", np.argmax),
            ("acceleration", "/s^2", "|qdd|", np.abs(qdd[:, j]),
             np.abs(qdd[:, j]) > lim["qdd_max"][j], lim["qdd_max"][j], "above the limit",
             np.argmax),
        )
        for kind, suffix, sym, values, bad, bound, words, worst in checks:
            count = int(np.count_nonzero(bad))
            if not count:
                continue
            i = int(worst(values))
            at = "" if t is None else f" at t = {t[i]:.6g} s"
            out.append(f"{label} {kind}: {sym} reaches {_fmt(values[i], ang, suffix)}{at}, "
                       f"{words} {_fmt(bound, ang, suffix)}; {count} of {len(values)} samples")
    return out


def check_trajectory(traj: FourierTrajectory, limits: JointLimits, times) -> None:
    """Raise ValueError naming the joints and limits that ``traj`` violates at ``times``."""
    if traj.n_joints != limits.n_joints:
        raise ValueError(f"trajectory has {traj.n_joints} joints, limits have "
                         f"{limits.n_joints}")
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or times.size == 0 or not np.all(np.isfinite(times)):
        raise ValueError(f"times must be a non-empty 1-D array of finite seconds, got shape "
                         f"{times.shape}")
    found = violations(limits, *_sample(traj, times), times=times)
    if found:
        more = f" (and {len(found) - 5} more)" if len(found) > 5 else ""
        raise ValueError(f"trajectory violates {len(found)} joint limit(s): "
                         + "; ".join(found[:5]) + more)


# --- condition number and design ----------------------------------------------------------


#: Samples per regressor call in :func:`condition_number`: the batch shape that
#: :func:`~sedsabso_jax.base_parameters.base_parameters` has already compiled (50 states).
_COND_CHUNK = 50


def condition_number(base: BaseParameters, q, qd, qdd) -> float:
    """2-norm condition number of the stacked base regressor ``W_b`` (Eq. 8) at the samples
    ``(T, n)``: ``sigma_max / sigma_min`` by an SVD (``inf`` when rank-deficient).

    The regressor is evaluated 50 samples at a time, the batch shape that
    ``base_parameters`` compiles by default, so no new compilation is needed for any ``T``."""
    n = base.robot.n_joints
    arrays = []
    for name, value in (("q", q), ("qd", qd), ("qdd", qdd)):
        arr = np.asarray(value, dtype=float)
        if arr.ndim != 2 or arr.shape[1] != n:
            raise ValueError(f"{name} must have shape (samples, {n}), got {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} contains NaN or Inf")
        arrays.append(arr)
    if not arrays[0].shape == arrays[1].shape == arrays[2].shape:
        raise ValueError(f"q, qd, qdd must have one shape, got "
                         f"{[a.shape for a in arrays]}")
    T = arrays[0].shape[0]
    pad = -T % _COND_CHUNK
    padded = [np.concatenate([a, np.zeros((pad, n))]) for a in arrays]
    blocks = [np.asarray(base.regressor(*(a[i: i + _COND_CHUNK] for a in padded)))
              for i in range(0, T + pad, _COND_CHUNK)]
    W = np.concatenate(blocks)[:T].reshape(-1, base.rank)
    s = np.linalg.svd(W, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else math.inf


def _gram_cond(W):
    """cond(W) as sqrt(lambda_max / lambda_min) of ``W^T W``: a (rank, rank) eigenproblem
    instead of an SVD of the tall W (several times faster under vmap on a CPU); accurate
    while cond(W) << 1e8, which covers every trajectory worth keeping. ``inf`` when
    ``lambda_min <= 0`` (rank-deficient)."""
    lam = jnp.linalg.eigvalsh(W.T @ W)
    return jnp.where(lam[0] > 0, jnp.sqrt(lam[-1] / jnp.where(lam[0] > 0, lam[0], 1.0)),
                     jnp.inf)


class _Problem(eqx.Module):
    """Everything the fitness needs, as a pytree passed through ``minimise(args=...)``."""

    robot: Robot
    kw: Array
    cond_basis: tuple[Array, Array]  # cos, sin at the design times
    check_basis: tuple[Array, Array] | None  # cos, sin over one period; None: the same
    centre: Array  # mid position range (0 when unbounded)
    half: Array  # allowed |q - centre|, tightened (inf when unbounded)
    qd_max: Array  # tightened
    qdd_max: Array  # tightened
    columns: tuple[int, ...] = eqx.field(static=True)
    n: int = eqx.field(static=True)
    N: int = eqx.field(static=True)
    graded: bool = eqx.field(static=True)

    def split(self, x):
        n, N = self.n, self.N
        return x[: n * N].reshape(n, N), x[n * N: 2 * n * N].reshape(n, N), x[2 * n * N:]

    def __call__(self, x):
        """Eq. 9: cond(W_b) + 1e8 if a limit is violated."""
        coef = self.split(x)
        q, qd, qdd = _evaluate(*coef, self.kw, *self.cond_basis)
        W = _regressor(self.robot, q, qd, qdd)[..., jnp.asarray(self.columns)]
        cond = _gram_cond(W.reshape(-1, len(self.columns)))
        if self.check_basis is not None:
            q, qd, qdd = _evaluate(*coef, self.kw, *self.check_basis)
        # largest |value| / limit per joint and kind; > 1 is a violation
        ratios = jnp.stack([jnp.max(jnp.abs(q - self.centre), 0) / self.half,
                            jnp.max(jnp.abs(qd), 0) / self.qd_max,
                            jnp.max(jnp.abs(qdd), 0) / self.qdd_max])
        violated = jnp.any(ratios > 1.0)
        penalty = PENALTY * violated
        if self.graded:
            penalty = penalty + PENALTY * jnp.sum(jnp.maximum(ratios - 1.0, 0.0))
        return cond + penalty


def sampling_margin(n_harmonics: int, samples: int) -> float:
    """Relative tightening ``delta = pi^2 N^2 / (2 S^2)`` that makes limits checked at ``S``
    equally spaced samples over a period hold between the samples too.

    Each of ``qd``, ``qdd`` and ``q - centre`` is a trigonometric polynomial ``p`` of degree
    ``N`` in ``wf t``, so ``|p''| <= (N wf)^2 max|p|`` (Bernstein's inequality, twice). At
    the time where ``|p|`` peaks, ``p' = 0``, and the nearest sample is at most ``h / 2``
    away (``h = 2 pi / (wf S)``), so by Taylor ``max|p| (1 - (N wf h)^2 / 8) <= max over
    the samples``, and ``(N wf h)^2 / 8 = pi^2 N^2 / (2 S^2)``: 1.2 % for N = 5, S = 100.
    """
    return math.pi**2 * n_harmonics**2 / (2.0 * samples**2)


def _problem(robot, base, limits, N: int, wf: float, duration: float, S: int,
             graded: bool = True) -> _Problem:
    """The fitness data: cond on ``S`` times over ``[0, duration)``, limits checked at ``S``
    times over one period, tightened by :func:`sampling_margin` and ``LIMIT_MARGIN``, so a
    feasible design satisfies the limits at every time, not only at the samples."""
    delta = sampling_margin(N, S)
    if delta >= 0.5:
        raise ValueError(f"design_samples={S} is too few for {N} harmonics (sampling "
                         f"margin {delta:.3g}); use at least {math.ceil(math.pi * N)}")
    period = 2 * math.pi / wf
    kw, c, s = _basis(duration * np.arange(S) / S, N, wf)
    shared = abs(duration - period) <= 1e-12 * period
    check = None if shared else _basis(period * np.arange(S) / S, N, wf)[1:]
    shrink = (1.0 - delta) * (1.0 - LIMIT_MARGIN)
    q_min, q_max = np.asarray(limits.q_min), np.asarray(limits.q_max)
    bounded = np.isfinite(q_min) & np.isfinite(q_max)
    return _Problem(
        robot=robot, kw=kw, cond_basis=(c, s), check_basis=check,
        centre=jnp.asarray(np.where(bounded, (q_max + q_min) / 2, 0.0)),
        half=jnp.asarray(np.where(bounded, (q_max - q_min) / 2 * shrink, np.inf)),
        qd_max=limits.qd_max * shrink, qdd_max=limits.qdd_max * shrink,
        columns=base.indices, n=robot.n_joints, N=N, graded=bool(graded),
    )


def _design_fitness(x, problem: _Problem):
    return problem(x)


@eqx.filter_jit
def _random_batch(problem: _Problem, lower, upper, key, size: int, valid):
    """``size`` uniform draws in the box, of which the first ``valid`` count: the best
    (x, fitness) among them and how many were feasible."""
    X = lower + (upper - lower) * jax.random.uniform(key, (size, lower.shape[0]), lower.dtype)
    f = jax.vmap(lambda x: _design_fitness(x, problem))(X)
    f = jnp.where(jnp.isfinite(f) & (jnp.arange(size) < valid), f, jnp.inf)
    i = jnp.argmin(f)
    return X[i], f[i], jnp.sum(f < PENALTY)


def search_box(limits: JointLimits, n_harmonics: int = DEFAULT_HARMONICS,
               wf: float = DEFAULT_WF) -> tuple[np.ndarray, np.ndarray]:
    """Bounds ``(lower, upper)`` on :meth:`FourierTrajectory.to_vector` derived from the
    limits.

    Harmonic ``k`` of joint ``j`` alone, with amplitude ``r``, moves the joint by ``r / (k
    wf)``, at speed ``r`` and acceleration ``r k wf``; the largest amplitude that keeps all
    three inside the limits is ``c_jk = min(qd_max, qdd_max / (k wf), R k wf)``, ``R``
    half the position range (pi when unbounded). The box is ``|a_k|, |b_k| <= c_jk /
    sqrt(2 N)``: each harmonic's amplitude ``sqrt(a_k^2 + b_k^2)`` is then at most
    ``c_jk / sqrt(N)``, so the root-sum-square of the N amplitudes is at most ``c_jk``.
    About a third of the box is feasible for RS010N (Table 3, N = 5), and on RS010N the
    swarm found better designs in this box than in ones 1.4 times wider or 1.1 times
    narrower (measured, 3-4 seeds each). ``q0``: the middle half of the position range
    (``[-pi/2, pi/2]`` when unbounded), leaving room for the motion about it.
    """
    n = limits.n_joints
    N = int(n_harmonics)
    if N < 1:
        raise ValueError(f"n_harmonics must be >= 1, got {n_harmonics!r}")
    wf = _check_wf(wf)
    q_min, q_max = np.asarray(limits.q_min), np.asarray(limits.q_max)
    bounded = np.isfinite(q_min) & np.isfinite(q_max)
    half = np.where(bounded, (q_max - q_min) / 2, math.pi)
    mid = np.where(bounded, (q_max + q_min) / 2, 0.0)
    kw = wf * np.arange(1, N + 1)
    c = np.minimum.reduce([
        np.broadcast_to(np.asarray(limits.qd_max)[:, None], (n, N)),
        np.asarray(limits.qdd_max)[:, None] / kw,
        half[:, None] * kw,
    ]) / math.sqrt(2 * N)
    upper = np.concatenate([c.ravel(), c.ravel(), mid + half / 2])
    lower = np.concatenate([-c.ravel(), -c.ravel(), mid - half / 2])
    return lower, upper


@dataclass(frozen=True, eq=False)
class ExcitationDesign:
    """What :func:`design_excitation` returns.

    Attributes:
        trajectory: the designed trajectory (feasible at ``times``).
        cond: its cond(W_b) over ``times``.
        random_cond: cond(W_b) over ``times`` of the best feasible trajectory among as many
            uniform random draws from the same box as the swarm made evaluations
            (``inf`` when none was feasible).
        times: the sample times (``duration * rate`` of them, from 0, endpoint excluded).
        result: the swarm's :class:`~sedsabso_jax.result.Result` (fitness on the design grid).
        random_trajectory: that best random trajectory (None when none was feasible).
        design_cond: the trajectory's cond on the design grid (what the swarm minimised).
        n_random: random draws made; n_random_feasible: how many were feasible.
        design_samples: size of the design grid.
        random_s: wall time of the random baseline (compilation included).
    """

    trajectory: FourierTrajectory
    cond: float
    random_cond: float
    times: np.ndarray
    result: Result
    random_trajectory: FourierTrajectory | None
    design_cond: float
    n_random: int
    n_random_feasible: int
    design_samples: int
    random_s: float
    robot_name: str = ""

    def summary(self) -> dict:
        """JSON-ready figures of the design (for results files)."""
        tr = self.trajectory
        return {"n_harmonics": tr.n_harmonics, "wf": tr.wf, "period_s": tr.period,
                "samples": len(self.times),
                "rate_hz": float(1.0 / (self.times[1] - self.times[0]))
                if len(self.times) > 1 else None,
                "cond": float(self.cond), "random_cond": _finite_or_none(self.random_cond),
                "design_samples": self.design_samples, "design_cond": float(self.design_cond),
                "solver": self.result.method, "evaluations": int(self.result.n_evaluations),
                "n_random": self.n_random, "n_random_feasible": self.n_random_feasible,
                "a": np.asarray(tr.a).tolist(), "b": np.asarray(tr.b).tolist(),
                "q0": np.asarray(tr.q0).tolist()}

    def __repr__(self) -> str:
        tr = self.trajectory
        dt = float(self.times[1] - self.times[0]) if len(self.times) > 1 else float("nan")
        return (
            f"ExcitationDesign({self.robot_name!r}, N={tr.n_harmonics}, wf={tr.wf:.6g} rad/s "
            f"(period {tr.period:.6g} s), {len(self.times)} samples at {1 / dt:.6g} Hz: "
            f"cond {self.cond:.6g} (design grid of {self.design_samples}: "
            f"{self.design_cond:.6g}); best random feasible {self.random_cond:.6g} "
            f"({self.n_random_feasible} of {self.n_random} draws feasible); "
            f"{self.result.method} {int(self.result.n_evaluations)} evaluations, compile "
            f"{self.result.compile_s:.2f} s, run {self.result.run_s:.2f} s, random "
            f"{self.random_s:.2f} s)"
        )


def _finite_or_none(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None


def default_solver():
    """The default swarm of :func:`design_excitation`: LDWPSO with 40 particles (the
    paper's LDWPSO settings otherwise); the module docstring compares it with BSO and
    SEDSABSO on this problem."""
    from .ldwpso import LDWPSO

    return LDWPSO(n_particles=40)


def design_excitation(robot: Robot, limits: JointLimits, *, n_harmonics: int = DEFAULT_HARMONICS,
                      wf: float = DEFAULT_WF, duration: float = DEFAULT_DURATION,
                      rate: float = DEFAULT_RATE, design_samples: int = DEFAULT_DESIGN_SAMPLES,
                      solver: AbstractSwarm | None = None,
                      iterations: int = DEFAULT_ITERATIONS, key=None,
                      graded_penalty: bool = True,
                      base: BaseParameters | None = None) -> ExcitationDesign:
    """Design an excitation trajectory by Eq. 9 with a swarm; compare with random search.

    The experiment samples ``times = arange(round(duration * rate)) / rate``. The swarm's
    condition number is taken at ``design_samples`` equally spaced times over ``[0,
    duration)``, the limits at as many over one period with :func:`sampling_margin`, so
    the design meets them at every time; ``ExcitationDesign.cond`` is recomputed at
    ``times``. The search box is :func:`search_box`; ``graded_penalty``: see the module
    docstring. ``solver``: any of the package's swarms (default :func:`default_solver`),
    run for ``iterations``; ``key``: a JAX PRNG key or an int seed (default 0), the same
    key giving the same design; ``base``: the robot's base parameters when already
    computed. Raises RuntimeError when the swarm found no feasible trajectory.
    """
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a Robot, got {type(robot).__name__}")
    if not isinstance(limits, JointLimits):
        raise TypeError(f"limits must be JointLimits, got {type(limits).__name__}")
    n = robot.n_joints
    if limits.n_joints != n:
        raise ValueError(f"limits are for {limits.n_joints} joints, robot {robot.name!r} has {n}")
    for name, value in (("n_harmonics", n_harmonics), ("design_samples", design_samples),
                        ("iterations", iterations)):
        if not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
    wf = _check_wf(wf)
    for name, value in (("duration", duration), ("rate", rate)):
        if not (isinstance(value, (int, float, np.number)) and math.isfinite(value)
                and value > 0):
            raise ValueError(f"{name} must be a positive number, got {value!r}")
    n_samples = int(round(duration * rate))
    if n_samples < 2:
        raise ValueError(f"duration * rate must give at least 2 samples, got {n_samples}")
    if not isinstance(graded_penalty, (bool, np.bool_)):
        raise TypeError(f"graded_penalty must be True or False, got {graded_penalty!r}")
    base = _base_parameters(robot) if base is None else base
    if not isinstance(base, BaseParameters) or base.robot.n_params != robot.n_params:
        raise ValueError(f"base must be the BaseParameters of robot {robot.name!r} "
                         f"({robot.n_params} parameters), got {base!r}")
    if design_samples * n < base.rank:
        raise ValueError(f"design_samples * n_joints = {design_samples * n} rows cannot "
                         f"determine {base.rank} base parameters; raise design_samples")
    if solver is None:
        solver = default_solver()
    if key is None or isinstance(key, (int, np.integer)):
        key = jax.random.key(0 if key is None else int(key))
    times = np.arange(n_samples) / rate
    problem = _problem(robot, base, limits, int(n_harmonics), wf, duration, int(design_samples),
                       graded_penalty)
    lower, upper = check_bounds(*search_box(limits, n_harmonics, wf))
    k_swarm, k_random = jax.random.split(key)
    result = minimise(_design_fitness, solver, lower, upper, key=k_swarm,
                      iterations=int(iterations), args=problem)
    if not float(result.f) < PENALTY:
        raise RuntimeError(
            f"no feasible excitation trajectory for {robot.name!r} in "
            f"{int(result.n_evaluations)} evaluations (best fitness {float(result.f):.6g}); "
            "give the swarm more iterations or a larger population")
    traj = FourierTrajectory.from_vector(result.x, n, n_harmonics, wf)
    check_trajectory(traj, limits, times)
    cond = condition_number(base, *_sample(traj, times))

    # Random baseline: as many uniform draws from the same box as the swarm's evaluations,
    # in batches of a fixed size (one compilation), the best by the same fitness.
    t0 = time.perf_counter()
    budget = int(result.n_evaluations)
    batch = RANDOM_BATCH
    lo, hi = jnp.asarray(lower), jnp.asarray(upper)
    best_x, best_f, n_feasible = None, math.inf, 0
    for i in range(math.ceil(budget / batch)):
        valid = jnp.int32(min(batch, budget - i * batch))
        x, f, nf = _random_batch(problem, lo, hi, jax.random.fold_in(k_random, i), batch, valid)
        n_feasible += int(nf)
        if float(f) < best_f:
            best_x, best_f = x, float(f)
    random_s = time.perf_counter() - t0
    random_traj, random_cond = None, math.inf
    if best_f < PENALTY:
        random_traj = FourierTrajectory.from_vector(best_x, n, n_harmonics, wf)
        random_cond = condition_number(base, *_sample(random_traj, times))
    return ExcitationDesign(
        trajectory=traj, cond=cond, random_cond=random_cond, times=times, result=result,
        random_trajectory=random_traj, design_cond=float(result.f), n_random=budget,
        n_random_feasible=n_feasible, design_samples=int(design_samples), random_s=random_s,
        robot_name=robot.name,
    )
