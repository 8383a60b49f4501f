"""Payload identification (``sj.identify_payload``, ``sedsabso-jax identify-payload``):
against pinocchio's RNEA with the payload added to a link's inertia (the KUKA LWR4+'s URDF,
on its last link and on a tool frame fixed to it), the standard deviations against the
spread over noise draws, what the data cannot determine, physical consistency, and the
command's bad inputs (exit status 2, one line, nothing written)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pinocchio as pin
import pytest
from conftest import PIN_TO_OURS, friction_torque
from test_cli_usability import _status  # the command's exit status, argparse's included

import sedsabso_jax as sj
from sedsabso_jax.dynamics import params_from_com, pseudo_inertia

#: The payload of the pinocchio test, in the tool frame: mass [kg], CoM [m], inertia
#: about the CoM [kg m^2] (a box's, turned).
MASS, COM = 2.3, np.array([0.03, -0.02, 0.07])
#: A flange fixed to the last link, and a tool frame fixed to the flange.
FLANGE = '<origin xyz="0.0 0.0 0.03" rpy="0.0 0.0 0.7"/>'
TOOL = '<origin xyz="0.01 0.02 0.05" rpy="0.3 -0.2 0.5"/>'


def _fourier(n: int, samples: int, seed: int, rate: float = 50.0):
    rng = np.random.default_rng(seed)
    traj = sj.FourierTrajectory(rng.uniform(-0.4, 0.4, (n, 3)), rng.uniform(-0.4, 0.4, (n, 3)),
                                rng.uniform(-0.5, 0.5, n), wf=0.7)
    times = np.arange(samples) / rate
    return (times, *traj.sample(times))


def _box_inertia() -> np.ndarray:
    c, s = np.cos(0.4), np.sin(0.4)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    return R @ np.diag([0.011, 0.017, 0.009]) @ R.T


@pytest.fixture(scope="module")
def kuka_tool(tmp_path_factory):
    """The KUKA URDF with a tool0 frame fixed to a flange fixed to lwr_7_link (two fixed
    joints, composed in order); its robot; recordings along two different motions without
    and with the payload (fixed to tool0), whose torques are pinocchio's RNEA plus the
    URDF's joint friction."""
    with sj.robots.kuka_lwr4_urdf() as path:
        text = path.read_text()
    fixed = [f'<link name="{child}"/><joint name="{child}_joint" type="fixed"><parent '
             f'link="{parent}"/><child link="{child}"/>{origin}</joint>'
             for parent, child, origin in (("lwr_7_link", "flange", FLANGE),
                                           ("flange", "tool0", TOOL))]
    text = text.replace("</robot>", "".join(fixed) + "</robot>")
    urdf = tmp_path_factory.mktemp("kuka") / "kuka_tool.urdf"
    urdf.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the vendored URDF's duplicate <origin>
        robot = sj.robots.from_urdf(urdf)
    model = pin.buildModelFromUrdf(str(urdf))
    frame = model.frames[model.getFrameId("tool0")]
    payload = pin.Inertia(MASS, COM, _box_inertia())  # in tool0's frame
    loaded = model.copy()
    loaded.inertias[frame.parentJoint] = (loaded.inertias[frame.parentJoint]
                                          + frame.placement.act(payload))

    def record(m, seed):
        data = m.createData()
        t, q, qd, qdd = _fourier(7, 150, seed)
        tau = np.array([pin.rnea(m, data, *s) for s in zip(q, qd, qdd)])
        return sj.Measurements(t, q, qd, qdd, tau + friction_torque(robot.params, qd))

    expected = {"tool0": payload.toDynamicParameters()[PIN_TO_OURS],
                "lwr_7_link": frame.placement.act(payload).toDynamicParameters()[PIN_TO_OURS]}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        torque_model = sj.TorqueModel.of(robot, (sj.Offset(),))  # the default, built once
    return robot, str(urdf), record(model, 1), record(loaded, 2), expected, torque_model


@pytest.mark.parametrize("link", ["lwr_7_link", "tool0"])
def test_noise_free_payload_matches_pinocchio(kuka_tool, link):
    """The joint fit (robot refitted along another motion) and the robot taken as given
    both recover pinocchio's payload in the named link's frame: mass, CoM, inertia about
    the origin and about the CoM."""
    robot, urdf, unloaded, loaded, expected, model = kuka_tool
    p_true = expected[link]
    for unload, with_model in ((unloaded, model), (None, None)):
        found = sj.identify_payload(robot, loaded, link, unloaded=unload, model=with_model,
                                    estimator=sj.WLS(), urdf=urdf)
        np.testing.assert_allclose(found.params10, p_true, atol=1e-7)
        assert found.mass == pytest.approx(MASS, rel=1e-9)
        consistent = sj.identify_payload(robot, loaded, link, unloaded=unload,
                                         model=with_model, urdf=urdf)  # the default
        np.testing.assert_allclose(consistent.params10, p_true, atol=1e-6)
        assert found.moving_link == "lwr_7_link"
        np.testing.assert_allclose(found.com, p_true[7:] / MASS, atol=1e-8)
        if link == "tool0":  # the payload as it was defined, in its own frame
            np.testing.assert_allclose(found.com, COM, atol=1e-8)
            np.testing.assert_allclose(found.inertia_com, _box_inertia(), atol=1e-7)
        assert found.physical["already_consistent"]
        assert found.settings["mode"] == ("joint fit" if unload else "robot fixed")
    doc = json.loads(json.dumps(found.as_dict()))
    assert doc["mass"] == pytest.approx(MASS) and len(doc["inertia"]) == 3


def test_an_identification_gives_the_robot(kuka_tool):
    """An ``sj.identify`` fit of the unloaded run stands for the robot: taken as it is
    without unloaded recordings, its torque model refitted with them."""
    robot, urdf, unloaded, loaded, expected, model = kuka_tool
    # no offsets: with a Coulomb column that does not change sign in this short run,
    # the unloaded run alone cannot tell them apart; 3 s excite the base parameters
    # poorly (said), noise-free torques fit them exactly all the same
    with pytest.warns(UserWarning, match="excite the robot's base parameters poorly"):
        fit = sj.identify(robot, unloaded, sj.OLS(), sj.TorqueModel.of(robot,
                                                                       base=model.base))
    for unload in (None, unloaded):
        found = sj.identify_payload(fit, loaded, "lwr_7_link", unloaded=unload)
        np.testing.assert_allclose(found.params10, expected["lwr_7_link"], atol=1e-6)
    assert found.robot_names == fit.names


@pytest.fixture(scope="module")
def rs010n_runs():
    """RS010N recordings along one motion without and with a 5 kg payload on link3, 2 %
    torque noise, per seed."""
    robot = sj.robots.rs010n()
    payload = params_from_com(5.0, [0.1, 0.05, -0.03], np.diag([0.02, 0.03, 0.04]))
    plant = np.asarray(robot.params).copy()
    plant[24:34] += payload
    t, q, qd, qdd = _fourier(3, 300, 7, rate=30.0)

    def runs(seed, noise=0.02):
        kw = dict(torque_noise=noise)
        return (sj.simulate_measurements(robot, q, qd, qdd, t, seed=2 * seed, **kw),
                sj.simulate_measurements(robot.with_params(plant), q, qd, qdd, t,
                                         seed=2 * seed + 1, **kw))

    return robot, payload, runs


def test_std_matches_the_spread_over_noise_draws(rs010n_runs):
    """Over 30 draws of noise (2 % of each joint's RMS torque, so of unequal size) the
    estimates' spread is the predicted standard deviation, ratio 0.7-1.4 for the mass and
    the CoM (30 draws give a std's ratio to about +-13 %; measured 0.90-0.98), with
    Gautier's weights (weighted residual variance near 1) and with weights half the noise
    (variance near 4, which the standard deviation must carry); the mass is unbiased."""
    robot, payload, runs = rs010n_runs
    model, found = sj.TorqueModel.of(robot, (sj.Offset(),)), []
    clean = runs(0, noise=0.0)
    sigma = 0.02 * np.sqrt(np.mean(clean[1].tau ** 2, axis=0))
    rng = np.random.default_rng(0)
    for _ in range(30):
        unloaded, loaded = (sj.Measurements(m.times, m.q, m.qd, m.qdd,
                                            m.tau + sigma * rng.standard_normal(m.tau.shape))
                            for m in clean)
        for estimator in (sj.WLS(), sj.OLS(tuple(sigma / 2))):
            p = sj.identify_payload(robot, loaded, "link3", unloaded=unloaded, model=model,
                                    estimator=estimator)
            found.append((p.mass, *p.com, p.std["mass"], *p.std["com"]))
    found = np.array(found).reshape(30, 2, 8)
    ratio = found[..., :4].std(axis=0, ddof=1) / np.sqrt(np.mean(found[..., 4:] ** 2, axis=0))
    assert np.all((ratio > 0.7) & (ratio < 1.4)), ratio
    assert abs(np.mean(found[:, 0, 0]) - 5.0) < 3 * np.std(found[:, 0, 0]) / np.sqrt(30)


def test_static_poses_leave_the_inertia_undetermined(rs010n_runs):
    """A quasi-static recording (no velocity, no acceleration) shows the payload's
    gravity only: mass and MX, MY determined; the inertia and MZ (along the horizontal
    joint axes, which gravity's torque does not feel) not: std inf, values NaN."""
    robot, payload, _ = rs010n_runs
    plant = np.asarray(robot.params).copy()
    plant[24:34] += payload
    t, q, _, _ = _fourier(3, 200, 3)
    zero = np.zeros_like(q)
    loaded = sj.simulate_measurements(robot.with_params(plant), q, zero, zero, t)
    p = sj.identify_payload(robot, loaded, "link3")
    assert p.determined.tolist() == [False] * 6 + [True, True, True, False]
    assert p.mass == pytest.approx(5.0, rel=1e-9)
    np.testing.assert_allclose(p.com[:2], [0.1, 0.05], atol=1e-9)
    assert np.isnan(p.com[2]) and np.all(np.isnan(p.inertia))
    assert np.isinf(p.std["com"][2]) and np.all(np.isinf(p.std["inertia_com"]))
    assert "not determined" in p.text()
    # the mass printed to its std's second significant digit, within half of it
    mass = next(r for r in p.text().splitlines() if r.startswith("| mass"))
    step = 10.0 ** (np.floor(np.log10(p.std["mass"])) - 1)
    assert abs(float(mass.split("|")[2]) - p.mass) <= 0.5 * step + 4e-16 * p.mass, mass


def test_consistent_estimate_kept_else_projected(rs010n_runs):
    """Noise-free: the unconstrained estimate is consistent and the physically consistent
    fit finds it. Noisy with a small payload inertia: the physically consistent fit keeps
    the payload's pseudo-inertia positive semidefinite, the unconstrained one does not."""
    robot, _, runs = rs010n_runs
    unloaded, loaded = runs(0, noise=0.0)
    exact = sj.identify_payload(robot, loaded, "link3", unloaded=unloaded)
    assert exact.physical["already_consistent"] and exact.physical["status"] == "optimal"
    np.testing.assert_allclose(exact.params10, exact.unconstrained10, rtol=1e-6, atol=1e-8)
    unloaded, loaded = runs(1, noise=0.05)
    noisy = sj.identify_payload(robot, loaded, "link3", unloaded=unloaded)
    assert np.linalg.eigvalsh(pseudo_inertia(noisy.unconstrained10)).min() < 0
    assert noisy.physical["status"] == "optimal" and not noisy.physical["already_consistent"]
    assert np.linalg.eigvalsh(pseudo_inertia(noisy.params10)).min() > 0
    # the robot given: the payload's own conic fit, its smallest eigenvalue at the margin
    # (1.0007e-6 measured; 1.08e-6 where Clarabel kept a trivial instance's equilibration)
    given = sj.identify_payload(robot, loaded, "link3")
    assert given.physical["solver"] == "Clarabel (cvxpy)" and given.physical["status"] == "optimal"
    assert 1e-6 <= np.linalg.eigvalsh(pseudo_inertia(given.params10)).min() < 1.005e-6


def test_the_data_are_what_identify_takes(rs010n_runs):
    """The recordings as identify takes them: arrays ``(q, qd, qdd, tau)`` as well as
    with the times first (0.5 took only the latter, and said "got tuple")."""
    robot, _, runs = rs010n_runs
    unloaded, loaded = runs(0, noise=0.0)
    arrays = (loaded.q, loaded.qd, loaded.qdd, loaded.tau)
    p = sj.identify_payload(robot, arrays, "link3", estimator=sj.WLS())
    assert p.mass == pytest.approx(5.0, rel=1e-6)
    with pytest.raises(ValueError, match=r"^loaded recordings: data must be a "
                                         r"Measurements, several, or one recording's arrays "
                                         r"\(q, qd, qdd, tau\) or \(times, q, qd, qdd, tau\), "
                                         r"got a tuple of 3$"):
        sj.identify_payload(robot, arrays[:3], "link3")


def test_a_fit_that_constrains_the_links_keeps_the_payload_a_body(rs010n_runs):
    """``PhysicallyConsistent(WLS())`` constrains the links and the payload (a body term)
    alike: the payload's pseudo-inertia stays positive semidefinite where the
    unconstrained estimate's is not, and the links' full parameters come back."""
    robot, _, runs = rs010n_runs
    unloaded, loaded = runs(1, noise=0.05)
    p = sj.identify_payload(robot, loaded, "link3", unloaded=unloaded,
                            estimator=sj.PhysicallyConsistent(sj.WLS()))
    assert np.linalg.eigvalsh(pseudo_inertia(p.unconstrained10)).min() < 0
    assert np.linalg.eigvalsh(pseudo_inertia(p.params10)).min() > 0
    assert p.identification.full_params is not None


@pytest.mark.parametrize("robot_name,link", [("rs010n", "link1"), ("rs010n", "link2"),
                                              ("kuka_lwr4", "lwr_2_link")])
def test_a_mass_the_joints_cannot_feel_is_refused(robot_name, link):
    """A link moved by a vertical axis only (link1), or whose frame origin every joint
    axis before it passes through (the KUKA's shoulder, RS010N link2's origin on joint
    2's axis... with joint 1's): its payload's mass never reaches the torques."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = sj.robots.load(robot_name)
    t, q, qd, qdd = _fourier(robot.n_joints, 120, 5)
    loaded = sj.simulate_measurements(robot, q, qd, qdd, t)
    with pytest.raises(ValueError, match="do not excite the payload's mass"):
        sj.identify_payload(robot, loaded, link)


def test_bad_arguments(rs010n_runs, kuka_tool):
    robot, _, runs = rs010n_runs
    unloaded, loaded = runs(0)
    with pytest.raises(ValueError, match="not a moving link.*tool0.*urdf="):
        sj.identify_payload(robot, loaded, "tool0")
    slow = sj.Measurements(loaded.times * 2, loaded.q, loaded.qd, loaded.qdd, loaded.tau)
    with pytest.raises(ValueError, match="different sampling rates"):
        sj.identify_payload(robot, slow, "link3", unloaded=unloaded)
    with pytest.raises(ValueError, match="no inertial parameters"):
        sj.identify_payload(robot.with_params(np.zeros(36)), loaded, "link3")
    with pytest.raises(ValueError, match="model: without unloaded"):
        sj.identify_payload(robot, loaded, "link3", model=sj.TorqueModel.of(robot))
    with pytest.raises(ValueError, match="limits"):
        sj.identify_payload(robot, loaded, "link3", estimator=sj.WLS("limits"))
    with pytest.raises(ValueError, match="least squares.*L1"):
        sj.identify_payload(robot, loaded, "link3", estimator=sj.L1())
    kuka, urdf, _, kuka_loaded, _, _ = kuka_tool
    with pytest.raises(sj.dynamics.URDFError, match="fixed to the base"), \
            warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the vendored URDF's duplicate <origin>
        sj.identify_payload(kuka, kuka_loaded, "box", urdf=urdf)


# ------------------------------------------------------------------------ the command
@pytest.fixture(scope="module")
def files(rs010n_runs, tmp_path_factory):
    d = tmp_path_factory.mktemp("payload")
    unloaded, loaded = rs010n_runs[2](3, noise=0.01)
    slow = sj.Measurements(loaded.times * 2, loaded.q, loaded.qd, loaded.qdd, loaded.tau)
    two = sj.Measurements(loaded.times, loaded.q[:, :2], loaded.qd[:, :2], loaded.qdd[:, :2],
                          loaded.tau[:, :2])
    return {name: str(m.save(d / f"{name}.npz")) for name, m in
            (("unloaded", unloaded), ("loaded", loaded), ("slow", slow), ("two", two))}


def test_command_writes_the_payload(files, tmp_path, capsys):
    out = tmp_path / "sub" / "payload.json"
    assert _status(["identify-payload", "--robot", "rs010n", "--data", files["unloaded"],
                    "--loaded", files["loaded"], "--link", "link3", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    payload = doc["payload"]
    assert payload["mass"] == pytest.approx(5.0, rel=0.02)
    np.testing.assert_allclose(payload["com"][:2], [0.1, 0.05], atol=0.01)
    assert np.shape(payload["inertia"]) == (3, 3) and payload["std"]["mass"] > 0
    assert doc["settings"]["link"] == "link3" and payload["settings"]["mode"] == "joint fit"
    text = capsys.readouterr().out
    assert "| mass " in text and "kg m^2" in text and text.endswith(f"written: {out}\n")


@pytest.mark.parametrize("argv,message", [
    (["--link", "link9"], "not a moving link"),
    (["--link", "link1"], "do not excite the payload's mass"),
    (["--link", "link3", "--loaded", "{slow}"], "different sampling rates"),
    (["--link", "link3", "--loaded", "{two}"], "joint"),
    (["--link", "link3", "--cutoff-hz", "0"], "--cutoff-hz"),
    (["--link", "link3", "--downsample", "0"], "--downsample"),
    (["--link", "link3", "--friction", "offset+nonsense"], "unknown friction term"),
])
def test_command_bad_input_is_one_line_and_writes_nothing(files, tmp_path, capsys, argv,
                                                          message):
    argv = [a.format(**files) for a in argv]
    loaded = [] if "--loaded" in argv else ["--loaded", files["loaded"]]
    out = tmp_path / "payload.json"
    code = _status(["identify-payload", "--robot", "rs010n", "--data", files["unloaded"],
                    *loaded, *argv, "--json", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1, err
    assert not out.exists() and list(tmp_path.iterdir()) == []
