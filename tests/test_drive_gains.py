"""Drive gains from a known payload (``sj.identify_drive_gains``, ``sedsabso-jax
identify-gains``) against the simulation's truth: exact on noise-free currents (joint
side and through a coupled transmission, with the payload's centre of mass known or
not), within their standard deviations on noisy ones where least squares is biased, a
joint the data cannot calibrate reported so; the payload fit's stack with friction that
grows with the load and friction at rest per recording; the gains' file read by
``identify`` and ``identify-payload``; and the command's bad inputs (exit status 2, one
line, nothing written)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from test_cli_usability import _status  # the command's exit status, argparse's included

import sedsabso_jax as sj
from sedsabso_jax.dynamics import params_from_com, pseudo_inertia
from sedsabso_jax.identification import dahl_state

GAINS = np.array([0.3, 1.2, 0.8])
MASS, COM = 10.0, np.array([0.05, 0.02, 0.1])


def _motion(n: int, samples: int, rate: float, seed: int = 0):
    rng = np.random.default_rng(seed)
    traj = sj.FourierTrajectory(rng.uniform(-0.5, 0.5, (n, 4)), rng.uniform(-0.5, 0.5, (n, 4)),
                                rng.uniform(-0.5, 0.5, n), wf=0.6)
    t = np.arange(samples) / rate
    return (t, *(np.asarray(a) for a in traj.sample(t)))


def _plant(robot, link: int):
    payload = params_from_com(MASS, COM, np.diag([0.05, 0.06, 0.04]))
    plant = np.asarray(robot.params).copy()
    plant[12 * link: 12 * link + 10] += payload
    return plant, payload


def _currents(robot, params, motion, gains, noise=0.0, seed=0, extra=None):
    t, q, qd, qdd = motion
    tau = sj.simulate_measurements(robot.with_params(params), q, qd, qdd, t,
                                   torque_noise=noise, seed=seed).tau
    if extra is not None:
        tau = tau + extra(params, q, qd, qdd)
    return sj.Measurements(t, q, qd, qdd, tau / gains)


@pytest.fixture(scope="module")
def rs010n():
    """RS010N runs of currents along one motion without and with a 10 kg payload on
    link3, noise-free."""
    robot = sj.robots.rs010n()
    motion = _motion(3, 400, 20.0)
    plant, payload = _plant(robot, 2)
    runs = [_currents(robot, p, motion, GAINS, seed=s)
            for s, p in ((0, robot.params), (1, plant))]
    return robot, motion, plant, payload, runs


METHODS = [m() for m in sj.identification.GAIN_METHODS.values()]


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_noise_free_gains_and_payload_are_exact(rs010n, method):
    robot, _, _, payload, (unloaded, loaded) = rs010n
    model = sj.TorqueModel.of(robot, sj.Offset())
    found = sj.identify_drive_gains(robot, unloaded, loaded, "link3", MASS, model=model,
                                    method=method)
    np.testing.assert_allclose(found.gains, GAINS, rtol=1e-8)
    np.testing.assert_allclose(found.payload10, payload, rtol=1e-6, atol=1e-8)
    assert found.payload_std10[6] == 0 and np.all(found.calibrated)
    # the robot's model in torque units: the base parameters of the plant
    base = np.asarray(model.base.values)
    np.testing.assert_allclose(found.robot_values[:base.size], base, rtol=1e-6, atol=1e-6)
    doc = json.loads(json.dumps(found.as_dict()))
    assert doc["drive_gains"] == pytest.approx(GAINS.tolist()) and not doc["motor_side"]
    torques = found.apply(loaded)
    np.testing.assert_allclose(torques.tau, loaded.tau * GAINS, rtol=1e-8)


def test_a_known_centre_of_mass_is_held(rs010n):
    robot, _, _, payload, (unloaded, loaded) = rs010n
    found = sj.identify_drive_gains(robot, unloaded, loaded, "link3", MASS, COM,
                                    model=sj.TorqueModel.of(robot, sj.Offset()))
    np.testing.assert_allclose(found.payload10[7:], MASS * COM, rtol=1e-12)
    assert np.all(found.payload_std10[6:] == 0) and np.all(found.payload_std10[:6] > 0)
    np.testing.assert_allclose(found.gains, GAINS, rtol=1e-8)
    assert found.settings["com"] == pytest.approx(COM.tolist())


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_motor_currents_through_a_coupled_transmission(rs010n, method):
    """Currents per motor behind gear ratios and a coupling: the motors' gains."""
    robot, motion, plant, _, _ = rs010n
    K = np.array([[50.0, 0, 0], [0, -80.0, 0], [0, 30.0, 40.0]])
    motor_gains = np.array([0.02, 0.01, 0.03])
    runs = []
    for seed, params in ((0, robot.params), (1, plant)):
        tau = _currents(robot, params, motion, np.ones(3), seed=seed)
        motor = np.linalg.solve(K.T, tau.tau.T).T  # tau = K^T tau_motor
        runs.append(sj.Measurements(tau.times, tau.q, tau.qd, tau.qdd, motor / motor_gains))
    found = sj.identify_drive_gains(robot, *runs, "link3", MASS, transmission=K, method=method,
                                    model=sj.TorqueModel.of(robot, sj.Offset()))
    np.testing.assert_allclose(found.gains, motor_gains, rtol=1e-8)
    assert found.motor_side and found.as_dict()["motor_side"]
    np.testing.assert_allclose(found.apply(runs[1]).tau,
                               _currents(robot, plant, motion, np.ones(3), seed=1).tau,
                               rtol=1e-8, atol=1e-8)


def test_noisy_currents_bias_least_squares_not_the_likelihood():
    """1 % noise in the currents: ordinary least squares pulls some gain toward zero by
    more than 5 of its standard deviations (errors in variables); the maximum likelihood
    stays within 4 of its own on every joint (measured 2.2 at most), its standard
    deviations are finite and small, and its weights are the currents' noise (least
    squares' are the torques')."""
    robot = sj.robots.rs010n()
    motion = _motion(3, 1200, 60.0, seed=2)
    plant, _ = _plant(robot, 2)
    unloaded, loaded = (_currents(robot, p, motion, GAINS, noise=0.01, seed=s)
                        for s, p in ((3, robot.params), (4, plant)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a joint's calibration is poor
        found = {m.name: sj.identify_drive_gains(robot, unloaded, loaded, "link3", MASS,
                                                 method=m, model=sj.TorqueModel.of(
                                                     robot, sj.Offset()))
                 for m in (sj.identification.OrdinaryGains(),
                           sj.identification.LikelihoodGains())}
    z = {m: np.abs(f.gains - GAINS) / f.std for m, f in found.items()}
    assert z["ordinary"].max() > 5, z
    assert z["likelihood"].max() < 4, z
    assert np.all(found["likelihood"].relative_std < 0.02)
    # its weights: each current's noise (1 % of the joint's RMS torque in each run, over
    # its gain), pooled over the two runs
    variance = [(0.01 * np.sqrt(np.mean(_currents(robot, p, motion, np.ones(3)).tau ** 2,
                                        axis=0))) ** 2 for p in (robot.params, plant)]
    noise = np.sqrt(np.mean(variance, axis=0)) / GAINS
    np.testing.assert_allclose(found["likelihood"].settings["solution"]["current_sigma"],
                               noise, rtol=0.1)
    # least squares' rows: Gautier's weights, near the torques' noise (its residual
    # is below the noise where the biased gain fits it: 12 % on joint 3)
    np.testing.assert_allclose(found["ordinary"].settings["solution"]["sigma"],
                               noise * GAINS, rtol=0.2)


def test_the_physical_method_refits_an_inconsistent_payload_of_the_given_mass():
    """5 % noise in the currents and a payload of small inertia: the likelihood's payload
    is no body (its pseudo-inertia has a negative eigenvalue); the physical method's is
    one, at the fits' margin, of the given mass, by Clarabel's solve, with the same
    gains (the method refits only the model's values)."""
    robot = sj.robots.rs010n()
    plant = np.asarray(robot.params).copy()
    plant[24:34] += params_from_com(MASS, COM, np.diag([0.001, 0.002, 0.001]))
    runs = [_currents(robot, p, _motion(3, 400, 20.0), GAINS, noise=0.05, seed=s)
            for s, p in ((0, robot.params), (1, plant))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a joint's calibration is poor
        found = [sj.identify_drive_gains(robot, *runs, "link3", MASS, method=m,
                                         model=sj.TorqueModel.of(robot, sj.Offset()))
                 for m in (sj.identification.LikelihoodGains(),
                           sj.identification.PhysicalGains())]
    smallest = [np.linalg.eigvalsh(pseudo_inertia(f.payload10)).min() for f in found]
    assert smallest[0] < -0.1 and 1e-6 <= smallest[1] < 1.05e-6, smallest
    assert found[1].payload10[6] == MASS
    solved = found[1].settings["solution"]["solver"]
    assert solved["solver"] == "Clarabel (cvxpy)" and solved["status"] == "optimal"
    np.testing.assert_array_equal(found[1].gains, found[0].gains)


def test_a_joint_the_data_cannot_calibrate_is_reported(rs010n):
    """The first joint held still: its gain is not determined: NaN, std inf, a warning
    naming it, null in the JSON, which --drive-gains then refuses."""
    robot, motion, plant, _, _ = rs010n
    t, q, qd, qdd = (a.copy() for a in motion)
    q[:, 0], qd[:, 0], qdd[:, 0] = 0.3, 0.0, 0.0
    runs = [_currents(robot, p, (t, q, qd, qdd), GAINS) for p in (robot.params, plant)]
    with pytest.warns(UserWarning, match=r"do not calibrate joint J1 \(not determined\)"):
        found = sj.identify_drive_gains(robot, *runs, "link3", MASS,
                                        model=sj.TorqueModel.of(robot, sj.Offset()))
    assert np.isnan(found.gains[0]) and np.isinf(found.std[0])
    assert found.calibrated.tolist() == [False, True, True]
    np.testing.assert_allclose(found.gains[1:], GAINS[1:], rtol=1e-8)
    assert found.as_dict()["drive_gains"][0] is None and "not determined" in found.text()
    with pytest.raises(ValueError, match=r"motors \[1\] were not determined"):
        found.apply(runs[0])


def _load_friction(params, q, qd, qdd, robot=sj.robots.rs010n(), share=0.05):
    rigid = np.asarray(params).reshape(-1, 12).copy()
    rigid[:, 10:] = 0.0
    return share * np.abs(np.asarray(sj.inverse_dynamics(robot, rigid.ravel(), q, qd,
                                                         qdd))) * np.sign(qd)


def test_friction_growing_with_the_load_is_fitted_with_the_gains(rs010n):
    """A plant whose Coulomb friction grows with the transmitted torque (5 %), payload
    included: with the load term (two stages) the gains are within 0.3 %, without it
    some gain is off by more than 1 %."""
    robot, motion, plant, _, _ = rs010n
    runs = [_currents(robot, p, motion, GAINS, extra=_load_friction)
            for p in (robot.params, plant)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        err = {load: np.abs(sj.identify_drive_gains(
            robot, *runs, "link3", MASS, model=sj.TorqueModel.of(
                robot, (sj.Offset(), *([sj.LoadFriction()] if load else [])))).gains / GAINS
            - 1) for load in (True, False)}
    assert err[True].max() < 3e-3 and err[False].max() > 1e-2, err


@pytest.mark.parametrize("term", ["load", "presliding"])
def test_payload_fit_reads_its_own_torque_and_restarts_its_state(rs010n, term):
    """identify_payload on the identification's stack: friction that grows with the
    load reads the payload's torque (a payload after the load term in the model: the
    first stage's values read by name), and Dahl's state starts again in each recording;
    noise-free plants of each, their mass within 0.3 % (load, two stages) and 1e-6."""
    robot, motion, plant, _, _ = rs010n
    q_c = 0.01
    if term == "load":
        # two stages: the load read off a fit without the term: 0.11 % off, noise-free
        extra, terms, tol = _load_friction, (sj.Offset(), sj.LoadFriction()), 3e-3
    else:
        def extra(params, q, qd, qdd):
            z = np.asarray(dahl_state(np.diff(q, axis=0, prepend=q[:1]),
                                      np.arange(len(q)) == 0, np.full(3, q_c)))
            return 2.0 * z
        terms, tol = (sj.Offset(), sj.Presliding(q_c)), 1e-6
    unloaded, loaded = (_currents(robot, p, motion, np.ones(3), extra=extra)
                        for p in (robot.params, plant))
    found = sj.identify_payload(robot, loaded, "link3", unloaded=unloaded, estimator=sj.WLS(),
                                model=sj.TorqueModel.of(robot, terms))
    assert found.mass == pytest.approx(MASS, rel=tol)


def test_bad_arguments(rs010n):
    robot, _, _, _, (unloaded, loaded) = rs010n
    cases = [({"mass": 0.0}, "mass must be positive"), ({"mass": float("nan")}, "mass must"),
             ({"com": [0.1, 0.2]}, "com must be 3"),
             ({"unloaded": []}, "unloaded recordings are needed"),
             ({"link": "link1"}, "do not excite the payload's mass"),
             ({"model": sj.TorqueModel.of(robot, sj.Presliding(fitted=True))},
              "parameters to search")]
    for change, match in cases:
        kw = {"unloaded": unloaded, "loaded": loaded, "link": "link3", "mass": MASS,
              **change}
        with pytest.raises(ValueError, match=match):
            sj.identify_drive_gains(robot, kw.pop("unloaded"), kw.pop("loaded"),
                                    kw.pop("link"), kw.pop("mass"), **kw)
    with pytest.raises(TypeError, match="method must be a drive gains' method"):
        sj.identify_drive_gains(robot, unloaded, loaded, "link3", MASS, method="likelihood")


# ------------------------------------------------------------------------ the command
@pytest.fixture(scope="module")
def files(rs010n, tmp_path_factory):
    robot, motion, plant, _, (unloaded, loaded) = rs010n
    d = tmp_path_factory.mktemp("gains")
    noisy = [_currents(robot, p, motion, GAINS, noise=0.002, seed=s)
             for s, p in ((5, robot.params), (6, plant))]
    two = sj.Measurements(loaded.times, loaded.q[:, :2], loaded.qd[:, :2], loaded.qdd[:, :2],
                          loaded.tau[:, :2])
    torques = _currents(robot, plant, motion, np.ones(3), seed=7)
    return {name: str(m.save(d / f"{name}.npz")) for name, m in
            (("unloaded", noisy[0]), ("loaded", noisy[1]), ("two", two),
             ("torques", torques))}


def test_command_writes_gains_that_identify_payload_reads(files, tmp_path, capsys):
    out = tmp_path / "sub" / "gains.json"
    assert _status(["identify-gains", "--robot", "rs010n", "--data", files["unloaded"],
                    "--loaded", files["loaded"], "--link", "link3", "--mass", str(MASS),
                    "--com", ",".join(map(str, COM)), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    np.testing.assert_allclose(doc["drive_gains"], GAINS, rtol=5e-3)
    assert doc["method"] == "likelihood" and len(doc["drive_gains_std"]) == 3
    assert doc["command"]["mass"] == MASS and doc["settings"]["friction"].endswith("+load")
    text = capsys.readouterr().out
    assert "| joint " in text and text.endswith(f"written: {out}\n")
    payload = tmp_path / "payload.json"
    assert _status(["identify-payload", "--robot", "rs010n", "--data", files["unloaded"],
                    "--loaded", files["loaded"], "--link", "link3", "--drive-gains",
                    str(out), "--json", str(payload)]) == 0
    found = json.loads(payload.read_text())["payload"]
    assert found["mass"] == pytest.approx(MASS, rel=5e-3)
    # the gains as numbers on the command line, the same torques
    again = tmp_path / "again.json"
    numbers = ",".join(repr(g) for g in doc["drive_gains"])
    assert _status(["identify-payload", "--robot", "rs010n", "--data", files["unloaded"],
                    "--loaded", files["loaded"], "--link", "link3", "--drive-gains",
                    numbers, "--json", str(again)]) == 0
    assert json.loads(again.read_text())["payload"]["mass"] == pytest.approx(found["mass"],
                                                                           rel=1e-12)


def test_identify_reads_the_gains_file(files, tmp_path, capsys):
    """``identify --drive-gains FILE.json``: the torque columns times the gains; a file of
    motor-side gains needs --motor-side; a gain not determined is refused."""
    gains = tmp_path / "gains.json"
    gains.write_text(json.dumps({"drive_gains": GAINS.tolist(), "motor_side": False}))
    out = tmp_path / "out"
    argv = ["identify", "--robot", "rs010n", "--data", files["unloaded"], "--method", "OLS",
            "--weights", "equal", "--friction", "viscous-coulomb", "--no-physical",
            "--folds", "0", "--json", str(out / "r.json")]
    assert _status([*argv, "--drive-gains", str(gains)]) == 0
    doc = json.loads((out / "r.json").read_text())
    assert doc["settings"]["loading"]["drive_gains"] == GAINS.tolist()
    m = sj.load_measurements(files["unloaded"])
    fit = sj.identify(sj.robots.rs010n(),
                      sj.Measurements(m.times, m.q, m.qd, m.qdd, m.tau * GAINS))
    np.testing.assert_allclose(doc["base_parameters"]["values"], fit.values, rtol=1e-9,
                               atol=1e-9)
    capsys.readouterr()
    for content, match in (({"drive_gains": GAINS.tolist(), "motor_side": True},
                            "give --motor-side"),
                           ({"drive_gains": [None, 1.0, 1.0]}, "joints 1 were not "),
                           ({"gains": [1, 2, 3]}, "no 'drive_gains' list")):
        gains.write_text(json.dumps(content))
        assert _status([*argv, "--drive-gains", str(gains)]) == 2
        err = capsys.readouterr().err
        assert match in err and err.count("\n") == 1, err


@pytest.mark.parametrize("argv,message", [
    (["--loaded", "{missing}"], "no such file"),
    (["--mass", "0"], "--mass: expected a finite number > 0"),
    (["--mass", "-3"], "--mass: expected a finite number > 0"),
    (["--link", "link1"], "do not excite the payload's mass"),
    (["--loaded", "{two}"], "joints"),
    (["--com", "0.1,0.2"], "--com: expected 3 numbers"),
    (["--drive-gains", "1,1,1"], "identify-gains finds the drive gains"),
    (["--friction", "offset+presliding:fit"], "parameters to search"),
    (["--method", "best"], "invalid choice"),
])
def test_command_bad_input_is_one_line_and_writes_nothing(files, tmp_path, capsys, argv,
                                                          message):
    argv = [a.format(missing=str(tmp_path / "none.npz"), **files) for a in argv]
    given = {a for a in argv if a.startswith("--")}
    base = {"--loaded": ["--loaded", files["loaded"]], "--mass": ["--mass", "10"],
            "--link": ["--link", "link3"]}
    rest = [a for flag, pair in base.items() if flag not in given for a in pair]
    out = tmp_path / "gains.json"
    code = _status(["identify-gains", "--robot", "rs010n", "--data", files["unloaded"],
                    *rest, *argv, "--json", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1, err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_command_without_loaded_recordings_is_a_usage_error(files, tmp_path, capsys):
    code = _status(["identify-gains", "--robot", "rs010n", "--data", files["unloaded"],
                    "--link", "link3", "--mass", "10", "--json", str(tmp_path / "g.json")])
    err = capsys.readouterr().err
    assert code == 2 and "--loaded" in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []
