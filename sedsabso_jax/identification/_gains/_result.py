"""What :func:`~._identify_gains.identify_drive_gains` returns (:class:`DriveGains`): the
drive gains with their standard deviations and whether the data calibrate each, the
payload's estimated moments, the robot's model values in torque units; as text and JSON,
and the gains applied to recordings of currents (:meth:`DriveGains.apply`)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ..._output import jsonable, markdown_table, to_its_std
from ...measurements._container import Measurements
from .._payload._term import PAYLOAD_PARAMETERS
from ._solvers import GAIN_METHODS

#: A gain whose relative standard deviation exceeds this is not calibrated by the data.
CALIBRATED_STD = 0.005


@dataclasses.dataclass(frozen=True, eq=False)
class DriveGains:
    """Drive gains identified with a known payload.

    Attributes:
        gains: per motor (per joint without a transmission), the torque per unit of the
            recorded quantity (N m per A for currents); NaN where the data do not
            determine it.
        std: their standard deviations (``inf``: not determined).
        motors: the transmission ``K`` the currents go through (the identity: the
            currents are the joints' own).
        method: how the equations were solved, the method's word (``"likelihood"``,
            ``"total"``, ``"ordinary"``, ``"physical"``: :data:`~._solvers.GAIN_METHODS`).
        payload10: the payload's ``XX YY ZZ XY XZ YZ M MX MY MZ`` in ``link``'s frame,
            its mass (and first moments with a known centre of mass) as given.
        payload_std10: their standard deviations (0 for the given ones).
        robot_names, robot_values, robot_std: the robot's model values (base
            parameters, terms) in torque units, with their standard deviations.
        fit: residual statistics: per joint the RMS of the loaded and unloaded rows (in
            torque units), ``sigma``, samples, the gains' condition number after the
            other columns.
        settings: the link, mass, centre of mass, torque model, method and the solver's
            report.
        joint_names: the robot's names of its joints (a URDF's), which label the gains
            on the joint side (:attr:`labels`).
    """

    gains: np.ndarray
    std: np.ndarray
    motors: np.ndarray
    method: str
    payload10: np.ndarray
    payload_std10: np.ndarray
    robot_names: tuple[str, ...]
    robot_values: np.ndarray
    robot_std: np.ndarray
    fit: dict
    settings: dict
    joint_names: tuple[str, ...] = ()

    def __post_init__(self):
        for value in vars(self).values():
            if isinstance(value, np.ndarray):
                value.setflags(write=False)

    @property
    def relative_std(self) -> np.ndarray:
        """``std / |gain|`` (``inf`` where not determined)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(np.isfinite(self.gains), self.std / np.abs(self.gains), np.inf)

    @property
    def calibrated(self) -> np.ndarray:
        """Per gain: whether the data calibrate it, its relative standard deviation at
        most :data:`CALIBRATED_STD`."""
        return self.relative_std <= CALIBRATED_STD

    @property
    def labels(self) -> tuple[str, ...]:
        """What each gain belongs to, as the table and the warnings name it: the joint's
        name (as ``identify`` names joints), or behind a transmission the motor's number
        (from 1)."""
        n = self.gains.size
        if self.motor_side or len(self.joint_names) != n:
            return tuple(str(i + 1) for i in range(n))
        return tuple(self.joint_names)

    @property
    def motor_side(self) -> bool:
        """Whether the gains are the motors' behind a transmission (not the identity)."""
        return not np.array_equal(self.motors, np.eye(self.motors.shape[0]))

    def apply(self, data: Measurements) -> Measurements:
        """``data`` whose ``tau`` holds the recorded currents (joint-side positions), with
        the joint torques ``K^T (g * c)`` in their place. A gain the data do not
        determine is refused."""
        if not isinstance(data, Measurements):
            raise TypeError(f"data must be a Measurements, got {type(data).__name__}")
        if data.n_joints != self.gains.size:
            raise ValueError(f"{data.source}: {data.n_joints} joints recorded, the gains are "
                             f"{self.gains.size}")
        if not np.all(np.isfinite(self.gains)):
            missing = [int(i) + 1 for i in np.flatnonzero(~np.isfinite(self.gains))]
            raise ValueError(f"the gains of motors {missing} were not determined: give them")
        tau = (data.tau * self.gains) @ self.motors
        return Measurements(data.times, data.q, data.qd, data.qdd, tau, source=data.source,
                            info=dict(data.info, drive_gains=self.gains.tolist()))

    def as_dict(self) -> dict:
        """Everything, JSON-ready (NaN and inf as null): ``drive_gains`` first, the
        form ``--drive-gains FILE.json`` reads."""
        return jsonable({
            "drive_gains": self.gains, "drive_gains_std": self.std,
            "relative_std_percent": 100 * self.relative_std,
            "calibrated": self.calibrated, "motor_side": self.motor_side,
            "names": [f"motor {k}" for k in self.labels] if self.motor_side
            else list(self.labels),
            "unit": "torque per unit of the recorded quantity (N m / A for currents)",
            "method": self.method,
            "payload": {"names": PAYLOAD_PARAMETERS, "params10": self.payload10,
                        "std10": self.payload_std10},
            "robot": {"names": self.robot_names, "values": self.robot_values,
                      "std": self.robot_std},
            "fit": self.fit, "settings": self.settings})

    def text(self) -> str:
        """The gains as a markdown table: motor, gain, std, relative std, calibrated."""
        label = "motor" if self.motor_side else "joint"
        cells = [[name, "not determined" if not np.isfinite(g) else to_its_std(g, s),
                  "inf" if not np.isfinite(s) else to_its_std(s, s),
                  "inf" if not np.isfinite(r) else f"{100 * r:.3g}", "yes" if ok else "NO"]
                 for name, g, s, r, ok in zip(self.labels, self.gains, self.std,
                                              self.relative_std, self.calibrated)]
        head = (f"drive gains (torque per unit recorded) by {GAIN_METHODS[self.method].label}, "
                f"payload {self.settings['mass']:g} kg on {self.settings['link']}")
        return head + "\n\n" + markdown_table(
            [label, "gain", "std", "std [%]", "calibrated"], cells,
            align=["left", "right", "right", "right", "left"])

    def __repr__(self) -> str:
        return (f"DriveGains({self.method}, gains={np.round(self.gains, 5).tolist()}, "
                f"calibrated={self.calibrated.tolist()})")


def read_gains(doc: Any, n: int, source: str) -> np.ndarray:
    """The ``n`` gains of a JSON document :meth:`DriveGains.as_dict` wrote (read from
    ``source``); a ValueError for anything else, or a gain not determined."""
    gains = doc.get("drive_gains") if isinstance(doc, dict) else None
    if not isinstance(gains, list):
        raise ValueError(f"{source}: no 'drive_gains' list (a file 'identify-gains --json' "
                         f"writes)")
    if len(gains) != n:
        raise ValueError(f"{source}: {len(gains)} drive gains, expected {n} (one per joint)")
    names = doc.get("names")
    if not (isinstance(names, list) and len(names) == n):
        names = [str(i + 1) for i in range(n)]
    missing = [names[i] for i, g in enumerate(gains) if not isinstance(g, (int, float))]
    if missing:
        raise ValueError(f"{source}: the drive gains of joints {', '.join(missing)} were not "
                         f"determined (null): calibrate them, or give the gains as numbers")
    return np.asarray(gains, dtype=float)
