"""Identify a robot's base parameters (plus friction and actuator terms) from joint data::

    model = TorqueModel.of(robot, (Offset(),))
    fit = identify(robot, data, WLS("limits"), model, limits=...)

``data`` is a :class:`~sedsabso_jax.Measurements` or the arrays ``(q, qd, qdd, tau)``
(each ``(samples, n)``, joint side); loading and filtering is
:mod:`sedsabso_jax.measurements`' job. The estimator is one of :mod:`._estimators` (OLS,
WLS, L1, Levenberg-Marquardt, a box search with any optimiser, physically consistent);
the torque model a :class:`~._model.TorqueModel`, built once.
"""
from __future__ import annotations

import dataclasses
import os
import time
import warnings
from collections.abc import Sequence
from typing import Any, TypeAlias

import numpy as np
from jaxtyping import ArrayLike, Float

from .._deprecation import caller_stacklevel
from .._output import jsonable
from .._version import __version__
from ..dynamics._robot import Robot
from ..dynamics._urdf_writer import to_urdf, update_urdf
from ..measurements._container import Measurements
from ..optim._linear import factorize
from ._estimators import OLS
from ._fitting import Estimator, Limits, describe, per_joint
from ._metrics import nrms_over_limits
from ._model import TorqueModel, regrouped_message
from ._shapes import Samples
from ._shapes import fit as fit_model
from ._uncertainty import parameter_std, relative_std_percent

#: Joint data: a :class:`~sedsabso_jax.Measurements`, several of them (recordings fitted
#: together), or its arrays ``(q, qd, qdd, tau)`` (``(times, q, qd, qdd, tau)`` where the
#: times are needed), each ``(samples, n)``.
Data: TypeAlias = Measurements | Sequence[Measurements] | Sequence[ArrayLike]
#: Recordings fitted together may differ in rate by this fraction.
RATE_TOLERANCE = 0.01


@dataclasses.dataclass(frozen=True, eq=False)
class Identification:
    """What :func:`identify` returns.

    Attributes:
        names: parameter names, base columns then extra columns (``OFF1``, ``FQ1``, ...).
        values: the identified values, one per name.
        model: the :class:`~._model.TorqueModel`; ``predict(q, qd, qdd)`` uses it.
        method: the estimator's name.
        settings: the settings used (JSON-ready).
        fit: statistics of the fit residual on the identification data (JSON-ready):
            per-joint RMS (``rms``), ``l1`` and ``l2`` (sum of |r| and of r^2, weighted as
            the estimator saw them), ``nrms_limits_percent`` when ``limits`` were given,
            ``condition_number`` of the stacked regressor (unit-norm columns), ``rank``.
        full_params: the full parameters (12 per link) of a physical fit, else ``None``.
        result: the optimiser's :class:`~sedsabso_jax.Result` (all runs) of a box search
            (or the baseline's for Levenberg-Marquardt), else ``None``.
        estimator: the estimator object.
        std: the standard deviation of each value from the residual covariance
            (:mod:`._uncertainty`: exact for OLS and WLS with independent errors and the
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
        scales = ", ".join(f"{n} = {v:.6g}" for _, found in self.model.shapes()
                           for n, v in zip(found.names, found.values))
        comment = (f"link parameters identified by sedsabso-jax {__version__} "
                   f"({self.method}, physically consistent, friction {self.model.friction})"
                   + (f"; terms URDF cannot hold: {extras}" if extras else "")
                   + (f"; their fitted scales: {scales}" if scales else ""))
        if source is not None:
            return update_urdf(source, self.model.robot, self.full_params, comment=comment)
        return to_urdf(self.model.robot, self.full_params, comment=comment)

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


def check_data(robot: Robot, q: Float[ArrayLike, "samples n"], qd: Float[ArrayLike, "samples n"],
               qdd: Float[ArrayLike, "samples n"], tau: Float[ArrayLike, "samples n"]
               ) -> list[Float[np.ndarray, "samples n"]]:
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


def data_arrays(robot: Robot, data: Data, *, times: bool = False) -> list[np.ndarray]:
    """``[q, qd, qdd, tau]`` of ``data`` (a :class:`~sedsabso_jax.Measurements` or a
    tuple of those arrays), checked; with ``times``, ``[times, q, qd, qdd, tau]`` (a tuple
    then holds the times first)."""
    fields = ("times", "q", "qd", "qdd", "tau") if times else ("q", "qd", "qdd", "tau")
    if isinstance(data, Measurements):
        arrays = [getattr(data, f) for f in fields]
    else:
        try:
            arrays = list(data)
        except TypeError:
            arrays = []
        if len(arrays) != len(fields) or isinstance(data, np.ndarray):
            raise ValueError(f"data must be a Measurements or a tuple ({', '.join(fields)}) "
                             f"of arrays, got {type(data).__name__}")
    if not times:
        return check_data(robot, *arrays)
    checked = check_data(robot, *arrays[1:])
    t = np.asarray(arrays[0], dtype=float)
    if t.shape != (checked[0].shape[0],):
        raise ValueError(f"times must have one entry per sample ({checked[0].shape[0]}), got "
                         f"shape {t.shape}")
    return [t, *checked]


def is_several(data: object) -> bool:
    """Whether ``data`` is a sequence of :class:`~sedsabso_jax.Measurements`."""
    return (isinstance(data, (list, tuple)) and len(data) > 0
            and all(isinstance(d, Measurements) for d in data))


def recordings_of(robot: Robot, data: Data) -> list[Measurements]:
    """``data`` as a list of recordings of ``robot``: one :class:`~sedsabso_jax.Measurements`,
    several, or the arrays ``(times, q, qd, qdd, tau)``. Several must have the robot's
    joints and one sampling rate (within :data:`RATE_TOLERANCE`); a ValueError names the
    recording that does not."""
    if isinstance(data, Measurements):
        data_arrays(robot, data)  # the robot's joints
        return [data]
    if not is_several(data):
        times, q, qd, qdd, tau = data_arrays(robot, data, times=True)
        return [Measurements(times, q, qd, qdd, tau)]
    found: list[Measurements] = list(data)  # type: ignore[arg-type]  # is_several
    rates = []
    for k, d in enumerate(found):
        if d.n_joints != robot.n_joints:
            raise ValueError(f"recording {k + 1} ({d.source}) has {d.n_joints} joints, robot "
                             f"{robot.name!r} has {robot.n_joints}")
        rates.append(d.rate)
    if max(rates) > (1 + RATE_TOLERANCE) * min(rates):
        listed = ", ".join(f"{d.source}: {r:.4g} Hz" for d, r in zip(found, rates))
        raise ValueError(f"the recordings have different sampling rates ({listed}): load "
                         f"them at one rate (load_measurements(..., resample_hz=...))")
    return found


def stacked(recordings: Sequence[Measurements]) -> tuple[np.ndarray, ...]:
    """``(q, qd, qdd, tau, recording index)`` of ``recordings``, concatenated."""
    arrays = [np.concatenate([getattr(d, f) for d in recordings])
              for f in ("q", "qd", "qdd", "tau")]
    index = np.concatenate([np.full(d.n_samples, k) for k, d in enumerate(recordings)])
    return (*arrays, index)


def joined(recordings: Sequence[Measurements]) -> Measurements:
    """One :class:`~sedsabso_jax.Measurements` of ``recordings`` one after the other (each
    later one's times shifted to start a sample step after the previous one's end), for
    reports and figures; one recording is returned as it is."""
    if len(recordings) == 1:
        return recordings[0]
    times, start = [], 0.0
    for d in recordings:
        t = d.times - d.times[0] + start
        times.append(t)
        start = float(t[-1]) + 1.0 / d.rate
    q, qd, qdd, tau, _ = stacked(recordings)
    return Measurements(np.concatenate(times), q, qd, qdd, tau,
                        source=" + ".join(d.source for d in recordings),
                        info={"recordings": [{"source": d.source, "samples": d.n_samples,
                                              **d.info} for d in recordings]})


def model_of(robot: Robot, model: TorqueModel | None) -> TorqueModel:
    """``model``, checked to be a :class:`~._model.TorqueModel` of ``robot``; None: the
    robot's rigid-body model with viscous and Coulomb friction."""
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a sedsabso_jax.Robot, got {type(robot).__name__}")
    if model is None:
        return TorqueModel.of(robot)
    if not isinstance(model, TorqueModel):
        raise TypeError(f"model must be a TorqueModel (TorqueModel.of(robot, terms); "
                        f"parse_friction reads the command line's 'a+b' text), got {model!r}")
    if model.robot.n_params != robot.n_params or model.robot.n_joints != robot.n_joints:
        raise ValueError(f"model is a TorqueModel of robot {model.robot.name!r} with "
                         f"{model.robot.n_joints} joints, not of {robot.name!r}")
    return model


def checked(estimator: Estimator) -> Estimator:
    """``estimator``, checked to be one."""
    if not isinstance(estimator, Estimator):
        raise TypeError(f"estimator must be an Estimator (OLS(), WLS(...), L1(), "
                        f"BoxSearch(...), ...), got {estimator!r}")
    return estimator


def one_or_more(value: Any, kind: type) -> tuple[Any, ...]:
    """``value`` as a tuple: one ``kind`` as a tuple of it, a sequence of them as a
    tuple."""
    return (value,) if isinstance(value, kind) else tuple(value)


def check_offsets(model: TorqueModel, count: int) -> None:
    """That a model with one torque offset per recording has ``count`` of them."""
    if model.recordings > 1 and model.recordings != count:
        raise ValueError(f"the torque model has one offset per recording for "
                         f"{model.recordings} recordings; the data hold {count}")


def identify(robot: Robot, data: Data, estimator: Estimator = OLS(),
             model: TorqueModel | None = None, *, limits: Limits = None) -> Identification:
    """Identify the base parameters (plus extra friction terms) of ``robot`` from
    ``data``.

    Args:
        data: a :class:`~sedsabso_jax.Measurements`, several (recordings fitted together:
            one robot, one sampling rate), or ``(q, qd, qdd, tau)``, each ``(samples,
            n)``.
        estimator: one of :mod:`._estimators`: ``OLS()`` (default), ``WLS(sigma)``,
            ``L1()``, ``LevenbergMarquardt()``, ``BoxSearch(solver, ...)``,
            ``PhysicallyConsistent(OLS() or WLS(...), prior_strength=...)``.
        model: a :class:`~._model.TorqueModel` of ``robot``
            (:meth:`~._model.TorqueModel.of`: its terms, transmission, precomputed base
            parameters, one offset per recording); None: viscous and Coulomb friction
            only. A model with one torque offset per recording
            (``TorqueModel.of(..., recordings=R)``) needs ``R`` recordings; new motions
            are predicted with the offsets' mean.
        limits: per-joint torque limits (N m): the fit reports its NRMS over them; needed
            by ``sigma="limits"``.

    Warns (``UserWarning``) with the condition number and the names of the columns
    concerned when the stacked regressor is rank deficient or poorly conditioned, and
    names the extra columns the base regressor already spans (left out).
    """
    checked(estimator)
    model = model_of(robot, model)
    several = is_several(data)
    check_offsets(model, len(data) if several else 1)  # type: ignore[arg-type]
    limits = per_joint("limits", limits, robot.n_joints)
    estimator.check(model, limits)
    if model.regrouped:
        warnings.warn(regrouped_message(model), stacklevel=caller_stacklevel())
    index = None
    if several:
        q, qd, qdd, tau, index = stacked(recordings_of(robot, data))
    else:
        q, qd, qdd, tau = data_arrays(robot, data)
    t0 = time.perf_counter()
    fitted = fit_model(estimator, model, Samples(q, qd, qdd, tau, index), limits)
    model, out, Y = fitted.model, fitted.fit, fitted.Y  # Y: (T, n, d)
    run_s = time.perf_counter() - t0

    x = out.x
    factor0 = out.factor0 if out.factor0 is not None else factorize(
        Y.reshape(-1, Y.shape[-1]), tau.reshape(-1))
    rms = np.sqrt(np.mean((Y @ x - tau) ** 2, axis=0))
    rw = out.W @ x - out.b
    fit = {"rms": rms, "l1": float(np.abs(rw).sum()), "l2": float(rw @ rw),
           "condition_number": factor0.condition_number, "rank": factor0.rank,
           "samples": int(Y.shape[0]), "seconds": float(run_s)}
    if limits is not None:
        fit["nrms_limits_percent"] = float(np.mean(nrms_over_limits(rms, limits)))
    settings = {**describe(estimator, model, limits), "sigma": out.sigma, **out.extra,
                **fitted.report}
    return Identification(names=model.names, values=x, model=model, method=estimator.name,
                          settings=jsonable(settings), fit=jsonable(fit),
                          full_params=out.full, result=out.result, estimator=estimator,
                          std=parameter_std(out.W, rw))
