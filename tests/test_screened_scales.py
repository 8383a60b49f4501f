"""The smooth Coulomb's scales in the default, searched where they validate better
(``sj.identification.ScreenedTerms``, ``SCREENED_TERMS``): the terms' bookkeeping, the
smallest scale from the velocities' noise, and the default on simulated arms whose
Coulomb friction turns slowly (the scales kept, the held-out error lower) or at once:
kept where the positions are clean, not where their noise would flip a sharp jump."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax import cli
from sedsabso_jax.identification import (
    SCREENED_TERMS,
    DefaultValidation,
    ScreenedTerms,
    parse_friction,
)


def test_the_screened_model_searches_the_scales_from_the_values_given():
    robot = sj.robots.rs010n()
    at_rest = sj.Presliding(fitted=True, largest=0.02)
    model = sj.TorqueModel.of(robot, terms=(sj.Offset(), sj.SmoothCoulomb(), at_rest))
    screened = sj.SmoothCoulomb(fitted=True, smallest=0.02)  # where no noise is measured
    assert SCREENED_TERMS.terms == (screened,)
    searched = SCREENED_TERMS.searched(model)
    assert searched.terms == (sj.Offset(), screened, at_rest)
    held = model.with_nonlinear(np.array([1e-3, 2e-3, 3e-3]))
    trial = SCREENED_TERMS.trial(held)
    # friction at rest fixed where the fit put it, the scales searched from the model's
    assert trial.terms[2] == sj.Presliding(displacement=(1e-3, 2e-3, 3e-3))
    assert trial.terms[1] == screened
    (_, searched_values), = trial.nonlinear()
    assert searched_values.names == ("v_smooth1", "v_smooth2", "v_smooth3")
    np.testing.assert_array_equal(searched_values.lower, 0.02)
    np.testing.assert_array_equal(searched_values.upper, 1.0)
    found = trial.with_nonlinear(np.array([0.1, 0.2, 0.3]))
    again = SCREENED_TERMS.searched(model, found)
    assert again.terms[1] == sj.SmoothCoulomb(velocity=(0.1, 0.2, 0.3), fitted=True,
                                              smallest=0.02)
    assert again.terms[2] == at_rest
    # nothing to screen: no smooth Coulomb, or its scales searched already
    assert SCREENED_TERMS.searched(sj.TorqueModel.of(robot, terms=(sj.Offset(),))) is None
    assert SCREENED_TERMS.searched(searched) is None
    assert trial.search == SCREENED_TERMS.search
    with pytest.raises(TypeError, match="fitted=True"):
        ScreenedTerms(sj.SmoothCoulomb())
    with pytest.raises(TypeError, match="search must be a search method"):
        ScreenedTerms(sj.SmoothCoulomb(fitted=True), search=sj.identification.Held())
    with pytest.raises(TypeError, match="screened must be ScreenedTerms"):
        DefaultValidation(screened=sj.SmoothCoulomb(fitted=True))
    assert DefaultValidation().screened == SCREENED_TERMS
    assert SCREENED_TERMS.noise_floor == 6.0 and SCREENED_TERMS.noise is None


def _recording(noise: float, rate: float = 100.0, T: int = 3000) -> sj.Measurements:
    """A slow sine on three joints, its positions with white ``noise`` [rad]."""
    t = np.arange(T) / rate
    q = 0.5 * np.sin(2 * np.pi * 0.2 * t[:, None] * [1.0, 1.3, 1.7])
    q = q + noise * np.random.default_rng(0).standard_normal(q.shape)
    qd, qdd = sj.measurements.differentiate(t, q)
    return sj.Measurements(t, q, qd, qdd, np.zeros_like(q))


@pytest.mark.parametrize("rate", [100.0, 1000.0])
def test_the_smallest_scale_is_the_floor_times_the_velocities_noise(rate):
    """The velocities' noise is what the positions' noise puts on the derived velocities:
    against the derived velocities' own error (the noise-free motion's derivative known)
    within 15 %, at 100 Hz and 1 kHz; the screened scale's smallest is the floor times it."""
    m = _recording(2e-4, rate)
    clean = _recording(0.0, rate)
    error = (m.qd - clean.qd)[int(rate):-int(rate)].std(axis=0)
    found = sj.measurements.velocity_noise(m.times, m.q)
    np.testing.assert_allclose(found, error, rtol=0.15)
    floored = SCREENED_TERMS.at_noise([m])
    assert floored.noise == pytest.approx(found.max())
    assert floored.terms[0].smallest == pytest.approx(6.0 * found.max())
    assert floored.terms[0].search_bounds()[0] == floored.terms[0].smallest


def test_the_velocities_noise_of_a_split_is_its_recordings():
    """A validation split's samples (stretches with gaps between them) give the noise of
    their recording: the differences are taken within the stretches only."""
    m = _recording(2e-4)
    part = m.subset((np.arange(m.n_samples) // 8) % 2 == 0)  # stretches of 8 samples
    whole = sj.measurements.velocity_noise(m.times, m.q)
    np.testing.assert_allclose(sj.measurements.velocity_noise(part.times, part.q), whole,
                               rtol=0.1)
    assert SCREENED_TERMS.at_noise([part]).noise == pytest.approx(whole.max(), rel=0.1)


@pytest.mark.parametrize("args, match", [
    ((np.arange(100) / 100.0, np.zeros(100)), r"q must be \(T, n\) finite"),
    ((np.arange(50) / 100.0, np.zeros((100, 2))), r"times must be \(100,\) increasing"),
    ((-np.arange(100) / 100.0, np.zeros((100, 2))), r"times must be \(100,\) increasing"),
    ((np.arange(100) / 100.0, np.full((100, 2), np.nan)), "with NaN or inf"),
    ((np.arange(100) / 100.0, np.zeros((100, 2)), 80.0), r"cutoff_hz must lie in \(0, 50\)"),
])
def test_the_velocities_noise_names_bad_input(args, match):
    with pytest.raises(ValueError, match=match):
        sj.measurements.velocity_noise(*args)


def test_the_velocities_noise_follows_the_recordings_chain():
    """Velocities derived at 5 Hz carry less of the positions' noise than at 10 Hz (about
    2^1.5 less, the derivative's gain growing with the frequency): the floor reads each
    recording's chain."""
    m = _recording(2e-4)
    at_5 = sj.measurements.recorded_signals(m.times, m.q, m.tau,
                                            chain=sj.measurements.SignalChain(cutoff_hz=5.0))
    noise_5 = SCREENED_TERMS.at_noise([at_5]).noise
    noise_10 = SCREENED_TERMS.at_noise([m]).noise
    assert noise_5 == pytest.approx(np.max(sj.measurements.velocity_noise(
        at_5.times, at_5.q, 5.0)))
    assert 2.0 < noise_10 / noise_5 < 3.5
    # several recordings: the noisiest sets the floor
    assert SCREENED_TERMS.at_noise([at_5, m]).noise == noise_10


def test_the_floor_falls_back_to_the_terms_own_where_the_noise_is_not_given():
    clean = _recording(0.0)
    assert SCREENED_TERMS.at_noise([clean]).terms[0].smallest == 1e-4  # the declared bound
    no_times = sj.Measurements(np.arange(3000.0), clean.q, clean.qd, clean.qdd, clean.tau)
    assert SCREENED_TERMS.at_noise([no_times]) is SCREENED_TERMS  # 1 Hz: no 10 Hz filter
    given = ScreenedTerms(sj.SmoothCoulomb(fitted=True, smallest=0.05))
    assert given.at_noise([_recording(2e-4)]) is given  # no floor: the term's own
    loud = SCREENED_TERMS.at_noise([_recording(0.05)])  # a floor above the box: its top
    assert 0.99 < loud.terms[0].smallest < 1.0
    with pytest.raises(ValueError, match="noise_floor must be a number > 0"):
        ScreenedTerms(sj.SmoothCoulomb(fitted=True), noise_floor=0)


def test_the_screens_line_names_what_set_the_smallest_scale():
    """The floor (6 x the noise); the terms' own lower bound where the floor lies below
    it; the top of their box where it lies above."""
    from types import SimpleNamespace

    from sedsabso_jax.identification._validation._screened_terms import Screen

    robot = sj.robots.rs010n()
    cv = SimpleNamespace(score=1.0, standard_error=0.1)

    def line(smallest: float, noise: float | None) -> str:
        found = sj.TorqueModel.of(robot, sj.SmoothCoulomb(fitted=True, smallest=smallest))
        return Screen(found, cv, cv, False, noise=noise, noise_floor=6.0).line()

    assert "from 0.006 rad/s up (6 x the velocities' noise, 0.001 rad/s)" in line(6e-3, 1e-3)
    assert ("from 0.0001 rad/s up (the terms' own lower bound, above 6 x the velocities' "
            "noise, 1e-09 rad/s)") in line(1e-4, 1e-9)
    assert ("from 1 rad/s up (just below the terms' upper bound: 6 x the velocities' "
            "noise, 0.5 rad/s lies above it)") in line(float(np.nextafter(1.0, 0)), 0.5)
    assert "from 0.02 rad/s up (the terms' own)" in line(0.02, None)


def test_the_smallest_scale_searched_is_the_terms_option():
    term = parse_friction("smooth:fit:0.02")[0]
    assert term == sj.SmoothCoulomb(fitted=True, smallest=0.02)
    assert term.text == "smooth:fit:0.02" and term.search_bounds() == (0.02, 1.0)
    assert term.settings()["smooth_smallest"] == 0.02
    assert term.fixed() == sj.SmoothCoulomb()
    assert sj.SmoothCoulomb(fitted=True).search_bounds() == (1e-4, 1.0)
    with pytest.raises(ValueError, match=r"smooth:fit:SMALLEST .* got smooth:fit:2"):
        parse_friction("smooth:fit:2")
    with pytest.raises(ValueError, match="smallest must be a number"):
        sj.SmoothCoulomb(smallest=0.02)


def _arm(tmp_path, velocity: float, noise: float = 0.0) -> list[str]:
    """The RS010N with Coulomb friction ``2 tanh(qd / velocity)``, fitted on an
    excitation, validated on a slower motion that spends its time where the shape
    matters; with position ``noise`` [rad], velocities and accelerations derived."""
    robot = sj.robots.rs010n()
    t = np.arange(1200) / 100.0
    w = 2 * np.pi / 6.0
    out = []
    for q, seed in ((0.8 * np.sin(w * t[:, None] * [1, 2, 3] + [0, 1, 2]), 0),
                    (0.15 * np.sin(0.5 * w * t[:, None] * [1, 1.5, 2]), 1)):
        qd = np.gradient(q, t, axis=0)
        qdd = np.gradient(qd, t, axis=0)
        tau = np.array(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
        tau += 2.0 * np.tanh(qd / velocity) + 0.5 * qd
        rng = np.random.default_rng(seed)
        tau += 0.02 * rng.standard_normal(tau.shape)
        if noise:
            q = q + noise * rng.standard_normal(q.shape)
            qd, qdd = sj.measurements.differentiate(t, q)
        out.append(str(sj.Measurements(t, q, qd, qdd, tau).save(tmp_path / f"m{seed}.npz")))
    return out


def _identify(paths: list[str], out, *flags: str) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cli.main(["identify", "--robot", "rs010n", "--data", paths[0], "--validate",
                         paths[1], "--no-friction-at-rest", "--json", str(out),
                         *flags]) == 0
    return json.loads(out.read_text())


def test_the_default_keeps_the_scales_where_the_friction_turns_slowly(tmp_path, capsys):
    paths = _arm(tmp_path, 0.2)
    doc = _identify(paths, tmp_path / "with.json")
    without = _identify(paths, tmp_path / "without.json", "--no-searched-scales")
    screen = doc["cross_validation"]["selection"]["screen"]
    assert screen["passed"] and screen["kept"]
    assert "smooth:fit" in doc["settings"]["friction"]
    assert "smooth:fit" not in without["settings"]["friction"]
    assert without["cross_validation"]["selection"]["screen"] is None
    np.testing.assert_allclose(list(screen["scales"].values()), 0.2, rtol=0.2)
    assert doc["cross_validation"]["selection"]["chosen"]["screened"]
    assert (doc["validation"]["relative_rms_percent_overall"]
            < 0.5 * without["validation"]["relative_rms_percent_overall"])
    assert "scales searched where they validate better" in capsys.readouterr().out


def test_a_sharp_jump_is_kept_where_the_positions_are_clean(tmp_path):
    """Coulomb friction that turns over 2 mrad/s, positions without noise: the scales are
    searched from the declared 1e-4 rad/s, found within a factor 3 on the joints whose
    jump the excitation crosses often, kept, and the held-out error falls by more than
    half."""
    paths = _arm(tmp_path, 0.002)
    doc = _identify(paths, tmp_path / "with.json")
    without = _identify(paths, tmp_path / "without.json", "--no-searched-scales")
    screen = doc["cross_validation"]["selection"]["screen"]
    assert screen["smallest"] == 1e-4 and screen["noise"] < 1e-5
    # the line names what set the smallest: the terms' own bound, not 6 x the noise
    assert ("from 0.0001 rad/s up (the terms' own lower bound, above 6 x the velocities' "
            "noise, ") in screen["line"]
    assert screen["passed"] and screen["kept"]
    assert 0.002 / 3 < screen["scales"]["v_smooth2"] < 0.002 * 3
    assert (doc["validation"]["relative_rms_percent_overall"]
            < 0.5 * without["validation"]["relative_rms_percent_overall"])


def test_a_sharp_jump_is_not_searched_below_the_velocities_noise(tmp_path):
    """The same arm, positions with 0.2 mrad of noise (velocities derived): the scales are
    searched from 6 times the velocities' noise up (about 17 mrad/s), which a jump of 2
    mrad/s does not reach: not kept, nothing validated beyond the screen."""
    doc = _identify(_arm(tmp_path, 0.002, noise=2e-4), tmp_path / "r.json")
    selection = doc["cross_validation"]["selection"]
    screen = selection["screen"]
    assert 0.01 < screen["smallest"] == pytest.approx(6 * screen["noise"])
    assert f"rad/s up (6 x the velocities' noise, {screen['noise']:.2g} rad/s)" in screen["line"]
    assert min(screen["scales"].values()) >= screen["smallest"]
    assert not screen["passed"] and not screen["kept"]
    assert "smooth:fit" not in doc["settings"]["friction"]
    assert not any(c.get("screened") for c in selection["candidates"])
