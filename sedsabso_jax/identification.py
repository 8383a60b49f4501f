"""Identify a robot's base parameters from joint data: least squares, weighted least
squares, the L1 optimum, Levenberg-Marquardt, the swarms, and a physically consistent fit.

Everything here works on arrays (``q, qd, qdd, tau`` of shape ``(samples, n)``); loading
and filtering measurements is not part of it.

Model (``friction``, terms joined by ``+``)::

    tau = Yb(q, qd, qdd) beta                   base regressor, Coulomb + viscous friction
          + OFF_j                               "offset": a constant torque per joint
          + FQ_j qd_j |qd_j|                    "quadratic": velocity-squared friction
    sign(qd_j) -> tanh(qd_j / smooth_velocity)  "smooth": Coulomb term without the jump

The extra columns come after the base columns, named ``OFF1..OFFn`` and ``FQ1..FQn``.

Methods: ``"OLS"`` (column-pivoted QR), ``"WLS"`` (OLS on rows divided by a per-joint
standard deviation; by default Gautier's two-step estimate from an OLS pass's residuals),
``"L1"`` (the exact minimiser of the summed absolute residual, the paper's Eq. 17, as the
dual linear programme with HiGHS), ``"LM"`` (optimistix Levenberg-Marquardt on the L2
problem), ``"SEDSABSO"``, ``"BSO"``, ``"LDWPSO"`` (the swarms on the L1 objective, in a box
around the a-priori base parameters). Any method takes ``weights``; the swarms and L1 then
minimise the weighted L1 norm.

``physical=True`` (with OLS or WLS) fits the full parameters instead, under physical
consistency (Wensing, Kim & Slotine 2017): each link's 4x4 pseudo-inertia
``J = [[tr(I)/2 1 - I, h], [h^T, m]]`` (``I`` about the link-frame origin, ``h = m c``)
positive definite (eigenvalues >= ``PSD_MARGIN``), which is positive mass, a positive
definite inertia satisfying the triangle inequalities and a CoM inside the mass's
ellipsoid; friction coefficients (Fc, Fv and FQ) >= 0; offsets free. The weighted least
squares under these constraints is a convex (semidefinite) problem; it is solved by a
log-barrier interior-point method (Newton steps on the 10 n + 2 n + extras variables), so
the optimum is global. ``prior_weight > 0`` adds ``prior_weight * ||p - prior||^2`` on the
full inertial and friction parameters (the squares of the weighted residual being the data
term); a pull of ``RIDGE`` (relative) is always there, so that directions the data leave
free stay finite.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from typing import Any

import numpy as np
import scipy.linalg
import scipy.optimize

from .base_parameters import BaseParameters, base_parameters
from .baselines import l1_solve
from .robot import N_LINK_PARAMETERS, Robot

METHODS = ("OLS", "WLS", "L1", "LM", "SEDSABSO", "BSO", "LDWPSO")
SWARMS = ("SEDSABSO", "BSO", "LDWPSO")
FRICTION_TERMS = ("viscous-coulomb", "offset", "quadratic", "smooth")
#: Relative pivoted-QR diagonal (unit-norm columns) below which a column is dependent.
RANK_RTOL = 1e-10
#: ... and below which it is called poorly identifiable (condition number warning).
ILL_RTOL = 1e-6
#: Smallest eigenvalue of each link's pseudo-inertia in a physical fit (kg m^2, kg).
PSD_MARGIN = 1e-6
#: Smallest pull to the prior in a physical fit, relative to the mean curvature of the data
#: term (keeps the non-identifiable directions finite).
RIDGE = 1e-9
#: Velocity scale (rad/s or m/s) of the "smooth" Coulomb term tanh(qd / v).
SMOOTH_VELOCITY = 0.02


# ----------------------------------------------------------------------------- model
@dataclasses.dataclass(frozen=True, eq=False)
class Model:
    """A linear torque model: the base regressor of ``robot`` plus extra friction terms.

    ``regressor(q, qd, qdd)`` is ``(..., n, d)`` with ``d = base.rank + len(extras) * n``;
    ``predict(values, q, qd, qdd)`` is ``regressor @ values``.
    """

    base: BaseParameters
    friction: str = "viscous-coulomb"
    smooth_velocity: float = SMOOTH_VELOCITY

    @property
    def robot(self) -> Robot:
        return self.base.robot

    @property
    def terms(self) -> tuple[str, ...]:
        return tuple(self.friction.split("+"))

    @property
    def extras(self) -> tuple[str, ...]:
        """Extra column groups in order: ``"OFF"`` and/or ``"FQ"``."""
        return tuple(k for t, k in (("offset", "OFF"), ("quadratic", "FQ")) if t in self.terms)

    @property
    def names(self) -> tuple[str, ...]:
        n = self.robot.n_joints
        return tuple(self.base.names) + tuple(f"{k}{j + 1}" for k in self.extras
                                              for j in range(n))

    @property
    def dim(self) -> int:
        return self.base.rank + len(self.extras) * self.robot.n_joints

    def regressor(self, q, qd, qdd) -> np.ndarray:
        q, qd, qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
        Y = np.asarray(self.base.regressor(q, qd, qdd))
        n = self.robot.n_joints
        batch = Y.shape[:-2]
        qd = np.broadcast_to(qd, batch + (n,))
        rows = np.arange(n)
        if "smooth" in self.terms:
            Y = Y.copy()
            Y[..., rows, self._fc_columns()] = np.tanh(qd / self.smooth_velocity)
        cols = [Y]
        for k in self.extras:
            E = np.zeros(batch + (n, n))
            E[..., rows, rows] = 1.0 if k == "OFF" else qd * np.abs(qd)
            cols.append(E)
        return np.concatenate(cols, -1) if len(cols) > 1 else Y

    def predict(self, values, q, qd, qdd) -> np.ndarray:
        values = np.asarray(values, dtype=float)
        if values.shape != (self.dim,):
            raise ValueError(f"values must have shape ({self.dim},), got {values.shape}")
        return self.regressor(q, qd, qdd) @ values

    def _fc_columns(self) -> np.ndarray:
        """Base column of each joint's Coulomb coefficient (friction never regroups)."""
        full = [self.base.indices.index(N_LINK_PARAMETERS * j + 10)
                if N_LINK_PARAMETERS * j + 10 in self.base.indices else -1
                for j in range(self.robot.n_joints)]
        if min(full) < 0:
            raise ValueError("friction='...+smooth' needs every joint's Coulomb column in the "
                             "base set")
        return np.asarray(full)


# ----------------------------------------------------------------------------- result
@dataclasses.dataclass(frozen=True, eq=False)
class Identification:
    """What :func:`identify` returns.

    Attributes:
        names: parameter names, base columns then extra columns (``OFF1``, ``FQ1``, ...).
        values: the identified values, one per name.
        model: the :class:`Model`; ``predict(q, qd, qdd)`` uses it.
        method: the method name.
        settings: the settings used (JSON-ready).
        fit: statistics of the fit residual on the identification data (JSON-ready):
            per-joint RMS (``rms``), ``l1`` and ``l2`` (sum of |r| and of r^2, weighted as
            the method saw them), ``nrms_limits_percent`` when ``limits`` were given,
            ``condition_number`` of the stacked regressor (unit-norm columns), ``rank``.
        full_params: the full parameters (12 per link) of a physical fit, else ``None``.
        result: the swarm's :class:`~sedsabso_jax.result.Result` (all runs) for a swarm
            (or the baseline's for ``"LM"``), else ``None``.
    """

    names: tuple[str, ...]
    values: np.ndarray
    model: Model
    method: str
    settings: dict
    fit: dict
    full_params: np.ndarray | None = None
    result: Any = None

    def predict(self, q, qd, qdd) -> np.ndarray:
        """Predicted torques ``(..., n)`` for states ``(..., n)``."""
        return self.model.predict(self.values, q, qd, qdd)

    def as_dict(self) -> dict:
        """Names, values, method, settings and fit statistics, JSON-ready."""
        out = {"method": self.method, "names": list(self.names),
               "values": [float(v) for v in self.values], "settings": self.settings,
               "fit": self.fit}
        if self.full_params is not None:
            out["full_params"] = [float(v) for v in self.full_params]
        return out

    def __repr__(self) -> str:
        rms = ", ".join(f"{r:.3g}" for r in self.fit["rms"])
        return (f"Identification({self.method}, {len(self.names)} parameters, "
                f"friction={self.model.friction!r}, fit RMS per joint [{rms}])")


# ----------------------------------------------------------------------------- checks
def _canonical_friction(friction) -> str:
    if not isinstance(friction, str) or not friction:
        raise ValueError(f"friction must be a string of terms joined by '+' from "
                         f"{FRICTION_TERMS}, got {friction!r}")
    terms = {t.strip() for t in friction.split("+")}
    unknown = terms - set(FRICTION_TERMS)
    if unknown:
        raise ValueError(f"unknown friction term(s) {sorted(unknown)}; known: {FRICTION_TERMS} "
                         f"(joined by '+', e.g. 'viscous-coulomb+offset')")
    terms.add("viscous-coulomb")
    return "+".join(t for t in FRICTION_TERMS if t in terms)


def _check_data(robot: Robot, q, qd, qdd, tau):
    n = robot.n_joints
    arrays = []
    for name, a in (("q", q), ("qd", qd), ("qdd", qdd), ("tau", tau)):
        a = np.asarray(a, dtype=float)
        if a.ndim != 2 or a.shape[1] != n:
            raise ValueError(f"{name} must have shape (samples, {n}) for robot {robot.name!r}, "
                             f"got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name} contains NaN or Inf")
        arrays.append(a)
    lengths = {a.shape[0] for a in arrays}
    if len(lengths) != 1:
        raise ValueError(f"q, qd, qdd and tau need the same number of samples, got "
                         f"{[a.shape[0] for a in arrays]}")
    if arrays[0].shape[0] == 0:
        raise ValueError("no samples")
    return arrays


def _per_joint(name, value, n, allow_none=True):
    if value is None and allow_none:
        return None
    v = np.asarray(value, dtype=float)
    if v.shape != (n,) or not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise ValueError(f"{name} must be {n} positive finite numbers (one per joint), got "
                         f"{value!r}")
    return v


# ----------------------------------------------------------------------------- solvers
def _triangular(W, tau):
    """Column scales (norms) and the triangular factor of ``[W / scale, tau]``: ``R`` and
    ``c`` with ``||W x - tau|| = ||R (scale x) - c||`` up to a constant."""
    norms = np.linalg.norm(W, axis=0)
    scale = np.where(norms > 0, norms, 1.0)
    d = W.shape[1]
    Ra = np.linalg.qr(np.column_stack([W / scale, tau]), mode="r")
    return norms, scale, Ra[:, :d], Ra[:, d]


def _pivoted_rank(norms, R0, names):
    """Rank, condition number (unit-norm columns) and the names of the columns a pivoted QR
    puts last below ``RANK_RTOL`` (dependent) and ``ILL_RTOL`` (poorly identifiable).
    The pivoted QR runs on the triangular factor ``R0`` of ``W`` (same column geometry)."""
    d = R0.shape[1]
    R, perm = scipy.linalg.qr(R0, mode="r", pivoting=True)
    diag = np.abs(np.diag(R))
    top = diag[0] if diag.size and diag[0] > 0 else 1.0
    rel = np.zeros(d)
    rel[: diag.size] = diag / top
    rel[norms[perm] == 0] = 0.0
    rank = int(np.sum(rel > RANK_RTOL))
    s = np.linalg.svd(R0, compute_uv=False)
    cond = float(s[0] / s[-1]) if s.size == d and s[-1] > 0 else np.inf
    weak = [names[perm[i]] for i in range(d) if rel[i] <= ILL_RTOL]
    return rank, cond, weak


def _l2(W, tau, factor=None):
    """argmin ||W x - tau||_2 on unit-norm columns (minimum norm if rank deficient), from
    the triangular factor (``_triangular``; computed unless given)."""
    _, scale, R, c = _triangular(W, tau) if factor is None else factor
    x = scipy.linalg.lstsq(R, c, cond=RANK_RTOL, lapack_driver="gelsd")[0]
    return x / scale


def _pseudo_inertia(p10):
    """(k, 10) link parameters [Ixx Iyy Izz Ixy Ixz Iyz m mx my mz] -> (k, 4, 4)."""
    p10 = np.asarray(p10, dtype=float)
    Ixx, Iyy, Izz, Ixy, Ixz, Iyz, m, mx, my, mz = np.moveaxis(p10, -1, 0)
    I = np.stack([np.stack([Ixx, Ixy, Ixz], -1), np.stack([Ixy, Iyy, Iyz], -1),
                  np.stack([Ixz, Iyz, Izz], -1)], -2)
    J = np.zeros(p10.shape[:-1] + (4, 4))
    J[..., :3, :3] = 0.5 * np.trace(I, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - I
    J[..., :3, 3] = J[..., 3, :3] = np.stack([mx, my, mz], -1)
    J[..., 3, 3] = m
    return J


def _link_params(J):
    """(k, 4, 4) pseudo-inertia -> (k, 10) link parameters (inverse of _pseudo_inertia)."""
    S = J[..., :3, :3]
    I = np.trace(S, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - S
    return np.stack([I[..., 0, 0], I[..., 1, 1], I[..., 2, 2], I[..., 0, 1], I[..., 0, 2],
                     I[..., 1, 2], J[..., 3, 3], J[..., 0, 3], J[..., 1, 3], J[..., 2, 3]], -1)


def is_physically_consistent(params, margin: float = 0.0) -> bool:
    """Whether every link of a full parameter vector (12 per link) has a pseudo-inertia
    with eigenvalues > ``margin`` (positive mass, positive-definite inertia satisfying the
    triangle inequalities)."""
    p = np.asarray(params, dtype=float).reshape(-1, N_LINK_PARAMETERS)
    return bool(np.all(np.linalg.eigvalsh(_pseudo_inertia(p[:, :10])) > margin))


_IU = np.triu_indices(4)
_SV = np.where(_IU[0] == _IU[1], 1.0, np.sqrt(2.0))  # svec: ||svec(J)|| = ||J||_F


def _svec(J):
    return J[..., _IU[0], _IU[1]] * _SV


def _smat(s):
    J = np.zeros(s.shape[:-1] + (4, 4))
    J[..., _IU[0], _IU[1]] = s / _SV
    return J + np.swapaxes(np.triu(J, 1), -1, -2)


def _physical(model: Model, W, tau, prior, prior_weight, factor=None, tol=1e-10,
              max_newton=500):
    """Least squares ``||W x - tau||^2`` over physically consistent full parameters.

    Variables ``v = [svec(J_1) .. svec(J_n), (Fc_j, Fv_j)_j, extras]`` (``svec`` keeps
    ``||J||_F``); the base values are ``x = C v``, linear in ``v``. Minimises
    ``f(v) = ||A v - c||^2 + lam ||P v - p0||^2`` subject to ``J_i - margin 1 >= 0`` and
    nonnegative friction coefficients by a log-barrier interior-point method (Boyd &
    Vandenberghe 2004, Sec. 11.3): damped Newton steps on ``f - mu sum(log det(J_i -
    margin 1)) - mu sum(log v_k)``, ``mu`` divided by 10 until the duality-gap bound
    ``m mu`` (``m`` = 4 per link + nonnegative entries) is below ``tol`` relative to ``f``.
    Returns base values, full parameters and the number of Newton steps.
    """
    n = model.robot.n_joints
    n_extra = len(model.extras) * n
    d_full = N_LINK_PARAMETERS * n
    nv = 10 * n + 2 * n + n_extra
    E = _smat(np.eye(10))  # svec unit k -> symmetric 4x4 with ||E_k||_F = 1
    # G: v -> [full params (12 n), extras]
    G = np.zeros((d_full + n_extra, nv))
    for i in range(n):
        G[12 * i: 12 * i + 10, 10 * i: 10 * i + 10] = _link_params(E).T
        G[12 * i + 10, 10 * n + 2 * i] = 1.0
        G[12 * i + 11, 10 * n + 2 * i + 1] = 1.0
    G[d_full:, 12 * n:] = np.eye(n_extra)
    K = np.asarray(model.base.matrix)
    C = np.zeros((model.dim, d_full + n_extra))
    C[: K.shape[0], :d_full] = K
    C[K.shape[0]:, d_full:] = np.eye(n_extra)
    CG = C @ G
    _, scale, R, c = _triangular(W, tau) if factor is None else factor
    A = (R * scale) @ CG
    H, g, cc = A.T @ A, A.T @ c, float(tau @ tau)
    # the data leave directions of v free (non-identifiable), and along some of them the
    # feasible set is unbounded: a tiny pull to the prior keeps the solution finite
    prior_weight = max(prior_weight, RIDGE * np.trace(H) / nv)
    if prior_weight > 0:
        P = G[:d_full]
        H = H + prior_weight * P.T @ P
        g = g + prior_weight * P.T @ prior
        cc += prior_weight * float(prior @ prior)
    # nonnegative: friction coefficients (Fc, Fv) and FQ; offsets free
    nonneg = np.zeros(nv, bool)
    nonneg[10 * n: 12 * n] = True
    if "FQ" in model.extras:
        k = model.extras.index("FQ")
        nonneg[12 * n + k * n: 12 * n + (k + 1) * n] = True
    m_barrier = 4 * n + int(nonneg.sum())
    margin = PSD_MARGIN * np.eye(4)

    def f(v):
        return float(v @ H @ v - 2 * g @ v + cc)

    def slack(v):
        return _smat(v[: 10 * n].reshape(n, 10)) - margin, v[nonneg]

    def feasible(v):
        S, w = slack(v)
        return bool(np.all(np.linalg.eigvalsh(S)[:, 0] > 0) and np.all(w > 0))

    def barrier(v):
        S, w = slack(v)
        return -float(np.sum(np.linalg.slogdet(S)[1]) + np.sum(np.log(w)))

    def barrier_derivatives(v):
        S, w = slack(v)
        Sinv = np.linalg.inv(S)  # (n, 4, 4)
        grad, hess = np.zeros(nv), np.zeros((nv, nv))
        gJ = -np.einsum("iab,kba->ik", Sinv, E)
        hJ = np.einsum("iab,kbc,icd,lda->ikl", Sinv, E, Sinv, E)
        for i in range(n):
            sl = slice(10 * i, 10 * i + 10)
            grad[sl], hess[sl, sl] = gJ[i], hJ[i]
        idx = np.flatnonzero(nonneg)
        grad[idx] = -1.0 / w
        hess[idx, idx] = 1.0 / w ** 2
        return grad, hess

    # strictly feasible start from the prior
    p0 = prior.reshape(n, N_LINK_PARAMETERS)
    J0 = _pseudo_inertia(p0[:, :10])
    lam, U = np.linalg.eigh(J0)
    floor = PSD_MARGIN + 1e-3 * np.maximum(lam[:, -1:], 1e-3)
    J0 = (U * np.maximum(lam, floor)[:, None, :]) @ np.swapaxes(U, -1, -2)
    v = np.concatenate([_svec(J0).reshape(-1), np.zeros(2 * n + n_extra)])
    v[10 * n: 12 * n] = p0[:, 10:].reshape(-1)
    v[nonneg] = np.maximum(v[nonneg], 1e-3)
    floor_f = 1e-12 * max(cc, 1e-300)  # scale of "zero residual" (exact data)
    mu = max(f(v), floor_f) / m_barrier
    steps = 0
    while steps < max_newton:
        for _ in range(max_newton - steps):  # centring: damped Newton
            gb, hb = barrier_derivatives(v)
            grad = 2 * (H @ v - g) + mu * gb
            hess = 2 * H + mu * hb
            try:
                dv = -scipy.linalg.cho_solve(scipy.linalg.cho_factor(hess), grad)
            except np.linalg.LinAlgError:
                dv = -np.linalg.lstsq(hess, grad, rcond=None)[0]
            decrement = -grad @ dv
            steps += 1
            if decrement / 2 <= 1e-12 * max(f(v), floor_f):
                break
            F0, t = f(v) + mu * barrier(v), 1.0
            while t > 1e-12:
                vt = v + t * dv
                if feasible(vt) and f(vt) + mu * barrier(vt) <= F0 - 0.25 * t * decrement:
                    break
                t *= 0.5
            else:
                break
            v = vt
        if m_barrier * mu <= tol * max(f(v), floor_f):
            break
        mu /= 10.0
    full = G @ v
    return CG @ v, full[:d_full], steps


# ----------------------------------------------------------------------------- identify
def identify(robot: Robot, q, qd, qdd, tau, *, method: str = "OLS",
             friction: str = "viscous-coulomb", weights=None, limits=None,
             physical: bool = False, prior=None, prior_weight: float = 0.0,
             box=(0.5, 0.5), runs: int = 1, iterations: int = 600, seed: int = 0,
             solver=None, smooth_velocity: float = SMOOTH_VELOCITY,
             base: BaseParameters | None = None) -> Identification:
    """Identify the base parameters (plus extra friction terms) of ``robot`` from
    ``q, qd, qdd, tau`` (each ``(samples, n)``).

    Args:
        method: one of ``METHODS`` (see the module docstring).
        friction: ``"viscous-coulomb"`` plus optional ``"+offset"``, ``"+quadratic"``,
            ``"+smooth"`` (any order).
        weights: per-joint standard deviations dividing each joint's rows: ``None`` (equal;
            for ``"WLS"`` it means ``"residual"``), ``"residual"`` (Gautier's two-step
            WLS: the RMS of each joint's OLS residual, corrected for the parameters on that
            joint), ``"limits"`` (the torque ``limits``, which makes the L2 objective the
            squared NRMS-over-limits error), or ``n`` positive numbers.
        limits: per-joint torque limits (N m): the fit reports its NRMS over them; needed
            by ``weights="limits"``.
        physical: fit physically consistent full parameters (OLS / WLS only).
        prior: full a-priori parameters (12 per link); default ``robot.params``. Centre of
            the swarms' box (projected on the base; extras centred on 0) and target of
            ``prior_weight``.
        prior_weight: weight of ``||p - prior||^2`` in a physical fit.
        box: the swarms' box: ``(fraction, floor)`` gives centre ``+- max(fraction
            |centre|, floor)``; or explicit ``(lower, upper)`` arrays of length ``dim``.
        runs, iterations, seed, solver: swarm runs (the best is kept), iterations, PRNG
            seed, and a solver instance (default: the method's ``.paper()`` settings).
        smooth_velocity: the "smooth" Coulomb term's ``tanh(qd / smooth_velocity)``.
        base: a precomputed ``base_parameters(robot)`` (computed when ``None``).

    Warns (``UserWarning``) with the condition number and the names of the columns
    concerned when the stacked regressor is rank deficient or poorly conditioned.
    """
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a sedsabso_jax.Robot, got {type(robot).__name__}")
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    friction = _canonical_friction(friction)
    n = robot.n_joints
    q, qd, qdd, tau = _check_data(robot, q, qd, qdd, tau)
    limits = _per_joint("limits", limits, n)
    if physical and method not in ("OLS", "WLS"):
        raise ValueError(f"physical=True is a least-squares fit: use method 'OLS' or 'WLS', "
                         f"not {method!r}")
    if not (np.isfinite(prior_weight) and prior_weight >= 0):
        raise ValueError(f"prior_weight must be >= 0, got {prior_weight!r}")
    if not (np.isfinite(smooth_velocity) and smooth_velocity > 0):
        raise ValueError(f"smooth_velocity must be > 0, got {smooth_velocity!r}")
    if method in SWARMS:
        for name, v in (("runs", runs), ("iterations", iterations)):
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
    prior = np.asarray(robot.params if prior is None else prior, dtype=float)
    if prior.shape != (robot.n_params,) or not np.all(np.isfinite(prior)):
        raise ValueError(f"prior must be {robot.n_params} finite full parameters (12 per "
                         f"link), got shape {prior.shape}")
    if base is None:
        base = base_parameters(robot)
    elif not isinstance(base, BaseParameters) or base.robot.n_params != robot.n_params:
        raise ValueError("base must be base_parameters(robot) of this robot")
    model = Model(base, friction, float(smooth_velocity))

    # weights
    if isinstance(weights, str):
        if weights not in ("residual", "limits"):
            raise ValueError(f"weights must be None, 'residual', 'limits' or {n} positive "
                             f"numbers, got {weights!r}")
        kind = weights
    elif weights is None:
        kind = "residual" if method == "WLS" else "equal"
    else:
        kind = "given"
        given = _per_joint("weights", weights, n, allow_none=False)
    if kind == "limits" and limits is None:
        raise ValueError("weights='limits' needs limits=(one torque limit per joint)")

    if method in SWARMS:
        solver = _check_swarm_settings(method, solver, box, model.dim)

    t0 = time.perf_counter()
    Y = model.regressor(q, qd, qdd)  # (T, n, d)
    T, d = Y.shape[0], Y.shape[-1]
    W0, tau0 = Y.reshape(-1, d), tau.reshape(-1)
    names = model.names
    factor0 = _triangular(W0, tau0)
    rank, cond, weak = _pivoted_rank(factor0[0], factor0[2], names)
    if rank < d:
        warnings.warn(f"identify: the stacked regressor ({W0.shape[0]} x {d}) is rank "
                      f"deficient (rank {rank}, condition number {cond:.3g} with unit-norm "
                      f"columns); unidentifiable from these data: {', '.join(weak)}",
                      stacklevel=2)
    elif weak:
        warnings.warn(f"identify: the stacked regressor is ill-conditioned (condition number "
                      f"{cond:.3g} with unit-norm columns); poorly identifiable: "
                      f"{', '.join(weak)}", stacklevel=2)

    if kind == "equal":
        sigma = np.ones(n)
    elif kind == "limits":
        sigma = limits
    elif kind == "given":
        sigma = given
    else:  # Gautier: sigma_j^2 = ||r_j||^2 / (T - d_j), d_j = parameters acting on joint j
        r = (Y @ _l2(W0, tau0, factor0) - tau)
        d_j = np.count_nonzero(np.any(Y != 0, axis=0), axis=-1)
        sigma = np.sqrt(np.sum(r ** 2, axis=0) / np.maximum(T - d_j, 1))
        sigma = np.where(sigma > 0, sigma, max(sigma.max(), 1e-12))
    if kind == "equal":
        W, b, factor = W0, tau0, factor0
    else:
        row = np.tile(1.0 / sigma, T)
        W, b, factor = W0 * row[:, None], tau0 * row, None

    result, full, extra = None, None, {}
    if physical:
        x, full, extra["newton_steps"] = _physical(model, W, b, prior, float(prior_weight),
                                                   factor)
    elif method in ("OLS", "WLS"):
        x = _l2(W, b, factor)
    elif method == "L1":
        x, extra["lp_iterations"] = l1_solve(W, b)
    elif method == "LM":
        from .baselines import least_squares
        from .fitness import L1Residual

        norms = np.linalg.norm(W, axis=0)
        scale = np.where(norms > 0, norms, 1.0)
        result = least_squares(L1Residual(W / scale, b), "LM")
        x = np.asarray(result.x, dtype=float) / scale
        extra.update(steps=int(result.n_evaluations), compile_s=float(result.compile_s),
                     run_s=float(result.run_s))
    else:
        x, result, extra = _swarm(method, model, W, b, prior, box, runs, iterations, seed,
                                  solver)
    run_s = time.perf_counter() - t0

    r = Y @ x - tau
    rms = np.sqrt(np.mean(r ** 2, axis=0))
    rw = (W @ x - b)
    fit = {"rms": [float(v) for v in rms], "l1": float(np.abs(rw).sum()),
           "l2": float(rw @ rw), "condition_number": float(cond), "rank": rank,
           "samples": int(T), "seconds": float(run_s)}
    if limits is not None:
        fit["nrms_limits_percent"] = float(np.mean(rms / (2 * limits)) * 100)
    settings = {"method": method, "friction": friction, "physical": bool(physical),
                "weights": kind, "sigma": [float(s) for s in sigma],
                "limits": None if limits is None else [float(v) for v in limits]}
    if "smooth" in friction:
        settings["smooth_velocity"] = float(smooth_velocity)
    if physical:
        settings.update(prior_weight=float(prior_weight), psd_margin=PSD_MARGIN)
    settings.update(extra)
    return Identification(names=names, values=np.asarray(x, dtype=float), model=model,
                          method=method, settings=settings, fit=fit, full_params=full,
                          result=result)


def _swarm(method, model, W, b, prior, box, runs, iterations, seed, solver):
    import jax

    from .fitness import L1Residual
    from .swarm import minimise

    d = model.dim
    centre = np.concatenate([np.asarray(model.base.project(prior)),
                             np.zeros(d - model.base.rank)])
    box_setting: Any
    lo_hi = _box_arrays(box, d)
    if lo_hi is None:
        fraction, floor = (float(v) for v in box)
        half = np.maximum(fraction * np.abs(centre), floor)
        lower, upper = centre - half, centre + half
        box_setting = {"fraction": fraction, "floor": floor, "centre": "prior"}
    else:
        lower, upper = lo_hi
        box_setting = "explicit"
    res = minimise(L1Residual(W, b), solver, lower, upper, key=jax.random.key(seed),
                   iterations=int(iterations), runs=int(runs))
    X, f = np.atleast_2d(np.asarray(res.x)), np.atleast_1d(np.asarray(res.f))
    best = int(np.argmin(f))
    hyper = {fld.name: _jsonable(getattr(solver, fld.name))
             for fld in dataclasses.fields(solver)}
    extra = {"box": box_setting, "runs": int(runs), "iterations": int(iterations),
             "seed": int(seed), "solver": hyper, "best_run": best,
             "f_runs": [float(v) for v in f], "compile_s": float(res.compile_s),
             "run_s": float(res.run_s)}
    return X[best], res, extra


def _check_swarm_settings(method, solver, box, d):
    """The solver (default: the method's ``.paper()``), after checking it and the box."""
    from . import BSO, LDWPSO, SEDSABSO

    classes = {"SEDSABSO": SEDSABSO, "BSO": BSO, "LDWPSO": LDWPSO}
    if solver is None:
        solver = classes[method].paper()
    elif type(solver) is not classes[method]:
        raise ValueError(f"solver must be a {method} instance for method {method!r}, got "
                         f"{type(solver).__name__}")
    solver.check()
    if _box_arrays(box, d) is None:
        fraction, floor = (float(v) for v in box)
        if not (fraction >= 0 and floor >= 0 and fraction + floor > 0):
            raise ValueError(f"box (fraction, floor) must be >= 0 and not both 0, got {box!r}")
    else:
        lower, upper = _box_arrays(box, d)
        if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))
                and np.all(lower < upper)):
            raise ValueError("box bounds must be finite with lower < upper")
    return solver


def _box_arrays(box, d):
    """``(lower, upper)`` arrays if ``box`` is explicit bounds, ``None`` if (fraction, floor)."""
    try:
        a, b = box
    except (TypeError, ValueError):
        raise ValueError(f"box must be (fraction, floor) or (lower, upper) arrays, got "
                         f"{box!r}") from None
    if np.ndim(a) == 0 and np.ndim(b) == 0:
        return None
    lower, upper = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if lower.shape != (d,) or upper.shape != (d,):
        raise ValueError(f"box bounds must both have shape ({d},), got {lower.shape} and "
                         f"{upper.shape}")
    return lower, upper


def _jsonable(v):
    if isinstance(v, (bool, int, float, str)) or v is None:
        return v
    a = np.asarray(v)
    return a.tolist() if a.ndim else a.item()


def nrms_limits(pred, meas, limits) -> tuple[float, np.ndarray]:
    """NRMS over torque limits in percent: per joint ``RMS(pred - meas) / (2 limit) * 100``,
    and its mean over the joints."""
    pred, meas = np.asarray(pred, dtype=float), np.asarray(meas, dtype=float)
    per = np.sqrt(np.mean((pred - meas) ** 2, axis=0)) / (2 * np.asarray(limits)) * 100
    return float(per.mean()), per
