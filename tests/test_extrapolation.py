"""How far held-out data go beyond the identification data (issue 22, part 2): closed-form
cases, the warning and whom it names, the KUKA repeat recording (no warning), and the
command's table and JSON key."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax import cli
from sedsabso_jax.identification import Extrapolation, extrapolation

NAMES = ("shoulder", "elbow", "wrist")


def _measurements(q, qd, qdd=None) -> sj.Measurements:
    q, qd = np.asarray(q, float), np.asarray(qd, float)
    qdd = np.ones_like(q) if qdd is None else np.asarray(qdd, float)
    return sj.Measurements(np.arange(len(q)) / 10.0, q, qd, qdd, np.zeros_like(q))


def _columns(*columns) -> np.ndarray:
    return np.stack([np.asarray(c, float) for c in columns], axis=1)


# identification data: positions over [0, 2], [-1, 1], [0, 1]; peak |qd| 1, 2, 0.5 (the
# peak of the second joint is negative); peak |qdd| 1, 1, 1
FIT = _measurements(_columns([0, 2, 1, 1], [-1, 1, 0, 0], [0, 1, 0.5, 0.5]),
                    _columns([1, -0.5, 0, 0], [0.5, -2, 1, 0], [0.5, 0, -0.5, 0]))


def test_closed_form_true_extremes():
    """Positions past the low end, past the high end and inside; speeds 1.5x, 1x, 0.4x;
    accelerations 3x on one joint."""
    new = _measurements(_columns([-0.5, 2, 1], [-1, 1.5, 0], [0.2, 0.8, 0.5]),
                        _columns([0, -1.5, 0], [2, 0, 0], [0.2, 0, -0.1]),
                        _columns([1, 1, 1], [1, -3, 0], [0.5, 0, 0]))
    e = extrapolation(FIT, new, joint_names=NAMES, quantile=0)
    np.testing.assert_array_equal(e.position_beyond, [0.25, 0.25, 0.0])  # 0.5/2, 0.5/2
    np.testing.assert_array_equal(e.speed_ratio, [1.5, 1.0, 0.4])
    np.testing.assert_array_equal(e.acceleration_ratio, [1.0, 3.0, 0.5])
    np.testing.assert_array_equal(e.fitted_range, [[0, 2], [-1, 1], [0, 1]])
    np.testing.assert_array_equal(e.new_range, [[-0.5, 2], [-1, 1.5], [0.2, 0.8]])
    np.testing.assert_array_equal(e.fitted_peak_speed, [1, 2, 0.5])
    assert e.flagged() == [0, 1]
    doc = e.as_dict()
    assert doc["beyond"] == ["shoulder", "elbow"]
    assert doc["position_beyond"] == [0.25, 0.25, 0.0]


def test_both_ends_the_larger_counts_and_a_still_joint():
    """Past both ends: the larger overshoot; a joint still in the fitted data that moves
    in the new data: inf; still in both: 0."""
    fit = _measurements(_columns([0, 4], [1, 1]), _columns([1, 0], [0, 0]))
    new = _measurements(_columns([-1, 7], [1, 1.5]), _columns([1, 0], [1, 0.5]))
    e = extrapolation(fit, new, quantile=0)
    assert e.joint_names == ("q1", "q2")
    np.testing.assert_array_equal(e.position_beyond, [0.75, np.inf])  # max(1, 3) / 4
    np.testing.assert_array_equal(e.speed_ratio, [1.0, np.inf])
    still = extrapolation(fit, fit, quantile=0)
    np.testing.assert_array_equal(still.position_beyond, [0.0, 0.0])
    np.testing.assert_array_equal(still.speed_ratio, [1.0, 0.0])


def test_time_scaled_motion_and_robust_extremes():
    """A motion time-scaled by 2 (q(2t): qd x2, qdd x4) gives exactly 2 and 4 with the
    default quantiles; one spike of 100x in the new speeds does not count by default but
    does with true extremes."""
    t = np.arange(1000) / 100.0
    q = _columns(np.sin(t), 0.5 * np.cos(2 * t))
    qd = _columns(np.cos(t), -np.sin(2 * t))
    qdd = _columns(-np.sin(t), -2 * np.cos(2 * t))
    slow = _measurements(q, qd, qdd)
    fast = sj.Measurements(t / 2, q, 2 * qd, 4 * qdd, np.zeros_like(q))
    e = extrapolation(slow, fast)
    np.testing.assert_allclose(e.speed_ratio, [2, 2], rtol=1e-12)
    np.testing.assert_allclose(e.acceleration_ratio, [4, 4], rtol=1e-12)
    np.testing.assert_array_equal(e.position_beyond, [0, 0])
    spiky = qd.copy()
    spiky[500, 0] = 100.0
    e = extrapolation(slow, _measurements(q, spiky, qdd))
    assert e.speed_ratio[0] == pytest.approx(1.0, abs=1e-3) and e.flagged() == []
    assert extrapolation(slow, _measurements(q, spiky, qdd), quantile=0).speed_ratio[0] > 99


def test_warning_names_the_joints_beyond_and_no_others():
    """Joint `elbow` 1.3x the fitted speed, `wrist` 0.2 of its range past it; `shoulder`
    1.2x the speed, 0.05 past, 1.4x the acceleration: just under every threshold."""
    new = _measurements(_columns([0, 2.1, 1], [-1, 1, 0], [0, 1.2, 0.5]),
                        _columns([1.2, 0, 0], [2.6, 0, 0], [0.5, 0, 0]),
                        _columns([1.4, 0, 0], [1, 0, 0], [1, 0, 0]))
    with pytest.warns(UserWarning, match="beyond the identification data") as caught:
        e = extrapolation(FIT, new, joint_names=NAMES, quantile=0, warn=True)
    assert len(caught) == 1
    text = str(caught[0].message)
    assert "elbow speed 1.30x" in text and "wrist position 0.20 of the fitted range" in text
    assert "shoulder" not in text and "elbow position" not in text and "wrist speed" not in text
    assert caught[0].filename == __file__  # the user's line
    assert [NAMES[j] for j in e.flagged()] == ["elbow", "wrist"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert extrapolation(FIT, FIT, warn=True).message() is None


@pytest.mark.parametrize("quantity", ["position", "speed", "acceleration"])
def test_each_threshold_alone(quantity):
    """Just over one threshold (0.105 of the range past it, 1.26x, 1.51x) flags the joint
    and names the quantity; just under (0.095, 1.24x, 1.49x) does not."""
    def new(over: bool) -> sj.Measurements:
        q = _columns([0, 2, 1, 1], [-1, 1, 0, 0], [0, 1, 0.5, 0.5])
        qd = _columns([1, -0.5, 0, 0], [0.5, -2, 1, 0], [0.5, 0, -0.5, 0])
        qdd = np.ones_like(q)
        if quantity == "position":
            q[1, 0] = 2.21 if over else 2.19
        elif quantity == "speed":
            qd[0, 0] = 1.26 if over else 1.24
        else:
            qdd[0, 0] = 1.51 if over else 1.49
        return _measurements(q, qd, qdd)

    e = extrapolation(FIT, new(True), joint_names=NAMES, quantile=0)
    assert e.flagged() == [0]
    assert e.message().endswith({"position": "shoulder position 0.10 of the fitted range "
                                 "past it", "speed": "shoulder speed 1.26x",
                                 "acceleration": "shoulder acceleration 1.51x"}[quantity])
    assert extrapolation(FIT, new(False), quantile=0).flagged() == []


def test_checks_its_arguments():
    with pytest.raises(ValueError, match="quantile"):
        extrapolation(FIT, FIT, quantile=0.5)
    with pytest.raises(ValueError, match="2 joint names for 3 joints"):
        extrapolation(FIT, FIT, joint_names=("a", "b"))


def test_kuka_repeat_recording_is_not_extrapolation():
    """measurements_2 repeats measurements_1's trajectory: inside its range, speeds and
    accelerations within 1 % (0.995-1.003 measured), no warning; the same run twice as
    fast is flagged on every joint."""
    m1, m2 = sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        e = extrapolation(m1, m2, warn=True)
    assert e.flagged() == [] and e.message() is None
    assert np.all(e.position_beyond < 0.01)
    np.testing.assert_allclose(e.speed_ratio, 1, atol=0.01)
    np.testing.assert_allclose(e.acceleration_ratio, 1, atol=0.01)
    fast = sj.Measurements(m1.times / 2, m1.q, 2 * m1.qd, 4 * m1.qdd, m1.tau)
    assert extrapolation(m1, fast).flagged() == list(range(7))


@pytest.fixture(scope="module")
def slow_and_fast(tmp_path_factory):
    """RS010N along one smooth motion and along the same motion twice as fast, sampled at
    the same positions."""
    d = tmp_path_factory.mktemp("rs010n_fast")
    robot = sj.robots.rs010n()
    rng = np.random.default_rng(3)
    traj = sj.FourierTrajectory(rng.uniform(-0.3, 0.3, (3, 3)),
                                rng.uniform(-0.3, 0.3, (3, 3)), np.zeros(3), wf=0.6)

    def fast(t):
        q, qd, qdd = (np.asarray(x) for x in traj(2 * t))
        return q, 2 * qd, 4 * qdd

    times = np.arange(300) / 40.0
    slow = sj.simulate_measurements_along(robot, traj, times).save(d / "slow.npz")
    quick = sj.simulate_measurements_along(robot, fast, times / 2).save(d / "fast.npz")
    return str(slow), str(quick)


def test_command_warns_and_writes_the_table_and_json(slow_and_fast, tmp_path, capsys):
    js = tmp_path / "r.json"
    assert cli.main(["identify", "--robot", "rs010n", "--data", slow_and_fast[0],
                     "--validate", slow_and_fast[1], "--method", "OLS", "--weights",
                     "equal", "--friction", "viscous-coulomb", "--folds", "0",
                     "--json", str(js)]) == 0
    out, err = capsys.readouterr()
    warning = [line for line in err.splitlines() if "beyond the identification" in line]
    assert len(warning) == 1 and warning[0].startswith("sedsabso-jax: warning: ")
    for name in sj.robots.rs010n().joint_names:
        assert f"{name} speed 2.00x, acceleration 4.00x" in warning[0]
    assert "extrapolation (how far the validation data go beyond" in out
    assert "| position beyond |" in out.replace("   ", " ").replace("  ", " ")
    assert "`speed ratio`: peak velocity of the held-out data" in " ".join(out.split())
    doc = json.loads(js.read_text())
    ext = doc["extrapolation"]
    np.testing.assert_allclose(ext["speed_ratio"], [2, 2, 2], rtol=1e-9)
    np.testing.assert_allclose(ext["acceleration_ratio"], [4, 4, 4], rtol=1e-9)
    np.testing.assert_allclose(ext["position_beyond"], [0, 0, 0], atol=1e-12)
    assert ext["beyond"] == list(sj.robots.rs010n().joint_names)
    assert ext["thresholds"] == {"position_beyond": 0.1, "speed_ratio": 1.25,
                                 "acceleration_ratio": 1.5}


def test_report_without_held_out_has_no_extrapolation(slow_and_fast):
    data = sj.load_measurements(slow_and_fast[0], n_joints=3)
    report = sj.select_and_identify(sj.robots.rs010n(), data, estimators=sj.OLS(),
                                    models=sj.TorqueModel.of(sj.robots.rs010n()),
                                    validation=None)
    assert report.extrapolation is None and "extrapolation" not in report.text()
    assert report.document({})["extrapolation"] is None
    assert isinstance(extrapolation(data, data), Extrapolation)
