"""The signal chain (``sj.measurements.SignalChain``): the loader is a chain applied to the
recorded signals, which the measurements keep; the default's validation chooses the
chain and the torques' delay (``DefaultValidation()``'s ``signals="auto"``, the
default), against figures computed here from the true motion."""

from __future__ import annotations

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.measurements import SignalChain, recorded_signals

ROBOT = sj.robots.rs010n()
LIMITS = np.array([300.0, 300.0, 150.0])
#: One candidate model and estimator: the chain is the only choice.
FAST = dict(estimators=sj.OLS(), models=sj.TorqueModel.of(ROBOT), physical=False)
#: The default's validation, the signal chain chosen, and with the signals as given.
CHOSEN = sj.identification.DefaultValidation()
AS_GIVEN = sj.identification.DefaultValidation(signals=None)
RATE = 200.0


def _motion(seconds: float, seed: int, scale: float = 1.0):
    """A sum of sines per joint (0.1-0.6 Hz): times, q, qd, qdd exact."""
    t = np.arange(int(seconds * RATE)) / RATE
    rng = np.random.default_rng(seed)
    f = rng.uniform(0.1, 0.6, (4, 3))
    a = scale * rng.uniform(0.1, 0.3, (4, 3))
    p = rng.uniform(0, 2 * np.pi, (4, 3))
    arg = 2 * np.pi * f[None] * t[:, None, None] + p[None]
    w = 2 * np.pi * f[None]
    q = (a * np.sin(arg)).sum(1)
    qd = (a * w * np.cos(arg)).sum(1)
    qdd = (-a * w ** 2 * np.sin(arg)).sum(1)
    return t, q, qd, qdd


def _torques(q, qd, qdd, seed):
    tau = np.asarray(sj.inverse_dynamics(ROBOT, ROBOT.params, q, qd, qdd)) + 2.0 * qd
    rms = np.sqrt(np.mean(tau ** 2, 0))
    return tau + 0.01 * rms * np.random.default_rng(seed).standard_normal(tau.shape)


def _recording(seconds, seed, *, lagging_qdd: bool, scale: float = 1.0):
    """The RS010N's recording; ``lagging_qdd``: the recorded accelerations are those of a
    logger's causal 0.5 Hz filter (late and small), as some drives record them."""
    import scipy.signal

    t, q, qd, qdd = _motion(seconds, seed, scale)
    tau = _torques(q, qd, qdd, seed + 100)
    q_rec = q + 2e-5 * np.random.default_rng(seed + 200).standard_normal(q.shape)
    recorded_qdd = qdd
    if lagging_qdd:
        b, a = scipy.signal.butter(2, 0.5, fs=RATE)
        recorded_qdd = scipy.signal.lfilter(b, a, qdd, axis=0)
    return recorded_signals(t, q_rec, tau, qd, recorded_qdd, source=f"run {seed}")


def test_the_loader_is_a_chain_of_the_recorded_signals(tmp_path):
    """``load_measurements(path, cutoff_hz, derive)`` equals the loaded measurements made
    again by that chain (``with_chain``), to the bit; the record says who chose it."""
    t, q, qd, qdd = _motion(12.0, 1)
    tau = _torques(q, qd, qdd, 2)
    path = sj.Measurements(t, q, qd, qdd, tau).save(tmp_path / "run.npz")
    plain = sj.load_measurements(path)
    assert plain.chain == SignalChain() and plain.info["chain"]["given"] is False
    np.testing.assert_array_equal(plain.qdd, qdd)  # recorded, nothing trimmed
    for chain in (SignalChain(5.0, derive=True), SignalChain(20.0, filter_torques=True)):
        loaded = sj.load_measurements(path, cutoff_hz=chain.cutoff_hz, derive=chain.derive,
                                      filter_torques=chain.filter_torques)
        again = plain.with_chain(chain)
        assert loaded.info["chain"]["given"] is True and loaded.chain == chain
        for a, b in zip(loaded.arrays().values(), again.arrays().values()):
            np.testing.assert_array_equal(a, b)
        assert loaded.info["trimmed_s"] == 2.0 / chain.cutoff_hz
    # a part keeps the recording: another chain makes the same samples (those it keeps)
    mask = np.sin(t) > 0
    part = plain.subset(mask).with_chain(SignalChain(5.0, derive=True))
    whole = plain.with_chain(SignalChain(5.0, derive=True))
    inner = np.isin(whole.times, t[mask])
    np.testing.assert_array_equal(part.times, whole.times[inner])
    np.testing.assert_array_equal(part.qdd, whole.qdd[inner])
    np.testing.assert_array_equal(plain.slice(0, 100).with_chain(SignalChain()).tau, tau[:100])
    with pytest.raises(ValueError, match="keep no recorded signals"):
        plain.delayed(0.01).with_chain(SignalChain())
    with pytest.raises(ValueError, match="cutoff_hz must be a positive number"):
        SignalChain(-1.0)


def test_a_transmission_carries_the_recorded_signals(tmp_path):
    """Motor-side recordings converted to the joint side keep their recorded signals
    converted alike: a chain applied after the conversion equals the chain applied when
    loading, then converted (filters and differences are linear, per column)."""
    t, q, _, _ = _motion(10.0, 3)
    tau = np.cos(q)
    path = sj.Measurements(t, q, q, q, tau).save(tmp_path / "motor.npz")
    raw = np.load(path)
    only_q = tmp_path / "motor_q.npz"
    np.savez(only_q, times=raw["times"], positions=raw["positions"], torques=raw["torques"])
    tr = sj.Transmission.from_gear_ratios([100.0, 80.0, 50.0], coupling={(3, 2): 0.5},
                                          drive_gains=[0.2, 0.3, 0.4])
    joint = tr.to_joint_side(sj.load_measurements(only_q))
    chain = SignalChain(5.0)
    direct = tr.to_joint_side(sj.load_measurements(only_q, cutoff_hz=5.0))
    again = joint.with_chain(chain)
    for a, b in zip(direct.arrays().values(), again.arrays().values()):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


@pytest.mark.filterwarnings("ignore:held-out data go beyond")
def test_the_choice_derives_what_the_recording_gets_wrong():
    """Recorded accelerations late and small (a causal logger filter): the default
    chooses accelerations derived from the positions, and the held-out error (a new
    motion, exact signals) is lower than with the recorded ones; with exact recorded
    signals it keeps them. Every candidate is scored on the same samples."""
    bad = _recording(30.0, 4, lagging_qdd=True)
    good = _recording(30.0, 4, lagging_qdd=False)
    t, q, qd, qdd = _motion(15.0, 5, scale=1.3)
    new = sj.Measurements(t, q, qd, qdd, _torques(q, qd, qdd, 6))
    chosen = sj.select_and_identify(ROBOT, bad, held_out=new, limits=LIMITS, **FAST)
    sel = chosen.chain_selection  # the default chooses (CHOSEN)
    assert sel.labels[0] == "recorded" and sel.labels[sel.chosen].startswith("derived")
    assert all(np.array_equal(cv.tested, sel.validations[0].tested) for cv in sel.validations)
    as_given = sj.select_and_identify(ROBOT, bad, held_out=new, limits=LIMITS, **FAST,
                                      validation=AS_GIVEN)
    assert as_given.chain_selection is None  # signals=None: taken as given
    assert chosen.validation.nrms_limits_percent < 0.5 * as_given.validation.nrms_limits_percent
    assert "derived" in chosen.text().split("signals chosen by validation")[1][:2000]
    document = chosen.document({})
    assert document["signals"]["choice"]["chosen"] == sel.labels[sel.chosen]
    assert document["signals"]["info"]["accelerations"].startswith("derived")
    kept = sj.select_and_identify(ROBOT, good, limits=LIMITS, **FAST,
                                  validation=CHOSEN).chain_selection
    assert kept.chosen == 0


@pytest.mark.filterwarnings("ignore:held-out data go beyond")
def test_a_part_of_a_recording_with_its_own_folds():
    """A part of a recording (a nested validation's outer fit), its folds given per
    sample: the chain chosen on its samples (the model with friction at rest, kept on the
    loaded signals), the choice validated again on the chosen signals by the same splits;
    the held-out part is made by the same chain."""
    data = _recording(30.0, 10, lagging_qdd=True)
    fit = data.times < 22.0
    labels = (np.arange(int(fit.sum())) * 5) // int(fit.sum())
    report = sj.select_and_identify(
        ROBOT, data.subset(fit), held_out=data.subset(~fit), limits=LIMITS,
        estimators=sj.OLS(), physical=False,
        models=sj.identification.candidate_models(ROBOT, [(), [sj.Offset()]]),
        validation=sj.identification.DefaultValidation(interpolation=sj.GivenFolds(labels),
                                                       signals="auto"))
    sel, chosen = report.chain_selection, report.selection
    assert sel.chosen != 0 and report.held_out.info["chain"]["derive"] is True
    # the kept terms were judged on the loaded signals; the choice validated again on the
    # chosen ones, with the same splits (those of the part's own folds)
    assert any(s.get("kept_terms") and "signals" not in s for s, _ in chosen.candidates)
    on_chain = [cv for s, cv in chosen.candidates if s.get("signals")]
    assert len(on_chain) == 1 and chosen.chosen["signals"] == sel.labels[sel.chosen]
    assert on_chain[0].split_names == sel.validations[0].split_names
    assert report.cross_validation is on_chain[0]
    assert report.data.info["trimmed_s"] == sel.trim_s


@pytest.mark.filterwarnings("ignore:held-out data go beyond")
def test_a_chain_given_is_applied_and_checked():
    """A chain the user gave is applied, not chosen; a chain given when loading is kept;
    bad values are named."""
    bad = _recording(20.0, 7, lagging_qdd=True)
    chain = SignalChain(5.0, derive=True)
    new = _recording(10.0, 8, lagging_qdd=True)
    fixed = sj.select_and_identify(ROBOT, bad, held_out=new, limits=LIMITS, **FAST,
                                   validation=sj.identification.DefaultValidation(signals=chain))
    assert fixed.chain_selection is None and fixed.held_out.info["chain"]["cutoff_hz"] == 5.0
    assert fixed.data.info["chain"] == {"cutoff_hz": 5.0, "derive": True,
                                        "filter_torques": False, "delay_s": 0.0,
                                        "given": True}
    given = bad.with_chain(SignalChain(10.0))  # chosen by the user: not chosen again
    assert sj.select_and_identify(ROBOT, given, limits=LIMITS, **FAST,
                                  validation=CHOSEN).chain_selection is None
    with pytest.raises(TypeError, match="signals must be 'auto', None or SignalChain"):
        sj.identification.DefaultValidation(signals="derived")
    with pytest.raises(ValueError, match="keeps no recorded signals"):
        sj.select_and_identify(ROBOT, bad.delayed(0.005), limits=LIMITS, **FAST,
                               validation=sj.identification.DefaultValidation(
                                   signals=[SignalChain(), SignalChain(5.0)]))


def _lagging(recording, delay_s: float):
    """``recording`` with its torques logged ``delay_s`` late: at ``t`` the torque of
    ``t - delay_s`` (linear interpolation, the first samples dropped)."""
    r = recording.recorded
    keep = r.times >= r.times[0] + delay_s
    tau = np.column_stack([np.interp(r.times[keep] - delay_s, r.times, c) for c in r.tau.T])
    return recorded_signals(r.times[keep], r.q[keep], tau, r.qd[keep], r.qdd[keep],
                            source=r.source)


@pytest.mark.filterwarnings("ignore:held-out data go beyond")
def test_a_delay_is_searched_and_kept_where_it_validates():
    """Torques logged 12 ms (2.4 samples) late: the choice searches the delay with the
    chosen model, finds it within a tenth of a sample, applies it (it validates better)
    to the identification and the held-out data, and the held-out error falls; the
    chain's delay pairs the recorded torques with the motion ``delay_s`` earlier; a
    delay is not kept where the torques are on time."""
    late = _lagging(_recording(30.0, 13, lagging_qdd=False), 0.012)
    new = _lagging(_recording(15.0, 14, lagging_qdd=False, scale=1.2), 0.012)
    chosen = sj.select_and_identify(ROBOT, late, held_out=new, limits=LIMITS, **FAST,
                                    validation=CHOSEN)
    sel = chosen.chain_selection
    assert abs(sel.delay.seconds - 0.012) < 0.1 / RATE and not sel.delay.at_bound
    assert sel.delayed and sel.chosen == 1 and sel.chain.delay_s == sel.delay.seconds
    # every other chain validated with its own delay, searched on each split
    assert all(len(d) == len(sel.validations[0].fold_scores) for d in sel.split_delays[1:])
    assert len(set(sel.split_delays[1])) == len(sel.split_delays[1])  # each its own
    assert all(abs(c.delay_s - 0.012) < 0.1 / RATE for c in sel.chains[1:])
    assert 0 < sel.delay.standard_error_s < 0.1 / RATE
    assert chosen.held_out.info["chain"]["delay_s"] == sel.delay.seconds
    assert "torques +12 ms" in sel.labels[sel.chosen]
    as_given = sj.select_and_identify(ROBOT, late, held_out=new, limits=LIMITS, **FAST,
                                      validation=AS_GIVEN)
    assert chosen.validation.nrms_limits_percent < 0.7 * as_given.validation.nrms_limits_percent
    assert "delay, searched with the chosen model on the recorded signals: the torques +12 ms" \
        in chosen.text()
    made = late.with_chain(SignalChain(delay_s=0.0123), trim_s=0.05)
    r = late.recorded
    same = np.isin(r.times, made.times)
    np.testing.assert_array_equal(made.tau, r.tau[same])  # the torques as recorded
    for got, x in ((made.q, r.q), (made.qd, r.qd)):
        earlier = np.column_stack([np.interp(made.times - 0.0123, r.times, c) for c in x.T])
        np.testing.assert_allclose(got, earlier, rtol=0, atol=1e-4 * np.abs(x).max())
    assert made.info["delay_s"] == 0.0123 and made.chain.delay_s == 0.0123
    on_time = sj.select_and_identify(ROBOT, _recording(30.0, 13, lagging_qdd=False),
                                     limits=LIMITS, **FAST, validation=CHOSEN).chain_selection
    assert abs(on_time.delay.seconds) < 0.1 / RATE and on_time.chain.delay_s == 0.0
    assert not on_time.delayed and all(c.delay_s == 0.0 for c in on_time.chains[2:])
    with pytest.raises(ValueError, match="delay_s must be a finite number of seconds"):
        SignalChain(delay_s="soon")
    with pytest.raises(ValueError, match="too short for a delay of 20 s"):
        late.with_chain(SignalChain(delay_s=20.0))



def test_a_delay_is_searched_on_derived_signals_where_the_recorded_ones_lag():
    """Recorded accelerations late (a causal logger filter) and torques logged 12 ms
    late: the recorded signals disagree in time among themselves, so their delay lies at
    the search's bound; the delay is then searched on the first chain derived from the
    positions, found within a tenth of a sample and kept, and every later chain is
    validated with its own delay before the cutoff is chosen."""
    late = _lagging(_recording(30.0, 4, lagging_qdd=True), 0.012)
    sel = sj.select_and_identify(ROBOT, late, limits=LIMITS, **FAST,
                                 validation=CHOSEN).chain_selection
    (on_loaded, at_bound, kept, index), (on_derived, found, kept_there, _) = sel.searches
    assert on_loaded == "recorded" and at_bound.at_bound and not kept and index == -1
    assert on_derived == "derived, 5 Hz" and kept_there and sel.delayed
    assert abs(found.seconds - 0.012) < 0.1 / RATE
    assert sel.labels[:3] == ("recorded", "derived, 5 Hz",
                              f"derived, 5 Hz, torques {1e3 * found.seconds:+.3g} ms")
    assert len(sel.chains) == 4 and all(  # the 10 Hz chain with its own delay
        abs(c.delay_s - 0.012) < 0.1 / RATE for c in sel.chains[2:])
    assert abs(sel.chain.delay_s - 0.012) < 0.1 / RATE
    assert "every later chain was validated with its own delay" in "\n".join(
        sel.delay_lines())

def test_the_chains_report_their_work():
    """``progress`` names each chain's validation (one call per split), ``done`` grows
    and ends at ``total``; the chains' work is in the total from the first call."""
    data = _recording(20.0, 9, lagging_qdd=True)
    calls: list[tuple[str, float, float]] = []
    sj.select_and_identify(ROBOT, data, limits=LIMITS, **FAST, validation=CHOSEN,
                           progress=lambda *call: calls.append(call))
    labels = [c[0] for c in calls]
    splits = labels.count("OLS, viscous-coulomb")
    for chain in ("recorded", "derived, 5 Hz", "derived, 10 Hz"):
        assert labels.count(f"signals: {chain}") == splits
    done = [c[1] for c in calls]
    assert (np.diff(done) >= 0).all() and done[-1] == calls[-1][2]
    chains_work = done[labels.index("signals: derived, 10 Hz") + splits - 1] - done[splits - 1]
    assert calls[0][2] > chains_work


def test_the_command_chooses_by_default(tmp_path, capsys):
    """``identify`` chooses the chain (``--signals auto``, the default: the report's table,
    the JSON's ``signals.choice``); with ``--signals as-loaded``, or with ``--cutoff-hz``
    given, the signals are taken as loaded."""
    import json

    from sedsabso_jax import cli

    t, q, qd, qdd = _motion(30.0, 11)
    np.savez(tmp_path / "run.npz", times=t, positions=q, torques=_torques(q, qd, qdd, 12))
    flags = ["identify", "--robot", "rs010n", "--data", str(tmp_path / "run.npz"),
             "--friction", "viscous-coulomb", "--method", "OLS", "--weights", "equal",
             "--no-physical"]
    for extra, chosen in (([], True), (["--signals", "as-loaded"], False),
                          (["--cutoff-hz", "10"], False)):
        js = tmp_path / "r.json"
        assert cli.main([*flags, *extra, "--json", str(js)]) == 0
        printed = capsys.readouterr().out
        choice = json.loads(js.read_text())["signals"]["choice"]
        assert (choice is not None) == chosen == ("signals chosen by validation" in printed)
        if chosen:
            found = [c["signals"].split(", torques ")[0] for c in choice["candidates"]]
            assert found == ["derived, 10 Hz", "derived, 10 Hz", "derived, 5 Hz"]
            assert choice["delay_searches"][0]["seconds"] == choice["candidates"][1]["delay_s"]


def test_splits_left_without_samples_are_dropped():
    """The chains are compared on the samples every chain keeps: a split whose samples to
    predict (or to fit) all lie in the trimmed ends is dropped, the others kept with their
    names and kinds (a short recording's fastest samples at its ends stopped the choice)."""
    from sedsabso_jax.identification._default._signals import restricted
    from sedsabso_jax.identification._validation._splits import Splits

    keep = np.r_[np.zeros(3, bool), np.ones(6, bool), np.zeros(3, bool)]
    ends = np.r_[np.ones(2, bool), np.zeros(8, bool), np.ones(2, bool)]
    middle = ~ends & ~np.eye(12, dtype=bool)[5]
    splits = Splits(train=(~ends, ~middle, middle), test=(ends, middle, ~middle),
                    names=("fast at the ends", "phase 1", "phase 2"),
                    parts=("speed splits", "phase folds", "phase folds"))
    left = restricted(splits, keep)
    assert left.names == ("phase 1", "phase 2") and left.parts == ("phase folds",) * 2
    np.testing.assert_array_equal(left.test[0], middle[keep])
    assert all(t.shape == (6,) for t in left.train + left.test)


def test_the_fit_on_all_the_data_reuses_the_chains_search(monkeypatch):
    """The model's nonlinear parameters are searched once on all the data where the
    loaded chain is kept: the chain's validation holds them where that search puts them,
    and the final fit takes the same search (the same samples), its report included."""
    from sedsabso_jax.identification import parse_friction
    from sedsabso_jax.identification._fit import _fit

    searched = []
    original = _fit._searched

    def counted(model, samples, weights):
        if samples.whole is None:  # all the data, not a split
            searched.append(len(samples.tau))
        return original(model, samples, weights)

    monkeypatch.setattr(_fit, "_searched", counted)
    model = sj.TorqueModel.of(ROBOT, parse_friction("viscous-coulomb+smooth:fit"))
    report = sj.select_and_identify(ROBOT, _recording(20.0, 14, lagging_qdd=False),
                                    limits=LIMITS, estimators=sj.OLS(), models=model,
                                    physical=False)
    assert report.chain_selection.chosen == 0 and len(searched) == 1
    assert report.ident.settings["searched"]["evaluations"] > 0
    with pytest.raises(ValueError, match="samples of"):
        sj.identification._fit._identify.identified(
            ROBOT, _recording(10.0, 15, lagging_qdd=False), sj.OLS(), model, LIMITS,
            samples=sj.identification._fit._samples.Samples.of(
                ROBOT, _recording(20.0, 14, lagging_qdd=False)))
