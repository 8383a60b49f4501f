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
    (``armature``, ``offset``, ``frictionloss``, dry friction beyond the links' Coulomb
    friction, each ``(n,)``) and what it cannot hold: ``left_out`` a line per term or part
    of a term (its ``--friction`` word, then what)."""

    armature: np.ndarray
    offset: np.ndarray
    frictionloss: np.ndarray
    left_out: tuple[str, ...]


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
    armature, offset, frictionloss, left_out = np.zeros(n), np.zeros(n), np.zeros(n), []
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
        if held.frictionloss is not None:
            frictionloss = frictionloss + held.frictionloss
        if held.lost:
            left_out.append(f"{term.text}: {held.lost}")
    return Simulated(armature, offset, frictionloss, tuple(left_out))


def mujoco_torques(xml: str, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray
                   ) -> np.ndarray:
    """The joint torques ``(T, n)`` as measured (each actuator's ``ctrl``) that MuJoCo's
    inverse dynamics (``mj_inverse``) gives for the MJCF ``xml`` at the states ``(T, n)``:
    a chain of ``n`` joints, each driven by one actuator of fixed gain whose bias is a
    constant, as :func:`~sedsabso_jax.dynamics.to_mjcf` writes it (a ValueError
    otherwise)."""
    mujoco = import_mujoco()
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    q, qd, qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
    constant = (np.all(m.actuator_gaintype == mujoco.mjtGain.mjGAIN_FIXED)
                and np.all(m.actuator_biasprm[:, 1:3] == 0.0)
                and np.all(m.actuator_trntype == mujoco.mjtTrn.mjTRN_JOINT))
    if (q.ndim != 2 or m.nq != q.shape[1] or m.nv != m.nq or m.nu != m.nv or not constant
            or sorted(m.actuator_trnid[:, 0]) != list(range(m.njnt))):
        raise ValueError(f"mujoco_torques reads a chain of {q.shape[-1]} hinge or slide "
                         f"joints each driven by one actuator of fixed gain and constant "
                         f"bias (as to_mjcf writes); this MJCF has {m.nq} positions, "
                         f"{m.nv} velocities and {m.nu} actuators")
    dof = m.jnt_dofadr[m.actuator_trnid[:, 0]]
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
