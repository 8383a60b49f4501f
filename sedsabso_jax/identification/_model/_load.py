"""Friction that grows with the torque a joint transmits: :class:`LoadFriction`, the one
term whose columns read the model's own fitted values."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
from typing import Any, ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._options import as_floats
from ._term import AbstractTerm, ModelView, Signals, diagonal


class LoadFriction(AbstractTerm):
    """``FL_j |tau_load_j| c_j(qd)``: Coulomb friction that grows with the torque the
    joint transmits (a harmonic drive's or gearbox's teeth and bearings, loaded by it),
    ``c_j`` the model's Coulomb shape and ``tau_load`` the model's own rigid-body torque
    (the base columns but friction, and bodies such as a payload) at ``load_point``,
    those columns' values (:meth:`~._torque_model.TorqueModel.rigid_values`); ``FL_j >=
    0``, dimensionless (N m of friction per N m transmitted). With ``viscous=True`` also
    ``FLV_j |tau_load_j| qd_j`` (s/rad).

    The coefficients are bilinear with the rigid-body parameters. Without a load point
    the term waits for one (:attr:`waiting`; its columns meanwhile read the robot's own
    parameters): the fit takes it from a least-squares fit of the model without this
    term, then fits the model with that load (two linear fits, any estimator); with
    ``fixed_point=True`` it goes on, reading each fit's values until the load settles
    (``load:fixed-point``). The fitted model keeps the load its fit used."""

    viscous: bool = False
    fixed_point: bool = False
    load_point: tuple[float, ...] | None = eqx.field(default=None, converter=as_floats)
    name: ClassVar[str] = "load"
    nonnegative: ClassVar[bool] = True
    read_fields: ClassVar[tuple[str, ...]] = ("load_point",)
    #: The command line's options, ``load:viscous,fixed-point``.
    options: ClassVar[tuple[str, ...]] = ("viscous", "fixed-point")

    def __check_init__(self):
        for field in ("viscous", "fixed_point"):
            if not isinstance(getattr(self, field), bool):
                raise ValueError(f"LoadFriction's {field} must be True or False, got "
                                 f"{getattr(self, field)!r}")
        if self.load_point is not None and not (isinstance(self.load_point, tuple)
                                                and np.all(np.isfinite(self.load_point))):
            raise ValueError(f"LoadFriction's load_point must be finite values of the "
                             f"model's rigid-body columns, got {self.load_point!r}")

    @property
    def unit(self) -> str:
        return ("N m per N m transmitted for friction growing with the load FL"
                + ", s/rad for viscous friction growing with the load FLV" * self.viscous)

    @property
    def iterates(self) -> bool:
        return self.fixed_point

    def read_line(self, step: dict) -> str:
        if "settled" in step:
            state = "settled" if step["settled"] else "NOT settled"
            return (f"friction growing with the load: the fit's own rigid-body torque after "
                    f"{step['iterations']} fits ({state})")
        return ("friction growing with the load: the rigid-body torque of a least-squares "
                "fit without it")

    @property
    def text(self) -> str:
        chosen = [o for o, on in zip(self.options, (self.viscous, self.fixed_point)) if on]
        return "load" + (":" + ",".join(chosen) if chosen else "")

    @classmethod
    def parse(cls, option: str | None) -> AbstractTerm:
        words = [] if option is None else option.split(",")
        if any(w not in cls.options for w in words) or len(set(words)) < len(words):
            raise ValueError(f"friction term 'load': expected load, load:viscous, "
                             f"load:fixed-point or load:viscous,fixed-point, got "
                             f"load:{option}")
        return cls(viscous="viscous" in words, fixed_point="fixed-point" in words)

    def names(self, model: ModelView) -> tuple[str, ...]:
        n = model.robot.n_joints
        kinds = ("FL", "FLV") if self.viscous else ("FL",)
        return tuple(f"{k}{j + 1}" for k in kinds for j in range(n))

    def columns(self, model: ModelView, s: Signals) -> Any:
        n = model.robot.n_joints
        point: Any
        if self.load_point is None:  # not fitted: the robot's own
            point = model.rigid_values(model.prior_values)
        else:  # floats, or a search's traced values
            point = self.load_point
        load = jnp.abs(s.rigid_torque(point))
        out = [diagonal(load * s.coulomb, n)]
        if self.viscous:
            out.append(diagonal(load * s.qd, n))
        return jnp.concatenate(out, -1)

    def settings(self) -> dict:
        return {"load_viscous": self.viscous, "load_fixed_point": self.fixed_point}
