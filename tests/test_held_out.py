"""Several held-out recordings (``select_and_identify(..., held_out=[...] or {...})``,
``identify --validate FILE [FILE ...]``): each judged alone, never fitted to, and their
mean, against figures the test computes from each recording itself; a bad entry named."""

from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pytest

import sedsabso_jax as sj
from benchmarks.extrapolation import dahl
from sedsabso_jax import cli
from sedsabso_jax.identification import extrapolation, rests

ROBOT = sj.robots.rs010n()
#: Torque limits given in Python (the RS010N's model has none): the NRMS over them is the
#: validation's measure.
LIMITS = np.array([300.0, 300.0, 150.0])
#: One candidate, validated by the default validation: a fit in a second.
FAST = dict(estimators=sj.OLS(), models=sj.TorqueModel.of(ROBOT), physical=False)
FAST_FLAGS = ["--friction", "viscous-coulomb", "--method", "OLS", "--weights", "equal",
              "--no-physical"]


def _recording(q: np.ndarray, t: np.ndarray, seed: int) -> sj.Measurements:
    """The RS010N along ``q``, with friction at rest its model lacks (Dahl's, 2 N m over
    5 mrad: the error grows where it rests) and 2 % torque noise."""
    qd = np.gradient(q, t, axis=0)
    qdd = np.gradient(qd, t, axis=0)
    tau = np.asarray(sj.inverse_dynamics(ROBOT, ROBOT.params, q, qd, qdd))
    tau = tau + 2.0 * dahl(q, np.full(3, 5e-3)) + 0.5 * qd
    tau += 0.02 * np.sqrt(np.mean(tau ** 2, 0)) * np.random.default_rng(seed).standard_normal(
        tau.shape)
    return sj.Measurements(t, q, qd, qdd, tau)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """An excitation to fit (1500 samples), a second excitation (600 samples) and a motion
    with dwells that rests much more (400 samples: lengths differ, so a mean weighed by
    samples is not the mean), each also as a file."""
    t = np.arange(1500) / 100.0
    w = 2 * np.pi / 7.5
    fit = _recording(0.8 * np.sin(w * t[:, None] * [1, 2, 3] + [0, 1, 2]), t, 0)
    t2 = t[:600]
    other = _recording(0.7 * np.sin(1.3 * w * t2[:, None] * [1, 1.5, 2] + [2, 0, 1]), t2, 1)
    t3 = t[:400]
    stops = 0.6 * np.clip(2 * np.sin(w * t3[:, None] * [1, 1.5, 2]), -1, 1) + 0.1
    resting = _recording(stops, t3, 2)
    d = tmp_path_factory.mktemp("held_out")
    paths = [str(m.save(d / f"{name}.npz")) for name, m in
             (("fit", fit), ("other", other), ("resting", resting))]
    return (fit, other, resting), paths


@pytest.fixture(scope="module")
def two(runs):
    """The default's report with two held-out recordings given by name, and one without."""
    (fit, other, resting), _ = runs
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        report = sj.select_and_identify(ROBOT, fit, held_out={"other": other, "resting": resting},
                                        limits=LIMITS, **FAST)
    alone = sj.select_and_identify(ROBOT, fit, limits=LIMITS, **FAST)
    return report, alone, [str(w.message) for w in caught]


def test_each_recording_is_judged_alone_and_never_fitted(runs, two):
    (fit, other, resting), _ = runs
    report, alone, _ = two
    # never fitted to nor choosing: the same fit and validation as without held-out data
    np.testing.assert_array_equal(report.ident.values, alone.ident.values)
    assert report.cross_validation.score == alone.cross_validation.score
    assert [h.name for h in report.validations] == ["other", "resting"]
    cv = report.cross_validation
    for h, m in zip(report.validations, (other, resting)):
        own = sj.validation_metrics(m.tau, alone.ident.predict(m.q, m.qd, m.qdd), LIMITS)
        assert h.data is m and h.measured == own.nrms_limits_percent
        np.testing.assert_allclose(h.metrics.rms, own.rms, rtol=1e-12)
        weighed = rests(fit, m, cross_validation=cv, limits=LIMITS)
        assert h.rests.predicted == pytest.approx(weighed.predicted, rel=1e-12)
        np.testing.assert_array_equal(h.extrapolation.speed_ratio,
                                      extrapolation(fit, m).speed_ratio)
    # the motion with dwells rests more: its prediction is weighed up, the other's not
    assert report.validations[1].rests.factor > 1.2 > report.validations[0].rests.factor
    # several: the single recording's fields are empty, each is in validations
    assert report.held_out is None and report.rests is None and report.extrapolation is None


def test_the_mean_is_the_mean_of_the_recordings(runs, two):
    (_, other, resting), _ = runs
    report, alone, _ = two
    own = [sj.validation_metrics(m.tau, alone.ident.predict(m.q, m.qd, m.qdd), LIMITS)
           for m in (other, resting)]
    mean = report.validation
    assert mean.nrms_limits_percent == pytest.approx(
        (own[0].nrms_limits_percent + own[1].nrms_limits_percent) / 2, rel=1e-12)
    assert mean.relative_rms_percent_overall == pytest.approx(
        (own[0].relative_rms_percent_overall + own[1].relative_rms_percent_overall) / 2,
        rel=1e-12)
    np.testing.assert_allclose(mean.rms, (own[0].rms + own[1].rms) / 2, rtol=1e-12)
    assert mean.n_samples == 600 + 400
    predicted = [h.rests.predicted for h in report.validations]
    doc = report.document({})
    held = doc["validations"]
    assert [r["name"] for r in held["recordings"]] == ["other", "resting"]
    assert held["measure"] == "nrms_limits_percent"
    assert held["mean"]["measured_percent"] == pytest.approx(mean.nrms_limits_percent,
                                                             rel=1e-12)
    assert held["mean"]["predicted_percent"] == pytest.approx(np.mean(predicted), rel=1e-12)
    assert doc["validation"]["nrms_limits_percent"] == held["mean"]["metrics"][
        "nrms_limits_percent"]
    assert doc["extrapolation"] is None and doc["rests"] is None
    # the text: a section per recording, then a row each and the mean's
    text = report.text()
    assert "validation on other (arrays, 600 samples):" in text
    assert "rests on resting (the share of its samples" in text
    rows = {cells[0]: cells for line in text.splitlines()
            if (cells := [c.strip() for c in line.strip("|").split("|")])[0]
            in ("other", "resting", "mean")}
    assert rows["mean"][5] == f"{(own[0].nrms_limits_percent + own[1].nrms_limits_percent) / 2:.4f}"
    assert rows["mean"][6] == f"{np.mean(predicted):.4f}"
    assert rows["resting"][6] == f"{predicted[1]:.4f}"
    assert rows["other"][1] == "600" and rows["mean"][1] == "1000"


def test_warnings_name_their_recording(two):
    _, _, messages = two
    resting = [m for m in messages if "rests or moves slowly more" in m]
    assert len(resting) == 1 and resting[0].startswith("resting: "), messages


def test_one_recording_as_before(runs, two):
    """One held-out recording, in a list or alone: the report of before (its fields, the
    text's sections, the JSON's keys), the same figures as among several."""
    (fit, other, _), _ = runs
    report, alone, _ = two
    single = sj.IdentificationReport.evaluate(alone.ident, fit, other, LIMITS,
                                              cross_validation=alone.cross_validation)
    listed = sj.IdentificationReport.evaluate(alone.ident, fit, [other], LIMITS,
                                              cross_validation=alone.cross_validation)
    assert single.text() == listed.text()
    assert single.held_out is other and single.rests is not None
    assert single.validation.nrms_limits_percent == report.validations[0].measured
    text = single.text()
    assert "validation (arrays, 600 samples):" in text and "held-out recordings" not in text
    doc = single.document({})
    assert doc["validation"] == doc["validations"]["recordings"][0]["metrics"]
    assert doc["rests"] == doc["validations"]["recordings"][0]["rests"]
    assert set(single.figures()) == {"torques_fit.png", "torques_validation.png"}
    assert set(report.figures()) == {"torques_fit.png", "torques_validation_1.png",
                                     "torques_validation_2.png"}


def test_names_from_the_sources(runs, two):
    (fit, other, resting), paths = runs
    _, alone, _ = two
    loaded = [sj.load_measurements(p, n_joints=3) for p in paths[1:]]

    def names(held_out):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            report = sj.IdentificationReport.evaluate(alone.ident, fit, held_out, LIMITS)
        return [h.name for h in report.validations]

    assert names(loaded) == paths[1:]          # the files' paths
    assert names((other, resting)) == ["held-out 1", "held-out 2"]  # both "arrays"


@pytest.mark.parametrize("bad, message", [
    (lambda o, r: [o, "resting.npz"],
     r"held_out\[1\]: expected a Measurements \(sj.load_measurements\(path\) reads a file\), "
     r"got str"),
    (lambda o, r: [o, sj.Measurements(r.times, r.q[:, :2], r.qd[:, :2], r.qdd[:, :2],
                                      r.tau[:, :2])],
     r"held_out\[1\] \(arrays\): q must have shape \(samples, 3\)"),
    (lambda o, r: {"other": o, "resting": None}, r"held_out\['resting'\]: expected a "),
    (lambda o, r: {"": o}, r"held_out: a mapping's keys name its recordings, got ''"),
    (lambda o, r: [], r"held_out: empty; give None"),
])
def test_a_bad_entry_is_named_before_any_work(bad, message, runs):
    (fit, other, resting), _ = runs
    calls = []
    with pytest.raises(ValueError, match=message):
        sj.select_and_identify(ROBOT, fit, held_out=bad(other, resting), limits=LIMITS,
                               progress=lambda *a: calls.append(a), **FAST)
    assert calls == []  # no fit made


def test_the_command_reports_each_file_and_the_mean(runs, tmp_path, capsys):
    (fit, other, resting), paths = runs
    out, js = tmp_path / "out", tmp_path / "r.json"
    assert cli.main(["identify", "--robot", "rs010n", "--data", paths[0], "--validate",
                     paths[1], paths[2], *FAST_FLAGS, "--out", str(out), "--json",
                     str(js)]) == 0
    printed, err = capsys.readouterr()
    doc = json.loads(js.read_text())
    held = doc["validations"]
    assert [r["name"] for r in held["recordings"]] == paths[1:]
    assert doc["settings"]["validate"] == paths[1:]
    # RS010N: no torque limits, the measure is the relative RMS error
    assert held["measure"] == "relative_rms_percent"
    model = sj.TorqueModel.of(ROBOT)
    fitted = sj.identify(ROBOT, fit, sj.OLS(), model)
    own = [sj.validation_metrics(m.tau, fitted.predict(m.q, m.qd, m.qdd))
           .relative_rms_percent_overall for m in (other, resting)]
    measured = [r["measured_percent"] for r in held["recordings"]]
    np.testing.assert_allclose(measured, own, rtol=1e-9)
    assert held["mean"]["measured_percent"] == pytest.approx(np.mean(own), rel=1e-9)
    assert doc["validation"]["relative_rms_percent_overall"] == pytest.approx(np.mean(own),
                                                                              rel=1e-9)
    for path in paths[1:]:
        assert f"validation on {path} (600 samples)" in printed or (
            f"validation on {path} (400 samples)" in printed)
    assert re.search(rf"\| mean +\| +1000 \|.*\| +{np.mean(own):.3f} \|", printed), printed
    assert f"sedsabso-jax: warning: {paths[2]}: the new motion rests" in err, err
    assert {p.name for p in out.iterdir()} == {"torques_fit.png", "torques_validation_1.png",
                                               "torques_validation_2.png",
                                               "identification.json"}


@pytest.mark.parametrize("second, message", [
    ("missing.npz", "missing.npz: no such file"),
    ("two-joints", "field 'positions': expected 3 joints"),
    ("again", "--validate: {again} is given twice"),
])
def test_a_bad_file_in_the_command(second, message, runs, tmp_path, capsys):
    _, paths = runs
    if second == "two-joints":
        arrays = {k: (v[:, :2] if v.ndim == 2 else v) for k, v in np.load(paths[1]).items()}
        second = str(tmp_path / "two.npz")
        np.savez(second, **arrays)
    elif second == "again":
        second = paths[1].replace("/held_out", "/./held_out", 1)
    out, js = tmp_path / "out", tmp_path / "r.json"
    try:
        status = cli.main(["identify", "--robot", "rs010n", "--data", paths[0], "--validate",
                           paths[1], second, *FAST_FLAGS, "--out", str(out), "--json",
                           str(js)])
    except SystemExit as exit_:
        status = exit_.code
    err = capsys.readouterr().err
    assert status == 2, err
    assert len(err.strip().splitlines()) == 1 and message.format(again=second) in err, err
    assert second in err and not out.exists() and not js.exists()
