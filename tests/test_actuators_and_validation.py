"""Motor side to joint side, the armature and coupled-motor terms, cross-validation over
the motion's phase, model choice by it, and the two real robots kept in ``data/`` (TX40
motor side with a coupled wrist; Panda) end to end through the command."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax import cli
from sedsabso_jax.identification._model._torque_model import TorqueModel
from sedsabso_jax.identification._validation._phase import phase_folds, repeat_period
from sedsabso_jax.identification._validation._selection import (
    choose_prior_strength,
    cross_validate,
    select_model,
)
from sedsabso_jax.measurements._transmission import Transmission

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "data"))
import real_robots  # noqa: E402  (the repository's data folder, not the package)

TX40_K = np.diag([32.0, 32.0, 45.0, -48.0, 45.0, 32.0])
TX40_K[5, 4] = 32.0


def _status(argv) -> int:
    try:
        return cli.main(argv)
    except SystemExit as exit_:
        return exit_.code


# -------------------------------------------------------------------- transmission
def test_motor_side_conversion_is_the_power_balance(rng):
    """theta = K (q + offset) and tau = K^T tau_m, written out for the TX40's wrist: motor
    6 turns with joints 5 and 6, so joint 5's torque gets motor 6's share."""
    tr = Transmission.from_gear_ratios([32, 32, 45, -48, 45, 32], coupling={(6, 5): 32},
                                       offset=[0, np.pi / 2, -np.pi / 2, 0, 0, 0])
    np.testing.assert_array_equal(tr.matrix, TX40_K)
    assert tr.coupled_motors == (5,)
    T = 50
    q, qd, qdd = rng.standard_normal((3, T, 6))
    tau = rng.standard_normal((T, 6))
    theta = (q + tr.offset) @ TX40_K.T
    tau_m = np.linalg.solve(TX40_K.T, tau.T).T  # what the motors deliver for tau
    motor = sj.Measurements(np.arange(T) / 100.0, theta, qd @ TX40_K.T, qdd @ TX40_K.T, tau_m)
    joint = tr.to_joint_side(motor)
    np.testing.assert_allclose(joint.q, q, atol=1e-12)
    np.testing.assert_allclose(joint.qd, qd, atol=1e-12)
    np.testing.assert_allclose(joint.tau, tau, atol=1e-12)
    assert joint.tau[0, 4] == pytest.approx(45 * tau_m[0, 4] + 32 * tau_m[0, 5])
    power_m = np.sum(tau_m * (qd @ TX40_K.T), axis=1)
    np.testing.assert_allclose(np.sum(joint.tau * joint.qd, axis=1), power_m, atol=1e-9)
    gains = Transmission(TX40_K, np.zeros(6), drive_gains=np.full(6, 0.5)).to_joint_side(
        motor)
    np.testing.assert_allclose(gains.tau, 0.5 * tau, atol=1e-12)


@pytest.mark.parametrize("make, match", [
    (lambda: Transmission.from_gear_ratios([32, 0, 45]), "finite and non-zero"),
    (lambda: Transmission.from_gear_ratios([1, 1], coupling={(2, 2): 3}),
     "a motor and another joint"),
    (lambda: Transmission.from_gear_ratios([1, 1], coupling={(3, 1): 3}), r"numbered 1\.\.2"),
    (lambda: Transmission(np.ones((2, 2)), np.zeros(2)), "singular"),
    (lambda: Transmission(np.eye(3)[:2], np.zeros(3)), r"square matrix"),
    (lambda: Transmission(np.eye(3), np.zeros(2)), "offset must have 3 entries"),
    (lambda: Transmission(np.eye(3), np.zeros(3), drive_gains=[1, 2]),
     "drive gains must have 3 entries"),
    (lambda: Transmission(np.eye(2), np.zeros(2), drive_gains=[1, 0]), "non-zero"),
])
def test_bad_transmission(make, match):
    with pytest.raises(ValueError, match=match):
        make()


# ------------------------------------------------------------- armature and coupling
def test_armature_and_coupling_columns(rng):
    """IA_m: column K_m^T (K_m . qdd); FVM_m, FCM_m for a coupled motor: K_m^T (K_m . qd)
    and K_m^T sign(K_m . qd); an armature the base regressor already spans is dropped and
    named: joint 1 turns about the fixed vertical axis (IA1 acts like ZZ1), and joint 2's
    axis is perpendicular to it (IA2 acts like ZZ2: Khalil & Dombre 2002, Sec. 10.3)."""
    robot = sj.robots.from_mdh([0, -np.pi / 2, np.pi / 2], [0, 0.3, 0.1], [0.2, 0, 0.1])
    base = sj.base_parameters(robot)
    K = np.diag([10.0, 20.0, 30.0])
    K[2, 1] = 30.0  # motor 3 turns with joints 2 and 3
    model = TorqueModel(base, (sj.Armature(), sj.CoupledMotorFriction()), transmission=K)
    assert model.regrouped == ("IA1", "IA2")
    assert model.names[base.rank:] == ("IA3", "FVM3", "FCM3")
    assert list(model.nonnegative[base.rank:]) == [True] * 3
    q, qd, qdd = rng.standard_normal((3, 4, 3))
    Y = model.regressor(q, qd, qdd)[..., base.rank:]
    for t in range(4):
        u3 = K[2] @ qdd[t]
        np.testing.assert_allclose(Y[t, :, 0], K[2] * u3)  # IA3
        np.testing.assert_allclose(Y[t, :, 1], K[2] * (K[2] @ qd[t]))  # FVM3
        np.testing.assert_allclose(Y[t, :, 2], K[2] * np.sign(K[2] @ qd[t]))  # FCM3
    with pytest.raises(ValueError, match="'coupling' needs a transmission"):
        TorqueModel(base, (sj.CoupledMotorFriction(),))
    with pytest.raises(ValueError, match=r"transmission must be a finite \(3, 3\)"):
        TorqueModel(base, (sj.Armature(),), transmission=np.eye(2))


def test_armature_is_identified_from_simulated_data(rng):
    """Torques of a 3-joint arm plus a known rotor inertia behind gear ratios: the
    identified IA3 is the simulated one (noise-free), and the warning names IA1, IA2."""
    robot = sj.robots.from_mdh([0, -np.pi / 2, np.pi / 2], [0, 0.3, 0.1], [0.2, 0, 0.1])
    from conftest import random_dh

    _, params = random_dh(rng, 3, prismatic_prob=0.0)
    robot = robot.with_params(params)
    K = np.diag([50.0, 80.0, 60.0])
    Ia = np.array([0.0, 0.0, 3e-4])  # IA1, IA2 would regroup with ZZ1, ZZ2: leave them 0
    T = 400
    q, qd, qdd = rng.uniform(-2, 2, (T, 3)), rng.standard_normal((T, 3)), \
        rng.standard_normal((T, 3))
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    tau = tau + (qdd @ K.T * Ia) @ K  # K^T diag(Ia) K qdd
    with pytest.warns(UserWarning, match="IA1, IA2 cannot be identified apart"):
        ident = sj.identify(robot, (q, qd, qdd, tau), sj.OLS(),
                            sj.TorqueModel.of(robot, [sj.Armature()], transmission=K))
    values = dict(zip(ident.names, ident.values))
    assert values["IA3"] == pytest.approx(3e-4, rel=1e-6)
    # the full model (all columns) predicts the torques exactly
    np.testing.assert_allclose(ident.predict(q, qd, qdd), tau, atol=1e-8)


# ------------------------------------------------------------------ cross-validation
def test_phase_folds_follow_the_repeat_period():
    t = np.arange(3000) / 100.0  # 30 s
    q = np.column_stack([np.sin(2 * np.pi * t / 12.0), np.cos(4 * np.pi * t / 12.0)])
    assert repeat_period(t, q) == pytest.approx(12.0, abs=0.02)
    labels, period = phase_folds(t, q, 4)
    assert period == pytest.approx(12.0, abs=0.02)
    # the same phase in every period is in the same fold: t and t + 12 s
    for i in (0, 450, 1000):
        assert labels[i] == labels[i + 1200]
    assert np.bincount(labels).min() >= 600  # 2.5 periods: 3 or 2 visits of each phase
    chirp = np.column_stack([np.sin(t ** 1.5), t])  # never repeats: contiguous blocks
    labels, period = phase_folds(t, chirp, 3)
    assert period is None and np.all(np.diff(labels) >= 0)
    with pytest.raises(ValueError, match="folds must be an integer >= 2"):
        phase_folds(t, q, 1)


def test_selection_finds_the_torque_offset_and_rejects_extra_terms(rng):
    """Simulated RS010N torques with a constant offset per joint and noise: the offset is
    chosen (cross-validated error far below without it) and the armature and load terms,
    which the data do not contain, are not (one-standard-error rule; every default
    candidate's Coulomb friction is smooth)."""
    robot = sj.robots.rs010n()
    traj = sj.FourierTrajectory(rng.uniform(-0.3, 0.3, (3, 4)), rng.uniform(-0.3, 0.3, (3, 4)),
                                np.zeros(3), wf=2 * np.pi / 10)
    t = np.arange(2000) / 100.0  # two periods
    data = sj.simulate_measurements_along(robot, traj, t, torque_noise=0.01, seed=3)
    tau = data.tau + np.array([5.0, -3.0, 2.0])
    recording = (t, data.q, data.qd, data.qdd, tau)
    sel = select_model(robot, recording, estimators=sj.OLS())
    assert sel.chosen["friction"] == "viscous-coulomb+offset+smooth"
    assert sel.model.friction == "viscous-coulomb+offset+smooth" and sel.estimator == sj.OLS()
    assert sel.cross_validation is dict(
        (s["friction"], cv) for s, cv in sel.candidates)["viscous-coulomb+offset+smooth"]
    scores = {s["friction"]: cv for s, cv in sel.candidates}
    offset, plain = scores["viscous-coulomb+offset+smooth"], scores["viscous-coulomb+smooth"]
    assert offset.score < 0.5 * plain.score
    assert scores["viscous-coulomb+offset+smooth"].period_s == pytest.approx(10.0, abs=0.05)
    cv = cross_validate(robot, recording, sj.OLS(), sel.model, validation=sj.PhaseFolds(5))
    assert cv.score == pytest.approx(scores["viscous-coulomb+offset+smooth"].score)
    assert cv.measure == "relative_rms_percent" and len(cv.fold_scores) == 5
    assert 0.8 < cv.score < 1.5  # about the 1 % noise: the model generalises
    with pytest.raises(ValueError, match="fold labels must be integers"):
        cross_validate(robot, recording, validation=sj.GivenFolds(np.zeros(3, int)))


def _rs010n_run(n, amplitude, noise, seed=1):
    robot = sj.robots.rs010n()
    rng = np.random.default_rng(seed)
    traj = sj.FourierTrajectory(rng.uniform(-amplitude, amplitude, (3, 4)),
                                rng.uniform(-amplitude, amplitude, (3, 4)), np.zeros(3),
                                wf=2 * np.pi / 10)
    t = np.arange(n) * (20.0 / n)  # two periods
    data = sj.simulate_measurements_along(robot, traj, t, torque_noise=noise, seed=3)
    return robot, t, data


def test_prior_strength_follows_what_the_data_can_say():
    """The pull of a physical fit toward the a-priori parameters, chosen by
    cross-validation. 60 noisy samples of a small motion, the robot's parameters (the
    data's source) as prior: the strongest pull predicts the held-out folds best and is
    chosen. Noise that drowns the differences: the strongest pull within one standard
    error, not the lowest. Rich clean data and a prior whose masses are doubled: a
    negligible pull at most, and a strong one several times worse."""
    robot, t, d = _rs010n_run(60, 0.1, 0.1)
    sel = choose_prior_strength(robot, d)
    cv = dict(sel.candidates)
    assert sel.best == sel.chosen == 1.0 and cv[1.0].score < cv[0.0].score
    assert sel.estimator == sj.PhysicallyConsistent(prior_strength=1.0)
    # torque noise (30 %) drowns the differences: every strength is within one standard
    # error of the lowest (1e-3 here), and the rule keeps the strongest pull
    robot, t, d = _rs010n_run(1000, 0.05, 0.3, seed=0)
    sel = choose_prior_strength(robot, d)
    assert sel.best != 1.0 and sel.chosen == 1.0
    robot, t, d = _rs010n_run(1000, 0.3, 0.01, seed=0)
    wrong = np.asarray(robot.params) * np.tile(np.r_[np.ones(6), 2.0, np.ones(5)], 3)
    sel = choose_prior_strength(robot, d, sj.PhysicallyConsistent(prior=wrong))
    cv = dict(sel.candidates)
    assert sel.chosen <= 1e-6 and cv[1.0].score > 5 * cv[sel.chosen].score
    assert sel.as_dict()["candidates"][0]["prior_strength"] == 0.0
    with pytest.raises(ValueError, match=r"^a physically consistent fit is a least-squares "
                                         r"fit: use method 'OLS' or 'WLS', not 'L1'$"):
        choose_prior_strength(robot, d, sj.L1())
    with pytest.raises(ValueError, match="strengths must be numbers >= 0"):
        choose_prior_strength(robot, d, strengths=(0.0, -1.0))


# ------------------------------------------------------------------- real robots
@pytest.fixture(scope="module")
def real_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("real")
    return {"panda": str(real_robots.panda_npz(d / "panda.npz")),
            "tx40": str(real_robots.tx40_npz(d / "tx40.npz"))}


def test_staubli_tx40_end_to_end_motor_side(real_files, tmp_path):
    """The TX40's motor-side run (coupled wrist) identified by the command: the motor
    angles and torques are converted, the coupling adds motor 6's friction, the model is
    chosen by cross-validation. Measured (1 kHz): fit 1.47 %, cross-validated 1.5-1.6 %
    NRMS over the joint torque limits; the raw motor torques carry ripple no rigid-body
    model predicts (relative RMS 15-17 %)."""
    js = tmp_path / "tx40.json"
    argv = ["identify", *real_robots.TX40_FLAGS, "--data", real_files["tx40"],
            "--downsample", "5", "--method", "OLS", "--weights", "equal", "--json", str(js)]
    assert _status(argv) == 0
    doc = json.loads(js.read_text())
    assert doc["settings"]["motor_side"] is True
    assert "FVM6" in doc["base_parameters"]["names"] and "FCM6" in doc["base_parameters"]["names"]
    cv = doc["cross_validation"]
    assert cv["period_s"] is None  # the TX40 run does not repeat: contiguous folds
    assert cv["measure"] == "nrms_limits_percent" and 1.2 < cv["score"] < 2.0
    assert 1.2 < doc["fit"]["nrms_limits_percent"] < 1.8


def test_franka_panda_cross_validated(real_files, tmp_path):
    """The Panda run (irregular time stamps, resampled to 1 kHz; accelerations derived,
    the filter's edges dropped), one torque model and weighting, unconstrained: validated
    over the phase of its 13.3 s trajectory. Measured: 0.331 % NRMS over the torque
    limits."""
    js = tmp_path / "panda.json"
    argv = ["identify", "--robot", "franka_panda", "--data", real_files["panda"],
            "--resample-hz", "1000", "--method", "OLS", "--weights", "equal",
            "--friction", "viscous-coulomb+offset", "--no-physical", "--validation", "phase",
            "--json", str(js)]
    assert _status(argv) == 0
    doc = json.loads(js.read_text())
    cv = doc["cross_validation"]
    assert cv["period_s"] == pytest.approx(13.33, abs=0.1)
    assert cv["score"] == pytest.approx(0.331, rel=0.05)
    assert doc["settings"]["loading"]["data_info"]["trimmed_s"] == pytest.approx(0.2)


@pytest.mark.parametrize("extra, match", [
    (["--motor-side"], "--motor-side needs --gear-ratios"),
    (["--gear-ratios", "32,32"], r"--gear-ratios: expected 3 numbers"),
    (["--gear-ratios", "1,1,1", "--coupling", "3:2"], "--coupling: expected MOTOR:JOINT=RATIO"),
    (["--gear-ratios", "1,1,1", "--coupling", "3:2=1", "--coupling", "2:3=1"], "singular"),
    (["--gear-ratios", "1,1,1", "--drive-gains", "1,2"], r"--drive-gains: expected 3"),
    (["--folds", "0"], "--folds 0 turns validation off"),
])
def test_bad_actuator_arguments(extra, match, tmp_path, capsys):
    robot = sj.robots.rs010n()
    t = np.arange(300) / 50.0
    q = np.column_stack([np.sin(t), np.cos(t), np.sin(2 * t)])
    data = sj.simulate_measurements(robot, q, np.cos(t)[:, None] * np.ones(3),
                                    np.zeros((300, 3)), t).save(tmp_path / "d.npz")
    out = tmp_path / "out"
    status = _status(["identify", "--robot", "rs010n", "--data", str(data), "--out",
                      str(out), *extra])
    err = capsys.readouterr().err
    assert status == 2 and match in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()
