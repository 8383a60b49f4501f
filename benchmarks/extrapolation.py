"""Does a validation predict the error on new motions? A simulation study (issue 22).

A simulated KUKA LWR4+ (the package's model as the rigid body) with effects no candidate
torque model has: Stribeck friction (static above Coulomb, decaying with speed),
load-dependent friction (proportional to the rigid-body torque), a saturating velocity
term, a torque offset drifting over the recording, Gaussian torque noise, and position
noise on the recorded angles, from which velocities and accelerations are derived as
``load_measurements`` does (zero-phase low-pass at 10 Hz, central differences, the
filter's edges dropped). Trajectories are the package's own excitation design (Eq. 9)
with different seeds; a trajectory played ``s`` times faster is ``q(s t)``.

For each plant (effect sizes drawn per plant), the 24 candidates ``identify`` chooses
among by default (OLS, Gautier's WLS and WLS by the limits; four torque models;
unconstrained and physically consistent) are fitted to ONE recording and scored by

- ``pooled``: the default validation, :class:`sedsabso_jax.Pooled` of the two below (its
  choice by the one-standard-error rule is the default's);
- ``phase``: :class:`sedsabso_jax.PhaseFolds` (5 folds of the motion's phase), its part;
- ``speed``: :class:`sedsabso_jax.SpeedSplits`, its other part;

and compared with

- ``new_Sx``: the error each fit makes on recordings of three other trajectories played
  at 1x, 1.5x and 2x the speed (what a user meets);
- ``loto``: leave one trajectory out (:class:`sedsabso_jax.RecordingFolds`) over four
  recordings of four trajectories (the fitted one at 1x, the three others at 1x, 1.5x
  and 2x); its ranking of the candidates is compared with the validations' ranking on
  the same four recordings pooled (``*_pooled``).

The defaults were chosen on plants 0-7 (the speed splits' thresholds on plants 0-3 of a
first version of this study, the pooling on all eight and on the real robots); plants
8-15 were not looked at before.

    python -m benchmarks.extrapolation [--plants 16] [--json benchmarks/results/extrapolation.json]

Figures: NRMS over the joint torque limits [%] (RMS error / (2 limit), mean over joints).
"""

from __future__ import annotations

import argparse
import time
import warnings

import jax
import numpy as np
import scipy.stats

import sedsabso_jax as sj
from benchmarks.device import device_info
from benchmarks.output import to_json
from sedsabso_jax.dynamics import joint_limits
from sedsabso_jax.identification import ESTIMATOR_CANDIDATES, candidate_models
from sedsabso_jax.measurements import DEFAULT_CUTOFF_HZ, differentiate

RATE, DURATION = 100.0, 10.0  # the design's period; recordings are two periods
SPEEDS = (1.0, 1.5, 2.0)
#: Plants whose results chose the defaults; the others are held out.
TUNED_ON = tuple(range(8))
#: The default's validation, and the scores compared: it, and each of its two parts.
DEFAULT = sj.Pooled((sj.PhaseFolds(), sj.SpeedSplits()))
SCORES = ("pooled", "speed", "phase")


class Plant:
    """The simulated robot's torques: rigid body plus effects the models lack."""

    def __init__(self, robot: sj.Robot, tau_max: np.ndarray, seed: int):
        rng = np.random.default_rng(seed)
        self.robot, self.tau_max, self.seed = robot, tau_max, seed
        self.fc = rng.uniform(0.01, 0.03, robot.n_joints) * tau_max     # Coulomb
        self.fs = self.fc * rng.uniform(1.2, 2.0, robot.n_joints)       # static (Stribeck)
        self.fv = rng.uniform(0.005, 0.02, robot.n_joints) * tau_max    # viscous, per rad/s
        self.vs = rng.uniform(0.03, 0.15)                               # Stribeck speed
        self.load = rng.uniform(0.0, 0.06)                              # load-dependent
        self.saturating = rng.uniform(0.0, 0.01, robot.n_joints) * tau_max
        self.drift = rng.uniform(0.0, 0.005, robot.n_joints) * tau_max
        self.noise = rng.uniform(0.002, 0.006)                          # of the limit
        self.position_noise = 2e-4                                      # rad

    def record(self, trajectory: sj.FourierTrajectory, speed: float, seed: int
               ) -> sj.Measurements:
        times = np.arange(int(round(2 * DURATION * RATE))) / RATE
        fast = sj.FourierTrajectory(np.asarray(trajectory.a) * speed,
                                    np.asarray(trajectory.b) * speed,
                                    np.asarray(trajectory.q0), trajectory.wf * speed)
        q, qd, qdd = (np.asarray(x) for x in fast(times))
        rng = np.random.default_rng([self.seed, seed])
        rigid = np.asarray(sj.inverse_dynamics(self.robot, self.robot.params, q, qd, qdd))
        friction = (np.sign(qd) * (self.fc + (self.fs - self.fc) * np.exp(-(qd / self.vs) ** 2))
                    + self.fv * qd + self.load * np.abs(rigid) * np.tanh(qd / 0.02)
                    + self.saturating * np.tanh(qd / 0.5))
        drift = self.drift * (times[:, None] - times[0]) / (times[-1] - times[0])
        tau = (rigid + friction + drift
               + self.noise * self.tau_max * rng.standard_normal(q.shape))
        q_recorded = q + self.position_noise * rng.standard_normal(q.shape)
        qd_derived, qdd_derived = differentiate(times, q_recorded, DEFAULT_CUTOFF_HZ)
        keep = slice(int(2 / DEFAULT_CUTOFF_HZ * RATE), -int(2 / DEFAULT_CUTOFF_HZ * RATE))
        return sj.Measurements(times[keep], q_recorded[keep], qd_derived[keep],
                               qdd_derived[keep], tau[keep], source=f"speed {speed}")


def _nrms(fit: sj.Identification, m: sj.Measurements, tau_max: np.ndarray) -> float:
    predicted = fit.predict(m.q, m.qd, m.qdd)
    return float(sj.validation_metrics(m.tau, predicted, tau_max).nrms_limits_percent)


def estimators() -> tuple[sj.Estimator, ...]:
    """The default's candidates: each estimator, unconstrained and physically consistent."""
    return tuple(e for base in ESTIMATOR_CANDIDATES
                 for e in (base, sj.PhysicallyConsistent(base)))


def study(plants: int) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the KUKA URDF's duplicate <origin>
        robot = sj.robots.kuka_lwr4()
    limits = joint_limits("kuka_lwr4", robot)
    tau_max = np.asarray(limits.tau_max)
    base = sj.base_parameters(robot)
    start = time.perf_counter()
    designs = [sj.design_excitation(robot, limits, key=seed, base=base,
                                    search=sj.excitation.DesignSearch(iterations=30),
                                    duration=DURATION, rate=RATE).trajectory
               for seed in range(plants + 3)]
    design_s = time.perf_counter() - start
    common = dict(estimators=estimators(), models=candidate_models(robot, base=base),
                  limits=tau_max)
    results = []
    for p in range(plants):
        t0 = time.perf_counter()
        plant = Plant(robot, tau_max, seed=p)
        data = plant.record(designs[p], 1.0, seed=0)
        others = range(plants, plants + 3)
        new = {(t, s): plant.record(designs[t], s, seed=1 + 10 * t + int(10 * s))
               for t in others for s in SPEEDS}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            # the default's validation, whose parts are the phase folds and speed splits
            one = sj.select_model(robot, data, validation=DEFAULT, **common)
            four = [data] + [new[(t, s)] for t, s in zip(others, SPEEDS)]
            pooled = sj.select_model(robot, four, validation=sj.Pooled(
                (sj.RecordingFolds(), sj.PhaseFolds(), sj.SpeedSplits())), **common)
        rows = []
        for i, ((settings, cv), (estimator, model)) in enumerate(
                zip(one.candidates, one.options)):
            fit = sj.identify(robot, data, estimator, model, limits=tau_max)
            measured = {s: float(np.mean([_nrms(fit, m, tau_max) for (t, sp), m in new.items()
                                          if sp == s])) for s in SPEEDS}
            four_cv = pooled.candidates[i][1]
            n_phase, n_speed = (four_cv.split_parts.count(k)
                                for k in ("phase folds", "speed splits"))
            parts = four_cv.part_scores
            rows.append({"candidate": {**settings}, "n_parameters": cv.n_parameters,
                         "pooled": cv.score, "phase": cv.part_scores["phase folds"],
                         "speed": cv.part_scores["speed splits"],
                         "loto": parts["recording folds"],
                         "speed_pooled": parts["speed splits"],
                         "phase_pooled": parts["phase folds"],
                         "pooled_pooled": (n_phase * parts["phase folds"]
                                           + n_speed * parts["speed splits"])
                         / (n_phase + n_speed),
                         **{f"new_{s:g}x": v for s, v in measured.items()},
                         "chosen": settings is one.chosen})
        results.append({"plant": p, "tuned_on": p in TUNED_ON, "rows": rows,
                        "summary": summarise(rows), "seconds": time.perf_counter() - t0})
        print(f"plant {p} ({results[-1]['seconds']:.0f} s): "
              f"{format_summary(results[-1]['summary'])}", flush=True)
    return {"design_s": design_s, "plants": results,
            "table": table(results)}


def summarise(rows: list[dict]) -> dict:
    """Per score: Spearman's rho with the measured error at each speed and with LOTO; the
    default's choice (``chosen``, the pooled score's one-standard-error rule) and the
    other scores' lowest: predicted / measured, and the measured error over the best
    candidate's."""
    out: dict = {}
    measured = {s: np.array([r[f"new_{s:g}x"] for r in rows]) for s in SPEEDS}
    loto = np.array([r["loto"] for r in rows])
    chosen = next(i for i, r in enumerate(rows) if r["chosen"])
    for score in SCORES:
        predicted = np.array([r[score] for r in rows])
        lowest = int(np.argmin(predicted))
        entry: dict = {"rho_loto_pooled": float(scipy.stats.spearmanr(
            [r[f"{score}_pooled"] for r in rows], loto).statistic),
            "rho_loto": float(scipy.stats.spearmanr(predicted, loto).statistic)}
        for s, m in measured.items():
            pick = chosen if score == "pooled" else lowest
            entry[f"{s:g}x"] = {
                "rho": float(scipy.stats.spearmanr(predicted, m).statistic),
                "predicted_over_measured": float(predicted[pick] / m[pick]),
                "chosen_over_best": float(m[pick] / m.min())}
        out[score] = entry
    return out


def format_summary(summary: dict) -> str:
    return "; ".join(
        f"{k}: rho LOTO {v['rho_loto_pooled']:.2f}, 2x rho {v['2x']['rho']:.2f} "
        f"pred/meas {v['2x']['predicted_over_measured']:.2f}" for k, v in summary.items())


def table(results: list[dict]) -> list[dict]:
    """Median (min-max) over the plants, separately for those tuned on and held out."""
    out = []
    for held_out in (False, True):
        group = [r["summary"] for r in results if r["tuned_on"] != held_out]
        if not group:
            continue
        for score in SCORES:
            row = {"plants": "held out" if held_out else "tuned on", "score": score}
            values = {"rho_loto_pooled": [g[score]["rho_loto_pooled"] for g in group],
                      "rho_loto": [g[score]["rho_loto"] for g in group]}
            for s in SPEEDS:
                for key in ("rho", "predicted_over_measured", "chosen_over_best"):
                    values[f"{s:g}x {key}"] = [g[score][f"{s:g}x"][key] for g in group]
            row.update({k: {"median": float(np.median(v)), "min": float(np.min(v)),
                            "max": float(np.max(v))} for k, v in values.items()})
            out.append(row)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plants", type=int, default=16)
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    found = study(args.plants)
    found["device"] = device_info()
    found["command"] = ("python -m benchmarks.extrapolation --plants "
                        f"{args.plants}" + (f" --json {args.json}" if args.json else ""))
    for row in found["table"]:
        print(row["plants"], row["score"], " ".join(
            f"{k}={v['median']:.2f}({v['min']:.2f}-{v['max']:.2f})" for k, v in row.items()
            if isinstance(v, dict)))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json(found))


if __name__ == "__main__":
    main()
