"""``sedsabso-jax identify``: real KUKA data end to end, simulated data, and a table of bad
inputs (exit status 2, one readable line naming the file and field, nothing written)."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest
from conftest import random_urdf

import sedsabso_jax as sj
from sedsabso_jax import cli


def _status(argv) -> int:
    try:
        return cli.main(argv)
    except SystemExit as exit_:
        return exit_.code


@pytest.fixture(scope="module")
def rs010n_files(tmp_path_factory):
    """Noise-free RS010N measurements along two different random smooth motions."""
    d = tmp_path_factory.mktemp("rs010n")
    robot = sj.robots.rs010n()
    paths = []
    for seed in (1, 2):
        rng = np.random.default_rng(seed)
        traj = sj.FourierTrajectory(rng.uniform(-0.3, 0.3, (3, 3)),
                                    rng.uniform(-0.3, 0.3, (3, 3)), np.zeros(3), wf=0.6)
        times = np.arange(400) / 40.0
        data = sj.simulate_measurements_along(robot, traj, times)
        paths.append(data.save(d / f"run{seed}.npz"))
    return [str(p) for p in paths]


def test_revolute_joints_whose_limit_gives_no_range_are_unlimited(tmp_path, capsys):
    """As a manufacturer's URDF (Kinova's Gen3) declares its unlimited joints: revolute,
    with a ``<limit>`` of effort and velocity only. Read without position limits, with one
    warning naming them (0.5 stopped: joint 1: q_min 0.0 must be below q_max 0.0)."""
    rng = np.random.default_rng(5)
    text, _ = random_urdf(rng, 2, prismatic_prob=0.0)
    text = text.replace('<limit lower="-3" upper="3" effort="100" velocity="5"/>',
                        '<limit effort="39" velocity="1.3963"/>')
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(text)
    traj = sj.FourierTrajectory(rng.uniform(-0.5, 0.5, (2, 3)), rng.uniform(-0.5, 0.5, (2, 3)),
                                np.zeros(2), wf=0.6)
    data = sj.simulate_measurements_along(sj.robots.from_urdf(urdf), traj,
                                          np.arange(400) / 40.0).save(tmp_path / "run.npz")
    code = cli.main(["identify", "--robot", str(urdf), "--data", str(data), "--method", "OLS",
                     "--friction", "viscous-coulomb", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 0, err
    assert err.count(" have a <limit> without a position range") == 1, err
    assert (f"sedsabso-jax: warning: URDF '{urdf}': joints ['j1', 'j2'] have a <limit> "
            "without a position range") in err, err


def test_rs010n_noise_free_recovers_the_true_parameters(rs010n_files, tmp_path, capsys):
    out = tmp_path / "out"
    code = cli.main(["identify", "--robot", "rs010n", "--data", rs010n_files[0],
                     "--validate", rs010n_files[1], "--method", "OLS",
                     "--friction", "viscous-coulomb", "--out", str(out)])
    assert code == 0
    doc = json.loads((out / "identification.json").read_text())
    base = sj.base_parameters(sj.robots.rs010n())
    assert doc["base_parameters"]["names"] == list(base.names)
    np.testing.assert_allclose(doc["base_parameters"]["values"], np.asarray(base.values),
                               atol=1e-6)
    assert doc["validation"]["nrms_limits_percent"] is None  # RS010N: no torque limits
    assert max(doc["validation"]["relative_rms_percent"]) < 1e-6
    assert (out / "torques_fit.png").is_file() and (out / "torques_validation.png").is_file()
    text = capsys.readouterr().out
    assert "ZZ1R" in text and "validation" in text


def test_kuka_real_data_end_to_end(kuka_identified):
    """The real KUKA LWR4+ runs (``KUKA_IDENTIFY``, conftest; the run the docs quote): the
    default method identifies on run 1 and validates on run 2; the JSON has the documented
    keys (how the signals were obtained among them, as loaded), the model chosen by the
    pooled phase folds and speed splits on run 1 (30 candidates: 15 unconstrained, 15
    physically consistent, then friction at rest added to the choice and kept: not worse
    by more than one standard error) is the physically consistent OLS fit with offset,
    smooth Coulomb friction, friction growing with the load and friction at rest, and the
    held-out NRMS over the torque limits is pinned to +-5 % (measured 0.1450 %; plain OLS
    with Coulomb + viscous friction gives 0.217 % on slices of these runs, outside the
    band); the report's figures are written."""
    doc, printed, out = kuka_identified
    assert set(doc) == {"base_parameters", "fit", "validation", "settings", "signals",
                        "cross_validation", "extrapolation", "rests", "validations", "mujoco"}
    # the shipped file's velocities and accelerations are the logger's: nothing derived
    assert doc["signals"]["info"]["accelerations"] == "recorded"
    assert doc["signals"]["description"].startswith(
        "positions, velocities, accelerations and torques as recorded; torques and "
        "positions taken as simultaneous (no delay). This is the measurement's")
    assert "signals: positions, velocities, accelerations and torques" in printed
    # the chain chosen (--signals auto, the default): the logger's signals kept, the
    # delay searched with the chosen model and not kept
    choice = doc["signals"]["choice"]
    assert choice["chosen"] == "recorded" and "signals chosen by validation" in printed
    assert [s["kept"] for s in choice["delay_searches"]] == [False]
    assert len(doc["base_parameters"]["names"]) == len(doc["base_parameters"]["values"])
    val = doc["validation"]
    assert len(val["nrms_range_percent"]) == len(val["relative_rms_percent"]) == 7
    assert val["nrms_limits_percent"] == pytest.approx(0.1450, rel=0.05)
    assert doc["settings"]["torque_limits"] == [176.0, 176.0, 100.0, 100.0, 100.0, 38.0, 38.0]
    assert (doc["settings"]["method"], doc["settings"]["friction"],
            doc["settings"]["physical"]) == (
        "OLS", "viscous-coulomb+offset+smooth+load+presliding:fit:0.02", True)
    cv = doc["cross_validation"]
    assert cv["validation"]["kind"] == "pooled" and len(cv["fold_scores"]) == 5 + 7
    assert set(cv["part_scores"]) == {"phase folds", "speed splits"}
    candidates = cv["selection"]["candidates"]
    assert len(candidates) == 31 and 0.15 < cv["score"] < 0.3
    kept = candidates[-1]
    assert kept["kept_terms"] and kept["score"] == cv["score"]
    assert cv["selection"]["chosen"]["kept_terms"] and not any(
        c.get("kept_terms") for c in candidates[:-1])
    assert "ZZ1R" in printed and "validation" in printed
    assert (out / "torques_fit.png").is_file() and (out / "torques_validation.png").is_file()


def _write_bad(tmp_path, case: str, good: str) -> str:
    arrays = dict(np.load(good, allow_pickle=False))
    path = tmp_path / f"{case}.npz"
    if case == "nan":
        arrays["torques"][5, 1] = np.nan
    elif case == "missing-key":
        del arrays["torques"]
    elif case == "ragged":
        arrays["velocities"] = arrays["velocities"][:-3]
    elif case == "joints":
        arrays = {k: (v[:, :2] if v.ndim == 2 else v) for k, v in arrays.items()}
    elif case == "times":
        arrays["times"][10] = arrays["times"][9]
    elif case == "not-data":
        path.write_text("this is not a data file\n")
        return str(path)
    elif case == "pickle":
        arrays["torques"] = np.array([object()] * 3, dtype=object)
        with open(path, "wb") as fh:
            np.savez(fh, **arrays)
        return str(path)
    elif case == "empty":
        path.write_bytes(b"")
        return str(path)
    np.savez(path, **arrays)
    return str(path)


@pytest.mark.parametrize("case, message", [
    ("nan", "torques"),
    ("missing-key", "torques"),
    ("ragged", "velocities"),
    ("joints", "3"),
    ("times", "times"),
    ("not-data", "not an .npz"),
    ("pickle", "torques"),
    ("empty", "npz"),
])
def test_bad_data_files(case, message, rs010n_files, tmp_path, capsys):
    bad = _write_bad(tmp_path, case, rs010n_files[0])
    out, js = tmp_path / "out", tmp_path / "r.json"
    status = _status(["identify", "--robot", "rs010n", "--data", bad, "--out", str(out),
                      "--json", str(js)])
    err = capsys.readouterr().err
    assert status == 2, err
    assert len(err.strip().splitlines()) == 1, err
    assert bad in err and message in err, err
    assert "Traceback" not in err
    assert not out.exists() and not js.exists()


def test_pickled_payload_is_never_executed(rs010n_files, tmp_path, capsys):
    marker = tmp_path / "executed"

    class Payload:
        def __reduce__(self):
            return (open, (str(marker), "w"))

    arrays = dict(np.load(rs010n_files[0], allow_pickle=False))
    arrays["torques"] = np.array([Payload()], dtype=object)
    path = tmp_path / "evil.npz"
    np.savez(path, **arrays)
    assert pickle.dumps(Payload())  # the payload is a real pickle
    status = _status(["identify", "--robot", "rs010n", "--data", str(path)])
    assert status == 2 and not marker.exists()
    assert "evil.npz" in capsys.readouterr().err


@pytest.mark.parametrize("argv, message", [
    (["--method", "magic"], "invalid choice: 'magic'"),
    (["--friction", "viscous-coulomb+glue"], "glue"),
    (["--robot", "nowhere.urdf"], "no such file"),
    (["--robot", "puma"], "--robot must be one of"),
    (["--data", "missing.npz"], "missing.npz"),
    (["--iterations", "0"], "expected an integer >= 1"),
    (["--cutoff-hz", "-3"], "expected a finite number > 0"),
    (["--prior-strength", "-1"], "expected a number >= 0 or 'cv'"),
    (["--prior-strength", "cv"], "--prior-strength needs --physical"),
])
def test_bad_arguments(argv, message, rs010n_files, tmp_path, capsys):
    args = {"--robot": "rs010n", "--data": rs010n_files[0], "--out": str(tmp_path / "o")}
    for flag, value in zip(argv[::2], argv[1::2]):
        args[flag] = value
    flat = [x for kv in args.items() for x in kv]
    status = _status(["identify", *flat])
    err = capsys.readouterr().err
    assert status == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "o").exists()


def test_existing_result_survives_a_failed_run(rs010n_files, tmp_path, capsys):
    js = tmp_path / "r.json"
    js.write_text('{"previous": true}\n')
    bad = _write_bad(tmp_path, "nan", rs010n_files[0])
    assert _status(["identify", "--robot", "rs010n", "--data", bad, "--json", str(js)]) == 2
    assert js.read_text() == '{"previous": true}\n'


def test_warnings_reach_stderr_as_one_line_each(tmp_path, capsys):
    """A joint that never moves leaves its friction unidentifiable: the command says so on
    stderr without --debug, one line, and still exits 0 with the minimum-norm fit."""
    robot = sj.robots.rs010n()
    t = np.arange(300) / 50.0
    q = np.column_stack([np.sin(t), 0.5 * np.cos(1.3 * t), np.full_like(t, 0.3)])
    qd = np.column_stack([np.cos(t), -0.65 * np.sin(1.3 * t), np.zeros_like(t)])
    qdd = np.column_stack([-np.sin(t), -0.845 * np.cos(1.3 * t), np.zeros_like(t)])
    data = sj.simulate_measurements(robot, q, qd, qdd, t, torque_noise=0.01, seed=4)
    path = data.save(tmp_path / "frozen.npz")
    assert cli.main(["identify", "--robot", "rs010n", "--data", str(path), "--method", "OLS"]
                    ) == 0
    err = capsys.readouterr().err.strip().splitlines()
    warning = [line for line in err if "rank deficient" in line]
    assert len(warning) == 1 and warning[0].startswith("sedsabso-jax: warning: identify:")
    assert "FC3" in warning[0] and "FV3" in warning[0]


def test_debug_is_accepted_after_the_subcommand(rs010n_files, tmp_path, capsys):
    argv = ["identify", "--robot", "rs010n", "--data", rs010n_files[0], "--method", "OLS",
            "--friction", "viscous-coulomb"]
    assert cli.main([*argv, "--debug"]) == 0
    assert cli.main(["--debug", *argv]) == 0
    with pytest.raises(FileNotFoundError):  # --debug: the exception itself, with traceback
        cli.main(["identify", "--robot", "rs010n", "--data", str(tmp_path / "none.npz"),
                  "--debug"])
    capsys.readouterr()


def test_json_creates_its_directory(rs010n_files, tmp_path):
    js = tmp_path / "new" / "deeper" / "r.json"
    assert cli.main(["identify", "--robot", "rs010n", "--data", rs010n_files[0], "--method",
                     "OLS", "--json", str(js)]) == 0
    assert json.loads(js.read_text())["settings"]["method"] == "OLS"


def test_prior_strength_chosen_by_cross_validation(rs010n_files, tmp_path, capsys):
    """``--physical --prior-strength cv``: every strength of the grid cross-validated, the
    choice and its table in the JSON and the text; the grid is the library's."""
    from sedsabso_jax.identification._validation._selection import PRIOR_STRENGTHS

    js = tmp_path / "r.json"
    assert cli.main(["identify", "--robot", "rs010n", "--data", rs010n_files[0], "--method",
                     "OLS", "--friction", "viscous-coulomb", "--physical",
                     "--prior-strength", "cv", "--json", str(js)]) == 0
    doc = json.loads(js.read_text())
    chosen = doc["cross_validation"]["prior_strength"]
    assert [c["prior_strength"] for c in chosen["candidates"]] == list(PRIOR_STRENGTHS)
    assert doc["settings"]["prior_strength"] == chosen["chosen"]
    # the RS010N's published parameters (the prior, and the data's source) are not
    # physically consistent (links 2 and 3 have negative pseudo-inertia eigenvalues), so a
    # consistent fit pulled toward them predicts worse: at most a negligible pull is
    # chosen, and from there on every stronger pull is worse
    scores = [c["score"] for c in chosen["candidates"]]
    assert chosen["chosen"] <= 1e-6 and scores[1:] == sorted(scores[1:])
    assert scores[-1] > 2 * min(scores)
    assert "pull toward the a-priori parameters" in capsys.readouterr().out


def _without_times(value):
    """A JSON document without the wall times (``seconds``, ``compile_s``, ``run_s``)."""
    if isinstance(value, dict):
        return {k: _without_times(v) for k, v in value.items()
                if k not in ("seconds", "compile_s", "run_s")}
    if isinstance(value, list):
        return [_without_times(v) for v in value]
    return value


@pytest.mark.parametrize("flags, call", [
    ([], {}),
    (["--physical", "--method", "OLS", "--weights", "equal", "--friction", "offset",
      "--prior-strength", "1e-3"],
     dict(estimators=sj.OLS(), models=sj.TorqueModel.of(sj.robots.rs010n(), [sj.Offset()]),
          physical=True, prior_strength=1e-3)),
], ids=["default", "physical"])
def test_the_command_is_one_library_call(flags, call, rs010n_files, tmp_path, capsys):
    """``sedsabso-jax identify`` prints and writes the report of
    ``sj.select_and_identify`` called with the objects its flags stand for."""
    js = tmp_path / "r.json"
    assert cli.main(["identify", "--robot", "rs010n", "--data", rs010n_files[0],
                     "--validate", rs010n_files[1], *flags, "--json", str(js)]) == 0
    printed = capsys.readouterr().out
    doc = json.loads(js.read_text())
    data, held_out = (sj.load_measurements(p, n_joints=3) for p in rs010n_files)
    report = sj.select_and_identify(sj.robots.rs010n(), data, held_out=held_out, **call)
    assert printed == f"{report.text()}\nwritten: {js}\n"
    cli_settings = {k: doc["settings"][k] for k in ("robot", "data", "validate",
                                                     "torque_limits", "loading", "motor_side")}
    assert _without_times(doc) == _without_times(report.document(cli_settings))
    # default: OLS and Gautier's WLS (no limits known), 5 torque models, both kinds, then
    # friction at rest added to the choice
    assert len(report.selection.candidates) == (1 if call else 21)


def test_select_and_identify_checks_its_arguments(rs010n_files):
    robot = sj.robots.rs010n()
    data = sj.load_measurements(rs010n_files[0], n_joints=3)
    one = dict(estimators=sj.OLS(), models=sj.TorqueModel.of(robot, [sj.Offset()]))
    for kwargs, match in [
            (dict(prior_strength=1e-3), "^prior_strength needs physical=True: the pull to the "
             "a-priori parameters is part of the physically consistent fit$"),
            (dict(validation=None), "^validation=None turns validation off, so nothing can be "
             "chosen by it: give one estimator and one torque model$"),
            (dict(physical=True, estimators=sj.L1()), "^a physically consistent fit is a "
             "least-squares fit: use method 'OLS' or 'WLS', not 'L1'$"),
            (dict(physical=True, prior_strength="cv", validation=None, **one),
             r"^prior_strength='cv' chooses by validation, which validation=None turns off: "
             r"give a number$"),
            (dict(physical="yes"), "^physical must be None"),
            (dict(physical=True, prior_strength=-1.0), "^prior_strength must be a number >= 0 "
             "or 'cv', got -1.0$"),
            (dict(validation=sj.RecordingFolds()), r"^validation \(recording folds\) needs "
             r"several recordings$"),
            (dict(models="viscous-coulomb+offset", **{k: v for k, v in one.items()
                                                      if k != "models"}),
             "^model must be a TorqueModel")]:
        with pytest.raises((ValueError, TypeError), match=match):
            sj.select_and_identify(robot, data, **kwargs)


def test_the_command_asks_the_library_for_its_rules():
    """The command's flags go through the library's Choice (its rules, the flags' names):
    the same one-line errors, before any data are read."""
    from sedsabso_jax.identification import Choice, DefaultValidation

    with pytest.raises(ValueError, match="^--prior-strength needs --physical"):
        Choice(prior_strength=1e-3, flags=True)
    with pytest.raises(ValueError, match="^--folds 0 turns validation off"):
        Choice(None, candidates=2, flags=True)
    with pytest.raises(ValueError, match=r"^one torque offset per recording needs several "
                                         r"recordings$"):
        Choice(offset_per_recording=True)
    with pytest.raises(ValueError, match=r"^folds must be an integer >= 2, got 1$"):
        DefaultValidation(1)
    assert Choice(None, candidates=1).validation is None
    assert DefaultValidation(3).of([None]).settings() == sj.Pooled(
        (sj.PhaseFolds(3), sj.SpeedSplits())).settings()
    assert DefaultValidation().of([None, None]).settings() == sj.Pooled(
        (sj.RecordingFolds(), sj.SpeedSplits())).settings()


def test_estimator_candidates_are_the_commands_policy():
    """--method and --weights to candidates: OLS / WLS by default, a fixed method with each
    weighting (WLS's None is its residual weighting), a box search alone (costly)."""
    from sedsabso_jax.identification import estimator_candidates as candidates

    assert candidates() == (sj.OLS(), sj.WLS("residual"), sj.WLS("limits"))
    assert candidates(sigma="equal") == (sj.OLS(),)
    assert candidates(sigma="limits") == (sj.WLS("limits"),)
    assert candidates("L1") == (sj.L1(), sj.L1("residual"), sj.L1("limits"))
    assert candidates("WLS") == (sj.WLS("residual"), sj.WLS("limits"))
    assert candidates("LM", "residual", runs=3) == (sj.LevenbergMarquardt("residual"),)
    assert candidates("SEDSABSO", runs=2, iterations=9, seed=4) == (
        sj.BoxSearch(sj.SEDSABSO.paper(), runs=2, iterations=9, seed=4),)
    with pytest.raises(ValueError, match="sigma must be 'auto'"):
        candidates("OLS", "robust")
