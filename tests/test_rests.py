"""Friction at rest in the default (``sj.identification.KeptTerms``, ``KEPT_TERMS``) and
the report on motions that rest (``sj.identification.rests``): shares and the weighed
error against closed forms, the kept terms' rule on hand-made validations, and the
default on a simulated arm whose joints hold friction at rest."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import sedsabso_jax as sj
from benchmarks.extrapolation import dahl
from sedsabso_jax import cli
from sedsabso_jax.identification import KEPT_TERMS, CrossValidation, KeptTerms, rests
from sedsabso_jax.identification._metrics import validation_metrics


def _motion(qd: np.ndarray, tau: np.ndarray | None = None) -> sj.Measurements:
    qd = np.asarray(qd, float)
    q = np.cumsum(qd, axis=0) / 100.0
    return sj.Measurements(np.arange(len(qd)) / 100.0, q, qd, np.zeros_like(qd),
                           np.ones_like(qd) if tau is None else tau)


def _speeds(fast: int, slow: int, still: int) -> np.ndarray:
    """One joint: ``fast`` samples at 1 rad/s, ``slow`` at 0.05 (slow), ``still`` at 0."""
    return np.r_[np.ones(fast), np.full(slow, 0.05), np.zeros(still)][:, None]


def test_shares_are_counted_against_the_fitted_peak():
    fit = _motion(_speeds(900, 50, 50))           # peak 1: 5 % at rest, 10 % slow
    # speeds 0.2, 0.05 and 0 against the fitted peak 1: 50 % at rest (below 0.02),
    # 60 % slow (below 0.1)
    new = _motion(np.r_[np.full(400, 0.2), np.full(100, 0.05), np.zeros(500)][:, None])
    found = rests(fit, new, joint_names=["j"])
    assert found.rest_share[0] == pytest.approx(0.05)
    assert found.slow_share[0] == pytest.approx(0.10)
    assert found.new_rest_share[0] == pytest.approx(0.50)
    assert found.new_slow_share[0] == pytest.approx(0.60)
    assert found.flagged() == [0] and found.factor is None
    with pytest.warns(UserWarning, match=r"j at rest 50 % \(fitted 5 %\), slow 60 % \(10 %\)"):
        rests(fit, new, joint_names=["j"], warn=True)
    same = rests(fit, fit)
    assert same.flagged() == [] and same.message() is None


def _validation(residual: np.ndarray) -> CrossValidation:
    """A validation that predicted every sample once with ``residual``."""
    tau = np.zeros_like(residual)
    return CrossValidation(metrics=validation_metrics(residual, tau, None),
                           fold_scores=np.array([2.0, 2.0]), period_s=None, folds=None,
                           n_parameters=1, settings={}, residuals=residual,
                           tested=np.arange(len(residual)))


def test_weighed_error_is_the_closed_form():
    """Residual 3 at rest, 1 moving; fitted 5 % at rest, new 50 %: the factor is
    sqrt(0.5 * 9 + 0.5 * 1) / sqrt(0.05 * 9 + 0.95 * 1), the prediction 2 x that."""
    fit = _motion(_speeds(950, 0, 50))
    residual = np.where(fit.qd == 0, 3.0, 1.0)
    new = _motion(_speeds(500, 0, 500))
    found = rests(fit, new, cross_validation=_validation(residual), limits=[10.0])
    factor = np.sqrt(0.5 * 9 + 0.5 * 1) / np.sqrt(0.05 * 9 + 0.95 * 1)
    assert found.factor == pytest.approx(factor, rel=1e-12)
    assert found.predicted == pytest.approx(2.0 * factor, rel=1e-12)
    # the fitted recording's own mix: the validated error as it is
    assert rests(fit, fit, cross_validation=_validation(residual)).factor == pytest.approx(1)


def test_a_band_with_too_few_samples_takes_the_faster_bands_error():
    fit = _motion(_speeds(990, 0, 10))             # 10 still samples: fewer than 20
    residual = np.where(fit.qd == 0, 100.0, 1.0)
    new = _motion(_speeds(500, 0, 500))
    found = rests(fit, new, cross_validation=_validation(residual))
    # the rest band's own 10 samples (error 100) would make it sqrt(5000.5 / 100.99) = 7.0
    assert found.factor == pytest.approx(1.0, rel=1e-12)


def test_rests_checks_its_arguments():
    fit = _motion(_speeds(90, 5, 5))
    with pytest.raises(ValueError, match="data have 1 joints, held_out 2"):
        rests(fit, _motion(np.ones((10, 2))))
    with pytest.raises(ValueError, match="2 joint names for 1 joints"):
        rests(fit, fit, joint_names=["a", "b"])
    short = _validation(np.ones((200, 1)))
    with pytest.raises(ValueError, match="not a validation on data"):
        rests(fit, fit, cross_validation=short)


def _cv(scores) -> CrossValidation:
    return CrossValidation(metrics=validation_metrics(np.ones((2, 1)), np.ones((2, 1)), None),
                           fold_scores=np.asarray(scores, float), period_s=None, folds=None,
                           n_parameters=1, settings={})


def test_kept_terms_are_kept_unless_worse():
    rule = KeptTerms([(sj.Presliding(),), (sj.Presliding(fitted=True),)])
    chosen = _cv([1.0, 2.0, 3.0, 4.0])
    slightly_worse = _cv([1.01, 2.0, 3.0, 4.0])   # within 1 % of the chosen: a tie
    better = _cv([0.9, 1.9, 2.9, 3.9])
    worse = _cv([1.5, 2.5, 3.5, 4.5])              # worse on every split
    assert rule.kept(chosen, [slightly_worse, worse]) == 0
    assert rule.kept(chosen, [slightly_worse, better]) == 1
    assert rule.kept(chosen, [worse, worse]) is None
    model = sj.TorqueModel.of(sj.robots.rs010n(), [sj.Offset(), sj.Presliding()])
    added = rule.models(model)  # the fixed one it has; the searched one replaces it
    assert [m.friction for m in added] == ["viscous-coulomb+offset+presliding:fit"]
    assert KEPT_TERMS == KeptTerms(sj.Presliding(fitted=True, largest=0.02))
    with pytest.raises(TypeError, match="KeptTerms takes terms"):
        KeptTerms([])


def test_independent_dahl_state_agrees():
    """The study's plant (benchmarks.extrapolation.dahl, a loop) and the package's
    compiled state agree."""
    rng = np.random.default_rng(0)
    q = np.cumsum(rng.normal(0, 2e-3, (400, 3)) * (rng.random((400, 3)) > 0.3), axis=0)
    q_c = np.array([1e-3, 5e-3, 2e-2])
    dq, start = sj.identification.increments(q)
    np.testing.assert_allclose(np.asarray(sj.identification.dahl_state(dq, start, q_c)),
                               dahl(q, q_c), atol=1e-12)


@pytest.fixture(scope="module")
def resting_arm(tmp_path_factory):
    """The RS010N with Coulomb friction that builds up over 5 mrad (Dahl) and holds at
    rest, fitted on an excitation-like motion, validated on point-to-point moves with
    dwells."""
    robot = sj.robots.rs010n()
    t = np.arange(1500) / 100.0
    w = 2 * np.pi / 7.5
    excitation = (0.8 * np.sin(w * t[:, None] * [1, 2, 3] + [0, 1, 2]),)
    stops = np.clip(np.sin(w * t[:, None] * [1, 1.5, 2]) * 2, -1, 1)  # dwells at +-1
    out = []
    for q, seed in ((excitation[0], 0), (0.6 * stops + 0.1, 1)):
        qd = np.gradient(q, t, axis=0)
        qdd = np.gradient(qd, t, axis=0)
        rigid = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
        tau = rigid + 2.0 * dahl(q, np.full(3, 5e-3)) + 0.5 * qd
        tau += 0.02 * np.random.default_rng(seed).standard_normal(tau.shape)
        out.append(sj.Measurements(t, q, qd, qdd, tau).save(
            tmp_path_factory.mktemp("rest") / f"m{seed}.npz"))
    return [str(p) for p in out]


def test_default_keeps_friction_at_rest_where_the_arm_has_it(resting_arm, tmp_path):
    js = tmp_path / "r.json"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cli.main(["identify", "--robot", "rs010n", "--data", resting_arm[0],
                         "--validate", resting_arm[1], "--json", str(js)]) == 0
        assert cli.main(["identify", "--robot", "rs010n", "--data", resting_arm[0],
                         "--validate", resting_arm[1], "--no-friction-at-rest",
                         "--json", str(tmp_path / "without.json")]) == 0
    doc, without = (json.loads(p.read_text()) for p in (js, tmp_path / "without.json"))
    assert doc["settings"]["friction"].endswith("+presliding:fit:0.02")
    assert "presliding" not in without["settings"]["friction"]
    assert [c for c in without["cross_validation"]["selection"]["candidates"]
            if not c.get("screened")] == [
        c for c in doc["cross_validation"]["selection"]["candidates"]
        if not c.get("kept_terms") and not c.get("screened")]
    # the dwells hold friction only the kept term predicts
    assert (doc["validation"]["relative_rms_percent_overall"]
            < 0.5 * without["validation"]["relative_rms_percent_overall"])
    assert doc["rests"]["rests_more"] and doc["rests"]["error_factor"] > 1


def test_default_validation_carries_the_kept_terms():
    from sedsabso_jax.identification import DefaultValidation

    assert DefaultValidation().kept == KEPT_TERMS
    labels = np.repeat(np.arange(3), 4)
    given = DefaultValidation(interpolation=sj.GivenFolds(labels)).of([None])
    assert given.settings() == sj.Pooled((sj.GivenFolds(labels), sj.SpeedSplits())).settings()
    with pytest.raises(TypeError, match="kept must be KeptTerms"):
        DefaultValidation(kept=sj.Presliding())
    with pytest.raises(TypeError, match="interpolation must be a Validation"):
        DefaultValidation(interpolation=3)


def test_one_candidate_is_not_extended(resting_arm):
    """Given one torque model, the default validation does not extend it."""
    robot = sj.robots.rs010n()
    data = sj.load_measurements(resting_arm[0], n_joints=3)
    report = sj.select_and_identify(robot, data, estimators=sj.OLS(),
                                    models=sj.TorqueModel.of(robot, sj.Offset()))
    # unconstrained and physically consistent: two candidates, no friction at rest added
    assert [s["friction"] for s, _ in report.selection.candidates] == [
        "viscous-coulomb+offset"] * 2
    assert report.ident.model.friction == "viscous-coulomb+offset"


def test_the_kept_displacements_are_searched_up_to_20_mrad():
    term = sj.identification.parse_friction("presliding:fit:0.02")[0]
    assert term == sj.Presliding(fitted=True, largest=0.02) and term.text == "presliding:fit:0.02"
    model = sj.TorqueModel.of(sj.robots.rs010n(), [sj.Offset(), term])
    (_, found), = model.nonlinear()
    np.testing.assert_array_equal(found.upper, [0.02] * 3)
    assert model.friction == "viscous-coulomb+offset+presliding:fit:0.02"
    (_, unbounded), = sj.TorqueModel.of(sj.robots.rs010n(), sj.Presliding(fitted=True)).nonlinear()
    np.testing.assert_array_equal(unbounded.upper, [0.5] * 3)
    with pytest.raises(ValueError, match="largest must be a number in"):
        sj.Presliding(largest=0.02)            # without fitted=True
    with pytest.raises(ValueError, match="largest must be a number in"):
        sj.Presliding(fitted=True, largest=1.0)
    with pytest.raises(ValueError, match="presliding:fit:LARGEST"):
        sj.identification.parse_friction("presliding:fit:wide")
