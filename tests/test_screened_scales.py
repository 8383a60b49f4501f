"""The smooth Coulomb's scales in the default, searched where they validate better
(``sj.identification.ScreenedTerms``, ``SCREENED_TERMS``): the terms' bookkeeping, and
the default on simulated arms whose Coulomb friction turns slowly (the scales kept, the
held-out error lower) or at once (not kept, nothing validated beyond the screen)."""

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
    screened = sj.SmoothCoulomb(fitted=True, smallest=0.02)  # never sharper than 0.02 rad/s
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


def _arm(tmp_path, velocity: float) -> list[str]:
    """The RS010N with Coulomb friction ``2 tanh(qd / velocity)``, fitted on an
    excitation, validated on a slower motion that spends its time where the shape
    matters."""
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
        tau += 0.02 * np.random.default_rng(seed).standard_normal(tau.shape)
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


def test_the_default_leaves_the_scales_where_the_friction_turns_at_once(tmp_path):
    """A jump sharper than the candidates' 0.02 rad/s is not searched for: it would flip
    with the velocity's noise wherever a joint rests, which an excitation cannot show."""
    doc = _identify(_arm(tmp_path, 0.002), tmp_path / "r.json")
    selection = doc["cross_validation"]["selection"]
    assert min(selection["screen"]["scales"].values()) >= 0.02
    assert not selection["screen"]["passed"] and not selection["screen"]["kept"]
    assert "smooth:fit" not in doc["settings"]["friction"]
    assert not any(c.get("screened") for c in selection["candidates"])

