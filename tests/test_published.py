"""Published models of the real robots in ``data/`` (``benchmarks/published.py``): Gaz et
al.'s Panda parameters as published, in the frames their own gravity vector confirms, and
this package's motor-side TX40 terms in FIGAROH's joint-side convention."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.identification._model._torque_model import TorqueModel

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
import published  # noqa: E402  (the repository's benchmarks folder, not the package)

#: Gaz et al. 2019, supplementary material: link masses [kg], links 1..7.
GAZ_MASSES = [4.970684, 0.646926, 3.228604, 3.587895, 1.225946, 1.666555, 0.735522]
READY = np.array([0.0, -np.pi / 4, 0.0, -3 * np.pi / 4, 0.0, np.pi / 2, np.pi / 4])


@pytest.fixture(scope="module")
def gaz():
    return published.load_gaz()


def _mdh_gravity(doc, q, g0=9.80665):
    """Gravity torques written out independently of the package: Craig's modified-DH
    transforms multiplied by hand, ``tau_j = -sum_{k>=j} m_k z_j . ((c_k - o_j) x g)``."""
    alpha = [0, -np.pi / 2, np.pi / 2, np.pi / 2, -np.pi / 2, np.pi / 2, np.pi / 2]
    a = [0, 0, 0, 0.0825, -0.0825, 0, 0.088]
    d = [0.333, 0, 0.316, 0, 0.384, 0, 0]
    g = np.array([0.0, 0.0, -g0])
    T, origins, axes, coms = np.eye(4), [], [], []
    for i in range(7):
        ca, sa, ct, st = np.cos(alpha[i]), np.sin(alpha[i]), np.cos(q[i]), np.sin(q[i])
        T = T @ np.array([[ct, -st, 0, a[i]], [st * ca, ct * ca, -sa, -sa * d[i]],
                          [st * sa, ct * sa, ca, ca * d[i]], [0, 0, 0, 1]])
        origins.append(T[:3, 3])
        axes.append(T[:3, 2])
        coms.append(T[:3, :3] @ np.asarray(doc["links"]["com_m"][i]) + T[:3, 3])
    m = doc["links"]["mass_kg"]
    return np.array([-sum(m[k] * axes[j] @ np.cross(coms[k] - origins[j], g)
                          for k in range(j, 7)) for j in range(7)])


def test_gaz_parameters_are_the_published_ones(gaz):
    """The data file holds the paper's masses; the links are physically consistent (their
    method enforces it); the inertia is read about the CoM in the order Ixx Ixy Ixz Iyy
    Iyz Izz: link 7's inertia about its joint axis is Izz + m (cx^2 + cy^2)."""
    assert gaz["links"]["mass_kg"] == GAZ_MASSES
    check = published.gaz_consistency(gaz)
    assert check["consistent"] and min(check["pseudo_inertia_min_eigenvalue"]) > 0
    p7 = published.gaz_params(gaz).reshape(7, 12)[6]
    assert p7[2] == pytest.approx(4.815e-3 + 0.735522 * (0.010517**2 + 0.004252**2), rel=1e-12)
    assert p7[6:10] == pytest.approx(0.735522 * np.array([1, 0.010517, -0.004252, 0.061597]))
    assert published.gaz_friction(gaz, np.zeros(7)) == pytest.approx(np.zeros(7), abs=1e-15)


def test_gaz_gravity_is_independent_and_in_their_frames(gaz, rng):
    """At rest the model's torques are gravity: equal to a hand-written computation, and
    within 0.1 N m of the repository's own closed-form gravity vector (generated from
    slightly different coefficients; a wrong frame convention is off by newtons)."""
    Q = np.vstack([np.zeros(7), READY, rng.uniform(-2.5, 2.5, (5, 7))])
    ours = published.gaz_torques(gaz, Q, np.zeros_like(Q), np.zeros_like(Q))
    independent = np.array([_mdh_gravity(gaz, q) for q in Q])
    np.testing.assert_allclose(ours, independent, atol=1e-9)
    code = gaz["repository_code_model"]
    Qc = np.asarray(code["gravity_configurations_rad"], dtype=float)
    g_code = np.asarray(code["gravity_torques_Nm"])
    tables = published.gaz_torques(gaz, Qc, np.zeros_like(Qc), np.zeros_like(Qc))
    np.testing.assert_allclose(tables, g_code, atol=0.1)
    assert np.abs(tables - g_code).max() > 1e-3  # the two published sets do differ
    swapped = published.gaz_torques(gaz, Qc, np.zeros_like(Qc), np.zeros_like(Qc),
                                    gravity="repository")
    np.testing.assert_allclose(swapped, g_code, atol=1e-9)
    wrong = np.array([_mdh_gravity({"links": {**gaz["links"], "com_m": -np.asarray(
        gaz["links"]["com_m"])}}, q) for q in Qc])  # CoM read in mirrored axes
    assert np.abs(wrong - g_code).max() > 1.0


def test_tx40_terms_in_figaroh_convention(rng):
    """The motor-side armature and coupled-motor friction, converted by figaroh_terms,
    give in FIGAROH's regressor form (fv qd + fs sign(qd) + off + Ia qdd per joint; on
    joints 5 and 6 Iam6 qdd_other + fvm6 qd_other + fsm6 sign(qd5 + qd6)) the torques this
    package's model gives."""
    K = np.diag([32.0, 32.0, 45.0, -48.0, 45.0, 32.0])
    K[5, 4] = 32.0
    model = TorqueModel(sj.base_parameters(sj.robots.staubli_tx40()),
                        (sj.Offset(), sj.Armature(), sj.CoupledMotorFriction()), transmission=K)
    assert model.regrouped == ("IA1", "IA2")
    names = model.names
    terms = [i for i, n in enumerate(names)
             if n.rstrip("0123456789") in ("FV", "FC", "OFF", "IA", "FVM", "FCM")]
    values = np.zeros(len(names))
    values[terms] = rng.uniform(0.01, 1.0, len(terms)) * np.where(
        [names[i].startswith("IA") for i in terms], 1e-4, 1.0)
    q, qd, qdd = rng.standard_normal((3, 20, 6))
    ours = model.regressor(q, qd, qdd) @ values
    t = published.figaroh_terms(names, values, K)
    assert t["Ia"][:2] == [None, None]
    ia = np.array([0.0, 0.0, *t["Ia"][2:]])
    theirs = (np.array(t["fv"]) * qd + np.array(t["fs"]) * np.sign(qd) + np.array(t["offset"])
              + ia * qdd)
    s = np.sign(qd[:, 4] + qd[:, 5])
    theirs[:, 4] += t["Iam6"] * qdd[:, 5] + t["fvm6"] * qd[:, 5] + t["fsm6"] * s
    theirs[:, 5] += t["Iam6"] * qdd[:, 4] + t["fvm6"] * qd[:, 4] + t["fsm6"] * s
    np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=1e-12)
    v = dict(zip(names, values))
    assert t["Ia"][4] == pytest.approx(45**2 * v["IA5"] + 32**2 * v["IA6"])
    assert t["fsm6"] == pytest.approx(32 * v["FCM6"])
