"""An identification as a rigid-body simulator holds it (MuJoCo: link inertias, joint
``damping``, ``frictionloss`` and ``armature``, an actuator bias): what each term gives it
(:meth:`~.._model._term.AbstractTerm.held`) and what is left out, said in words."""

from __future__ import annotations

import dataclasses

import numpy as np

from .._model._torque_model import TorqueModel


@dataclasses.dataclass(frozen=True, eq=False)
class Simulated:
    """The joint-space quantities beyond the links' 12 parameters a simulator holds
    (``armature``, ``offset``, each ``(n,)``) and what it cannot hold: ``left_out`` a line
    per term or part of a term (its ``--friction`` word, then what)."""

    armature: np.ndarray
    offset: np.ndarray
    left_out: tuple[str, ...]

    def comment(self) -> str:
        """One line for a model file."""
        return ("not held by the simulator (left out): " + "; ".join(self.left_out)
                if self.left_out else "every term of the model is held")


def term_values(model: TorqueModel, values: np.ndarray) -> list[np.ndarray]:
    """Each term's coefficients (one per its names) from the model's ``values``; a column
    the base spans (regrouped) is 0: the base parameters hold it."""
    index = {name: k for k, name in enumerate(model.names)}
    values = np.asarray(values, dtype=float)
    return [np.array([values[index[name]] if name in index else 0.0
                      for name in term.names(model)]) for term in model.terms]


def simulated(model: TorqueModel, values: np.ndarray) -> Simulated:
    """What a simulator holds of ``model`` at ``values`` (its terms beyond the links)."""
    n = model.robot.n_joints
    armature, offset, left_out = np.zeros(n), np.zeros(n), []
    for term, coefficients in zip(model.terms, term_values(model, values)):
        held = term.held(model, coefficients)
        if held is None:
            names = term.names(model)
            shown = ", ".join(f"{k} = {v:.4g}" for k, v in zip(names, coefficients))
            left_out.append(f"{term.text}" + (f" ({shown})" if shown else ""))
            continue
        if held.armature is not None:
            armature = armature + held.armature
        if held.offset is not None:
            offset = offset + held.offset
        if held.lost:
            left_out.append(f"{term.text}: {held.lost}")
    return Simulated(armature, offset, tuple(left_out))


def mujoco_torques(xml: str, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray
                   ) -> np.ndarray:
    """The joint torques ``(T, n)`` as measured (each actuator's ``ctrl``) that MuJoCo's
    inverse dynamics (``mj_inverse``) gives for the MJCF ``xml`` (one joint, one
    actuator of fixed gain and affine bias per joint, as :func:`~sedsabso_jax.dynamics.to_mjcf`
    writes) at the states ``(T, n)``."""
    mujoco = import_mujoco()
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    dof = m.jnt_dofadr[m.actuator_trnid[:, 0]]
    q, qd, qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
    out = np.empty((len(q), m.nu))
    for k in range(len(q)):
        d.qpos[:], d.qvel[:], d.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(m, d)
        out[k] = d.qfrc_inverse[dof]
    # force = gain ctrl + bias0 (no position or velocity bias written)
    return (out - m.actuator_biasprm[:, 0]) / m.actuator_gainprm[:, 0]


def import_mujoco():
    """The ``mujoco`` module, or an ImportError that says how to install it."""
    try:
        import mujoco
    except ImportError:
        raise ImportError("MuJoCo's model needs the mujoco package: "
                          "pip install 'sedsabso-jax[mujoco]'") from None
    return mujoco


@dataclasses.dataclass(frozen=True, eq=False)
class SimulatorCheck:
    """A written MJCF judged in MuJoCo beside the package's own model, on each data set
    (``rows``, one dict each: ``data``, the torque error ``own`` and ``mujoco`` (MuJoCo's
    inverse dynamics) in ``measure``, and the median end errors of open-loop rollouts,
    ``rollouts_own`` and ``rollouts_mujoco``, one per length of ``lengths`` s, in
    degrees), and what was left out (``left_out``)."""

    measure: str
    lengths: tuple[float, ...]
    rows: tuple[dict, ...]
    left_out: tuple[str, ...]
    #: each data set's :class:`~._rollouts.RolloutErrors` (its figure), by name
    rollouts: dict = dataclasses.field(default_factory=dict)

    @classmethod
    def of(cls, ident, xml: str, recordings: dict, limits=None) -> SimulatorCheck:
        """``ident``'s MJCF ``xml`` against its own model on each recording (``{name:
        Measurements}``; new motions: their offsets' mean): the torques by the NRMS over
        the torque limits (or the relative RMS error without limits), and rollouts
        (:func:`~._rollouts.rollout_errors`)."""
        from .._metrics import validation_metrics
        from ._rollouts import LENGTHS, rollout_errors

        measure = ("nrms_limits_percent" if limits is not None
                   else "relative_rms_percent_overall")
        rows, rollouts = [], {}
        for name, d in recordings.items():
            own = ident.predict(d.q, d.qd, d.qdd)
            written = mujoco_torques(xml, d.q, d.qd, d.qdd)
            rollouts[name] = rollout_errors(ident, d, xml, LENGTHS)
            medians = rollouts[name].medians()
            rows.append({"data": name,
                         "own": float(validation_metrics(d.tau, own, limits)[measure]),
                         "mujoco": float(validation_metrics(d.tau, written, limits)[measure]),
                         "rollouts_own": medians["own"],
                         "rollouts_mujoco": medians["mujoco"]})
        return cls(measure, LENGTHS, tuple(rows),
                   simulated(ident.model, ident.values).left_out, rollouts)

    def lines(self) -> list[str]:
        """The report's section."""
        from ..._output import columns_note, markdown_table

        lengths = [f"{x:g} s" for x in self.lengths]
        table = markdown_table(
            ["data", "own [%]", "MuJoCo [%]", "MuJoCo / own",
             *(f"rollout {x} own [deg]" for x in lengths),
             *(f"rollout {x} MuJoCo [deg]" for x in lengths)],
            [[r["data"], f"{r['own']:.4f}", f"{r['mujoco']:.4f}",
              f"{r['mujoco'] / r['own']:.3f}", *(f"{e:.3g}" for e in r["rollouts_own"]),
              *(f"{e:.3g}" for e in r["rollouts_mujoco"])] for r in self.rows])
        return ["", "the identified model simulated, and written as MJCF for MuJoCo:", "",
                table, "", columns_note(
                    ("own [%]", f"the package's model's torque error (`{self.measure}`)"),
                    ("MuJoCo [%]", "the written MJCF's, from MuJoCo's inverse dynamics "
                     "(`mj_inverse`)"),
                    ([*(f"rollout {x} own [deg]" for x in lengths),
                      *(f"rollout {x} MuJoCo [deg]" for x in lengths)], "open-loop rollouts from measured states driven by the "
                     "measured torques: the median over windows and joints of the position "
                     "error after that time (own: the package's model in JAX, linearly "
                     "implicit Euler in steps of at most 1 ms; MuJoCo: the MJCF, its "
                     "integrator; `inf`: most windows diverged)")),
                "", "left out (MuJoCo has no parameter for it): "
                + ("; ".join(self.left_out) if self.left_out else "nothing")]

    def as_dict(self) -> dict:
        return {"measure": self.measure, "rollout_lengths_s": list(self.lengths),
                "left_out": list(self.left_out), "rows": list(self.rows)}


def held_frictions(frictions):
    """The candidate term sets (each a tuple of terms) with only the terms a simulator
    holds in full (:attr:`~.._model._term.AbstractTerm.held_in_full`), each set once: the
    candidates of a model made to be written for MuJoCo (a smooth Coulomb becomes
    MuJoCo's dry friction, a load friction is dropped)."""
    kept: dict[str, tuple] = {}
    for terms in frictions:
        held = tuple(t for t in terms if t.held_in_full)
        kept.setdefault("+".join(t.text for t in held), held)
    return tuple(kept.values())
