"""Does a validator predict the error on new, faster motions? A simulation study (issue 22).

A simulated KUKA LWR4+ (the package's model as the rigid body) with effects no candidate
torque model has: Stribeck friction (static above Coulomb, decaying with speed),
load-dependent friction (proportional to the rigid-body torque), a saturating velocity
term, a torque offset drifting over the recording, Gaussian torque noise and position
noise on the recorded angles. Trajectories are the package's own excitation design
(Eq. 9) with different seeds; a trajectory played ``s`` times faster is ``q(s t)``.

For each of several plants (effect sizes drawn per plant), every candidate model
(the estimators and friction models ``identify`` chooses among, and physically consistent
fits) is identified on one recording and scored by

- ``phase_cv``: the package's cross-validation over the motion's phase (5 folds);
- ``speed_split``: fitted on the samples where every joint moves below ``lo`` of its peak
  speed, predicting those where one exceeds ``hi`` (0.6 / 0.75; what the issue measured);

and measured on new recordings of other trajectories at 1x, 1.5x and 2x the speed (the
truth a user meets). The table gives Spearman's rank correlation of each score with the
measured error over the candidates, and, for the model each score would choose, its
score over the error it measured (1 = a perfect prediction).

    python -m benchmarks.extrapolation [--plants 3] [--json benchmarks/results/extrapolation.json]

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
from sedsabso_jax.identification import ESTIMATOR_CANDIDATES, FRICTION_CANDIDATES

RATE, DURATION = 100.0, 10.0  # the design's period; recordings are two periods
SPEEDS = (1.0, 1.5, 2.0)
SPLIT = (0.6, 0.75)


def candidates() -> list[tuple[str, sj.Estimator, str]]:
    found = [(f"{e!r} {f}", e, f) for e in ESTIMATOR_CANDIDATES for f in FRICTION_CANDIDATES]
    for e in (sj.OLS(), sj.WLS("residual")):
        for f in FRICTION_CANDIDATES[:2]:
            found.append((f"physical {e!r} {f}", sj.PhysicallyConsistent(e), f))
    return found


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
        return sj.Measurements(times, q_recorded, qd, qdd, tau, source=f"speed {speed}")


def _subset(m: sj.Measurements, keep: np.ndarray) -> sj.Measurements:
    return sj.Measurements(m.times[keep], m.q[keep], m.qd[keep], m.qdd[keep], m.tau[keep])


def _nrms(fit: sj.Identification, m: sj.Measurements, tau_max: np.ndarray) -> float:
    predicted = fit.predict(m.q, m.qd, m.qdd)
    return float(sj.validation_metrics(m.tau, predicted, tau_max).nrms_limits_percent)


def speed_split(robot, data, estimator, friction, tau_max, base, lo=SPLIT[0], hi=SPLIT[1]):
    """Fit where every joint moves below ``lo`` of its peak speed, predict where one
    exceeds ``hi``: NRMS over the limits [%]."""
    speed = np.abs(data.qd) / np.abs(data.qd).max(0)
    train, test = np.all(speed < lo, axis=1), np.any(speed > hi, axis=1)
    fit = sj.identify(robot, _subset(data, train), estimator, friction, limits=tau_max,
                      base=base)
    return _nrms(fit, _subset(data, test), tau_max)


def study(plants: int) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the KUKA URDF's duplicate <origin>
        robot = sj.robots.kuka_lwr4()
    limits = joint_limits("kuka_lwr4", robot)
    tau_max = np.asarray(limits.tau_max)
    base = sj.base_parameters(robot)
    start = time.perf_counter()
    designs = [sj.design_excitation(robot, limits, key=seed, iterations=30, base=base,
                                    duration=DURATION, rate=RATE).trajectory
               for seed in range(plants + 3)]
    design_s = time.perf_counter() - start
    results = []
    for p in range(plants):
        plant = Plant(robot, tau_max, seed=p)
        data = plant.record(designs[p], 1.0, seed=0)
        new = {(t, s): plant.record(designs[t], s, seed=1 + 10 * t + int(10 * s))
               for t in range(plants, plants + 3) for s in SPEEDS}
        rows = []
        for name, estimator, friction in candidates():
            cv = sj.cross_validate(robot, data, estimator, friction, limits=tau_max, base=base)
            split = speed_split(robot, data, estimator, friction, tau_max, base)
            fit = sj.identify(robot, data, estimator, friction, limits=tau_max, base=base)
            measured = {s: float(np.mean([_nrms(fit, m, tau_max) for (t, sp), m in new.items()
                                          if sp == s])) for s in SPEEDS}
            rows.append({"candidate": name, "phase_cv": cv.score, "speed_split": split,
                         **{f"new_{s:g}x": v for s, v in measured.items()}})
        results.append({"plant": p, "rows": rows, "summary": summarise(rows)})
        print(f"plant {p}: {format_summary(results[-1]['summary'])}", flush=True)
    return {"design_s": design_s, "plants": results}


def summarise(rows: list[dict]) -> dict:
    """Per score and speed: Spearman's rho with the measured error, and the chosen
    model's score / measured error."""
    out: dict = {}
    for score in ("phase_cv", "speed_split"):
        predicted = np.array([r[score] for r in rows])
        chosen = int(np.argmin(predicted))
        for s in SPEEDS:
            measured = np.array([r[f"new_{s:g}x"] for r in rows])
            out[f"{score} vs new_{s:g}x"] = {
                "spearman": float(scipy.stats.spearmanr(predicted, measured).statistic),
                "chosen": rows[chosen]["candidate"],
                "predicted_over_measured": float(predicted[chosen] / measured[chosen]),
                "chosen_over_best": float(measured[chosen] / measured.min())}
    return out


def format_summary(summary: dict) -> str:
    return "; ".join(f"{k}: rho {v['spearman']:.2f}, pred/meas {v['predicted_over_measured']:.2f}"
                     for k, v in summary.items())


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plants", type=int, default=3)
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    argv = [f"--plants {args.plants}"] + ([f"--json {args.json}"] if args.json else [])
    jax.config.update("jax_enable_x64", True)
    found = study(args.plants)
    found["device"] = device_info()
    found["command"] = "python -m benchmarks.extrapolation " + " ".join(argv or [])
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json(found))


if __name__ == "__main__":
    main()
