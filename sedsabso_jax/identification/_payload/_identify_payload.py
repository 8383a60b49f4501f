"""Payload identification: the inertial parameters of a body fixed to one link of a
robot, from joint data with it (Khalil & Dombre, *Modeling, Identification and Control
of Robots*, 2002, Ch. 12)::

    payload = identify_payload(fit, loaded, "tool0", unloaded=without, urdf=path)
    payload.mass, payload.com, payload.inertia, payload.std["mass"]

A payload fixed to link ``k`` adds its 10 inertial parameters ``p`` (the robot's order
``XX YY ZZ XY XZ YZ M MX MY MZ``, inertia about the frame's origin, first moments ``m c``;
Kubus, Kroger & Wahl, IROS 2008) to the link's, and the torques are linear in them
(:class:`~._term.PayloadInertia`)::

    tau = Ym x + Y_k A p    with the payload   (loaded recordings)
    tau = Ym x              without it         (unloaded recordings)

With unloaded recordings the payload is a term of the robot's torque model and the two
are fitted together by :func:`~sedsabso_jax.identify`'s stack: any of its estimators (a
physically consistent one constrains the payload as it does the links), the model's
terms as they are fitted there (friction growing with the load reads the payload's
torque too, in two stages; friction at rest restarts in each recording), one sampling
rate, the recordings need not align. Without unloaded recordings the robot is given (an
identification's prediction, or a robot's own parameters, a URDF's) and the payload
alone is fitted to what it leaves, by the estimator's least squares (its row weights),
projected onto consistent bodies for a physically consistent estimator
(:mod:`._least_squares`).
"""

from __future__ import annotations

import os
import warnings
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from ..._deprecation import caller_stacklevel
from ..._output import jsonable
from ...dynamics._regressor import inverse_dynamics
from ...dynamics._robot import N_LINK_PARAMETERS, Robot
from .._data_checks import check_payload_data
from .._estimators._estimator import Estimator, checked_estimator
from .._estimators._least_squares import WLS, PhysicallyConsistent
from .._fit._identify import Identification, identified
from .._fit._uncertainty import function_std
from .._model._checks import model_of
from .._model._offset import Offset
from .._model._torque_model import TorqueModel
from .._recordings import Data, recordings_of, stacked
from ._least_squares import LinearFit, consistent, is_consistent, joint_sigma
from ._result import Payload, quantities
from ._term import PayloadInertia, payload_frame

#: A mass whose standard deviation exceeds this fraction of it is warned of.
POOR_MASS = 0.1
#: The estimator unless told: Gautier's weighted least squares (its weights made twice,
#: the second time from the weighted fit's residual), the payload (and the model's terms)
#: physically consistent, the robot's links free.
DEFAULT_ESTIMATOR = PhysicallyConsistent(WLS(passes=2), links=False)


def _recordings(robot: Robot, data: Data | None, label: str) -> list:
    if data is None:
        return []
    try:
        return recordings_of(robot, data)
    except ValueError as err:
        raise ValueError(f"{label} recordings: {err}") from None


def _joint_model(robot: Robot | Identification, model: TorqueModel | None, count: int
                 ) -> TorqueModel:
    """The torque model of a joint fit of ``count`` recordings: an identification's (with
    one offset per recording, for these recordings), ``model``, or the default."""
    if isinstance(robot, Identification):
        if model is not None:
            raise ValueError("model: an Identification brings its own torque model")
        model = robot.model
        if model.recordings > 1 and model.recordings != count:
            model = TorqueModel.of(model.robot, model.terms, transmission=model.transmission,
                                   base=model.base, recordings=count, search=model.search)
        return model
    model = TorqueModel.of(robot, Offset()) if model is None else model_of(robot, model)
    model.check_recordings(count)
    return model


def _lift(d: int, columns: np.ndarray) -> np.ndarray:
    """The rows that take the payload's 10 values out of a model's ``d`` values."""
    lift = np.zeros((10, d))
    lift[np.arange(10), columns] = 1.0
    return lift


def _determined(W: np.ndarray, b: np.ndarray, mass_row: np.ndarray, link: str) -> None:
    if not LinearFit.of(W, b).determined(mass_row)[0]:
        raise ValueError(f"the loaded recordings do not excite the payload's mass on link "
                         f"{link!r}: its torque is in the span of the other columns (every "
                         f"joint axis moving the link passes through the frame's origin, or "
                         f"the arm does not move)")


def _joint_fit(robot: Robot, recordings: list, model: TorqueModel, term: PayloadInertia,
               estimator: Estimator, link: str) -> dict[str, Any]:
    """The robot's model and the payload fitted together (module docstring)."""
    full = TorqueModel.of(robot, (*model.terms, term), transmission=model.transmission,
                          base=model.base, recordings=model.recordings, search=model.search)
    columns = np.array([full.names.index(n) for n in term.names(full)])
    q, qd, qdd, tau, index = stacked(recordings)
    Y = full.regressor(q, qd, qdd, index)  # before the fit: a mass it cannot see is refused
    _determined(Y.reshape(-1, full.dim), tau.reshape(-1), _lift(full.dim, columns)[6], link)
    ident, out = identified(robot, recordings, estimator, full, None)
    lift = _lift(len(ident.names), columns)
    p = ident.values[columns]
    unconstrained = LinearFit.of(out.W, out.b).x[columns]  # the same rows, unconstrained
    residual = out.W @ ident.values - out.b
    rest = np.setdiff1d(np.arange(len(ident.names)), columns)
    return {"p": p, "unconstrained": unconstrained, "identification": ident,
            "W": out.W, "residual": residual, "lift": lift, "rest": rest,
            "sigma": out.sigma, "physical": {
                "already_consistent": is_consistent(unconstrained),
                **({"solver": "Clarabel (cvxpy)", **ident.settings.get("physical_fit", {})}
                   if estimator.physical else {})}}


def _fixed_fit(robot: Robot | Identification, rob: Robot, recordings: list,
               term: PayloadInertia, estimator: Estimator, term_link: str) -> dict[str, Any]:
    """The payload alone, the robot given (module docstring)."""
    q, qd, qdd, tau, _ = stacked(recordings)
    model = TorqueModel.of(rob)
    Y = term.columns(model, model.signals(q, qd, qdd))
    if isinstance(robot, Identification):
        known = robot.predict(q, qd, qdd)
    elif not np.any(np.asarray(rob.params).reshape(-1, N_LINK_PARAMETERS)[:, :10]):
        raise ValueError(f"robot {rob.name!r} has no inertial parameters (all zero): give "
                         f"recordings without the payload (unloaded=, --data)")
    else:
        known = np.asarray(inverse_dynamics(rob, rob.params, q, qd, qdd))
    weights = {"equal": None, "residual": "residual"}.get(estimator.weights, estimator.sigma)
    s = joint_sigma(Y, tau - known, weights)
    W, b = (Y / s[:, None]).reshape(-1, 10), ((tau - known) / s).reshape(-1)
    fit = LinearFit.of(W, b)
    _determined(W, b, np.eye(10)[6], term_link)
    report: dict[str, Any] = {"already_consistent": is_consistent(fit.x)}
    p = fit.x
    if estimator.physical and not report["already_consistent"]:
        p, solved = consistent(fit, 0)
        report.update(solved)
    return {"p": p, "unconstrained": fit.x, "identification": None, "W": W,
            "residual": W @ p - b, "lift": np.eye(10), "rest": np.zeros(0, int),
            "sigma": s, "physical": report}


def identify_payload(robot: Robot | Identification, loaded: Data, link: str, *,
                     unloaded: Data | None = None,
                     estimator: Estimator = DEFAULT_ESTIMATOR,
                     model: TorqueModel | None = None,
                     urdf: str | os.PathLike[str] | None = None) -> Payload:
    """Identify a payload fixed to ``link`` from recordings with it (module docstring).

    Args:
        robot: an :class:`~sedsabso_jax.Identification` (its torque model; its values too
            without ``unloaded``) or a :class:`~sedsabso_jax.Robot` (its own parameters,
            e.g. a URDF's, without ``unloaded``).
        loaded: recordings with the payload: :data:`~.._recordings.Data` as
            :func:`~sedsabso_jax.identify` takes, joint side.
        link: the link the payload is fixed to: one of ``robot.link_names`` or, with
            ``urdf``, a link fixed to one (a flange, ``tool0``); the payload is reported
            in its frame.
        unloaded: recordings without the payload (one sampling rate with ``loaded``):
            the robot's model and the payload are fitted together.
        estimator: any of :func:`~sedsabso_jax.identify`'s with ``unloaded`` (default
            :data:`DEFAULT_ESTIMATOR`: Gautier's WLS, the payload physically consistent,
            the links free; ``PhysicallyConsistent(WLS())`` constrains the links too); a
            least-squares one (OLS, WLS, or their physically consistent form) without.
        model: the robot's torque model in the joint fit (default: viscous and Coulomb
            friction and a torque offset per joint); one offset per recording counts the
            unloaded recordings first, then the loaded ones.
        urdf: the URDF the robot was read from, to find a fixed link.

    Raises ValueError, before any fit, for too few samples for the parameters (5
    torque equations each), recordings where no joint moves and a recording given both
    loaded and unloaded (:func:`~.._data_checks.check_payload_data`), and when the
    loaded recordings do not determine the payload's mass
    (e.g. a link whose every joint axis passes through the payload's frame origin, or a
    link moved only by a vertical axis), and warns when its standard deviation exceeds
    :data:`POOR_MASS` of it.
    """
    rob = robot.model.robot if isinstance(robot, Identification) else robot
    if not isinstance(rob, Robot):
        raise TypeError(f"robot must be a sedsabso_jax.Robot or an Identification, got "
                        f"{type(robot).__name__}")
    checked_estimator(estimator)
    k, T = payload_frame(rob, link, urdf)
    loaded_recs = _recordings(rob, loaded, "loaded")
    unloaded_recs = _recordings(rob, unloaded, "unloaded")
    recordings = recordings_of(rob, [*unloaded_recs, *loaded_recs])  # one rate for all
    term = PayloadInertia(k, T, tuple(range(len(unloaded_recs), len(recordings))))  # type: ignore[arg-type]
    if unloaded_recs:
        tm = _joint_model(robot, model, len(recordings))
        check_payload_data(rob, unloaded_recs, loaded_recs, tm.dim + 10)
        found = _joint_fit(rob, recordings, tm, term, estimator, link)
    else:
        if model is not None:
            raise ValueError("model: without unloaded recordings the robot is taken as "
                             "given; a torque model is refitted only with unloaded=")
        if not estimator.normal_equations:
            raise ValueError(f"without unloaded recordings the payload is fitted by least "
                             f"squares: use OLS, WLS or their physically consistent form, "
                             f"not {estimator.name!r}")
        check_payload_data(rob, [], loaded_recs, 10)
        tm, found = None, _fixed_fit(robot, rob, recordings, term, estimator, link)
    p = found["p"]
    jac = np.asarray(jax.jacfwd(quantities)(jnp.asarray(p)))
    quantity_std = function_std(found["W"], found["residual"], jac @ found["lift"])
    std10 = function_std(found["W"], found["residual"], found["lift"])
    _, _, _, tau, index = stacked(recordings)
    on = np.isin(index, term.carried)
    settings = {"mode": "joint fit" if tm is not None else "robot fixed",
                "robot": rob.name, "friction": None if tm is None else tm.friction,
                "method": estimator.name, "weights": estimator.weights,
                "physical": bool(estimator.physical)}
    if quantity_std[0] > POOR_MASS * abs(p[6]):
        warnings.warn(f"payload: the mass is poorly determined ({p[6]:.4g} kg +- "
                      f"{quantity_std[0]:.2g}): the loaded recordings barely excite it",
                      stacklevel=caller_stacklevel())
    ident = found["identification"]
    return Payload(link=link, moving_link=rob.link_names[k], frame=T, params10=p,
                   unconstrained10=found["unconstrained"], std10=std10,
                   quantity_std=quantity_std, physical=found["physical"],
                   fit=jsonable(_statistics(found, tau, on)), settings=settings,
                   robot_names=() if ident is None else tuple(
                       ident.names[i] for i in found["rest"]),
                   robot_values=np.zeros(0) if ident is None else ident.values[found["rest"]],
                   identification=ident)


def _statistics(found: dict, tau: np.ndarray, on: np.ndarray) -> dict:
    """Residual statistics of the payload's fit: per-joint RMS of the loaded and unloaded
    rows, the row sigma, samples, the payload columns' condition after the others."""
    W, sigma = found["W"], np.asarray(found["sigma"], dtype=float)
    out: dict[str, Any] = {"sigma": sigma, "samples_loaded": int(on.sum()),
                           "samples_unloaded": int((~on).sum()), "columns": int(W.shape[1])}
    r = found["residual"].reshape(tau.shape[0], -1) * sigma
    out["rms_loaded"] = np.sqrt(np.mean(r[on] ** 2, axis=0))
    if (~on).any():
        out["rms_unloaded"] = np.sqrt(np.mean(r[~on] ** 2, axis=0))
    fit = LinearFit.of(W, W @ np.zeros(W.shape[1]) - found["residual"])
    columns = np.flatnonzero(found["lift"].any(axis=0))
    out.update(variance=float(found["residual"] @ found["residual"])
               / max(W.shape[0] - fit.rank, 1), rank=fit.rank,
               condition_number=fit.condition(columns))
    return out
