"""Identify a robot's base parameters from joint data: least squares, weighted least
squares, the L1 optimum, Levenberg-Marquardt, the swarms, and a physically consistent fit.

Everything here works on arrays (``q, qd, qdd, tau`` of shape ``(samples, n)``); loading
and filtering measurements is :mod:`sedsabso_jax.measurements`'s job. The torque model
(friction terms) is :mod:`.model`'s.

Methods: ``"OLS"`` (column-pivoted QR, :mod:`sedsabso_jax.optim.linear`), ``"WLS"`` (OLS
on rows divided by a per-joint standard deviation ``sigma``; by default Gautier's two-step
estimate from an OLS pass's residuals), ``"L1"`` (the exact minimiser of the summed absolute
residual, the paper's Eq. 17, as the dual linear programme with HiGHS), ``"LM"``
(optimistix Levenberg-Marquardt on the L2 problem), ``"SEDSABSO"``, ``"BSO"``, ``"LDWPSO"``
(the swarms on the L1 objective, in a box around the a-priori base parameters). Any method
takes ``sigma``; the swarms and L1 then minimise the weighted L1 norm.

``physical=True`` (with OLS or WLS) fits the full parameters instead, under physical
consistency (:mod:`.physical`: every link's pseudo-inertia positive definite, friction
coefficients >= 0; a semidefinite programme solved by Clarabel); ``prior_weight > 0`` adds
``prior_weight * ||p - prior||^2`` on the full inertial and friction parameters.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from typing import Any

import jax
import numpy as np

from .. import _deprecation
from .._output import jsonable
from .._version import __version__
from ..dynamics.base_parameters import BaseParameters, base_parameters
from ..dynamics.robot import Robot
from ..dynamics.urdf_writer import to_urdf
from ..optim.baselines import least_squares
from ..optim.box import box_around, check_bounds
from ..optim.driver import minimise
from ..optim.fitness import L1Residual
from ..optim.linear import factorize, l1_solve
from ..optim.registry import SWARMS
from .metrics import nrms_over_limits
from .model import SMOOTH_VELOCITY, TorqueModel, canonical_friction
from .physical import PSD_MARGIN, fit_physical

#: The estimators :func:`identify` offers (see the module docstring).
METHODS = ("OLS", "WLS", "L1", "LM", *SWARMS)
_UNSET = object()


@dataclasses.dataclass(frozen=True, eq=False)
class Identification:
    """What :func:`identify` returns.

    Attributes:
        names: parameter names, base columns then extra columns (``OFF1``, ``FQ1``, ...).
        values: the identified values, one per name.
        model: the :class:`~.model.TorqueModel`; ``predict(q, qd, qdd)`` uses it.
        method: the method name.
        settings: the settings used (JSON-ready).
        fit: statistics of the fit residual on the identification data (JSON-ready):
            per-joint RMS (``rms``), ``l1`` and ``l2`` (sum of |r| and of r^2, weighted as
            the method saw them), ``nrms_limits_percent`` when ``limits`` were given,
            ``condition_number`` of the stacked regressor (unit-norm columns), ``rank``.
        full_params: the full parameters (12 per link) of a physical fit, else ``None``.
        result: the swarm's :class:`~sedsabso_jax.Result` (all runs) for a swarm
            (or the baseline's for ``"LM"``), else ``None``.
    """

    names: tuple[str, ...]
    values: np.ndarray
    model: TorqueModel
    method: str
    settings: dict
    fit: dict
    full_params: np.ndarray | None = None
    result: Any = None

    def predict(self, q, qd, qdd) -> np.ndarray:
        """Predicted torques ``(..., n)`` for states ``(..., n)``."""
        return self.model.predict(self.values, q, qd, qdd)

    def urdf(self) -> str:
        """The robot's URDF with the identified link parameters and joint friction (a
        physical fit only: a simulator needs real bodies). Extra terms a URDF cannot
        hold (offsets, quadratic friction, armature, ...) are listed in a comment."""
        if self.full_params is None:
            raise ValueError("a URDF needs the full link parameters of a physically "
                             "consistent fit: identify with physical=True (--physical)")
        base = self.model.base.rank
        extras = ", ".join(f"{n} = {v:.6g}" for n, v in zip(self.names[base:],
                                                           self.values[base:]))
        comment = (f"link parameters identified by sedsabso-jax {__version__} "
                   f"({self.method}, physically consistent, friction {self.model.friction})"
                   + (f"; terms URDF cannot hold: {extras}" if extras else ""))
        return to_urdf(self.model.robot, self.full_params, comment=comment)

    def as_dict(self) -> dict:
        """Names, values, method, settings and fit statistics, JSON-ready."""
        out = {"method": self.method, "names": self.names, "values": self.values,
               "settings": self.settings, "fit": self.fit}
        if self.full_params is not None:
            out["full_params"] = self.full_params
        return jsonable(out)

    def __repr__(self) -> str:
        rms = ", ".join(f"{r:.3g}" for r in self.fit["rms"])
        return (f"Identification({self.method}, {len(self.names)} parameters, "
                f"friction={self.model.friction!r}, fit RMS per joint [{rms}])")


def check_data(robot: Robot, q, qd, qdd, tau):
    """``q, qd, qdd, tau`` as float arrays ``(samples, n)`` of one length, finite."""
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


@dataclasses.dataclass(frozen=True, eq=False)
class Setup:
    """A checked identification problem: the torque model and how to fit it. Built by
    :func:`prepare` from :func:`identify`'s arguments; :func:`fit_regressor` fits it to
    any rows of data (all of them, or the training folds of a cross-validation)."""

    model: TorqueModel
    method: str
    kind: str  # how sigma is chosen: "equal", "residual", "limits" or "given"
    given: np.ndarray | None
    limits: np.ndarray | None
    physical: bool
    prior: np.ndarray
    prior_weight: float
    prior_strength: float
    box: Any
    runs: int
    iterations: int
    seed: int
    solver: Any

    def settings(self) -> dict:
        """The settings that do not depend on the data."""
        out = {"method": self.method, "friction": self.model.friction,
               "physical": self.physical, "weights": self.kind, "limits": self.limits}
        if self.model.transmission is not None:
            out["transmission"] = self.model.transmission
        if self.model.regrouped:
            out["regrouped"] = list(self.model.regrouped)
        if "smooth" in self.model.friction:
            out["smooth_velocity"] = float(self.model.smooth_velocity)
        if self.physical:
            out.update(prior_weight=self.prior_weight, prior_strength=self.prior_strength,
                       psd_margin=PSD_MARGIN)
        return out


def prepare(robot: Robot, *, method: str = "OLS", friction: str = "viscous-coulomb",
            sigma=None, limits=None, physical: bool = False, prior=None,
            prior_weight: float = 0.0, prior_strength: float = 0.0, box=(0.5, 0.5),
            runs: int = 1, iterations: int = 600, seed: int = 0, solver=None,
            smooth_velocity: float = SMOOTH_VELOCITY, base: BaseParameters | None = None,
            transmission=None, warn: bool = True) -> Setup:
    """Check :func:`identify`'s settings (its docstring says what they mean) and build the
    torque model; nothing is fitted. ``warn``: say which extra columns the base regressor
    already spans."""
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a sedsabso_jax.Robot, got {type(robot).__name__}")
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    friction = canonical_friction(friction)
    n = robot.n_joints
    limits = _per_joint("limits", limits, n)
    if physical and method not in ("OLS", "WLS"):
        raise ValueError(f"physical=True is a least-squares fit: use method 'OLS' or 'WLS', "
                         f"not {method!r}")
    for name, v in (("prior_weight", prior_weight), ("prior_strength", prior_strength)):
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
                or not (np.isfinite(v) and v >= 0):
            raise ValueError(f"{name} must be a number >= 0, got {v!r}")
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
    K = getattr(transmission, "matrix", transmission)
    model = TorqueModel(base, friction, float(smooth_velocity), K)
    if warn and model.regrouped:
        warnings.warn(f"identify: {', '.join(model.regrouped)} cannot be identified apart from "
                      f"the base parameters (their columns are in the base regressor's span); "
                      f"left out of the model", stacklevel=3)
    given = None
    if isinstance(sigma, str):
        if sigma not in ("residual", "limits"):
            raise ValueError(f"sigma must be None, 'residual', 'limits' or {n} positive "
                             f"numbers, got {sigma!r}")
        kind = sigma
    elif sigma is None:
        kind = "residual" if method == "WLS" else "equal"
    else:
        kind = "given"
        given = _per_joint("sigma", sigma, n, allow_none=False)
    if kind == "limits" and limits is None:
        raise ValueError("sigma='limits' needs limits=(one torque limit per joint)")
    if method in SWARMS:
        solver = _check_swarm_settings(method, solver, box, model.dim)
    return Setup(model=model, method=method, kind=kind, given=given, limits=limits,
                 physical=bool(physical), prior=prior, prior_weight=float(prior_weight),
                 prior_strength=float(prior_strength),
                 box=box, runs=int(runs), iterations=int(iterations), seed=int(seed),
                 solver=solver)


@dataclasses.dataclass(frozen=True, eq=False)
class RegressorFit:
    """What :func:`fit_regressor` returns: the model's values (and full parameters of a
    physical fit), the sigma used, the factorisation of the unweighted rows (None when
    neither the diagnostics nor the fit needed it), the weighted rows ``W x ~ b``, the
    solver's :class:`~sedsabso_jax.Result` (swarms, LM) and extra settings."""

    x: np.ndarray
    full: np.ndarray | None
    sigma: np.ndarray
    factor0: Any
    W: np.ndarray
    b: np.ndarray
    result: Any
    extra: dict


def fit_regressor(setup: Setup, Y, tau, *, warn: bool = True) -> RegressorFit:
    """Fit ``setup`` to the model's regressor ``Y (T, n, d)`` and the torques ``tau (T, n)``
    (rows of one data set, or of the training folds of a cross-validation)."""
    n = setup.model.robot.n_joints
    T, d = Y.shape[0], Y.shape[-1]
    W0, tau0 = Y.reshape(-1, d), tau.reshape(-1)
    kind = setup.kind
    # the unweighted factor: the diagnostics, the OLS fit and Gautier's first pass
    factor0 = factorize(W0, tau0) if warn or kind in ("equal", "residual") else None
    if warn:
        factor0.warn("identify: the stacked regressor", setup.model.names, stacklevel=3)
    if kind == "equal":
        sigma = np.ones(n)
    elif kind == "limits":
        sigma = setup.limits
    elif kind == "given":
        sigma = setup.given
    else:  # Gautier: sigma_j^2 = ||r_j||^2 / (T - d_j), d_j = parameters acting on joint j
        r = Y @ factor0.solve() - tau
        d_j = np.count_nonzero(np.any(Y != 0, axis=0), axis=-1)
        sigma = np.sqrt(np.sum(r ** 2, axis=0) / np.maximum(T - d_j, 1))
        sigma = np.where(sigma > 0, sigma, max(sigma.max(), 1e-12))
    method = setup.method
    if kind == "equal":
        W, b, factor = W0, tau0, factor0
    else:
        row = np.tile(1.0 / sigma, T)
        W, b = W0 * row[:, None], tau0 * row
        factor = factorize(W, b) if method in ("OLS", "WLS") else None

    result, full, extra = None, None, {}
    if setup.physical:
        fit_p = fit_physical(setup.model, factor, setup.prior, setup.prior_weight,
                             setup.prior_strength)
        x, full = fit_p.values, fit_p.full_params
        extra["physical_fit"] = {"solver": fit_p.solver, "status": fit_p.status,
                                 "iterations": fit_p.iterations, "seconds": fit_p.seconds}
    elif method in ("OLS", "WLS"):
        x = factor.solve()
    elif method == "L1":
        x, extra["lp_iterations"] = l1_solve(W, b)
    elif method == "LM":
        norms = np.linalg.norm(W, axis=0)
        scale = np.where(norms > 0, norms, 1.0)
        result = least_squares(L1Residual(W / scale, b), "LM")
        x = np.asarray(result.x, dtype=float) / scale
        extra.update(steps=int(result.n_evaluations), compile_s=float(result.compile_s),
                     run_s=float(result.run_s))
    else:
        x, result, extra = _swarm(setup, W, b)
    return RegressorFit(x=np.asarray(x, dtype=float), full=full, sigma=np.asarray(sigma),
                        factor0=factor0, W=W, b=b, result=result, extra=extra)


def identify(robot: Robot, q, qd, qdd, tau, *, method: str = "OLS",
             friction: str = "viscous-coulomb", sigma=None, limits=None,
             physical: bool = False, prior=None, prior_weight: float = 0.0,
             prior_strength: float = 0.0, box=(0.5, 0.5), runs: int = 1,
             iterations: int = 600, seed: int = 0,
             solver=None, smooth_velocity: float = SMOOTH_VELOCITY,
             base: BaseParameters | None = None, transmission=None,
             weights=_UNSET) -> Identification:
    """Identify the base parameters (plus extra friction terms) of ``robot`` from
    ``q, qd, qdd, tau`` (each ``(samples, n)``).

    Args:
        method: one of :data:`METHODS` (see the module docstring).
        friction: ``"viscous-coulomb"`` plus optional ``"+offset"``, ``"+quadratic"``,
            ``"+smooth"``, ``"+armature"``, ``"+coupling"`` (any order; :mod:`.model`).
        sigma: per-joint standard deviations; each joint's rows are divided by its sigma
            (the weights are ``1 / sigma``): ``None`` (equal; for ``"WLS"`` it means
            ``"residual"``), ``"residual"`` (Gautier's two-step WLS: the RMS of each
            joint's OLS residual, corrected for the parameters on that joint), ``"limits"``
            (the torque ``limits``, which makes the L2 objective the squared
            NRMS-over-limits error), or ``n`` positive numbers.
        limits: per-joint torque limits (N m): the fit reports its NRMS over them; needed
            by ``sigma="limits"``.
        physical: fit physically consistent full parameters (OLS / WLS only).
        prior: full a-priori parameters (12 per link); default ``robot.params``. Centre of
            the swarms' box (projected on the base; extras centred on 0) and target of
            ``prior_weight``.
        prior_weight: weight of ``||p - prior||^2`` in a physical fit.
        prior_strength: the same pull, scale-free: times the data term's mean curvature
            (added to ``prior_weight``); :func:`~.validation.choose_prior_strength`
            chooses it by cross-validation (``--prior-strength cv``).
        box: the swarms' box: ``(fraction, floor)`` gives centre ``+- max(fraction
            |centre|, floor)`` (:func:`~sedsabso_jax.optim.box_around`); or explicit
            ``(lower, upper)`` arrays of length ``dim``.
        runs, iterations, seed, solver: swarm runs (the best is kept), iterations, PRNG
            seed, and a solver instance (default: the method's ``.paper()`` settings).
        smooth_velocity: the "smooth" Coulomb term's ``tanh(qd / smooth_velocity)``.
        base: a precomputed ``base_parameters(robot)`` (computed when ``None``).
        transmission: the motors' transmission (a
            :class:`~sedsabso_jax.measurements.transmission.Transmission` or its matrix
            ``K``, motor angles ``K q``) for the ``armature`` and ``coupling`` terms; the
            data ``q, qd, qdd, tau`` are joint side whatever it is.
        weights: deprecated name of ``sigma``.

    Warns (``UserWarning``) with the condition number and the names of the columns
    concerned when the stacked regressor is rank deficient or poorly conditioned.
    """
    if weights is not _UNSET:
        _deprecation.warn("identify(weights=...)", "sigma=...")
        sigma = weights
    setup = prepare(robot, method=method, friction=friction, sigma=sigma, limits=limits,
                    physical=physical, prior=prior, prior_weight=prior_weight,
                    prior_strength=prior_strength, box=box,
                    runs=runs, iterations=iterations, seed=seed, solver=solver,
                    smooth_velocity=smooth_velocity, base=base, transmission=transmission)
    q, qd, qdd, tau = check_data(robot, q, qd, qdd, tau)
    t0 = time.perf_counter()
    Y = setup.model.regressor(q, qd, qdd)  # (T, n, d)
    out = fit_regressor(setup, Y, tau)
    run_s = time.perf_counter() - t0

    x = out.x
    rms = np.sqrt(np.mean((Y @ x - tau) ** 2, axis=0))
    rw = out.W @ x - out.b
    fit = {"rms": rms, "l1": float(np.abs(rw).sum()), "l2": float(rw @ rw),
           "condition_number": out.factor0.condition_number, "rank": out.factor0.rank,
           "samples": int(Y.shape[0]), "seconds": float(run_s)}
    if setup.limits is not None:
        fit["nrms_limits_percent"] = float(np.mean(nrms_over_limits(rms, setup.limits)))
    settings = {**setup.settings(), "sigma": out.sigma, **out.extra}
    return Identification(names=setup.model.names, values=x, model=setup.model,
                          method=setup.method, settings=jsonable(settings),
                          fit=jsonable(fit), full_params=out.full, result=out.result)


def swarm_box(setup: Setup) -> tuple[np.ndarray, np.ndarray, Any]:
    """``(lower, upper, setting)``: the swarms' search box of ``setup`` (see
    :func:`identify`'s ``box``): around the prior projected on the base parameters, the
    extra columns centred on 0, or the explicit arrays."""
    model, d = setup.model, setup.model.dim
    lo_hi = _box_arrays(setup.box, d)
    if lo_hi is not None:
        return *lo_hi, "explicit"
    centre = np.concatenate([np.asarray(model.base.project(setup.prior)),
                             np.zeros(d - model.base.rank)])
    fraction, floor = (float(v) for v in setup.box)
    lower, upper = box_around(centre, fraction, floor)
    return lower, upper, {"fraction": fraction, "floor": floor, "centre": "prior"}


def _swarm(setup, W, b):
    """The swarm on the weighted L1 objective in the box; the best of the runs."""
    solver, runs, iterations, seed = setup.solver, setup.runs, setup.iterations, setup.seed
    lower, upper, box_setting = swarm_box(setup)
    res = minimise(L1Residual(W, b), solver, lower, upper, key=jax.random.key(seed),
                   iterations=int(iterations), runs=int(runs))
    X, f = np.atleast_2d(np.asarray(res.x)), np.atleast_1d(np.asarray(res.f))
    best = int(np.argmin(f))
    hyper = {fld.name: getattr(solver, fld.name) for fld in dataclasses.fields(solver)}
    extra = {"box": box_setting, "runs": int(runs), "iterations": int(iterations),
             "seed": int(seed), "solver": hyper, "best_run": best,
             "f_runs": [float(v) for v in f], "compile_s": float(res.compile_s),
             "run_s": float(res.run_s)}
    return X[best], res, extra


def _check_swarm_settings(method, solver, box, d):
    """The solver (default: the method's ``.paper()``), after checking it and the box."""
    if solver is None:
        solver = SWARMS[method].paper()
    elif type(solver) is not SWARMS[method]:
        raise ValueError(f"solver must be a {method} instance for method {method!r}, got "
                         f"{type(solver).__name__}")
    solver.check()
    explicit = _box_arrays(box, d)
    if explicit is None:
        box_around(np.zeros(1), *box)  # checks (fraction, floor)
    else:
        check_bounds(*explicit, d)
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
