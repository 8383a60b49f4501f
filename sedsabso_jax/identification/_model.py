"""The torque model an identification fits: the base regressor plus friction and actuator
terms.

Model (``friction``, terms joined by ``+``)::

    tau = Yb(q, qd, qdd) beta                   base regressor, Coulomb + viscous friction
          + OFF_j                               "offset": a constant torque per joint
          + FQ_j qd_j |qd_j|                    "quadratic": velocity-squared friction
          + K_m^T IA_m (K_m . qdd)              "armature": rotor inertia of motor m
          + K_m^T (FVM_m u_m + FCM_m sign(u_m)) "coupling": friction of a motor that turns
                                                with several joints, u_m = K_m . qd
    sign(qd_j) -> tanh(qd_j / smooth_velocity)  "smooth": Coulomb term without the jump

With ``recordings = R > 1`` (several recordings fitted together) the offset is one per
joint and recording, ``OFF1.1 .. OFF1.R, OFF2.1 ..``: a torque sensor's zero that moved
between the recordings. Rows of recording ``r`` carry 1 in the ``OFFj.r`` column; rows of
no recording (new motions) carry ``1/R`` in each, their mean.

``K`` is the transmission (motor angles ``theta = K q``, :class:`~sedsabso_jax.measurements.
transmission.Transmission`); without one, ``K = 1`` and the armature of joint ``j`` is the
joint-side column ``qdd_j``. With a diagonal ``K`` an ``IA`` value is the motor-side rotor
inertia (kg m^2), its joint-side effect ``N_j^2 IA_j``. The extra columns come after the
base columns, named ``OFF1..``, ``FQ1..``, ``IA1..``, ``FVM6, FCM6`` (motor numbers from 1).

An extra column that the base regressor already spans (e.g. the armature of a first joint
about a fixed vertical axis, which regroups with ``ZZ1``) is dropped: it cannot be
identified apart. :attr:`TorqueModel.regrouped` names them.
"""

from __future__ import annotations

import dataclasses
import functools
import numbers

import numpy as np
from jaxtyping import ArrayLike, Float, Int

from ..dynamics._base_parameters import (
    RANK_TOLERANCE,
    BaseParameters,
    base_parameters,
    random_states,
)
from ..dynamics._robot import N_LINK_PARAMETERS, Robot
from ..measurements._transmission import TransmissionLike, coupled_motors

FRICTION_TERMS = ("viscous-coulomb", "offset", "quadratic", "smooth", "armature", "coupling")
#: Velocity scale (rad/s or m/s) of the "smooth" Coulomb term tanh(qd / v).
SMOOTH_VELOCITY = 0.02
#: Extra column groups whose coefficients a physical body has non-negative.
NONNEGATIVE = ("FQ", "IA", "FVM", "FCM")


@dataclasses.dataclass(frozen=True, eq=False)
class TorqueModel:
    """A linear torque model: the base regressor of ``robot`` plus extra terms (see the
    module docstring); ``transmission`` is ``K`` (``n x n``) or None.

    ``regressor(q, qd, qdd)`` is ``(..., n, d)`` with ``d`` = :attr:`dim`;
    ``predict(values, q, qd, qdd)`` is ``regressor @ values``. :meth:`of` builds one from
    a robot.
    """

    base: BaseParameters
    friction: str = "viscous-coulomb"
    smooth_velocity: float = SMOOTH_VELOCITY
    transmission: np.ndarray | None = None
    recordings: int = 1

    def __post_init__(self):
        if not isinstance(self.recordings, (int, np.integer)) or isinstance(
                self.recordings, bool) or self.recordings < 1:
            raise ValueError(f"recordings must be an integer >= 1, got {self.recordings!r}")
        if self.recordings > 1 and "offset" not in self.terms:
            raise ValueError("one torque offset per recording needs the 'offset' term in the "
                             "friction model (e.g. 'viscous-coulomb+offset')")
        if self.transmission is not None:
            K = np.asarray(self.transmission, dtype=float)
            n = self.robot.n_joints
            if K.shape != (n, n) or not np.all(np.isfinite(K)):
                raise ValueError(f"transmission must be a finite ({n}, {n}) matrix for robot "
                                 f"{self.robot.name!r}, got shape {K.shape}")
            object.__setattr__(self, "transmission", K)
        if "coupling" in self.terms and not self._coupled:
            raise ValueError("friction term 'coupling' needs a transmission with a motor that "
                             "turns several joints (a coupling)")

    @classmethod
    def of(cls, robot: Robot, friction: str = "viscous-coulomb", *,
           transmission: TransmissionLike = None,
           smooth_velocity: float = SMOOTH_VELOCITY,
           base: BaseParameters | None = None, recordings: int = 1) -> TorqueModel:
        """The model of ``robot`` with the ``friction`` terms (``"viscous-coulomb"`` plus
        any of ``"+offset"``, ``"+quadratic"``, ``"+smooth"``, ``"+armature"``,
        ``"+coupling"``, in any order), ``transmission`` (a
        :class:`~sedsabso_jax.measurements._transmission.Transmission` or its matrix ``K``)
        for the armature and coupling terms, the smooth Coulomb term's velocity scale, and
        ``base``, a precomputed ``base_parameters(robot)`` (computed when None), and
        ``recordings``: one torque offset per joint and recording (module docstring)."""
        if not isinstance(robot, Robot):
            raise TypeError(f"robot must be a sedsabso_jax.Robot, got {type(robot).__name__}")
        friction = canonical_friction(friction)
        if isinstance(smooth_velocity, bool) or not isinstance(smooth_velocity, numbers.Real) \
                or not (np.isfinite(smooth_velocity) and smooth_velocity > 0):
            raise ValueError(f"smooth_velocity must be > 0, got {smooth_velocity!r}")
        if base is None:
            base = base_parameters(robot)
        elif not isinstance(base, BaseParameters) or base.robot.n_params != robot.n_params:
            raise ValueError("base must be base_parameters(robot) of this robot")
        return cls(base, friction, float(smooth_velocity),
                   getattr(transmission, "matrix", transmission), recordings)

    @property
    def robot(self) -> Robot:
        return self.base.robot

    def settings(self) -> dict:
        """What the reports write about the model besides its friction terms."""
        out: dict = {}
        if self.transmission is not None:
            out["transmission"] = self.transmission
        if self.regrouped:
            out["regrouped"] = list(self.regrouped)
        if "smooth" in self.terms:
            out["smooth_velocity"] = float(self.smooth_velocity)
        if self.recordings > 1:
            out["offset_per_recording"] = self.recordings
        return out

    @property
    def terms(self) -> tuple[str, ...]:
        return tuple(self.friction.split("+"))

    @property
    def _K(self) -> np.ndarray:
        n = self.robot.n_joints
        return np.eye(n) if self.transmission is None else self.transmission

    @property
    def _coupled(self) -> tuple[int, ...]:
        return coupled_motors(self._K)

    @property
    def extras(self) -> tuple[str, ...]:
        """Extra column groups in order: ``"OFF"``, ``"FQ"``, ``"IA"``, ``"FVM"/"FCM"``."""
        groups = [k for t, k in (("offset", "OFF"), ("quadratic", "FQ"), ("armature", "IA"))
                  if t in self.terms]
        return tuple(groups + (["FVM", "FCM"] if "coupling" in self.terms else []))

    def _extra_names(self) -> list[str]:
        n = self.robot.n_joints
        names = []
        for k in self.extras:
            if k == "OFF" and self.recordings > 1:
                names += [f"OFF{j + 1}.{r + 1}" for j in range(n) for r in range(self.recordings)]
                continue
            motors = self._coupled if k in ("FVM", "FCM") else range(n)
            names += [f"{k}{m + 1}" for m in motors]
        return names

    def _offsets(self, batch: tuple[int, ...], recording) -> np.ndarray:
        """The offset columns ``(..., n, n R)``: joint ``j``'s row has its recording's
        indicator in columns ``j R .. j R + R - 1`` (``1/R`` each without a recording)."""
        n, R = self.robot.n_joints, self.recordings
        if recording is None:
            share = np.full(batch + (R,), 1.0 / R)
        else:
            index = np.asarray(recording)
            if index.shape != batch or index.dtype.kind not in "iu" or (
                    index.size and (index.min() < 0 or index.max() >= R)):
                raise ValueError(f"recording must hold one integer in [0, {R}) per sample "
                                 f"{batch}, got shape {index.shape}")
            share = (index[..., None] == np.arange(R)).astype(float)
        E = np.zeros(batch + (n, n, R))
        E[..., np.arange(n), np.arange(n), :] = share[..., None, :]
        return E.reshape(batch + (n, n * R))

    def _extra_columns(self, qd, qdd, recording=None) -> np.ndarray:
        """All extra columns, ``(..., n, len(_extra_names()))``."""
        n = self.robot.n_joints
        batch = qd.shape[:-1]
        K = self._K
        cols = []
        for k in self.extras:
            if k == "OFF" and self.recordings > 1:
                cols.append(self._offsets(batch, recording))
                continue
            if k in ("OFF", "FQ"):
                E = np.zeros(batch + (n, n))
                E[..., np.arange(n), np.arange(n)] = 1.0 if k == "OFF" else qd * np.abs(qd)
                cols.append(E)
                continue
            motors = list(self._coupled) if k in ("FVM", "FCM") else list(range(n))
            u = (qdd if k == "IA" else qd) @ K[motors].T  # (..., motors): K_m . qdd or qd
            if k == "FCM":
                u = np.sign(u)
            cols.append(K[motors].T * u[..., None, :])  # joint j, motor m: K[m, j] u_m
        return np.concatenate(cols, -1) if cols else np.zeros(batch + (n, 0))

    @functools.cached_property
    def _kept(self) -> np.ndarray:
        """Indices of the extra columns that the base regressor does not span, found as
        the base parameters are: at random states, scaled columns, ordered QR."""
        names = self._extra_names()
        if not names:
            return np.zeros(0, dtype=int)
        robot = self.robot
        # the sample count base_parameters uses: the regressor is compiled for it already
        q, qd, qdd = random_states(robot, max(50, -(-4 * robot.n_params // robot.n_joints)),
                                   seed=1)
        recording = np.random.default_rng(1).integers(0, self.recordings, q.shape[0])
        Y = self._full_regressor(q, qd, qdd, recording if self.recordings > 1 else None)
        W = Y.reshape(-1, Y.shape[-1])
        W = W / np.where(np.linalg.norm(W, axis=0) > 0, np.linalg.norm(W, axis=0), 1.0)
        d = np.abs(np.diag(np.linalg.qr(W, mode="r")))
        independent = d > RANK_TOLERANCE * d.max()
        return np.flatnonzero(independent[self.base.rank:])

    @property
    def regrouped(self) -> tuple[str, ...]:
        """Extra columns dropped because the base regressor spans them."""
        names = self._extra_names()
        return tuple(n for i, n in enumerate(names) if i not in set(self._kept.tolist()))

    @property
    def names(self) -> tuple[str, ...]:
        extra = self._extra_names()
        return tuple(self.base.names) + tuple(extra[i] for i in self._kept)

    @property
    def nonnegative(self) -> np.ndarray:
        """Per column (:attr:`names`): whether a physical value is >= 0 (friction and
        armature extras; the base columns are constrained through the full parameters)."""
        return np.array([False] * self.base.rank
                        + [n.rstrip("0123456789") in NONNEGATIVE for n in self.names[
                            self.base.rank:]])

    @property
    def dim(self) -> int:
        return len(self.names)

    def _full_regressor(self, q, qd, qdd, recording=None) -> np.ndarray:
        q, qd, qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
        Y = np.asarray(self.base.regressor(q, qd, qdd))
        n = self.robot.n_joints
        batch = Y.shape[:-2]
        qd, qdd = np.broadcast_to(qd, batch + (n,)), np.broadcast_to(qdd, batch + (n,))
        if "smooth" in self.terms:
            Y = Y.copy()
            Y[..., np.arange(n), self._fc_columns()] = np.tanh(qd / self.smooth_velocity)
        return np.concatenate([Y, self._extra_columns(qd, qdd, recording)], -1)

    def regressor(self, q: Float[ArrayLike, "*batch n"], qd: Float[ArrayLike, "*batch n"],
                  qdd: Float[ArrayLike, "*batch n"],
                  recording: Int[ArrayLike, "*batch"] | None = None
                  ) -> Float[np.ndarray, "*batch n d"]:
        """``(..., n, dim)``: the base columns, then the identifiable extra columns;
        ``recording``: the recording of each sample, for one offset per recording (None:
        new motions, the offsets' mean)."""
        Y = self._full_regressor(q, qd, qdd, recording)
        keep = np.r_[np.arange(self.base.rank), self.base.rank + self._kept]
        return Y[..., keep] if len(keep) < Y.shape[-1] else Y

    def predict(self, values: Float[ArrayLike, " d"], q: Float[ArrayLike, "*batch n"],
                qd: Float[ArrayLike, "*batch n"], qdd: Float[ArrayLike, "*batch n"],
                recording: Int[ArrayLike, "*batch"] | None = None
                ) -> Float[np.ndarray, "*batch n"]:
        """Torques ``regressor(q, qd, qdd, recording) @ values``, ``(..., n)``."""
        values = np.asarray(values, dtype=float)
        if values.shape != (self.dim,):
            raise ValueError(f"values must have shape ({self.dim},), got {values.shape}")
        return self.regressor(q, qd, qdd, recording) @ values

    def _fc_columns(self) -> np.ndarray:
        """Base column of each joint's Coulomb coefficient (friction never regroups)."""
        full = [self.base.indices.index(N_LINK_PARAMETERS * j + 10)
                if N_LINK_PARAMETERS * j + 10 in self.base.indices else -1
                for j in range(self.robot.n_joints)]
        if min(full) < 0:
            raise ValueError("friction='...+smooth' needs every joint's Coulomb column in the "
                             "base set")
        return np.asarray(full)


def canonical_friction(friction: object) -> str:
    """``friction`` with its terms checked, ``viscous-coulomb`` added, in canonical order."""
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

