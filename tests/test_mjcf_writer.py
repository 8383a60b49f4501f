"""MJCF out: the identified robot as a MuJoCo model that MuJoCo loads as written, whose
inverse dynamics (MuJoCo's own, ``mj_inverse``) are the package's: the links, armature,
viscous friction, the torque offset in the actuators' bias, and dry friction that acts as
Coulomb's once the joint slides."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from conftest import random_dh

import sedsabso_jax as sj
from sedsabso_jax import cli
from sedsabso_jax.dynamics._mjcf_writer import to_mjcf
from sedsabso_jax.identification._default._policy import DEFAULT
from sedsabso_jax.identification._fit._simulator import held_frictions, mujoco_torques

mujoco = pytest.importorskip("mujoco")


def _robot(rng, n=4, friction=True):
    t, params = random_dh(rng, n, prismatic_prob=0.3)
    if not friction:
        params[10::12] = 0.0
    return sj.robots.from_dh(t["d"], t["a"], t["alpha"], t["theta"], prismatic=t["prismatic"],
                             params=params, gravity=9.81 * np.array([0.3, -0.2, -0.93]))


def test_written_model_has_the_package_dynamics(rng):
    """Links (standard DH: axes off the link origins, prismatic joints), armature, damping
    and the offset through the actuators: MuJoCo's inverse dynamics and its actuator
    force are the package's to 1e-9 of the largest torque."""
    robot = _robot(rng, friction=False)
    armature, offset = rng.uniform(0.0, 0.5, 4), rng.normal(size=4)
    xml = to_mjcf(robot, armature=armature, offset=offset)
    q, qd, qdd = rng.uniform(-2, 2, (3, 10, 4))
    ours = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd)) + armature * qdd
    measured = mujoco_torques(xml, q, qd, qdd)  # ctrl: the torque as a sensor reads it
    scale = np.abs(ours).max()
    np.testing.assert_allclose(measured, ours + offset, atol=1e-9 * scale)
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    d.ctrl[:] = ours[0] + offset
    mujoco.mj_forward(m, d)
    np.testing.assert_allclose(d.qfrc_actuator, ours[0], atol=1e-12 * scale)
    assert m.nu == 4 and list(m.actuator_trntype) == [mujoco.mjtTrn.mjTRN_JOINT] * 4


def test_written_model_reads_back(rng, tmp_path):
    """The package's MJCF reader (MuJoCo's compiled model) gives back the written chain:
    torques, friction and armature."""
    robot = _robot(rng)
    armature = rng.uniform(0.0, 0.5, 4)
    path = tmp_path / "r.xml"
    path.write_text(to_mjcf(robot, armature=armature))
    with pytest.warns(UserWarning, match="armature"):
        back = sj.robots.from_mjcf(path)
    q, qd, qdd = rng.uniform(-2, 2, (3, 10, 4))
    ours = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    np.testing.assert_allclose(np.asarray(sj.inverse_dynamics(back, back.params, q, qd, qdd)),
                               ours, atol=1e-9 * np.abs(ours).max())
    np.testing.assert_allclose(sj.robots.armature_from_mjcf(path, back), armature, atol=1e-15)


def test_dry_friction_is_coulomb_once_sliding(rng):
    """MuJoCo's frictionloss is a soft constraint; the writer's impedance makes its torque
    ``Fc sign(qd)`` (to 1 %) once a joint moves at 0.05 rad/s or more, on a chain whose
    first joint turns an arm stretched along its axis (a large inverse weight at qpos0,
    where MuJoCo's default impedance leaves most of the friction out)."""
    robot = sj.robots.kuka_lwr4()
    p = np.asarray(robot.params).copy()
    p[11::12] = 0.0
    p[10::12] = 0.5
    xml = to_mjcf(robot, p)
    q = rng.uniform(-1, 1, (200, 7))
    qd = rng.choice([-1, 1], (200, 7)) * rng.uniform(0.05, 2.0, (200, 7))
    qdd = rng.normal(size=(200, 7))
    friction = mujoco_torques(xml, q, qd, qdd) - mujoco_torques(
        xml.replace('frictionloss="0.5"', 'frictionloss="0.0"'), q, qd, qdd)
    np.testing.assert_allclose(friction, 0.5 * np.sign(qd), rtol=0.01)


def test_bad_inputs_are_refused(rng):
    robot = _robot(rng)
    with pytest.raises(ValueError, match="physically consistent link parameters"):
        to_mjcf(sj.robots.rs010n())  # Table 2: Ixx2 = -10.02
    with pytest.raises(ValueError, match="armature must be 4 finite numbers"):
        to_mjcf(robot, armature=[1.0, 2.0])
    with pytest.raises(ValueError, match="armature must be >= 0"):
        to_mjcf(robot, armature=[0.1, -0.1, 0.0, 0.0])
    with pytest.raises(ValueError, match="integrator must be one of"):
        to_mjcf(robot, integrator="rk4")


def test_identified_model_and_what_is_left_out(rng):
    """An identification with offsets and armature (held) and Coulomb friction under load
    (not held): the MJCF's torques in MuJoCo are the fit's without the load friction;
    the file names what is left out with its values."""
    robot = _robot(rng, n=3)
    q = rng.uniform(-2, 2, (400, 3))
    qd = rng.choice([-1, 1], (400, 3)) * rng.uniform(0.2, 2.0, (400, 3))
    qdd = rng.normal(size=(400, 3))
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd)) \
        + [0.3, -0.2, 0.1] + 0.05 * qdd
    data = sj.Measurements(np.arange(400) / 100.0, q, qd, qdd, tau)
    terms = (sj.Offset(), sj.Armature(), sj.LoadFriction())
    with warnings.catch_warnings():  # a first joint's armature is in the base: regrouped
        warnings.filterwarnings("ignore", "identify: IA1 cannot be identified")
        fit = sj.identify(robot, data, sj.PhysicallyConsistent(sj.OLS()),
                          sj.TorqueModel.of(robot, terms))
    xml = fit.mjcf()
    assert "left out" in xml and "load (FL1 = " in xml
    names, values = list(fit.names), np.asarray(fit.values)
    load = [names.index(f"FL{j}") for j in (1, 2, 3)]
    without_load = np.where(np.isin(np.arange(len(values)), load), 0.0, values)
    expected = fit.model.predict(without_load, q, qd, qdd)
    np.testing.assert_allclose(mujoco_torques(xml, q, qd, qdd), expected,
                               atol=0.01 * np.abs(expected).max())
    m = mujoco.MjModel.from_xml_string(xml)
    np.testing.assert_allclose(m.actuator_biasprm[:, 0],
                               -values[[names.index(f"OFF{j}") for j in (1, 2, 3)]])
    assert np.all(m.dof_armature >= 0)


def test_mujoco_candidates_hold_every_term():
    """--mujoco-terms: the default's candidates with only the terms MuJoCo holds, each
    once (a smooth Coulomb is MuJoCo's dry friction, a load friction is dropped)."""
    texts = ["+".join(t.text for t in terms) for terms in held_frictions(DEFAULT.frictions)]
    assert texts == ["", "offset", "offset+armature"]


def test_identify_mjcf_out(tmp_path, capsys):
    """`identify --mjcf-out`: a physically consistent fit written as MJCF that MuJoCo
    loads, the report's MuJoCo section (its error beside the package's own) in the text
    and the JSON; --no-physical contradicts it."""
    m = sj.load_kuka_lwr4(1).slice(0, 1500)
    data = m.save(tmp_path / "m.npz")
    out, js = tmp_path / "out" / "kuka.xml", tmp_path / "r.json"
    argv = ["identify", "--robot", "kuka_lwr4", "--data", str(data), "--method", "OLS",
            "--weights", "equal", "--friction", "viscous-coulomb+offset", "--folds", "0",
            "--mjcf-out", str(out), "--json", str(js)]
    assert cli.main(argv) == 0
    text = capsys.readouterr().out
    assert "written as MJCF for MuJoCo" in text and "left out (MuJoCo has no parameter " \
        "for it): nothing" in text
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.nu == 7 and model.opt.timestep == pytest.approx(1 / m.rate)
    row, = json.loads(js.read_text())["mujoco"]["rows"]
    assert row["mujoco"] == pytest.approx(row["own"], rel=0.01)
    assert len(row["rollouts_own"]) == len(row["rollouts_mujoco"]) == 2
    out.unlink()
    assert cli.main([*argv, "--no-physical"]) == 2
    assert "--mjcf-out needs physically consistent" in capsys.readouterr().err
    assert not out.exists()


def test_rollouts_of_an_exact_fit_follow_the_recording(rng):
    """A recording simulated from a known chain (RK4, torques held over each 5 ms
    sample, a sensor offset added), identified exactly: the fit's open-loop rollouts, in
    JAX and in MuJoCo on its MJCF, follow the recording (the integrators' error only)."""
    from sedsabso_jax.dynamics import forward_dynamics, rollout
    from sedsabso_jax.identification._fit._rollouts import rollout_errors

    robot = _robot(rng, n=3, friction=False)
    dt, T = 0.005, 600
    t = np.arange(T) * dt
    tau = np.stack([np.sin(2 * np.pi * f * t + p) for f, p in
                    zip((0.7, 1.1, 1.6), rng.uniform(0, 6, 3))], -1) * [20.0, 10.0, 5.0]
    gravity = np.asarray(sj.inverse_dynamics(robot, robot.params, np.zeros((1, 3)),
                                             np.zeros((1, 3)), np.zeros((1, 3))))[0]
    tau = tau + gravity  # about the hanging pose
    q, qd = (np.asarray(a) for a in rollout(robot, None, np.zeros(3), np.zeros(3),
                                             tau[:-1], dt, substeps=8))
    qdd = np.asarray(forward_dynamics(robot, None, q, qd, tau))
    offset = np.array([0.4, -0.3, 0.2])
    data = sj.Measurements(t, q, qd, qdd, tau + offset)
    fit = sj.identify(robot, data, sj.PhysicallyConsistent(sj.OLS()),
                      sj.TorqueModel.of(robot, (sj.Offset(),)))
    errors = rollout_errors(fit, data, fit.mjcf(timestep=dt, integrator="RK4"))
    own, theirs = errors.medians()["own"], errors.medians()["mujoco"]
    assert max(own) < 0.1 and max(theirs) < 0.1, (own, theirs)


def test_friction_at_rest_is_held_as_dry_friction(rng):
    """Friction at rest (Dahl's presliding) saturates at FP in steady sliding: the MJCF's
    frictionloss is FC + FP, and its gradual build-up after a reversal is named as lost."""
    robot = _robot(rng, n=2)
    q = np.cumsum(rng.normal(size=(300, 2)), 0) * 0.02
    qd = np.gradient(q, 0.01, axis=0)
    qdd = rng.normal(size=(300, 2))
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    data = sj.Measurements(np.arange(300) / 100.0, q, qd, qdd, tau + 0.3 * np.sign(qd))
    fit = sj.identify(robot, data, sj.PhysicallyConsistent(sj.OLS()),
                      sj.TorqueModel.of(robot, (sj.Presliding(),)))
    names, values = list(fit.names), np.asarray(fit.values)
    fp = values[[names.index("FP1"), names.index("FP2")]]
    assert np.all(fp > 0)
    xml = fit.mjcf()
    m = mujoco.MjModel.from_xml_string(xml)
    fc = np.asarray(fit.full_params).reshape(-1, 12)[:, 10]
    np.testing.assert_allclose(m.dof_frictionloss, fc + fp, rtol=1e-12)
    assert "presliding" in xml and "gradual build-up" in xml


def test_identified_into_the_users_mjcf(rng, tmp_path):
    """``mjcf(source)``: the user's MJCF (read with from_mjcf) with the identified links
    and joint friction written into it, its actuators kept (so the offsets are named, not
    written): read back, it is the fit."""
    from conftest import random_mjcf

    path = tmp_path / "arm.xml"
    path.write_text(random_mjcf(rng, 3, damping=True, gravity=[0, 0, -9.81]))
    robot = sj.robots.from_mjcf(path)
    q, qd, qdd = rng.uniform(-2, 2, (3, 300, 3))
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd)) + [0.3, 0, -0.2]
    data = sj.Measurements(np.arange(300) / 100.0, q, qd, qdd, tau)
    fit = sj.identify(robot, data, sj.PhysicallyConsistent(sj.OLS()),
                      sj.TorqueModel.of(robot, (sj.Offset(),)))
    out = tmp_path / "arm_identified.xml"
    out.write_text(fit.mjcf(path))
    text = out.read_text()
    assert "the file's own actuators are kept (OFF = 0.3" in text
    assert text.count("<motor") == 3  # the user's actuators
    back = sj.robots.from_mjcf(out)
    np.testing.assert_allclose(np.asarray(back.params), fit.full_params,
                               atol=1e-9 * np.abs(fit.full_params).max())


def test_mujoco_torques_refuses_other_actuators(rng):
    """A position servo's force depends on the state: its ctrl is no measured torque."""
    robot = _robot(rng, n=2)
    xml = to_mjcf(robot).replace('biasprm="-0.0 0 0"', 'biasprm="0 -10 0"', 1)
    q = np.zeros((1, 2))
    with pytest.raises(ValueError, match="each driven by one actuator of fixed gain"):
        mujoco_torques(xml, q, q, q)


def test_the_report_sets_the_choice_made_for_mujoco_beside(tmp_path, capsys):
    """`identify --mjcf-out` with the friction left to the validation: the choice is
    written and, beside it in the report, the choice among the terms MuJoCo holds, each
    judged in MuJoCo."""
    data = sj.load_kuka_lwr4(1).slice(0, 800).save(tmp_path / "m.npz")
    out, js = tmp_path / "kuka.xml", tmp_path / "r.json"
    assert cli.main(["identify", "--robot", "kuka_lwr4", "--data", str(data), "--method",
                     "OLS", "--weights", "equal", "--validation", "phase", "--folds", "2",
                     "--mjcf-out", str(out), "--json", str(js)]) == 0
    assert "beside it, the choice among the terms MuJoCo holds" in capsys.readouterr().out
    doc = json.loads(js.read_text())["mujoco"]
    made = doc["made_for_mujoco"]
    assert made["left_out"] == [] and made["friction"] in (
        "viscous-coulomb", "viscous-coulomb+offset", "viscous-coulomb+offset+armature")
    assert made["rows"][0]["mujoco"] == pytest.approx(made["rows"][0]["own"], rel=0.02)
    assert doc["friction"] in out.read_text()


def test_mujoco_terms_refuses_a_friction_it_cannot_hold(tmp_path, capsys):
    data = sj.load_kuka_lwr4(1).slice(0, 200).save(tmp_path / "m.npz")
    assert cli.main(["identify", "--robot", "kuka_lwr4", "--data", str(data),
                     "--friction", "viscous-coulomb+load", "--mujoco-terms"]) == 2
    assert "--mujoco-terms: --friction viscous-coulomb+load has terms MuJoCo cannot " \
        "hold" in capsys.readouterr().err
