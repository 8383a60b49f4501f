"""What :func:`~._identify_payload.identify_payload` returns: a body fixed to a link
(:class:`Payload`), its mass, centre of mass and inertia with standard deviations, as
text and JSON."""

from __future__ import annotations

import dataclasses
from typing import Any

import jax.numpy as jnp
import numpy as np
from jaxtyping import Float

from ..._output import jsonable, markdown_table, to_its_std
from ...dynamics._inertia import inertia_matrix
from ._term import PAYLOAD_PARAMETERS

_INERTIA = PAYLOAD_PARAMETERS[:6]


def quantities(p):
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
    """What :func:`~sedsabso_jax.identify_payload` returns: a body fixed to a link, in
    the link's frame.

    Attributes:
        link: the link named (a moving link, or one fixed to it: a flange, ``tool0``).
        moving_link: the robot's moving link that carries it.
        frame: ``(4, 4)`` pose of ``link``'s frame in ``moving_link``'s.
        params10: ``[XX YY ZZ XY XZ YZ M MX MY MZ]`` in ``link``'s frame (inertia about its
            origin [kg m^2], mass [kg], first moments [kg m]): physically consistent where
            the estimator is (``PhysicallyConsistent``). Where the data do not determine a parameter
            (:attr:`determined`), its value is a placeholder of a consistent body, not an
            estimate; the quantities below are NaN there.
        unconstrained10: the least-squares estimate without the consistency constraint.
        std10: standard deviation of each parameter (``inf``: undetermined).
        quantity_std: standard deviations of ``[mass, com (3), inertia (6), inertia_com
            (6)]`` (inertia entries ``XX YY ZZ XY XZ YZ``), propagated through the
            Jacobian at :attr:`params10` (:attr:`std` as arrays).
        physical: whether the unconstrained estimate was already consistent, and the
            conic solver's report where the estimator is physically consistent.
        fit: residual statistics: per-joint RMS [N m] of the loaded and unloaded rows,
            the row ``sigma`` per joint, the weighted residual ``variance``, samples,
            ``rank``, the payload columns' ``condition_number`` after the robot's.
        settings: the mode (``joint fit`` or ``robot fixed``), torque model, estimator.
        robot_names, robot_values: the robot's refitted model values (joint mode), else
            empty.
        identification: the joint fit of the robot and the payload, an
            :class:`~sedsabso_jax.Identification` (its report, parameters and standard
            deviations; joint mode), else None.
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
    identification: Any = None

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
        values = np.asarray(quantities(jnp.asarray(self.params10)))[10:]
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
        cells = [[r[0], "not determined" if not np.isfinite(r[1]) else to_its_std(r[1], r[2]),
                  "inf" if not np.isfinite(r[2]) else to_its_std(r[2], r[2]), r[3]]
                 for r in rows]
        where = self.link if self.link == self.moving_link else (
            f"{self.link} (fixed to {self.moving_link})")
        how = ("the unconstrained estimate, already consistent"
               if self.physical.get("already_consistent") else
               "physically consistent" if self.physical.get("solver") else "unconstrained")
        return (f"payload on {where}, in its frame ({self.settings['mode']}; {how})\n\n"
                + markdown_table(["quantity", "value", "std", "unit"], cells,
                                 align=["left", "right", "right", "left"]))

    def __repr__(self) -> str:
        return (f"Payload(link={self.link!r}, mass={self.mass:.4g} kg "
                f"+- {self.quantity_std[0]:.2g}, com={np.round(self.com, 4).tolist()} m)")
