"""Identify a robot's base parameters (plus friction and actuator terms) from joint data::

    model = TorqueModel.of(robot, (Offset(),))
    fit = identify(robot, data, WLS("limits"), model, limits=...)

``data`` is :data:`~.._recordings.Data` (joint side; loading and filtering is
:mod:`sedsabso_jax.measurements`' job), the estimator one of
:mod:`sedsabso_jax.identification`'s, the torque model a
:class:`~sedsabso_jax.TorqueModel`, built once; :func:`~._fit.fit` fits it.
"""
from __future__ import annotations

import dataclasses
import os
import time
import warnings
from typing import Any

import numpy as np
from jaxtyping import ArrayLike, Float

from ..._deprecation import caller_stacklevel
from ..._output import jsonable
from ..._version import __version__
from ...dynamics._limits import JointLimits
from ...dynamics._robot import Robot
from ...dynamics._urdf_writer import to_urdf, update_urdf
from ...optim._linear import factorize
from .._data_checks import check_fit_data, pulled
from .._estimators._estimator import (
    Estimator,
    EstimatorFit,
    Limits,
    checked_estimator,
    describe,
    per_joint,
)
from .._estimators._least_squares import OLS
from .._metrics import nrms_over_limits
from .._model._checks import model_of, regrouped_message
from .._model._torque_model import TorqueModel
from .._recordings import Data, recordings_of
from ._fit import fit as fit_model
from ._samples import Samples, recorded
from ._uncertainty import parameter_std, relative_std_percent, searched_std


@dataclasses.dataclass(frozen=True, eq=False)
class Identification:
    """What :func:`identify` returns.

    Attributes:
        names: parameter names, base columns then extra columns (``OFF1``, ``FQ1``, ...).
        values: the identified values, one per name.
        model: the :class:`~sedsabso_jax.TorqueModel` as fitted (its searched
            parameters found, the values its terms read set); ``predict(q, qd, qdd)``
            uses it, and ``identify(robot, data, fit.estimator, fit.model)`` fits it
            again.
        method: the estimator's name.
        settings: the settings used (JSON-ready).
        fit: statistics of the fit residual on the identification data (JSON-ready):
            per-joint RMS (``rms``), ``l1`` and ``l2`` (sum of |r| and of r^2, weighted as
            the estimator saw them), ``nrms_limits_percent`` when ``limits`` were given,
            ``condition_number`` of the stacked regressor (unit-norm columns), ``rank``.
        full_params: the full parameters (12 per link) of a physical fit, else ``None``.
        result: the optimiser's :class:`~sedsabso_jax.Result` (all runs) of a box search
            (or the baseline's for Levenberg-Marquardt), else ``None``.
        estimator: the estimator object (with every option it was fitted with).
        std: the standard deviation of each value from the residual covariance
            (exact for OLS and WLS with independent errors and the
            model right, a least-squares linearisation for the other estimators; ``inf``
            where the data do not determine a value), in the value's unit;
            :attr:`relative_std_percent` is ``100 std / |value|``.
    """

    names: tuple[str, ...]
    values: np.ndarray
    model: TorqueModel
    method: str
    settings: dict
    fit: dict
    full_params: np.ndarray | None = None
    result: Any = None
    estimator: Estimator | None = None
    std: np.ndarray | None = None

    @property
    def relative_std_percent(self) -> Float[np.ndarray, " d"] | None:
        """``100 std / |value|`` [%] (``inf`` for a value of 0), or None without ``std``."""
        return None if self.std is None else relative_std_percent(self.std, self.values)

    def predict(self, q: Float[ArrayLike, "*batch n"], qd: Float[ArrayLike, "*batch n"],
                qdd: Float[ArrayLike, "*batch n"]) -> Float[np.ndarray, "*batch n"]:
        """Predicted torques ``(..., n)`` for states ``(..., n)``."""
        return self.model.predict(self.values, q, qd, qdd)

    def dynamics(self) -> tuple[Robot, np.ndarray, np.ndarray, Any]:
        """``(robot, params, armature, extra)`` of a physical fit as a simulator holds it,
        for :func:`~sedsabso_jax.dynamics.rollout` (:func:`~._rollouts.simulated_dynamics`)."""
        from ._rollouts import simulated_dynamics

        return simulated_dynamics(self)

    def urdf(self, source: str | os.PathLike[str] | None = None) -> str:
        """The robot's URDF with the identified link parameters and joint friction (a
        physical fit only: a simulator needs real bodies): ``source``, the URDF the robot
        was read from, with its inertials and joint friction replaced and everything else
        kept (:func:`~sedsabso_jax.dynamics.update_urdf`), or without one a new URDF of the
        chain (:func:`~sedsabso_jax.dynamics.to_urdf`). Extra terms a URDF cannot hold
        (offsets, quadratic friction, armature, presliding, ...) and the scales fitted
        (a presliding displacement ``q_c``, a Stribeck velocity) are listed in a
        comment."""
        if self.full_params is None:
            raise ValueError("a URDF needs the full link parameters of a physically "
                             "consistent fit: identify with PhysicallyConsistent(...) "
                             "(--physical)")
        base = self.model.base.rank
        extras = ", ".join(f"{n} = {v:.6g}" for n, v in zip(self.names[base:],
                                                           self.values[base:]))
        scales = ", ".join(f"{n} = {v:.6g} {found.unit}" for _, found in self.model.nonlinear()
                           for n, v in zip(found.names, found.values))
        comment = (f"link parameters identified by sedsabso-jax {__version__} "
                   f"({self.method}, physically consistent, friction {self.model.friction})"
                   + (f"; terms URDF cannot hold: {extras}" if extras else "")
                   + (f"; their searched parameters: {scales}" if scales else ""))
        if source is not None:
            return update_urdf(source, self.model.robot, self.full_params, comment=comment)
        return to_urdf(self.model.robot, self.full_params, comment=comment)

    def mjcf(self, source: str | os.PathLike[str] | None = None, *,
             limits: JointLimits | None = None, timestep: float = 0.002,
             integrator: str = "implicitfast") -> str:
        """The identified robot as a MuJoCo model (MJCF) that MuJoCo loads as written: a
        physical fit's link parameters, each joint's ``damping`` (viscous),
        ``frictionloss`` (Coulomb, and a term's dry friction such as friction at rest's
        level) and ``armature`` (a rotor inertia term), one torque actuator per joint
        whose bias is the torque offset, so that ``ctrl`` is the torque as measured
        (:func:`~sedsabso_jax.dynamics.to_mjcf`; ``limits``, ``timestep``, ``integrator``
        its). With ``source``, the MJCF the robot was read from, that file with the
        links' inertials and the joints' friction and armature replaced and all else
        kept, its actuators too, so the offsets are not written
        (:func:`~sedsabso_jax.dynamics.update_mjcf`). What MuJoCo has no parameter for is
        listed in a comment (:func:`~._simulator.simulated`)."""
        from ...dynamics._mjcf_update import update_mjcf
        from ...dynamics._mjcf_writer import to_mjcf
        from ._simulator import simulated

        if self.full_params is None:
            raise ValueError("an MJCF needs the full link parameters of a physically "
                             "consistent fit: identify with PhysicallyConsistent(...) "
                             "(--physical)")
        held = simulated(self.model, self.values)
        p = np.asarray(self.full_params, dtype=float).reshape(-1, 12).copy()
        p[:, 10] += held.frictionloss  # a term's dry friction joins the Coulomb level
        left_out = held.left_out
        if source is not None and np.any(held.offset):
            left_out += ("offset: the file's own actuators are kept (OFF = "
                         + ", ".join(f"{v:.4g}" for v in held.offset) + " N m)",)
        comment = (f"identified by sedsabso-jax {__version__} ({self.method}, physically "
                   f"consistent, friction {self.model.friction}); "
                   + ("not held by the simulator (left out): " + "; ".join(left_out)
                      if left_out else "every term of the model is held"))
        if source is not None:
            return update_mjcf(source, self.model.robot, p.ravel(), armature=held.armature,
                               comment=comment)
        return to_mjcf(self.model.robot, p.ravel(), armature=held.armature,
                       offset=held.offset, limits=limits, timestep=timestep,
                       integrator=integrator, comment=comment)

    def as_dict(self) -> dict:
        """Names, values (and their standard deviations), method, settings and fit
        statistics, JSON-ready."""
        out: dict[str, Any] = {"method": self.method, "names": self.names,
                               "values": self.values, "settings": self.settings,
                               "fit": self.fit}
        if self.std is not None:
            out["std"], out["relative_std_percent"] = self.std, self.relative_std_percent
        if self.full_params is not None:
            out["full_params"] = self.full_params
        return jsonable(out)

    def __repr__(self) -> str:
        rms = ", ".join(f"{r:.3g}" for r in self.fit["rms"])
        return (f"Identification({self.method}, {len(self.names)} parameters, "
                f"friction={self.model.friction!r}, fit RMS per joint [{rms}])")


def identify(robot: Robot, data: Data, estimator: Estimator = OLS(),
             model: TorqueModel | None = None, *, limits: Limits = None) -> Identification:
    """Identify the base parameters (plus extra friction terms) of ``robot`` from
    ``data``.

    Args:
        data: a :class:`~sedsabso_jax.Measurements`, several (recordings fitted together:
            one robot, one sampling rate), or ``(q, qd, qdd, tau)``, each ``(samples,
            n)``, with or without the times first.
        estimator: ``OLS()`` (default), ``WLS(sigma)``,
            ``L1()``, ``LevenbergMarquardt()``, ``BoxSearch(solver, ...)``,
            ``PhysicallyConsistent(OLS() or WLS(...), prior_strength=...)``.
        model: a :class:`~sedsabso_jax.TorqueModel` of ``robot``
            (:meth:`~sedsabso_jax.TorqueModel.of`: its terms, transmission, precomputed
            base parameters, one offset per recording, how its nonlinear parameters are
            searched); None: viscous and Coulomb friction only. The fit does what its
            terms ask (:mod:`._fit`). A model with one torque offset per recording
            (``TorqueModel.of(..., recordings=R)``) needs ``R`` recordings; new motions
            are predicted with the offsets' mean.
        limits: per-joint torque limits (N m): the fit reports its NRMS over them; needed
            by ``sigma="limits"``.

    Raises ValueError, before the fit, for data that cannot give an answer
    (:func:`~.._data_checks.check_fit_data`: fewer than 5 torque equations per
    parameter, no joint that moves, a regressor of the base parameters whose condition
    number exceeds 1e6 without a prior, torques 10 times the ``limits``).
    Warns (``UserWarning``) with the condition number and the names of the columns
    concerned when the stacked regressor is rank deficient or poorly conditioned, names
    a joint that never moves, and names the extra columns the base regressor already
    spans (left out).
    """
    return identified(robot, data, estimator, model, limits, check=True)[0]


def identified(robot: Robot, data: Data, estimator: Estimator, model: TorqueModel | None,
               limits: Limits, *, check: bool = False, samples: Samples | None = None
               ) -> tuple[Identification, EstimatorFit]:
    """:func:`identify`'s result and the estimator's fit behind it (its weighted rows,
    for what a caller derives from the values); ``check``: the data checked first
    (:func:`~.._data_checks.check_fit_data`); ``samples``: ``data``'s
    (:func:`~._samples.recorded`), given to reuse what was computed on them (the rows,
    a search of the same model)."""
    checked_estimator(estimator)
    model = model_of(robot, model)
    limits = per_joint("limits", limits, robot.n_joints)
    estimator.check(model, limits)  # what can be checked before any data are read
    if samples is None:
        recordings, samples = recorded(robot, data)
    else:  # the recordings checked, not stacked again
        recordings = recordings_of(robot, data)
        if samples.tau.shape[0] != sum(r.n_samples for r in recordings):
            raise ValueError(f"samples of {samples.tau.shape[0]} samples given for data of "
                             f"{sum(r.n_samples for r in recordings)}")
    model.check_recordings(len(recordings))
    if check:
        check_fit_data(robot, recordings, model.dim, model.base, limits,
                       regularized=pulled(estimator))
    if model.regrouped:
        warnings.warn(regrouped_message(model), stacklevel=caller_stacklevel())
    t0 = time.perf_counter()
    fitted = fit_model(estimator, model, samples, limits)
    model, out = fitted.model, fitted.fit
    Y = samples.rows(model)  # (T, n, d)
    run_s = time.perf_counter() - t0

    x, tau = out.x, samples.tau
    factor0 = out.factor0 if out.factor0 is not None else factorize(
        Y.reshape(-1, Y.shape[-1]), tau.reshape(-1))
    rms = np.sqrt(np.mean((Y @ x - tau) ** 2, axis=0))
    rw = out.W @ x - out.b
    fit = {"rms": rms, "l1": float(np.abs(rw).sum()), "l2": float(rw @ rw),
           "condition_number": factor0.condition_number, "rank": factor0.rank,
           "samples": int(Y.shape[0]), "seconds": float(run_s)}
    if limits is not None:
        fit["nrms_limits_percent"] = float(np.mean(nrms_over_limits(rms, limits)))
    report = dict(fitted.report)
    if "searched" in report:
        report["searched"] = {**report["searched"],
                              "parameters": searched_std(model, out, samples)}
    settings = {**describe(estimator, model, limits), "sigma": out.sigma, **out.extra,
                **report}
    ident = Identification(names=model.names, values=x, model=model, method=estimator.name,
                           settings=jsonable(settings), fit=jsonable(fit),
                           full_params=out.full, result=out.result, estimator=estimator,
                           std=parameter_std(out.W, rw))
    return ident, out
