"""The signal chain the default chooses, against every fixed chain, on simulated plants
judged on a motion no choice or fit saw.

Each plant is the RS010N with viscous, smooth Coulomb friction and a torque offset, 1 %
torque noise, recorded at 100 Hz or 1 kHz with position noise of 1e-5 or 2e-4 rad, its
velocities and accelerations not recorded (derived), recorded by the drive (exact, with
noise), or recorded by a logger that filters them causally (a second-order 5 Hz
low-pass: late at the motion's higher harmonics), its torques logged 0, 6 or -13 ms
late (the torque signal lagging or leading the positions). A 40 s excitation (sums of
sines up to 1.2 or 3 Hz) is identified; a 20 s motion of other frequencies is held out.
For each fixed chain (``sj.identification.DEFAULT.chains``: recorded where there are,
derived at 5 and 10 Hz; each also with the plant's true delay) and for the default's
choice among them (the delay searched), the model is chosen and fitted by
``select_and_identify`` (OLS, the plant's terms) and its error on the held-out motion
(made by the same chain) measured: NRMS over the torque limits %.

    python -m benchmarks.signal_chain [--json benchmarks/results/signal_chain.json]

Figures: per plant, today's chain (as loaded: recorded where there are, 10 Hz, no
delay), the best fixed chain, the choice; ``choice / best`` and ``choice / today``; the
delay applied (none where none validated better) against the plant's.

``--real CUTOFFS`` instead sweeps cutoffs on the shipped robots: each chain's validated
error (the default's validation, OLS, ``--terms`` the model's terms beyond viscous and
Coulomb friction) and, for the KUKA LWR4+, the error on its run 2 of the same fit (the
run made by the same chain): where the validation within one recording and a new
recording agree on the cutoff, and where not.

    python -m benchmarks.signal_chain --real 2.5,5,10,20,40
"""

from __future__ import annotations

import argparse
import itertools
import time
import warnings
from pathlib import Path

import equinox as eqx
import jax
import numpy as np
import scipy.signal

import sedsabso_jax as sj
from benchmarks.output import to_json
from sedsabso_jax.identification import (
    DEFAULT,
    Default,
    DefaultValidation,
    candidate_models,
    parse_friction,
)
from sedsabso_jax.measurements import recorded_signals

LIMITS = np.array([300.0, 300.0, 150.0])


def motion(rate: float, seconds: float, seed: int, top_hz: float):
    """Sums of four sines per joint (0.1 to ``top_hz`` Hz, amplitudes falling as
    ``1 / (1 + f)^2``): times, q, qd, qdd exact."""
    t = np.arange(int(seconds * rate)) / rate
    rng = np.random.default_rng(seed)
    f = rng.uniform(0.1, top_hz, (4, 3))
    a = rng.uniform(0.05, 0.25, (4, 3)) / (1 + f) ** 2
    p = rng.uniform(0, 2 * np.pi, (4, 3))
    arg = 2 * np.pi * f[None] * t[:, None, None] + p[None]
    w = 2 * np.pi * f[None]
    return (t, (a * np.sin(arg)).sum(1), (a * w * np.cos(arg)).sum(1),
            (-a * w ** 2 * np.sin(arg)).sum(1))


#: What the plant's logger records beside the positions and torques.
LOGGERS = {"q only": None, "qd, qdd of the drive (exact, noisy)": "drive",
           "qd, qdd by a causal 5 Hz logger filter": "causal"}


#: The plants' torque delays [s] (positive: the torques lag the positions).
DELAYS = (0.0, 0.006, -0.013)


def plant(robot, t, q, qd, qdd, *, position_noise: float, logger: str | None, seed: int,
          delay_s: float = 0.0):
    """The plant's recording of the motion (module docstring)."""
    rng = np.random.default_rng(seed)
    tau = np.array(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    tau += 3.0 * qd + 4.0 * np.tanh(qd / 0.02) + np.array([2.0, -3.0, 1.0])
    if delay_s:  # logged delay_s late: at t the torque of t - delay_s (ends held)
        tau = np.column_stack([np.interp(t - delay_s, t, c) for c in tau.T])
    tau += 0.01 * np.sqrt(np.mean(tau ** 2, 0)) * rng.standard_normal(tau.shape)
    q_rec = q + position_noise * rng.standard_normal(q.shape)
    if logger is None:
        return recorded_signals(t, q_rec, tau, source="plant")
    if logger == "drive":
        return recorded_signals(t, q_rec, tau, qd + 1e-4 * rng.standard_normal(q.shape),
                                qdd + 5e-3 * rng.standard_normal(q.shape), source="plant")
    sos = scipy.signal.butter(2, 5.0, fs=1 / np.median(np.diff(t)), output="sos")
    return recorded_signals(t, q_rec, tau, scipy.signal.sosfilt(sos, qd, axis=0),
                            scipy.signal.sosfilt(sos, qdd, axis=0), source="plant")


def held_out_error(robot, model, data, held, signals) -> tuple[float, str, float]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = sj.select_and_identify(robot, data, held_out=held, limits=LIMITS,
                                        estimators=sj.OLS(), models=model, physical=False,
                                        validation=DefaultValidation(signals=signals))
    sel = report.chain_selection
    label = sel.labels[sel.chosen] if sel is not None else "given"
    applied = sel.chain.delay_s if sel is not None else float("nan")
    return float(report.validation.nrms_limits_percent), label, applied


def real(cutoffs: tuple[float, ...], terms: str) -> list[dict]:
    """The ``--real`` sweep (module docstring)."""
    import tempfile

    from benchmarks.real_robots import datasets

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, robot, data, limits, tr, held in datasets(Path(tmp)):
            lim = np.asarray(limits.torque_limits)
            model, = candidate_models(robot, [parse_friction(terms)], transmission=tr)
            chains = Default(cutoffs=cutoffs).chains([data.recorded], data.chain)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sel = sj.select_and_identify(
                    robot, data, limits=lim, estimators=sj.OLS(), models=model,
                    physical=False, validation=DefaultValidation(signals=chains)
                ).chain_selection
            for label, chain, cv in zip(sel.labels, chains, sel.validations):
                other = {}
                for run, h in held.items():
                    fit = sj.identify(robot, data.with_chain(chain, given=False), sj.OLS(),
                                      model, limits=lim)
                    h = h.with_chain(chain, given=False)
                    other[run] = float(sj.validation_metrics(
                        h.tau, fit.predict(h.q, h.qd, h.qdd), lim).nrms_limits_percent)
                rows.append({"robot": name, "signals": label, "validated": cv.score,
                             "standard_error": cv.standard_error, "other_runs": other})
                print(f"{name:34s} {label:20s} validated {cv.score:.4f} +- "
                      f"{cv.standard_error:.4f}" + "".join(
                          f", {k.split(' (')[0]} {v:.4f}" for k, v in other.items()),
                      flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", default=None)
    parser.add_argument("--seeds", type=int, default=1, help="plants per setting")
    parser.add_argument("--real", default=None, metavar="CUTOFFS",
                        help="sweep these cutoffs [Hz] on the shipped robots instead")
    parser.add_argument("--terms", default="offset+smooth",
                        help="the model's terms for --real (default offset+smooth)")
    args = parser.parse_args()
    jax.config.update("jax_enable_x64", True)
    if args.real:
        found = real(tuple(float(c) for c in args.real.split(",")), args.terms)
        if args.json:
            Path(args.json).write_text(to_json({
                "rows": found, "command": f"python -m benchmarks.signal_chain --real "
                                         f"{args.real} --terms {args.terms}"}))
        return
    robot = sj.robots.rs010n()
    model = sj.TorqueModel.of(robot, (sj.Offset(), sj.SmoothCoulomb()))
    rows = []
    for delay, rate, noise, (said, logger), top, seed in itertools.product(
            DELAYS, (100.0, 1000.0), (1e-5, 2e-4), LOGGERS.items(), (1.2, 3.0),
            range(args.seeds)):
        fit = plant(robot, *motion(rate, 40.0, 10 + seed, top), position_noise=noise,
                    logger=logger, seed=20 + seed, delay_s=delay)
        held = plant(robot, *motion(rate, 20.0, 30 + seed, top), position_noise=noise,
                     logger=logger, seed=40 + seed, delay_s=delay)
        chains = DEFAULT.chains([fit.recorded], fit.chain)
        chains += tuple(eqx.tree_at(lambda c: c.delay_s, c, delay) for c in chains
                        if delay)
        start = time.perf_counter()
        fixed = {c.label(fit.recorded): held_out_error(robot, model, fit, held, c)[0]
                 for c in chains}
        chosen, label, found = held_out_error(robot, model, fit, held, "auto")
        today = fixed[chains[0].label(fit.recorded)]
        best = min(fixed.values())
        rows.append({"delay_s": delay, "rate_hz": rate, "position_noise_rad": noise,
                     "recorded": said, "top_hz": top, "seed": seed, "fixed": fixed,
                     "today": today, "best": best, "chosen": label, "choice": chosen,
                     "choice_over_best": chosen / best, "choice_over_today": chosen / today,
                     "delay_applied_s": found, "seconds": time.perf_counter() - start})
        print(f"{1e3 * delay:+4g} ms, {rate:6g} Hz, noise {noise:.0e}, {said:38s} motion to "
              f"{top:g} Hz, seed {seed}: today {today:.4f}, best {best:.4f}, choice "
              f"{chosen:.4f} ({label}; delay applied {1e3 * found:+.2f} ms): /best "
              f"{chosen / best:.3f}, /today {chosen / today:.3f}", flush=True)
    over_best = [r["choice_over_best"] for r in rows]
    over_today = [r["choice_over_today"] for r in rows]
    print(f"choice / best fixed chain: median {np.median(over_best):.3f}, worst "
          f"{max(over_best):.3f}; choice / today's chain: median {np.median(over_today):.3f}, "
          f"worst {max(over_today):.3f} ({len(rows)} plants)")
    for rate in (100.0, 1000.0):
        miss = [abs(r["delay_applied_s"] - r["delay_s"]) for r in rows if r["rate_hz"] == rate]
        print(f"delay applied - the plant's, {rate:g} Hz: median {1e3 * np.median(miss):.3f} "
              f"ms, worst {1e3 * max(miss):.3f} ms ({1e-3 * rate * 1e3 * max(miss):.2f} "
              f"samples)")
    if args.json:
        Path(args.json).write_text(to_json({"rows": rows,
                                            "command": "python -m benchmarks.signal_chain"}))


if __name__ == "__main__":
    main()
