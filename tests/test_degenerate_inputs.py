"""Data that cannot give an answer, and inputs in the user's words (issue 42): each is
refused before any work with one line on stderr, exit status 2 and nothing written, or
gets a warning naming what and where. Too few samples, no motion, a poor excitation,
signals far outside the robot's limits, the same recording with and without a payload,
drive gains that are not positive, a validation that cannot measure an error; messages
that name the command's flags and the data's columns; contradicting flags; outputs
checked before the work."""

from __future__ import annotations

import json

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax import cli
from sedsabso_jax.cli._checks import check_signals
from sedsabso_jax.identification._data_checks import COND_ERROR, COND_WARN
from sedsabso_jax.identification._gains._result import DriveGains

#: The quickest identify: one candidate, no validation.
QUICK = ["--method", "OLS", "--weights", "equal", "--friction", "viscous-coulomb",
         "--no-physical", "--folds", "0"]


def _status(argv) -> int:
    try:
        return cli.main(argv)
    except SystemExit as exit_:
        return int(exit_.code or 0)


def _refused(argv, capsys, *words, written=()) -> str:
    """Run the command: exit status 2, one line on stderr holding ``words``, none of the
    paths ``written`` there."""
    code = _status(argv)
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and err.startswith("sedsabso-jax: error: "), err
    for word in words:
        assert word in err, (word, err)
    for path in written:
        assert not path.exists(), path
    return err


def _sine(robot, amplitude, frequencies, samples=400, rate=40.0) -> sj.Measurements:
    t = np.arange(samples) / rate
    w = np.asarray(frequencies, dtype=float)
    q, qd, qdd = (amplitude * np.sin(np.outer(t, w)), amplitude * w * np.cos(np.outer(t, w)),
                  -amplitude * w ** 2 * np.sin(np.outer(t, w)))
    return sj.simulate_measurements(robot, q, qd, qdd, t)


def _save(tmp_path, name, d: sj.Measurements, **changes) -> str:
    fields = {"times": d.times, "q": d.q, "qd": d.qd, "qdd": d.qdd, "tau": d.tau, **changes}
    return str(sj.Measurements(fields["times"], fields["q"], fields["qd"], fields["qdd"],
                               fields["tau"]).save(tmp_path / name))


@pytest.fixture(scope="module")
def rs010n_run():
    """Noise-free RS010N measurements along a smooth motion (10 s at 40 Hz)."""
    robot = sj.robots.rs010n()
    rng = np.random.default_rng(1)
    traj = sj.FourierTrajectory(rng.uniform(-0.3, 0.3, (3, 3)),
                                rng.uniform(-0.3, 0.3, (3, 3)), np.zeros(3), wf=0.6)
    return robot, sj.simulate_measurements_along(robot, traj, np.arange(400) / 40.0)


@pytest.fixture(scope="module")
def kuka_run():
    """The first 2 s of the real KUKA LWR4+ run 1 (checks of the signals need no fit)."""
    return sj.robots.kuka_lwr4(), sj.load_kuka_lwr4(1).slice(0, 400)


# ------------------------------------------------------------------ data that cannot answer
def test_five_samples_are_refused_before_any_fit(rs010n_run, tmp_path, capsys):
    """The issue's header and 5 rows: exit 0 after 2 min with a "validated error"."""
    robot, run = rs010n_run
    five = _save(tmp_path, "five.csv", run.slice(0, 5))
    out = tmp_path / "out"
    _refused(["identify", "--robot", "rs010n", "--data", five, "--json", str(out / "r.json")],
             capsys, "five.csv: 5 samples x 3 joints = 15 torque equations", "parameters",
             "record a longer motion", written=[out])
    with pytest.raises(ValueError, match="5 samples x 3 joints"):
        sj.identify(robot, run.slice(0, 5))
    with pytest.raises(ValueError, match="5 samples x 3 joints"):
        sj.select_and_identify(robot, run.slice(0, 5))


def test_too_few_samples_for_a_payload_or_the_gains(rs010n_run):
    robot, run = rs010n_run
    few = run.slice(0, 6)
    with pytest.raises(ValueError, match="6 samples x 3 joints = 18 torque equations for the "
                                         "10 parameters of the payload"):
        sj.identify_payload(robot, few, "link3")
    with pytest.raises(ValueError, match="12 samples x 3 joints = 36 torque equations"):
        sj.identify_drive_gains(robot, few, run.slice(10, 16), "link3", 5.0)


def test_no_joint_moves(rs010n_run, tmp_path, capsys):
    """Not "SpeedSplits: no joint moves": where, and what it needs."""
    robot, run = rs010n_run
    still = _save(tmp_path, "still.npz", run, q=np.tile(run.q[0], (run.n_samples, 1)),
                  qd=np.zeros_like(run.qd), qdd=np.zeros_like(run.qdd))
    err = _refused(["identify", "--robot", "rs010n", "--data", still, "--json",
                    str(tmp_path / "r.json")], capsys, "no joint moves in the data",
                   "spans less than 0.01 rad", "excitation", written=[tmp_path / "r.json"])
    assert "SpeedSplits" not in err


def test_a_joint_that_never_moves_is_named(rs010n_run):
    robot, run = rs010n_run
    q = run.q.copy()
    q[:, 2] = 0.3
    qd, qdd = run.qd.copy(), run.qdd.copy()
    qd[:, 2] = qdd[:, 2] = 0.0
    data = sj.simulate_measurements(robot, q, qd, qdd, run.times)
    with pytest.warns(UserWarning, match=r"joint 3 \(spans 0\) never moves in the data .*its "
                                         r"friction"):
        sj.identify(robot, data)


def test_an_excitation_that_determines_nothing_is_refused(tmp_path, capsys):
    """Every joint moves, 0.05 rad at one frequency: the base regressor's condition number
    is 7e6 (unit-norm columns); 0.3 rad: 2e4, a warning."""
    robot = sj.robots.rs010n()
    poor = _save(tmp_path, "poor.npz", _sine(robot, 0.05, (1.0, 1.0, 1.0)))
    _refused(["identify", "--robot", "rs010n", "--data", poor, *QUICK, "--json",
              str(tmp_path / "r.json")], capsys, "condition number is 7.0", "unit-norm columns",
             f"above {COND_ERROR:.0e}", "record a longer or richer motion",
             written=[tmp_path / "r.json"])
    with pytest.warns(UserWarning, match=r"excite the robot's base parameters poorly: .*"
                                         r"condition number is 2\.2\de\+04"):
        sj.identify(robot, _sine(robot, 0.3, (1.0, 1.0, 1.0)))
    assert COND_WARN < 2.2e4 < COND_ERROR < 7e6
    # a prior pulls what the data leave undetermined: a warning, the fit goes on
    with pytest.warns(UserWarning, match=r"condition number is 7\.0"):
        sj.identify(robot, _sine(robot, 0.05, (1.0, 1.0, 1.0)),
                    sj.PhysicallyConsistent(sj.OLS(), prior_strength=1e-3))


def test_positions_in_degrees(rs010n_run, tmp_path, capsys):
    robot, run = rs010n_run
    degrees = _save(tmp_path, "degrees.csv", run, q=np.degrees(run.q))
    _refused(["identify", "--robot", "rs010n", "--data", degrees, *QUICK], capsys,
             "degrees.csv: joint", "positions (column q", "beyond its limits of --robot "
             "rs010n", "by more than their range: positions in degrees? expected rad")


def test_torques_in_another_unit(kuka_run, tmp_path, capsys):
    """The issue's torques x 1e12 (here x 1000, mN m for N m): NRMS 8.7e11 % before."""
    _, run = kuka_run
    milli = _save(tmp_path, "milli.csv", run, tau=1000 * run.tau)
    _refused(["identify", "--robot", "kuka_lwr4", "--data", milli, *QUICK, "--json",
              str(tmp_path / "r.json")], capsys, "milli.csv: joint 2 (lwr_1_joint)'s torques "
             "(column tau2) reach", "x its effort limit 176 N m", "torques in another unit?",
             written=[tmp_path / "r.json"])
    with pytest.raises(ValueError, match="x its effort limit 176 N m"):
        sj.identify(kuka_run[0], sj.Measurements(run.times, run.q, run.qd, run.qdd,
                                                 1000 * run.tau), limits=[176, 176, 100, 100,
                                                                          100, 38, 38])


def test_speeds_in_degrees(kuka_run, tmp_path, capsys):
    _, run = kuka_run
    fast = _save(tmp_path, "fast.npz", run, qd=np.degrees(run.qd))
    _refused(["identify", "--robot", "kuka_lwr4", "--data", fast, *QUICK], capsys,
             "fast.npz: joint", "'s velocities reach", "x its velocity limit of --robot "
             "kuka_lwr4", "speeds in another unit? expected rad/s")


def test_torques_beyond_the_effort_limit_are_a_named_warning(kuka_run):
    robot, run = kuka_run
    strong = sj.Measurements(run.times, run.q, run.qd, run.qdd, 12 * run.tau, source="x.npz")
    with pytest.warns(UserWarning, match=r"x\.npz: joint 2 \(lwr_1_joint\)'s torques reach "
                                         r"[\d.]+, 1\.\d+ x its effort limit 176 N m: beyond"):
        check_signals("kuka_lwr4", robot, [[strong]])


@pytest.fixture(scope="module")
def currents(rs010n_run, tmp_path_factory):
    """Recordings of currents without and with a 10 kg payload on link3, and one with the
    payload at rest."""
    robot, run = rs010n_run
    d = tmp_path_factory.mktemp("currents")
    plant = np.asarray(robot.params).copy()
    plant[24:34] += sj.dynamics.params_from_com(10.0, np.array([0.05, 0.02, 0.1]),
                                                np.diag([0.05, 0.06, 0.04]))
    loaded = sj.simulate_measurements(robot.with_params(plant), run.q, run.qd, run.qdd,
                                      run.times)
    rest = np.tile(run.q[100], (run.n_samples, 1))
    resting = sj.simulate_measurements(robot.with_params(plant), rest, 0 * run.qd,
                                       0 * run.qdd, run.times)
    return {"unloaded": _save(d, "unloaded.npz", run), "loaded": _save(d, "loaded.npz", loaded),
            "rest": _save(d, "rest.npz", resting)}


@pytest.mark.parametrize("command", ["identify-gains", "identify-payload"])
def test_the_same_recording_with_and_without_the_payload(currents, tmp_path, capsys,
                                                         command):
    """identify-gains wrote gains such as -17595 with one warning."""
    mass = ["--mass", "10"] if command == "identify-gains" else []
    out = tmp_path / "g.json"
    _refused([command, "--robot", "rs010n", "--data", currents["unloaded"], "--loaded",
              currents["unloaded"], "--link", "link3", *mass, "--json", str(out)], capsys,
             "the unloaded (--data) recording", "and the loaded (--loaded) one",
             "are the same", written=[out])


def test_gains_from_a_payload_at_rest(currents, tmp_path, capsys):
    """Not "the start of the maximum likelihood has a zero gain"."""
    out = tmp_path / "g.json"
    _refused(["identify-gains", "--robot", "rs010n", "--data", currents["unloaded"],
              "--loaded", currents["rest"], "--link", "link3", "--mass", "10", "--json",
              str(out)], capsys, "no joint moves in the loaded recordings (--loaded",
             written=[out])


@pytest.mark.parametrize("gains", ["1,-1,1", "1,nan,1", "1,0,1", "inf,1,1", "json"])
def test_drive_gains_must_be_positive(rs010n_run, tmp_path, capsys, gains):
    """identify --drive-gains with a negative gain was silent."""
    _, run = rs010n_run
    data = _save(tmp_path, "run.npz", run)
    if gains == "json":
        path = tmp_path / "gains.json"
        path.write_text(json.dumps({"drive_gains": [1.0, -2.0, 1.0], "motor_side": False}))
        gains = str(path)
    _refused(["identify", "--robot", "rs010n", "--data", data, *QUICK, "--drive-gains", gains,
              "--json", str(tmp_path / "r.json")], capsys, "--drive-gains", "gain ",
             "expected positive finite numbers", written=[tmp_path / "r.json"])


def test_a_validation_that_cannot_measure_an_error(rs010n_run, tmp_path, capsys):
    """36 samples spread over the motion: 108 equations fit 21 parameters, but a split
    of 2 phase folds fits half of them: no predicted error from it."""
    robot, _ = rs010n_run
    rng = np.random.default_rng(1)
    traj = sj.FourierTrajectory(rng.uniform(-0.3, 0.3, (3, 3)),
                                rng.uniform(-0.3, 0.3, (3, 3)), np.zeros(3), wf=0.6)
    sparse = sj.simulate_measurements_along(robot, traj, np.linspace(0, 10.5, 36))
    path = _save(tmp_path, "sparse.npz", sparse)
    quick = [a for a in QUICK if a not in ("--folds", "0")]
    _refused(["identify", "--robot", "rs010n", "--data", path, *quick, "--validation",
              "phase", "--folds", "2", "--json", str(tmp_path / "r.json")], capsys,
             "the validation cannot measure an error: its split 'phase 1/2' fits",
             "or none (--folds 0", written=[tmp_path / "r.json"])


# ------------------------------------------------------------------ the user's words
def test_presliding_fit_negative(rs010n_run, tmp_path, capsys):
    """Not "Presliding's largest must be a number in ... (fitted=True)"."""
    _, run = rs010n_run
    err = _refused(["identify", "--robot", "rs010n", "--data", _save(tmp_path, "r.npz", run),
                    "--friction", "presliding:fit:-1"], capsys,
                   "presliding:fit:LARGEST", "a number in (1e-05, 0.5], got presliding:fit:-1")
    assert "fitted=" not in err


def test_csv_with_semicolons_decimal_commas_and_units(rs010n_run, tmp_path, capsys):
    _, run = rs010n_run
    plain = _save(tmp_path, "plain.csv", run.slice(0, 50))
    lines = open(plain).read().splitlines()
    header = lines[0].split(",")
    units = {"time": "s", "q": "rad", "qd": "rad/s", "qdd": "rad/s^2", "tau": "N m"}
    named = [f"{h} [{units[h.rstrip('0123456789')]}]" for h in header]
    (tmp_path / "semi.csv").write_text("\n".join(
        [";".join(named)] + [line.replace(",", ";").replace(".", ",") for line in lines[1:]]))
    (tmp_path / "units.csv").write_text("\n".join([",".join(named)] + lines[1:]))
    expected = sj.load_measurements(plain)
    for name in ("semi.csv", "units.csv"):
        found = sj.load_measurements(tmp_path / name)
        np.testing.assert_array_equal(found.q, expected.q)
        np.testing.assert_array_equal(found.tau, expected.tau)
    (tmp_path / "deg.csv").write_text("\n".join(
        [",".join(named).replace("q2 [rad]", "q2 [deg]")] + lines[1:]))
    _refused(["identify", "--robot", "rs010n", "--data", str(tmp_path / "deg.csv")], capsys,
             "column 'q2 [deg]': positions in 'deg'; expected rad", "x pi/180")
    (tmp_path / "pipes.csv").write_text("time|q1|tau1\n0|0|0\n")
    _refused(["identify", "--robot", "rs010n", "--data", str(tmp_path / "pipes.csv")], capsys,
             "column 'time': missing", "separated by commas, semicolons or tabs",
             "got 1 column(s) 'time|q1|tau1'")


def test_recordings_of_different_rates_point_to_the_flag(rs010n_run, tmp_path, capsys):
    _, run = rs010n_run
    a, b = _save(tmp_path, "a.npz", run), _save(tmp_path, "b.npz", run.downsample(2))
    err = _refused(["identify", "--robot", "rs010n", "--data", a, b, *QUICK], capsys,
                   "different sampling rates", "--data", "40 Hz", "20 Hz",
                   "give --resample-hz HZ", "--resample-hz 20")
    assert "resample_hz" not in err


def test_an_unwritable_output_is_found_before_the_work(rs010n_run, tmp_path, capsys):
    """--json where no file can be made (root may write everywhere os.access says):
    found after 56 s of work, with a temporary file's name, before."""
    _, run = rs010n_run
    data = _save(tmp_path, "run.npz", run)
    for flag in ("--json", "--urdf-out"):
        err = _refused(["identify", "--robot", "rs010n", "--data", data, *QUICK, flag,
                        "/proc/sedsabso/r.json"], capsys, f"{flag} '/proc/sedsabso/r.json': "
                       "cannot write in directory '/proc'")
        assert ".tmp" not in err
    with pytest.raises(OSError, match="/proc/r.json") as raised:
        sj._output.write_text("/proc/r.json", "{}")
    assert ".tmp" not in str(raised.value)


@pytest.mark.parametrize("flags, words", [
    (["--friction", "viscous-coulomb", "--no-friction-at-rest"],
     ["--no-friction-at-rest acts on --friction auto only"]),
    (["--friction", "smooth", "--no-searched-scales"],
     ["--no-searched-scales acts on --friction auto only", "smooth:fit"]),
    (["--folds", "0", "--validation", "speed"],
     ["--folds 0 turns validation off: --validation speed"]),
    (["--folds", "3", "--validation", "recordings"],
     ["--folds 3 sets the folds of the motion's phase", "--validation recordings"]),
    (["--method", "OLS", "--iterations", "50", "--seed", "2"],
     ["--iterations, --seed: only a swarm's search reads them", "--method OLS"]),
    (["--iterations", "50"], ["--method auto (OLS or WLS) solves in closed form"]),
    (["--json", "{data}"], ["--json {data} is the input --data {data}"]),
    (["--json", "{out}", "--urdf-out", "{out}"], ["--json and --urdf-out name the same"]),
])
def test_contradicting_flags_are_refused(rs010n_run, tmp_path, capsys, flags, words):
    _, run = rs010n_run
    data = _save(tmp_path, "run.npz", run)
    before = (tmp_path / "run.npz").read_bytes()
    out = str(tmp_path / "r.json")
    flags = [f.format(data=data, out=out) for f in flags]
    _refused(["identify", "--robot", "rs010n", "--data", data, *flags], capsys,
             *(w.format(data=data) for w in words), written=[tmp_path / "r.json"])
    assert (tmp_path / "run.npz").read_bytes() == before


def test_gains_are_labelled_with_the_robots_joint_names():
    """identify-gains labelled joints 1..n where identify uses the URDF's names."""
    def gains(motors):
        three = np.array([0.3, 1.2, 0.8])
        return DriveGains(three, three / 1e3, motors, "likelihood", np.zeros(10),
                          np.zeros(10), (), np.zeros(0), np.zeros(0), {},
                          {"mass": 2.0, "link": "tool0"},
                          joint_names=("shoulder", "elbow", "wrist"))

    joint_side = gains(np.eye(3))
    assert joint_side.labels == ("shoulder", "elbow", "wrist")
    assert "| shoulder |" in joint_side.text() and "| joint " in joint_side.text()
    assert joint_side.as_dict()["names"] == ["shoulder", "elbow", "wrist"]
    motors = gains(np.array([[2.0, 0, 0], [0, 3.0, 0], [0, 0.5, 4.0]]))
    assert motors.labels == ("1", "2", "3") and "| motor " in motors.text()
    assert motors.as_dict()["names"] == ["motor 1", "motor 2", "motor 3"]
