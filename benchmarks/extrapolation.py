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
from sedsabso_jax.identification import (
    ESTIMATOR_CANDIDATES,
    candidate_models,
    simplest_not_worse,
)
from sedsabso_jax.measurements import DEFAULT_CUTOFF_HZ, differentiate

RATE, DURATION = 100.0, 10.0  # the design's period; recordings are two periods
SPEEDS = (1.0, 1.5, 2.0)
#: The new motions each fit is judged on: the three other trajectories at each speed,
#: and point-to-point motions with rests (:class:`PointToPoint`).
MOTIONS = tuple(f"{s:g}x" for s in SPEEDS) + ("p2p",)
#: Plants whose results chose the defaults; the others are held out.
TUNED_ON = tuple(range(8))
#: The default's validation, and the scores compared: it, and each of its two parts.
DEFAULT = sj.Pooled((sj.PhaseFolds(), sj.SpeedSplits()))
SCORES = ("pooled", "speed", "phase")
#: A validation whose speed splits extrapolate further (fit below half of each joint's
#: peak speed, predict above 0.8 of it: up to 2x), tried in place of the default's.
FAR = sj.Pooled((sj.PhaseFolds(), sj.SpeedSplits(fit_below=0.5, predict_above=0.8)))
#: The torque models of 0.5.0's default, fitted beside the default's own so that its
#: choice (made again among their rows) is compared on the same plants and motions.
PREVIOUS_FRICTIONS = ((), (sj.Offset(),), (sj.Offset(), sj.Armature()),
                      (sj.Offset(), sj.Quadratic(), sj.SmoothCoulomb()))
#: The choices compared: the rule's pick among the default's candidates by the default's
#: validation (``default``) and by :data:`FAR` (``far``), and among 0.5.0's
#: (``previous``).
CHOICES = ("default", "far", "previous")


class PointToPoint:
    """A point-to-point motion with rests: from the excitation's mean position to
    ``moves`` random waypoints within the middle of each joint's excitation range, each
    reached by a minimum-jerk move of ``move_s`` seconds, then held for ``rest_s``
    seconds (the joints stand still, as on a pick-and-place cycle)."""

    def __init__(self, trajectory: sj.FourierTrajectory, seed: int, moves: int = 8,
                 move_s: float = 1.5, rest_s: float = 1.0):
        times = np.arange(int(round(DURATION * RATE))) / RATE
        q = np.asarray(trajectory(times)[0])
        lo, hi = np.quantile(q, 0.2, axis=0), np.quantile(q, 0.8, axis=0)
        rng = np.random.default_rng([seed, 7])
        self.points = np.vstack([np.mean(q, 0), lo + (hi - lo) * rng.random((moves, q.shape[1]))])
        self.move_s, self.rest_s = move_s, rest_s

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        period = self.move_s + self.rest_s
        k = np.minimum((t // period).astype(int), len(self.points) - 2)
        u = np.clip((t - k * period) / self.move_s, 0.0, 1.0)[:, None]
        dq = self.points[k + 1] - self.points[k]
        s = 10 * u ** 3 - 15 * u ** 4 + 6 * u ** 5
        sd = (30 * u ** 2 - 60 * u ** 3 + 30 * u ** 4) / self.move_s
        sdd = (60 * u - 180 * u ** 2 + 120 * u ** 3) / self.move_s ** 2
        moving = (t - k * period < self.move_s)[:, None]
        return self.points[k] + s * dq, sd * dq * moving, sdd * dq * moving


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

    def record(self, trajectory: sj.FourierTrajectory | PointToPoint, speed: float,
               seed: int) -> sj.Measurements:
        times = np.arange(int(round(2 * DURATION * RATE))) / RATE
        if isinstance(trajectory, PointToPoint):
            q, qd, qdd = trajectory(times)
        else:
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


def study(plants: int, loto: bool = False, only: list[int] | None = None,
          with_far: bool = False) -> dict:
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
    models = candidate_models(robot, base=base)
    previous_models = candidate_models(robot, PREVIOUS_FRICTIONS, base=base)
    defaults = {m.friction for m in models}
    union = models + tuple(m for m in previous_models if m.friction not in defaults)
    common = dict(estimators=estimators(), limits=tau_max)
    results = []
    for p in range(plants) if only is None else only:
        t0 = time.perf_counter()
        plant = Plant(robot, tau_max, seed=p)
        data = plant.record(designs[p], 1.0, seed=0)
        others = range(plants, plants + 3)
        new = {(f"{s:g}x", t): plant.record(designs[t], s, seed=1 + 10 * t + int(10 * s))
               for t in others for s in SPEEDS}
        new.update({("p2p", t): plant.record(PointToPoint(designs[t], seed=p), 1.0,
                                             seed=5 + 10 * t) for t in others})
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            # the default's validation, whose parts are the phase folds and speed splits
            one = sj.select_model(robot, data, validation=DEFAULT, models=union, **common)
            far = sj.select_model(robot, data, validation=FAR, models=models,
                                  **common) if with_far else None
            pooled = sj.select_model(robot, [data] + [new[(f"{s:g}x", t)] for t, s in zip(
                others, SPEEDS)], validation=sj.Pooled(
                (sj.RecordingFolds(), sj.PhaseFolds(), sj.SpeedSplits())),
                models=models, **common) if loto else None
        cvs = [cv for _, cv in one.candidates]
        physical = [e.physical for e, _ in one.options]
        in_default = [m.friction in defaults for _, m in one.options]
        picks = {"default": choice(cvs, physical, in_default),
                 "far": -1 if far is None else next(
                     i for i, (s, _) in enumerate(far.candidates) if s is far.chosen),
                 "previous": choice(cvs, physical, [
                     m.friction in {x.friction for x in previous_models}
                     for _, m in one.options])}
        rows = []
        for i, ((settings, cv), (estimator, model)) in enumerate(
                zip(one.candidates, one.options)):
            fit = sj.identify(robot, data, estimator, model, limits=tau_max)
            measured = {k: float(np.mean([_nrms(fit, m, tau_max) for (kind, _), m
                                          in new.items() if kind == k])) for k in MOTIONS}
            row = {"candidate": {**settings}, "n_parameters": cv.n_parameters,
                   "default_candidate": in_default[i],
                   "pooled": cv.score, "phase": cv.part_scores["phase folds"],
                   "speed": cv.part_scores["speed splits"],
                   **{f"new_{k}": v for k, v in measured.items()},
                   **{f"{c}_chosen": i == picks[c] for c in CHOICES}}
            if in_default[i] and far is not None:  # the default's come first, as in far's
                row["far"] = far.candidates[i][1].score
            if pooled is not None and in_default[i]:
                four_cv = pooled.candidates[i][1]
                n_phase, n_speed = (four_cv.split_parts.count(k)
                                    for k in ("phase folds", "speed splits"))
                parts = four_cv.part_scores
                row.update({"loto": parts["recording folds"],
                            "speed_pooled": parts["speed splits"],
                            "phase_pooled": parts["phase folds"],
                            "pooled_pooled": (n_phase * parts["phase folds"]
                                              + n_speed * parts["speed splits"])
                            / (n_phase + n_speed)})
            rows.append(row)
        results.append({"plant": p, "tuned_on": p in TUNED_ON, "rows": rows,
                        "summary": summarise(rows), "seconds": time.perf_counter() - t0})
        print(f"plant {p} ({results[-1]['seconds']:.0f} s): "
              f"{format_summary(results[-1]['summary'])}", flush=True)
    return {"design_s": design_s, "plants": results,
            "table": table(results)}


def choice(cvs: list, physical: list[bool], among: list[bool]) -> int:
    """The index the default's one-standard-error rule picks among the candidates
    ``among`` marks."""
    keep = [i for i in range(len(cvs)) if among[i]]
    return keep[simplest_not_worse([cvs[i] for i in keep], [physical[i] for i in keep])]


def summarise(rows: list[dict]) -> dict:
    """Among the default's candidates, per score: Spearman's rho with the measured error
    on each kind of new motion (and with LOTO where it ran). Per choice
    (:data:`CHOICES`), on each kind of new motion: its predicted / measured error (the
    prediction: the score it was chosen by; the previous default's, the default
    validation's), its measured error over the best of the default's candidates and
    over the previous default's choice."""
    out: dict = {}
    default = [r for r in rows if r["default_candidate"]]
    measured = {k: np.array([r[f"new_{k}"] for r in default]) for k in MOTIONS}
    for score in SCORES:
        predicted = np.array([r[score] for r in default])
        entry: dict = {k: float(scipy.stats.spearmanr(predicted, m).statistic)
                       for k, m in measured.items()}
        if "loto" in default[0]:
            entry["loto_pooled"] = float(scipy.stats.spearmanr(
                [r[f"{score}_pooled"] for r in default],
                [r["loto"] for r in default]).statistic)
        out[f"rho_{score}"] = entry
    previous = next(r for r in rows if r["previous_chosen"])
    for c in CHOICES:
        pick = next((r for r in rows if r[f"{c}_chosen"]), None)
        if pick is None:  # far's choice without --far
            continue
        score = pick["far" if c == "far" else "pooled"]
        out[c] = {k: {"predicted_over_measured": score / pick[f"new_{k}"],
                      "chosen_over_best": pick[f"new_{k}"] / m.min(),
                      "over_previous": pick[f"new_{k}"] / previous[f"new_{k}"]}
                  for k, m in measured.items()}
        out[c]["friction"] = pick["candidate"]["friction"]
    return out


def format_summary(summary: dict) -> str:
    return "; ".join(
        f"{c} {summary[c]['friction'][16:]}: " + ", ".join(
            f"{k} {v['chosen_over_best']:.2f}/{v['predicted_over_measured']:.2f}"
            for k, v in summary[c].items() if k != "friction")
        for c in CHOICES if c in summary)


def table(results: list[dict]) -> list[dict]:
    """Median (min-max) over the plants, separately for those tuned on and held out:
    per choice and kind of new motion, chosen over best, predicted over measured and
    over the previous default's; per score, its rank correlations."""
    out = []
    for held_out in (False, True):
        group = [r["summary"] for r in results if r["tuned_on"] != held_out]
        if not group:
            continue
        label = "held out" if held_out else "tuned on"
        for c in (c for c in CHOICES if c in group[0]):
            values = {f"{k} {key}": [g[c][k][key] for g in group] for k in MOTIONS
                      for key in ("chosen_over_best", "predicted_over_measured",
                                  "over_previous")}
            out.append({"plants": label, "choice": c, **_spread(values)})
        for score in SCORES:
            values = {k: [g[f"rho_{score}"][k] for g in group]
                      for k in group[0][f"rho_{score}"]}
            out.append({"plants": label, "rho": score, **_spread(values)})
    return out


def _spread(values: dict) -> dict:
    return {k: {"median": float(np.median(v)), "min": float(np.min(v)),
                "max": float(np.max(v))} for k, v in values.items()}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plants", type=int, default=16)
    parser.add_argument("--json", default=None)
    parser.add_argument("--loto", action="store_true",
                        help="also leave one trajectory out over four recordings (slow)")
    parser.add_argument("--far", action="store_true",
                        help="also choose by speed splits that extrapolate to 2x (FAR)")
    parser.add_argument("--only", type=int, nargs="+", default=None,
                        help="run these plants only (the designs stay those of --plants)")
    args = parser.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    found = study(args.plants, args.loto, args.only, args.far)
    found["device"] = device_info()
    found["command"] = ("python -m benchmarks.extrapolation --plants "
                        f"{args.plants}" + " --loto" * args.loto + " --far" * args.far
                        + (" --only " + " ".join(map(str, args.only)) if args.only else "")
                        + (f" --json {args.json}" if args.json else ""))
    for row in found["table"]:
        print(row["plants"], row.get("choice", row.get("rho")), " ".join(
            f"{k}={v['median']:.2f}({v['min']:.2f}-{v['max']:.2f})" for k, v in row.items()
            if isinstance(v, dict)))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json(found))


if __name__ == "__main__":
    main()
