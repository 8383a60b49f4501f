"""Drive gains from a known payload: the gains, the robot's torque model and the payload's
unknown moments identified together (Gautier & Briot, "Global identification of joint
drive gains and dynamic parameters of robots", ASME J. Dyn. Sys., Meas., Control 136(5),
2014)::

    gains = identify_drive_gains(robot, unloaded, loaded, "tool0", 3.02, urdf=path)
    gains.gains, gains.std, gains.calibrated
    torques = gains.apply(currents)

The recordings' ``tau`` hold what the drives report (currents) on the joint side (or per
motor, with a transmission). Recordings without the payload and with it (of known mass,
and centre of mass when known) give the equations of :mod:`._equations`, linear in the
gains, the torque model's values and the payload's unknown moments, solved by
:mod:`._solvers`. The torque model's terms are fitted as :func:`~sedsabso_jax.identify`
fits them: a term that reads the model's own torque (friction growing with the load)
reads a first ordinary fit's, payload included; friction at rest starts again in each
recording. Searched nonlinear parameters (``presliding:fit``) are not: fix them.

A gain is determined where its column is not in the span of the others: the payload's
torque must reach the joint (a joint about a vertical first axis sees a payload only
through its inertia, and needs fast motions of that joint with the payload). Each gain's
standard deviation says how well; one above :data:`~._result.CALIBRATED_STD` of it is
reported as not calibrated, with a warning naming the joint.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence

import numpy as np
from jaxtyping import ArrayLike, Float

from ..._deprecation import caller_stacklevel
from ...dynamics._robot import Robot
from ...measurements._transmission import Transmission, TransmissionLike
from .._data_checks import check_payload_data
from .._model._checks import model_of
from .._model._load import LoadFriction
from .._model._offset import Offset
from .._model._torque_model import TorqueModel
from .._payload._least_squares import LinearFit
from .._payload._term import PayloadInertia, payload_frame
from .._recordings import Data, recordings_of, stacked
from ._compressed import compress, std
from ._equations import GainEquations, equations, payload_columns, with_payload
from ._result import CALIBRATED_STD, DriveGains
from ._solvers import AbstractGainMethod, LikelihoodGains, Solution

#: How the equations are solved unless told (chosen by ``python -m benchmarks.drive_gains``).
DEFAULT_METHOD = LikelihoodGains()


def _motors(robot: Robot, transmission: TransmissionLike) -> np.ndarray:
    n = robot.n_joints
    if transmission is None:
        return np.eye(n)
    K = transmission.matrix if isinstance(transmission, Transmission) else np.asarray(
        transmission, dtype=float)
    if K.shape != (n, n) or not np.all(np.isfinite(K)):
        raise ValueError(f"transmission must be a finite ({n}, {n}) matrix, got shape "
                         f"{K.shape}")
    return K


def _checked(mass: object, com: object) -> tuple[float, np.ndarray | None]:
    try:
        m = float(mass)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ValueError(f"mass must be a number of kg, got {mass!r}") from None
    if not (np.isfinite(m) and m > 0):
        raise ValueError(f"mass must be positive and finite (the weighed payload's, kg), "
                         f"got {mass!r}")
    if com is None:
        return m, None
    r = np.asarray(com, dtype=float)
    if r.shape != (3,) or not np.all(np.isfinite(r)):
        raise ValueError(f"com must be 3 finite coordinates [m] in the link's frame, got "
                         f"{com!r}")
    return m, r


def _recordings(robot: Robot, data: Data | None, label: str) -> list:
    if data is None or (isinstance(data, (list, tuple)) and not data):
        raise ValueError(f"{label} recordings are needed: the gains come from the payload's "
                         f"torque, the difference between recordings with it and without")
    try:
        return recordings_of(robot, data)
    except ValueError as err:
        raise ValueError(f"{label} recordings: {err}") from None


def _excited(eq: GainEquations, link: str) -> None:
    """That the loaded recordings determine the known payload's torque apart from the
    model's other columns (else nothing fixes the gains' scale)."""
    d = eq.A.shape[-1]
    A = compress(eq.A).reshape(-1, d)  # the same column space, a few rows per joint
    G = np.zeros(d)
    G[eq.fixed] = eq.known
    if not LinearFit.of(A, np.zeros(A.shape[0])).determined(G)[0]:
        raise ValueError(f"the loaded recordings do not excite the payload's mass on link "
                         f"{link!r}: its torque is in the span of the other columns (every "
                         f"joint axis moving the link passes through the frame's origin, or "
                         f"the arm does not move)")


def _fitted(model: TorqueModel, first_eq: GainEquations, signals: tuple, motors: np.ndarray,
            mass: float, com: np.ndarray | None, method: AbstractGainMethod
            ) -> tuple[GainEquations, Solution, dict]:
    """The model's terms completed as :func:`~sedsabso_jax.identify` completes them
    (``first_eq``: the equations of the model without the terms that wait for fitted
    values), then the equations solved by ``method``."""
    report: dict = {}
    if model.nonlinear():
        raise ValueError(f"drive gains: the torque model {model.friction!r} has parameters "
                         f"to search; fix them (e.g. presliding:0.005, smooth:0.02)")
    if model.iterates:
        raise ValueError("drive gains: load:fixed-point is not supported; use load (two "
                         "stages)")
    if not model.waiting:
        return first_eq, method.solve(first_eq), report
    # the first stage by the method itself: ordinary least squares (identify's first
    # stage) would read the load off values its biased gains distort
    first = method.first_stage().solve(first_eq)
    values, _ = first_eq.split(first.theta)
    by_name = dict(zip(first_eq.model.names, values))
    model = model.reading(np.array([by_name.get(n, 0.0) for n in model.names]),
                          only=lambda term: term.waiting)
    report["stages"] = 2
    eq = equations(model, signals, motors, mass, com)
    return eq, method.solve(eq), report


def identify_drive_gains(robot: Robot, unloaded: Data, loaded: Data, link: str, mass: float,
                         com: Float[ArrayLike, " 3"] | Sequence[float] | None = None, *,
                         model: TorqueModel | None = None,
                         method: AbstractGainMethod = DEFAULT_METHOD,
                         transmission: TransmissionLike = None,
                         urdf: str | os.PathLike[str] | None = None) -> DriveGains:
    """Identify the drive gains from recordings of currents without and with a payload of
    known ``mass`` fixed to ``link`` (module docstring).

    Args:
        robot: the robot (its structure; its parameters are not used).
        unloaded: recordings without the payload, :data:`~.._recordings.Data` whose ``tau``
            hold the recorded currents.
        loaded: recordings with it (one sampling rate with ``unloaded``).
        link: the link the payload is fixed to (``robot.link_names``, or with ``urdf`` a
            link fixed to one, a flange, ``tool0``).
        mass: the payload's weighed mass [kg], > 0.
        com: its centre of mass [m] in ``link``'s frame, when known (None: estimated).
        model: the robot's torque model (default: viscous and Coulomb friction, a torque
            offset and Coulomb friction growing with the load per joint, ``(Offset(),
            LoadFriction())``: the payload's torque moves the friction too); one offset
            per recording counts the unloaded recordings first.
        method: how the equations are solved: :class:`~._solvers.LikelihoodGains`
            (default), :class:`~._solvers.TotalGains`, :class:`~._solvers.OrdinaryGains`
            or :class:`~._solvers.PhysicalGains` (:mod:`._solvers`).
        transmission: the motors' transmission (a :class:`~sedsabso_jax.Transmission` or
            its matrix ``K``) when the currents are the motors' behind it (positions
            joint side); None: the joints' own currents.
        urdf: the URDF the robot was read from, to find a fixed link.

    Raises ValueError for a non-positive mass, missing recordings, too few samples for
    the unknowns (5 torque equations each), recordings where no joint moves, a
    recording given both loaded and unloaded
    (:func:`~.._data_checks.check_payload_data`), a link the loaded motion does not
    excite; warns naming each joint the data do not calibrate (relative
    standard deviation above :data:`~._result.CALIBRATED_STD`).
    """
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a sedsabso_jax.Robot, got {type(robot).__name__}")
    mass, r = _checked(mass, com)
    if not isinstance(method, AbstractGainMethod):
        raise TypeError(f"method must be a drive gains' method (LikelihoodGains(), "
                        f"TotalGains(), OrdinaryGains(), PhysicalGains()), got {method!r}")
    motors = _motors(robot, transmission)
    k, T = payload_frame(robot, link, urdf)
    unloaded_recs = _recordings(robot, unloaded, "unloaded")
    loaded_recs = _recordings(robot, loaded, "loaded")
    recordings = recordings_of(robot, [*unloaded_recs, *loaded_recs])  # one rate for all
    base_model = TorqueModel.of(robot, (Offset(), LoadFriction()), transmission=transmission) \
        if model is None else model_of(robot, model)
    base_model.check_recordings(len(recordings))
    term = PayloadInertia(k, tuple(float(v) for v in np.reshape(T, -1)),
                          tuple(range(len(unloaded_recs), len(recordings))))
    full = with_payload(base_model, term)
    check_payload_data(robot, unloaded_recs, loaded_recs, full.dim + robot.n_joints)
    signals = stacked(recordings)
    first_eq = equations(full.without_waiting(), signals, motors, mass, r)
    _excited(first_eq, link)
    eq, sol, report = _fitted(full, first_eq, signals, motors, mass, r, method)
    return _result(eq, sol, signals, motors, {
        "link": link, "moving_link": robot.link_names[k], "mass": mass,
        "com": None if r is None else r.tolist(), "friction": base_model.friction,
        "method": method.name, "robot": robot.name, **report,
        "solution": sol.report})


def _result(eq: GainEquations, sol: Solution, signals: tuple, motors: np.ndarray,
            settings: dict) -> DriveGains:
    values, gains = eq.split(sol.theta)
    spread = std(sol.W, float(sol.residual @ sol.residual), sol.rows, sol.G)
    values_std = np.zeros(values.size)
    values_std[eq.free] = spread[:eq.free.size]
    gains_std = spread[eq.free.size:]
    gains = np.where(np.isfinite(gains_std), gains, np.nan)
    payload = payload_columns(eq.model)
    rest = np.setdiff1d(np.arange(values.size), payload)
    index = signals[-1]
    carried = [t.carried for t in eq.model.terms if isinstance(t, PayloadInertia)][0]
    on = np.isin(index, carried)
    residual = eq.A @ values - eq.C @ np.nan_to_num(gains)  # torque units
    found = DriveGains(
        gains=gains, std=gains_std, motors=np.array(motors, dtype=float),
        method=settings["method"], payload10=values[payload], payload_std10=values_std[payload],
        robot_names=tuple(eq.model.names[i] for i in rest), robot_values=values[rest],
        robot_std=values_std[rest],
        fit={"rms_loaded": np.sqrt(np.mean(residual[on] ** 2, axis=0)),
             "rms_unloaded": np.sqrt(np.mean(residual[~on] ** 2, axis=0)),
             "samples_loaded": int(on.sum()), "samples_unloaded": int((~on).sum()),
             "condition_number": LinearFit.of(sol.W, sol.residual).condition(
                 np.arange(eq.free.size, sol.theta.size))},
        settings=settings, joint_names=tuple(eq.model.robot.joint_names))
    poor = [f"{name} ({f'{100 * r:.2g} %' if np.isfinite(r) else 'not determined'})"
            for name, r in zip(found.labels, found.relative_std) if not r <= CALIBRATED_STD]
    if poor:
        plural = "s" if len(poor) > 1 else ""
        label = "motor" if found.motor_side else "joint"
        warnings.warn(f"drive gains: the data do not calibrate {label}{plural} "
                      f"{', '.join(poor)} (a gain's relative standard deviation above "
                      f"{100 * CALIBRATED_STD:g} %): the payload's torque barely reaches "
                      f"{'them' if plural else 'it'}; record faster motions of "
                      f"{'those' if plural else 'that'} {label}{plural} with the payload, "
                      f"give the centre of mass (com=, --com), or give the gain{plural}",
                      stacklevel=caller_stacklevel())
    return found
