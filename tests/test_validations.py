"""Validations (speed splits, phase folds, leave one recording out), the fits on normal
equations they use, several recordings with one offset each, and friction that stays
physical beyond the fitted speeds. References: numpy's least squares and closed-form
masks, never the package's own fits."""

from __future__ import annotations

import json

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax import cli
from sedsabso_jax.identification import FitProblem
from sedsabso_jax.identification._estimators._programme import _programme
from sedsabso_jax.identification._fit._samples import Samples


def _status(argv) -> int:
    try:
        return cli.main(argv)
    except SystemExit as exit_:
        return exit_.code


def _run(seed: int, *, n=1200, rate=100.0, offset=(0.0, 0.0, 0.0), speed=1.0, noise=0.02,
         friction=None) -> sj.Measurements:
    """RS010N along a smooth random motion, with torque noise, a torque offset and, when
    given, ``friction(qd)`` added to the torques."""
    robot = sj.robots.rs010n()
    rng = np.random.default_rng(seed)
    traj = sj.FourierTrajectory(rng.uniform(-0.4, 0.4, (3, 3)) * speed,
                                rng.uniform(-0.4, 0.4, (3, 3)) * speed, np.zeros(3),
                                wf=0.6 * speed)
    times = np.arange(n) / rate
    data = sj.simulate_measurements_along(robot, traj, times, torque_noise=noise, seed=seed)
    tau = data.tau + np.asarray(offset) + (0.0 if friction is None else friction(data.qd))
    return sj.Measurements(data.times, data.q, data.qd, data.qdd, tau, source=f"run {seed}")


# --------------------------------------------------------------------------- the splits
def test_speed_splits_are_the_documented_masks():
    data = _run(1)
    splits = sj.SpeedSplits(0.5, 0.6).splits([data])
    peak = np.quantile(np.abs(data.qd), 0.995, axis=0)
    assert len(splits) == 3 and splits.labels is None
    for j in range(3):
        np.testing.assert_array_equal(splits.train[j], np.abs(data.qd[:, j]) < 0.5 * peak[j])
        np.testing.assert_array_equal(splits.test[j], np.abs(data.qd[:, j]) > 0.6 * peak[j])
    assert splits.names == ("joint 1 faster", "joint 2 faster", "joint 3 faster")
    with pytest.raises(ValueError, match="0 < fit_below <= predict_above < 1"):
        sj.SpeedSplits(0.8, 0.7)
    with pytest.raises(ValueError, match="0 < fit_below <= predict_above < 1"):
        sj.SpeedSplits(0.0, 0.5)


def test_recording_folds_leave_one_recording_out():
    a, b = _run(1, n=300), _run(2, n=200)
    splits = sj.RecordingFolds().splits([a, b])
    np.testing.assert_array_equal(splits.labels, np.r_[np.zeros(300), np.ones(200)])
    np.testing.assert_array_equal(splits.test[1], np.r_[np.zeros(300), np.ones(200)] == 1)
    with pytest.raises(ValueError, match="needs at least 2 recordings"):
        sj.RecordingFolds().splits([a])
    with pytest.raises(TypeError, match="validation must be a Validation"):
        sj.cross_validate(sj.robots.rs010n(), a, validation="speed")


def test_pooled_splits_are_both_validations_and_score_each_part():
    """The default's validation: the phase folds' and the speed splits' splits together;
    the score is the mean over all of them, and each part's mean is reported."""
    data = _run(2)
    pooled = sj.Pooled((sj.PhaseFolds(4), sj.SpeedSplits()))
    splits = pooled.splits([data])
    phase, speed = sj.PhaseFolds(4).splits([data]), sj.SpeedSplits().splits([data])
    assert splits.names == phase.names + speed.names
    assert splits.parts == ("phase folds",) * 4 + ("speed splits",) * 3
    for a, b in zip(splits.test, phase.test + speed.test):
        np.testing.assert_array_equal(a, b)
    robot = sj.robots.rs010n()
    model = sj.TorqueModel.of(robot, (sj.Offset(),))
    cv = sj.cross_validate(robot, data, sj.OLS(), model, validation=pooled)
    alone = {v.kind: sj.cross_validate(robot, data, sj.OLS(), model, validation=v).score
             for v in pooled.validations}
    assert cv.part_scores == pytest.approx(alone, rel=1e-12)
    assert cv.score == pytest.approx((4 * alone["phase folds"] + 3 * alone["speed splits"]) / 7)
    with pytest.raises(ValueError, match="Pooled needs at least two validations"):
        sj.Pooled((sj.PhaseFolds(),))


def test_the_rule_prefers_the_physically_consistent_fit_within_a_standard_error():
    """RS010N data from its own (physical) parameters with 5 % torque noise: the
    unconstrained fit scores lowest by a hair, the physically consistent one, as simple
    and within one standard error, is chosen."""
    data = _run(3, noise=0.05)
    sel = sj.select_model(sj.robots.rs010n(), data,
                          estimators=(sj.OLS(), sj.PhysicallyConsistent()),
                          models=sj.TorqueModel.of(sj.robots.rs010n()),
                          validation=sj.Pooled((sj.PhaseFolds(), sj.SpeedSplits())))
    assert sel.best["physical"] is False and sel.chosen["physical"] is True
    assert isinstance(sel.estimator, sj.PhysicallyConsistent)


# ---------------------------------------------------------- fits on the normal equations
def subset_problems(model, data, limits, masks):
    """The compressed problems of a validation's subsets (the whole's rows at hand, so that
    a subset that is most of the samples takes the whole's normal equations less the
    rows it leaves out)."""
    samples = Samples(data.q, data.qd, data.qdd, data.tau)
    samples.rows(model)
    return [samples.split(mask).problem(model, limits) for mask in masks]


@pytest.mark.parametrize("sigma", [None, "residual", "limits"])
def test_fits_on_normal_equations_are_least_squares_on_the_rows(sigma):
    """A validation's subset fits, from the normal equations of all rows minus the
    left-out ones, equal numpy's least squares on the subset's rows, weighted by each
    joint's sigma (Gautier's: the RMS of its OLS residual over T - d_j, d_j the columns
    acting on the joint) to 1e-9."""
    data = _run(3, noise=0.2)
    limits = np.array([300.0, 200.0, 50.0])
    model = sj.TorqueModel.of(sj.robots.rs010n(), (sj.Offset(),))
    Y = model.regressor(data.q, data.qd, data.qdd)
    keep = np.arange(len(Y)) % 4 != 0  # most samples: all minus the left-out rows
    slow = np.abs(data.qd[:, 0]) < 0.3 * np.abs(data.qd[:, 0]).max()  # a minority
    for mask, problem in zip((keep, slow), subset_problems(model, data, limits,
                                                           [keep, slow])):
        Ys, tau = Y[mask], data.tau[mask]
        if sigma is None:
            s = np.ones(3)
        elif sigma == "limits":
            s = limits
        else:
            x0 = np.linalg.lstsq(Ys.reshape(-1, Ys.shape[-1]), tau.reshape(-1), rcond=None)[0]
            d_j = np.count_nonzero(np.any(Ys != 0, axis=0), axis=-1)
            s = np.sqrt(np.sum((Ys @ x0 - tau) ** 2, axis=0) / (len(Ys) - d_j))
        W = (Ys / s[:, None]).reshape(-1, Ys.shape[-1])
        reference = np.linalg.lstsq(W, (tau / s).reshape(-1), rcond=None)[0]
        x = sj.WLS(sigma).fit(problem).x if sigma else sj.OLS().fit(problem).x
        np.testing.assert_allclose(Y @ x, Y @ reference, atol=1e-9 * np.abs(data.tau).max())


def test_physical_fit_is_the_same_on_rows_and_normal_equations_and_repeats_exactly():
    """The conic fit reads the rows only through their factor: on the normal equations it
    gives the rows' fit (1e-7 of the torques), and the same call twice gives the same
    numbers to the last bit, the first after the programme is built included."""
    data = _run(4, noise=0.2)
    model = sj.TorqueModel.of(sj.robots.rs010n(), (sj.Offset(),))
    Y = model.regressor(data.q, data.qd, data.qdd)
    mask = np.abs(data.qd[:, 1]) < 0.7 * np.abs(data.qd[:, 1]).max()
    estimator = sj.PhysicallyConsistent(sj.WLS("residual"), prior_strength=1e-4)
    _programme.cache_clear()
    rows = [estimator.fit(FitProblem(model, Y[mask], data.tau[mask], warn=False)).x
            for _ in range(2)]
    compressed = estimator.fit(subset_problems(model, data, None, [mask])[0]).x
    np.testing.assert_array_equal(rows[0], rows[1])
    np.testing.assert_allclose(Y @ compressed, Y @ rows[0], atol=1e-7 * np.abs(data.tau).max())



def test_a_split_predicts_each_model_with_its_own_rows():
    """A split keeps the rows of the last model it predicted (a validation's estimators
    predict one model in turn): models that read their fitted values (the load), taken in
    turn and again, each give their own torques on the split (numpy on the split's
    samples, from the model's own regressor)."""
    data = _run(7, noise=0.05)
    robot = sj.robots.rs010n()
    samples = Samples.of(robot, data)
    test = samples.split(np.arange(data.n_samples) % 3 == 0)
    models = [sj.TorqueModel.of(robot, terms) for terms in (
        (sj.Offset(), sj.LoadFriction()), (sj.LoadFriction(viscous=True),))]
    rng = np.random.default_rng(0)
    values = [rng.normal(size=m.dim) for m in models]
    for k in (0, 1, 0, 1):
        expected = models[k].predict(values[k], test.q, test.qd, test.qdd)
        np.testing.assert_allclose(test.predict(models[k], values[k]), expected,
                                   rtol=1e-12, atol=1e-12)

# ----------------------------------------------------------------- several recordings
def test_one_offset_per_recording():
    """Two recordings whose torque sensors' zeros differ (+2 and -1 N m on joint 1, whose
    vertical axis sees no gravity to confound them): with one offset per recording both
    are found (OFF1.1, OFF1.2), new motions are predicted with their mean, and the fit is
    far better than with one offset for both."""
    robot = sj.robots.rs010n()
    a = _run(5, offset=(2.0, 0.5, 0.0), noise=0.002)
    b = _run(6, offset=(-1.0, 0.5, 0.0), noise=0.002)
    per = sj.identify(robot, [a, b], sj.OLS(), sj.TorqueModel.of(robot, [sj.Offset()],
                                                                   recordings=2))
    values = dict(zip(per.names, per.values))
    assert per.model.friction == "viscous-coulomb+offset" and per.model.recordings == 2
    assert values["OFF1.1"] == pytest.approx(2.0, abs=0.01)
    assert values["OFF1.2"] == pytest.approx(-1.0, abs=0.01)
    q = np.zeros((1, 3))
    mean = per.predict(q, q, q) - per.model.predict(per.values, q, q, q, np.array([0]))
    expected = (values["OFF1.1"] + values["OFF1.2"]) / 2 - values["OFF1.1"]
    assert mean[0, 0] == pytest.approx(expected, abs=1e-9)
    one = sj.identify(robot, [a, b], sj.OLS(), sj.TorqueModel.of(robot, [sj.Offset()]))
    assert one.fit["rms"][0] > 10 * per.fit["rms"][0]
    with pytest.raises(ValueError, match=r"^the torque model has one offset per recording for "
                                         r"2 recordings; the data hold 1$"):
        sj.identify(robot, a, sj.OLS(), per.model)
    with pytest.raises(ValueError, match="^one torque offset per recording needs several "
                                         "recordings$"):
        sj.select_and_identify(robot, a, models=per.model, estimators=sj.OLS())


def test_several_recordings_must_share_robot_and_rate():
    robot = sj.robots.rs010n()
    a, slow = _run(1), _run(2, rate=50.0)
    with pytest.raises(ValueError, match=r"different sampling rates \(run 1: 100 Hz, run 2: "
                                         r"50 Hz\)"):
        sj.identify(robot, [a, slow])
    wrong = sj.Measurements(a.times, a.q[:, :2], a.qd[:, :2], a.qdd[:, :2], a.tau[:, :2],
                            source="two joints")
    with pytest.raises(ValueError, match=r"recording 2 \(two joints\) has 2 joints"):
        sj.select_and_identify(robot, [a, wrong])


def test_command_fits_several_files_and_leaves_one_out(tmp_path, capsys):
    a = _run(7, offset=(1.0, 0.0, 0.0)).save(tmp_path / "a.npz")
    b = _run(8, offset=(-1.0, 0.0, 0.0)).save(tmp_path / "b.npz")
    js = tmp_path / "r.json"
    assert cli.main(["identify", "--robot", "rs010n", "--data", str(a), str(b),
                     "--offset-per-recording", "--method", "OLS", "--weights", "equal",
                     "--friction", "viscous-coulomb", "--json", str(js)]) == 0
    doc = json.loads(js.read_text())
    assert doc["settings"]["data"] == [str(a), str(b)]
    assert {"OFF1.1", "OFF1.2"} <= set(doc["base_parameters"]["names"])
    cv = doc["cross_validation"]
    assert [v["kind"] for v in cv["validation"]["validations"]] == ["recording folds",
                                                                    "speed splits"]
    assert cv["splits"][:2] == [f"recording 1 ({a})", f"recording 2 ({b})"]
    assert set(cv["part_scores"]) == {"recording folds", "speed splits"}
    assert "by kind of split: recording folds " in capsys.readouterr().out


@pytest.mark.parametrize("rate, joints, extra, message", [
    (50.0, 3, [], "different sampling rates"),
    (100.0, 2, [], "b.npz: field 'positions': expected 3 joints"),
    (100.0, 3, ["--offset-per-recording"], "needs several --data files"),
    (100.0, 3, ["--validation", "recordings"], "needs several --data files"),
])
def test_bad_several_files(rate, joints, extra, message, tmp_path, capsys):
    a = _run(1).save(tmp_path / "a.npz")
    d = _run(2, rate=rate)
    b = sj.Measurements(d.times, d.q[:, :joints], d.qd[:, :joints], d.qdd[:, :joints],
                        d.tau[:, :joints]).save(tmp_path / "b.npz")
    files = [str(a), str(b)] if not extra else [str(a)]
    out = tmp_path / "out"
    assert _status(["identify", "--robot", "rs010n", "--data", *files, *extra,
                    "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and not out.exists()


# ------------------------------------------------------- friction beyond fitted speeds
def test_physical_friction_stays_physical_beyond_the_fitted_speeds():
    """Friction that saturates with speed (5 tanh(qd / 0.3) N m on every joint): the
    unconstrained quadratic term fits it with a negative coefficient, so its friction
    torque turns against the motion at 3x the fitted speed; the physically consistent
    fit keeps every Coulomb, viscous and quadratic coefficient >= 0, and its friction
    torque opposes the motion at any speed."""
    robot = sj.robots.rs010n()
    data = _run(9, friction=lambda qd: 5.0 * np.tanh(qd / 0.3))
    model = sj.TorqueModel.of(robot, [sj.Quadratic()])
    free = sj.identify(robot, data, sj.OLS(), model)
    physical = sj.identify(robot, data, sj.PhysicallyConsistent(), model)

    def friction_torque(fit, speed):
        v = dict(zip(fit.names, fit.values))
        return np.array([v[f"FC{j}"] + v[f"FV{j}"] * speed + v[f"FQ{j}"] * speed ** 2
                         for j in (1, 2, 3)])

    peak = np.abs(data.qd).max()
    assert np.any(friction_torque(free, 3 * peak) < 0)  # the planted failure shows
    v = dict(zip(physical.names, physical.values))
    assert min(v[f"{k}{j}"] for k in ("FC", "FV", "FQ") for j in (1, 2, 3)) >= 0
    assert np.all(friction_torque(physical, 10 * peak) > 0)


def test_splits_fitted_at_once_give_the_numbers_fitted_in_turn(monkeypatch):
    """A validation's splits are fitted on several threads at once: each split's fit
    (a searched Coulomb shape, the physically consistent conic fit) and its scores are
    those of the splits fitted one after another, in the splits' order, to the bit."""
    from sedsabso_jax.identification._validation._cross_validation import (
        THREADS_VARIABLE,
        split_threads,
    )

    data = _run(11, noise=0.1, friction=lambda qd: 2.0 * np.tanh(qd / 0.05))
    robot = sj.robots.rs010n()
    model = sj.TorqueModel.of(robot, (sj.SmoothCoulomb(fitted=True), sj.Offset()))
    estimator = sj.PhysicallyConsistent(sj.WLS("residual"))
    validations = {}
    for workers in (1, 4):
        monkeypatch.setenv(THREADS_VARIABLE, str(workers))
        validations[workers] = sj.cross_validate(robot, data, estimator, model,
                                                 validation=sj.PhaseFolds(6))
    in_turn, at_once = validations[1], validations[4]
    assert np.asarray(in_turn.fold_scores).tobytes() == np.asarray(at_once.fold_scores).tobytes()
    assert in_turn.residuals.tobytes() == at_once.residuals.tobytes()
    np.testing.assert_array_equal(in_turn.tested, at_once.tested)
    for bad in ("0", "two", "-1"):
        monkeypatch.setenv(THREADS_VARIABLE, bad)
        with pytest.raises(ValueError, match=f"{THREADS_VARIABLE} must be a whole number"):
            split_threads()


def test_searches_on_threads_at_once_do_not_wait_on_each_other():
    """Two threads each evaluating populations of 98 trials whose losses form a 21 x 21
    Gram matrix and factorise it (as the searches of a validation's splits do with 21
    moved columns): the Cholesky then runs on one of XLA's intra-op threads (after the
    products) and waits there for the parts of its batch it gave the others, so two at
    once on 2 cores waited on each other for ever; ``losses`` takes turns and both
    finish. Each thread's losses are those of one thread alone."""
    import threading

    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from sedsabso_jax.identification._search._problem import losses

    class Gram(eqx.Module):
        X: jax.Array
        g: jax.Array

        def loss(self, u):
            Y = self.X * jnp.exp(u[0] * jnp.linspace(0.0, 1.0, self.X.shape[1]))
            factor = jax.scipy.linalg.cho_factor(Y.T @ Y)
            return self.g @ jax.scipy.linalg.cho_solve(factor, self.g)

    rng = np.random.default_rng(0)
    problem = Gram(jnp.asarray(rng.standard_normal((200, 21))), jnp.ones(21))
    U = rng.standard_normal((98, 3))
    alone = losses(problem, U)
    done = [0, 0]

    def evaluate(i):
        for _ in range(200):
            assert losses(problem, U).tobytes() == alone.tobytes()
            done[i] += 1

    threads = [threading.Thread(target=evaluate, args=(i,), daemon=True) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert done == [200, 200]
