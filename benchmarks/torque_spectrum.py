"""Whether a low-pass cutoff read off the torques' own spectrum is a signal chain worth
choosing among (issue 45): on the three shipped robots, the cutoff each rule gives, and
the default's validation of the chain that derives velocities and accelerations at it,
beside the chains it chooses among now.

The rules, per joint, on the Welch spectrum of the torques (mean removed, 8 s segments):

- ``power``: the frequency below which a fraction (90, 99, 99.9 %) of the power lies;
- ``floor``: the highest frequency whose power is above k (10, 100, 1000) times the noise
  floor, the median power above a quarter of the rate.

A robot's cutoff by a rule is the median over its joints. Its chain (derived at that
cutoff, where it lies below half the rate) is validated by the default
(``DefaultValidation(signals=...)`` given the candidates' chains and it, the model and
estimator chosen by the grid as usual) on the whole recording: the chains' table scores,
and the error on another run where there is one (the KUKA's run 2, made by the chosen
chain).

    python -m benchmarks.torque_spectrum [--robots kuka,panda,tx40] [--json PATH]
"""

from __future__ import annotations

import argparse
import tempfile
import time
import warnings
from pathlib import Path

import jax
import numpy as np
from scipy import signal

import sedsabso_jax as sj
from benchmarks.output import write_json
from benchmarks.real_robots import ROBOTS, datasets, judged_on, nrms
from sedsabso_jax.identification import candidate_models
from sedsabso_jax.measurements import SignalChain

FRACTIONS = (0.9, 0.99, 0.999)
FLOORS = (10.0, 100.0, 1000.0)
#: The rules whose cutoffs are validated (the others are only printed).
VALIDATED = ("power 99%", "floor 100x")


def cutoffs(times: np.ndarray, tau: np.ndarray) -> dict[str, np.ndarray]:
    """Each rule's cutoff per joint [Hz] (module docstring)."""
    rate = 1.0 / float(np.median(np.diff(times)))
    f, P = signal.welch(tau - tau.mean(0), fs=rate, axis=0,
                        nperseg=min(len(tau), int(8 * rate)))
    share = np.cumsum(P, 0) / np.sum(P, 0)
    out = {f"power {100 * a:g}%": f[np.argmax(share >= a, axis=0)] for a in FRACTIONS}
    floor = np.median(P[f > rate / 4], axis=0)
    for k in FLOORS:
        above = P > k * floor
        out[f"floor {k:g}x"] = np.array([f[np.flatnonzero(above[:, j])[-1]]
                                         if above[:, j].any() else 0.0
                                         for j in range(P.shape[1])])
    return out


def main(argv=None) -> dict:
    jax.config.update("jax_enable_x64", True)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)
    robots = tuple(args.robots.split(","))
    out: dict = {"robots": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for name, robot, data, limits, transmission, runs in datasets(Path(tmp), robots):
            recorded = data.recorded
            rate = 1.0 / float(np.median(np.diff(recorded.times)))
            rules = cutoffs(recorded.times, recorded.tau)
            median = {k: float(np.median(v)) for k, v in rules.items()}
            print(f"{name} ({rate:.0f} Hz): the cutoff of each rule, per joint [Hz]")
            for k, v in rules.items():
                print(f"  {k:>11}: {np.array2string(v, precision=2)}  median {median[k]:.3g}")
            loaded = data.chain
            chains = [loaded, SignalChain(5.0, derive=True),
                      SignalChain(10.0, derive=True)]
            chains += [SignalChain(median[k], derive=True) for k in VALIDATED
                       if 0 < median[k] < rate / 2]
            t0 = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                report = sj.select_and_identify(
                    robot, data, models=candidate_models(robot, transmission=transmission),
                    limits=limits.torque_limits,
                    validation=sj.identification.DefaultValidation(signals=tuple(chains)))
            chosen = report.chain_selection
            scores = {label: float(cv.score) for label, cv in zip(chosen.labels,
                                                                  chosen.validations)}
            held = {run: nrms(report.ident, judged_on(report, d), limits)
                    for run, d in runs.items()}
            print(f"  the chains validated ({time.perf_counter() - t0:.0f} s), chosen: "
                  f"{chosen.labels[chosen.chosen]}"
                  + "".join(f"; {run}: {v:.4f} %" for run, v in held.items()))
            for label, score in scores.items():
                print(f"    {label:<40} {score:.4f} %")
            out["robots"][name] = {"rate_hz": rate,
                                   "cutoffs_hz": {k: v.tolist() for k, v in rules.items()},
                                   "median_hz": median, "validated_percent": scores,
                                   "chosen": chosen.labels[chosen.chosen],
                                   "held_out_percent": held}
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
