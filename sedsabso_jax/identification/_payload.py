"""Payload identification: the inertial parameters of a body fixed to one link of an
identified robot, from joint data with it (Khalil & Dombre, *Modeling, Identification and
Control of Robots*, 2002, Ch. 12, the load's inertial parameters identified from the
joint torques with the robot's own parameters known)::

    payload = identify_payload(fit, loaded, "tool0", unloaded=without, urdf=path)
    payload.mass, payload.com, payload.inertia, payload.std["mass"]

A payload fixed to link ``k`` adds its 10 inertial parameters ``p`` (the robot's order
``XX YY ZZ XY XZ YZ M MX MY MZ``, inertia about the frame's origin, first moments ``m c``;
the body's linear model, as Kubus, Kroger & Wahl, "On-line estimation of inertial
parameters using a recursive total least-squares approach", IROS 2008) to the link's,
and the torques are linear in them: link ``k``'s 10 inertial columns ``Y_k`` of the full
regressor, times ``A``, the change from the named frame to link ``k``'s
(:func:`~sedsabso_jax.dynamics._inertia.transform_params`, linear)::

    tau = Ym x + Y_k A p    with the payload   (loaded recordings)
    tau = Ym x              without it         (unloaded recordings)

With unloaded recordings the robot's torque model ``Ym`` (base parameters, friction,
offsets) and the payload are fitted together: ``x`` shared, ``p`` on the loaded rows only.
Samples need no alignment (the recordings may differ in motion, length and time), every
row is used once (the sample-by-sample difference of two aligned runs adds both runs'
noise: twice the variance), and friction or offsets that moved between the runs are
refitted, not subtracted. Without unloaded recordings the robot is taken as given (an
identification's values, or a robot's own parameters, e.g. a URDF's) and only ``p`` is
fitted to what it leaves. Rows are weighted per joint (Gautier's two-step sigma unless
told), the estimate and its standard deviations are :mod:`._payload_fit`'s, and the
returned payload is physically consistent (its pseudo-inertia positive semidefinite,
Wensing, Kim & Slotine, IEEE RA-L 2018).
"""

from __future__ import annotations

import dataclasses
import os
import warnings
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Float

from .._deprecation import caller_stacklevel
from .._output import jsonable, markdown_table
from ..dynamics._inertia import inertia_matrix, transform_params
from ..dynamics._regressor import inverse_dynamics, regressor
from ..dynamics._robot import LINK_PARAMETERS, N_LINK_PARAMETERS, Robot
from ..dynamics._urdf import fixed_link_pose
from ..measurements._container import Measurements
from ._fitting import Sigma
from ._identify import Data, Identification, check_offsets, model_of, recordings_of, stacked
from ._model import TorqueModel
from ._payload_fit import LinearFit, consistent, is_consistent, joint_sigma
from ._terms import Offset

#: The payload's parameter names, in :attr:`Payload.params10`'s order.
PAYLOAD_PARAMETERS = LINK_PARAMETERS[:10]
#: A mass whose standard deviation exceeds this fraction of it is warned of.
POOR_MASS = 0.1
_INERTIA = PAYLOAD_PARAMETERS[:6]


def _quantities(p):
    """``[m, c (3), inertia about the origin (6), inertia about the CoM (6)]`` of ``p``."""
    m, h = p[6], p[7:10]
    shift = (h @ h * jnp.eye(3) - jnp.outer(h, h)) / m  # parallel-axis term m(|c|^2 - c c^T)
    about_com = p[:6] - jnp.stack([shift[0, 0], shift[1, 1], shift[2, 2], shift[0, 1],
                                   shift[0, 2], shift[1, 2]])
    return jnp.concatenate([p[6:7], h / m, p[:6], about_com])


def _masked(values: np.ndarray, std: np.ndarray) -> np.ndarray:
    return np.where(np.isfinite(std), values, np.nan)


@dataclasses.dataclass(frozen=True, eq=False)
class Payload:
    """What :func:`identify_payload` returns: a body fixed to a link, in the link's frame.

    Attributes:
        link: the link named (a moving link, or one fixed to it: a flange, ``tool0``).
        moving_link: the robot's moving link that carries it.
        frame: ``(4, 4)`` pose of ``link``'s frame in ``moving_link``'s.
        params10: ``[XX YY ZZ XY XZ YZ M MX MY MZ]`` in ``link``'s frame (inertia about its
            origin [kg m^2], mass [kg], first moments [kg m]): physically consistent unless
            ``physical=False``. Where the data do not determine a parameter
            (:attr:`determined`), its value is a placeholder of a consistent body, not an
            estimate; the quantities below are NaN there.
        unconstrained10: the least-squares estimate before the consistency constraint.
        std10: standard deviation of each parameter (``inf``: undetermined).
        quantity_std: standard deviations of ``[mass, com (3), inertia (6), inertia_com
            (6)]`` (inertia entries ``XX YY ZZ XY XZ YZ``), propagated through the
            Jacobian at :attr:`params10` (:attr:`std` as arrays).
        physical: whether the estimate was already consistent, and the solver's report
            where it was not.
        fit: residual statistics: per-joint RMS [N m] of the loaded and unloaded rows,
            the row ``sigma`` per joint, the weighted residual ``variance``, samples,
            ``rank``, the payload columns' ``condition_number`` after the robot's.
        settings: the mode (``joint`` or ``robot fixed``), torque model, weighting.
        robot_names, robot_values: the robot's refitted model values (joint mode), else
            empty.
    """

    link: str
    moving_link: str
    frame: np.ndarray
    params10: np.ndarray
    unconstrained10: np.ndarray
    std10: np.ndarray
    quantity_std: np.ndarray
    physical: dict
    fit: dict
    settings: dict
    robot_names: tuple[str, ...] = ()
    robot_values: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))

    def __post_init__(self):
        for value in vars(self).values():
            if isinstance(value, np.ndarray):
                value.setflags(write=False)

    @property
    def determined(self) -> np.ndarray:
        """Per parameter of :attr:`params10`: whether the data determine it."""
        return np.isfinite(self.std10)

    @property
    def mass(self) -> float:
        """[kg]"""
        return float(self.params10[6])

    @property
    def com(self) -> Float[np.ndarray, " 3"]:
        """Centre of mass [m] in :attr:`link`'s frame (NaN where undetermined)."""
        return _masked(self.params10[7:10] / self.mass, self.quantity_std[1:4])

    @property
    def inertia(self) -> Float[np.ndarray, "3 3"]:
        """Inertia [kg m^2] about :attr:`link`'s origin, in its frame."""
        return inertia_matrix(_masked(self.params10[:6], self.quantity_std[4:10]))

    @property
    def inertia_com(self) -> Float[np.ndarray, "3 3"]:
        """Inertia [kg m^2] about the centre of mass, in :attr:`link`'s axes."""
        values = np.asarray(_quantities(jnp.asarray(self.params10)))[10:]
        return inertia_matrix(_masked(values, self.quantity_std[10:]))

    @property
    def std(self) -> dict[str, Any]:
        """Standard deviations of ``mass``, ``com``, ``inertia``, ``inertia_com`` (3x3)
        and ``params10``, in their units (``inf``: undetermined)."""
        s = self.quantity_std
        return {"mass": float(s[0]), "com": s[1:4], "inertia": inertia_matrix(s[4:10]),
                "inertia_com": inertia_matrix(s[10:]), "params10": self.std10}

    def as_dict(self) -> dict:
        """Everything, JSON-ready (NaN and inf as null)."""
        return jsonable({
            "link": self.link, "moving_link": self.moving_link, "frame": self.frame,
            "mass": self.mass, "com": self.com, "inertia": self.inertia,
            "inertia_com": self.inertia_com, "std": self.std,
            "names": PAYLOAD_PARAMETERS, "params10": self.params10,
            "determined": dict(zip(PAYLOAD_PARAMETERS, self.determined.tolist())),
            "unconstrained_params10": self.unconstrained10, "physical": self.physical,
            "fit": self.fit, "settings": self.settings,
            "robot": {"names": self.robot_names, "values": self.robot_values}})

    def text(self) -> str:
        """The payload as a markdown table: quantity, value, standard deviation, unit."""
        s, q = self.std, self.quantity_std
        rows = [["mass", self.mass, s["mass"], "kg"]]
        rows += [[f"com {a}", self.com[i], q[1 + i], "m"] for i, a in enumerate("xyz")]
        for label, values, off in (("inertia", self.inertia, 4),
                                   ("inertia about com", self.inertia_com, 10)):
            flat = [values[i, j] for i, j in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))]
            rows += [[f"{label} {n}", v, q[off + i], "kg m^2"]
                     for i, (n, v) in enumerate(zip(_INERTIA, flat))]
        cells = [[r[0], "not determined" if not np.isfinite(r[1]) else f"{r[1]:.6g}",
                  "inf" if not np.isfinite(r[2]) else f"{r[2]:.3g}", r[3]] for r in rows]
        where = self.link if self.link == self.moving_link else (
            f"{self.link} (fixed to {self.moving_link})")
        how = ("the unconstrained estimate, already consistent"
               if self.physical.get("already_consistent") else
               "projected onto consistent bodies" if self.physical.get("solver") else
               "unconstrained (physical=False)")
        return (f"payload on {where}, in its frame ({self.settings['mode']}; {how})\n\n"
                + markdown_table(["quantity", "value", "std", "unit"], cells,
                                 align=["left", "right", "right", "left"]))

    def __repr__(self) -> str:
        return (f"Payload(link={self.link!r}, mass={self.mass:.4g} kg "
                f"+- {self.quantity_std[0]:.2g}, com={np.round(self.com, 4).tolist()} m)")


def _frame_map(T: np.ndarray) -> np.ndarray:
    """``A`` with ``p_link = A p_frame`` for a frame at pose ``T`` in the link's frame."""
    return np.stack([transform_params(T, e) for e in np.eye(10)], axis=1)


def payload_frame(robot: Robot, link: str, urdf: str | os.PathLike[str] | None
                  ) -> tuple[int, np.ndarray]:
    """``(index of the moving link, pose of link's frame in it)``; a ValueError for a link
    the robot (or its URDF) lacks."""
    if not isinstance(link, str):
        raise TypeError(f"link must be a link name (robot.link_names), got {link!r}")
    if link in robot.link_names:
        return robot.link_names.index(link), np.eye(4)
    if urdf is None:
        raise ValueError(f"link {link!r} is not a moving link of robot {robot.name!r} "
                         f"({', '.join(robot.link_names)}); a link fixed to one (a flange, "
                         f"tool0) needs the robot's URDF (urdf=, --robot FILE.urdf)")
    moving, T = fixed_link_pose(urdf, link, robot.link_names)
    return robot.link_names.index(moving), T


def _recordings(robot: Robot, data: Data | None, label: str) -> list[Measurements]:
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
                                   base=model.base, recordings=count)
        return model
    model = TorqueModel.of(robot, (Offset(),)) if model is None else model_of(robot, model)
    check_offsets(model, count)
    return model


def _known_torques(robot: Robot | Identification, q: np.ndarray, qd: np.ndarray,
                   qdd: np.ndarray) -> np.ndarray:
    """The robot's torques as given: an identification's prediction, or a robot's own
    parameters' (a URDF's)."""
    if isinstance(robot, Identification):
        return robot.predict(q, qd, qdd)
    if not np.any(np.asarray(robot.params).reshape(-1, N_LINK_PARAMETERS)[:, :10]):
        raise ValueError(f"robot {robot.name!r} has no inertial parameters (all zero): give "
                         f"recordings without the payload (unloaded=, --data)")
    return np.asarray(inverse_dynamics(robot, robot.params, q, qd, qdd))


def _estimate(fit: LinearFit, d_r: int, physical: bool) -> tuple[np.ndarray, dict]:
    """The estimate: unconstrained, kept where it is already a body or when ``physical``
    is off, else projected (:func:`~._payload_fit.consistent`); and what was done."""
    report: dict[str, Any] = {"already_consistent": is_consistent(fit.x[d_r:])}
    if not physical or report["already_consistent"]:
        return fit.x, report
    x, solved = consistent(fit, d_r)
    return x, {**report, **solved}


def identify_payload(robot: Robot | Identification, loaded: Data, link: str, *,
                     unloaded: Data | None = None, model: TorqueModel | None = None,
                     sigma: Sigma = "residual", urdf: str | os.PathLike[str] | None = None,
                     physical: bool = True) -> Payload:
    """Identify a payload fixed to ``link`` from recordings with it (module docstring).

    Args:
        robot: an :class:`~sedsabso_jax.Identification` (its torque model; its values too
            without ``unloaded``) or a :class:`~sedsabso_jax.Robot` (its own parameters,
            e.g. a URDF's, without ``unloaded``).
        loaded: recordings with the payload: a :class:`~sedsabso_jax.Measurements`,
            several, or ``(times, q, qd, qdd, tau)``; joint side.
        link: the link the payload is fixed to: one of ``robot.link_names`` or, with
            ``urdf``, a link fixed to one (a flange, ``tool0``); the payload is reported
            in its frame.
        unloaded: recordings without the payload (one sampling rate with ``loaded``):
            the robot's model is refitted with the payload, jointly.
        model: the torque model of a joint fit with a robot (default: viscous and Coulomb
            friction and a torque offset per joint); one offset per recording counts the
            unloaded recordings first, then the loaded ones.
        sigma: row weights per joint: ``"residual"`` (Gautier's two-step), None or
            ``"equal"``, or one number per joint.
        urdf: the URDF the robot was read from, to find a fixed link.
        physical: project the estimate onto physically consistent bodies.

    Raises ValueError when the loaded recordings do not determine the payload's mass
    (e.g. a link whose every joint axis passes through the payload's frame origin, or a
    link moved only by a vertical axis), and warns when its standard deviation exceeds
    :data:`POOR_MASS` of it.
    """
    rob = robot.model.robot if isinstance(robot, Identification) else robot
    if not isinstance(rob, Robot):
        raise TypeError(f"robot must be a sedsabso_jax.Robot or an Identification, got "
                        f"{type(robot).__name__}")
    k, T = payload_frame(rob, link, urdf)
    loaded_recs = _recordings(rob, loaded, "loaded")
    unloaded_recs = _recordings(rob, unloaded, "unloaded")
    recordings_of(rob, [*unloaded_recs, *loaded_recs])  # one rate for all
    joint = bool(unloaded_recs)
    if not joint and model is not None:
        raise ValueError("model: without unloaded recordings the robot is taken as given; "
                         "a torque model is refitted only with unloaded=")
    q, qd, qdd, tau, index = stacked([*unloaded_recs, *loaded_recs])
    on = index >= len(unloaded_recs)  # the loaded rows
    cols = slice(N_LINK_PARAMETERS * k, N_LINK_PARAMETERS * k + 10)
    Yp = np.zeros(q.shape + (10,))
    Yp[on] = np.asarray(regressor(rob, q[on], qd[on], qdd[on]))[..., cols] @ _frame_map(T)
    count = len(unloaded_recs) + len(loaded_recs)
    tm = _joint_model(robot, model, count) if joint else None
    if tm is not None:
        Ym = tm.regressor(q, qd, qdd, index if tm.recordings > 1 else None)
        Y, b = np.concatenate([Ym, Yp], -1), tau
    else:
        Y, b = Yp, tau - _known_torques(robot, q, qd, qdd)
    s = joint_sigma(Y, b, sigma)
    fit = LinearFit.of((Y / s[:, None]).reshape(-1, Y.shape[-1]), (b / s).reshape(-1))
    d_r = Y.shape[-1] - 10
    lift = np.hstack([np.zeros((10, d_r)), np.eye(10)])  # payload rows of x
    if not fit.determined(lift[6])[0]:
        raise ValueError(f"the loaded recordings do not excite the payload's mass on link "
                         f"{link!r}: its torque is in the span of the other columns (every "
                         f"joint axis moving the link passes through the frame's origin, or "
                         f"the arm does not move)")
    x, report = _estimate(fit, d_r, physical)
    p = x[d_r:]
    jac = np.asarray(jax.jacfwd(_quantities)(jnp.asarray(p)))
    quantity_std = fit.std(jac @ lift)
    residual = Y @ x - b
    rms = {"rms_loaded": np.sqrt(np.mean(residual[on] ** 2, axis=0))}
    if joint:
        rms["rms_unloaded"] = np.sqrt(np.mean(residual[~on] ** 2, axis=0))
    stats = {**rms, "sigma": s, "variance": fit.variance,
             "samples_loaded": int(on.sum()), "samples_unloaded": int((~on).sum()),
             "rank": fit.rank, "columns": int(Y.shape[-1]),
             "condition_number": fit.condition(np.arange(d_r, d_r + 10))}
    settings = {"mode": "joint fit" if tm is not None else "robot fixed",
                "robot": rob.name, "friction": None if tm is None else tm.friction,
                "weights": sigma if isinstance(sigma, str) or sigma is None else "given",
                "physical": bool(physical)}
    if quantity_std[0] > POOR_MASS * abs(p[6]):
        warnings.warn(f"payload: the mass is poorly determined ({p[6]:.4g} kg +- "
                      f"{quantity_std[0]:.2g}): the loaded recordings barely excite it",
                      stacklevel=caller_stacklevel())
    return Payload(link=link, moving_link=rob.link_names[k], frame=T, params10=p,
                   unconstrained10=fit.x[d_r:], std10=fit.std(lift), quantity_std=quantity_std,
                   physical=report, fit=jsonable(stats), settings=settings,
                   robot_names=() if tm is None else tm.names,
                   robot_values=x[:d_r])

