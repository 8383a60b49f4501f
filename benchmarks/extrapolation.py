"""Does a validation predict the error on new motions? A simulation study (issues 22, 36).

A simulated KUKA LWR4+ (the package's model as the rigid body) with effects no candidate
torque model has: Stribeck friction (static above Coulomb, decaying with speed),
load-dependent friction (proportional to the rigid-body torque), a saturating velocity
term, a torque offset drifting over the recording, Gaussian torque noise, position noise
on the recorded angles (velocities and accelerations derived as ``load_measurements``
does), and friction at rest: on most joints a share of the Coulomb friction follows
Dahl's state (:func:`dahl`), every fourth plant without any (:data:`WITHOUT_RESTS`).
Trajectories are the package's own excitation design (Eq. 9) with different seeds; a
trajectory played ``s`` times faster is ``q(s t)``.

For each plant the default's grid (OLS, Gautier's WLS and WLS by the limits; five torque
models; unconstrained and physically consistent), the same with friction at rest added
(fixed and searched, :data:`REST_VARIANTS`) and 0.5.0's candidates are fitted to ONE
recording, scored by the default validation (and its two parts), and judged on new
motions (:data:`MOTIONS`): three other trajectories at 1x, 1.5x and 2x the speed, point to
point with dwells, pick and place, slow reversals. The rules compared (:func:`choices`)
pick among the rows; each pick's validated error, and that error weighed to the new
motion's speeds (``sj.identification.rests``), is compared with its error on the new
motions. ``--loto`` adds leaving one trajectory out over four recordings.

Plants 0-7 chose the defaults, 8-15 are held out (docs/results/extrapolation.md says
which choice was made on which plants).

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
#: The new motions that rest: point to point with dwells, pick and place, slow reversals
#: (:class:`PointToPoint`, :func:`pick_and_place`, :class:`SlowReversals`).
RESTING = ("p2p", "pick", "reversals")
#: The new motions each fit is judged on: the three other trajectories at each speed,
#: and the motions that rest (each from the three other trajectories' ranges).
MOTIONS = tuple(f"{s:g}x" for s in SPEEDS) + RESTING
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
#: The choices compared (:func:`choices`), and the rule's pick among the grid by
#: :data:`FAR` (``far``, with ``--far``).
CHOICES = ("default", "grid", "kept_fixed", "kept_fit", "kept_either", "grid_rest",
           "previous", "far")


def _middle(trajectory: sj.FourierTrajectory) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The excitation's positions' mean and their 20 % and 80 % quantiles per joint."""
    times = np.arange(int(round(DURATION * RATE))) / RATE
    q = np.asarray(trajectory(times)[0])
    return np.mean(q, 0), np.quantile(q, 0.2, axis=0), np.quantile(q, 0.8, axis=0)


class PointToPoint:
    """A point-to-point motion with rests: from the excitation's mean position to
    ``moves`` random waypoints within the middle of each joint's excitation range, each
    reached by a minimum-jerk move of ``move_s`` seconds, then held for ``rest_s``
    seconds (the joints stand still). ``points``: the waypoints instead (the first is
    the start)."""

    def __init__(self, trajectory: sj.FourierTrajectory, seed: int, moves: int = 8,
                 move_s: float = 1.5, rest_s: float = 1.0, points: np.ndarray | None = None):
        mean, lo, hi = _middle(trajectory)
        rng = np.random.default_rng([seed, 7])
        self.points = np.vstack([mean, lo + (hi - lo) * rng.random((moves, len(mean)))]) \
            if points is None else np.asarray(points)
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


def pick_and_place(trajectory: sj.FourierTrajectory, seed: int) -> PointToPoint:
    """A pick-and-place cycle: from one pick pose to a random place pose and back, seven
    times (13 moves of 1 s, each followed by a 0.5 s dwell; the joints reverse at every
    pose)."""
    mean, lo, hi = _middle(trajectory)
    rng = np.random.default_rng([seed, 11])
    pick = lo + (hi - lo) * rng.random(len(mean))
    places = lo + (hi - lo) * rng.random((7, len(mean)))
    points = np.vstack([mean] + [p for place in places for p in (pick, place)])
    return PointToPoint(trajectory, seed, move_s=1.0, rest_s=0.5, points=points)


class SlowReversals:
    """Slow back-and-forth motion: each joint a sine about the excitation's mean with an
    amplitude of 10-25 % of its excitation range and a period of 4-8 s (no dwell; the
    joints reverse slowly, at a tenth or so of the excitation's speeds)."""

    def __init__(self, trajectory: sj.FourierTrajectory, seed: int):
        mean, lo, hi = _middle(trajectory)
        rng = np.random.default_rng([seed, 13])
        n = len(mean)
        self.mean = mean
        self.amplitude = (hi - lo) / 0.6 * rng.uniform(0.1, 0.25, n)
        self.omega = 2 * np.pi / rng.uniform(4.0, 8.0, n)
        self.phase = rng.uniform(0, 2 * np.pi, n)

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        arg = self.omega * t[:, None] + self.phase
        a, w = self.amplitude, self.omega
        return (self.mean + a * (np.sin(arg) - np.sin(self.phase)), a * w * np.cos(arg),
                -a * w ** 2 * np.sin(arg))


def dahl(q: np.ndarray, q_c: np.ndarray) -> np.ndarray:
    """Dahl's presliding state along the positions ``q`` (``(T, n)``) from ``z = 0``,
    integrated exactly per increment, written here apart from the package's
    ``sj.identification.dahl_state``: ``z <- s + (z - s) exp(-|dq| / q_c)``."""
    z = np.zeros_like(q)
    for k in range(1, len(q)):
        dq = q[k] - q[k - 1]
        s = np.sign(dq)
        z[k] = np.where(dq != 0, s + (z[k - 1] - s) * np.exp(-np.abs(dq) / q_c), z[k - 1])
    return z


#: Plants whose joints hold no friction at rest (every fourth: 3, 7, 11, 15).
WITHOUT_RESTS = 4


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
        # friction at rest (Dahl's state): the share of each joint's Coulomb friction
        # that builds up over a displacement q_c after a reversal and holds at rest
        # (0 on a joint in five, and on every joint of every fourth plant)
        self.rest_share = np.where(rng.random(robot.n_joints) < 0.8,
                                   rng.uniform(0.3, 1.0, robot.n_joints), 0.0)
        if seed % WITHOUT_RESTS == WITHOUT_RESTS - 1:
            self.rest_share = np.zeros(robot.n_joints)
        self.q_c = np.exp(rng.uniform(np.log(1e-3), np.log(2e-2), robot.n_joints))  # rad

    @property
    def rests(self) -> bool:
        """Whether a joint holds friction at rest."""
        return bool(np.any(self.rest_share > 0))

    def record(self, trajectory: sj.FourierTrajectory | PointToPoint | SlowReversals,
               speed: float, seed: int) -> sj.Measurements:
        times = np.arange(int(round(2 * DURATION * RATE))) / RATE
        if not isinstance(trajectory, sj.FourierTrajectory):
            q, qd, qdd = trajectory(times)
        else:
            fast = sj.FourierTrajectory(np.asarray(trajectory.a) * speed,
                                        np.asarray(trajectory.b) * speed,
                                        np.asarray(trajectory.q0), trajectory.wf * speed)
            q, qd, qdd = (np.asarray(x) for x in fast(times))
        rng = np.random.default_rng([self.seed, seed])
        rigid = np.asarray(sj.inverse_dynamics(self.robot, self.robot.params, q, qd, qdd))
        coulomb = self.fc * ((1 - self.rest_share) * np.sign(qd)
                             + self.rest_share * dahl(q, self.q_c))
        friction = (coulomb + np.sign(qd) * (self.fs - self.fc) * np.exp(-(qd / self.vs) ** 2)
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


def new_motions(plant: Plant, designs, others) -> dict:
    """The plant's new motions, ``{(kind, t): recording}`` for each of :data:`MOTIONS` and
    each trajectory ``designs[t]`` of ``others``: played at each of :data:`SPEEDS`, and
    made into motions that rest."""
    p = plant.seed
    new = {(f"{s:g}x", t): plant.record(designs[t], s, seed=1 + 10 * t + int(10 * s))
           for t in others for s in SPEEDS}
    new.update({("p2p", t): plant.record(PointToPoint(designs[t], seed=p), 1.0,
                                         seed=5 + 10 * t) for t in others})
    new.update({("pick", t): plant.record(pick_and_place(designs[t], seed=p), 1.0,
                                          seed=6 + 10 * t) for t in others})
    new.update({("reversals", t): plant.record(SlowReversals(designs[t], seed=p), 1.0,
                                               seed=7 + 10 * t) for t in others})
    return new


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
    # each default model with friction at rest added, at a fixed displacement and searched
    resting = tuple(m for kind in REST_VARIANTS.values() for g in models
                    for m in kind.models(g))
    union = (models + tuple(m for m in previous_models if m.friction not in defaults)
             + resting)
    kinds = {m.friction: "grid" for m in models} | {m.friction: "rest" for m in resting}
    common = dict(estimators=estimators(), limits=tau_max)
    results = []
    for p in range(plants) if only is None else only:
        t0 = time.perf_counter()
        plant = Plant(robot, tau_max, seed=p)
        data = plant.record(designs[p], 1.0, seed=0)
        others = range(plants, plants + 3)
        new = new_motions(plant, designs, others)
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
        picks = choices(one, kinds, previous_models)
        if far is not None:
            picks["far"] = next(i for i, (s, _) in enumerate(far.candidates) if s is far.chosen)
        rows = []
        for i, ((settings, cv), (estimator, model)) in enumerate(
                zip(one.candidates, one.options)):
            fit = sj.identify(robot, data, estimator, model, limits=tau_max)
            measured = {k: float(np.mean([_nrms(fit, m, tau_max) for (kind, _), m
                                          in new.items() if kind == k])) for k in MOTIONS}
            # the validated error weighed to each new motion's speeds (sj.identification.rests)
            weighed = {k: float(np.mean([sj.identification.rests(
                data, m, cross_validation=cv, limits=tau_max).predicted
                for (kind, _), m in new.items() if kind == k])) for k in MOTIONS}
            row = {"candidate": {**settings}, "n_parameters": cv.n_parameters,
                   "kind": kinds.get(model.friction, "previous"),
                   "default_candidate": model.friction in defaults,
                   "pooled": cv.score, "phase": cv.part_scores["phase folds"],
                   "speed": cv.part_scores["speed splits"],
                   **{f"new_{k}": v for k, v in measured.items()},
                   **{f"weighed_{k}": v for k, v in weighed.items()},
                   **{f"{c}_chosen": i == picks.get(c) for c in CHOICES}}
            if model.friction in defaults and far is not None:  # the default's first, as in far's
                row["far"] = far.candidates[i][1].score
            if pooled is not None and model.friction in defaults:
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
        results.append({"plant": p, "tuned_on": p in TUNED_ON, "rests": plant.rests,
                        "rest_share": plant.rest_share.tolist(), "q_c": plant.q_c.tolist(),
                        "rows": rows, "summary": summarise(rows),
                        "seconds": time.perf_counter() - t0})
        print(f"plant {p} ({results[-1]['seconds']:.0f} s): "
              f"{format_summary(results[-1]['summary'])}", flush=True)
    return {"design_s": design_s, "plants": results,
            "table": table(results)}


#: Friction at rest added to a default candidate: at the package's fixed displacement,
#: and with the displacements searched up to 20 mrad (the default's, ``KEPT_TERMS``).
REST_VARIANTS = {"fixed": sj.identification.KeptTerms(sj.Presliding()),
                 "fit": sj.identification.KEPT_TERMS}


def choices(selection: sj.identification.Selection, kinds: dict, previous_models) -> dict:
    """The row each rule picks (:data:`CHOICES`), from the rows of ``selection``:

    - ``grid``: the one-standard-error rule among the grid (the default's torque models
      without friction at rest: 0.6's default);
    - ``kept_fixed``, ``kept_fit``, ``kept_either``: the grid's pick, then friction at
      rest added (fixed, searched, or both tried) and kept unless it validates worse
      (:class:`sj.identification.KeptTerms`);
    - ``default``: the package's rule (:data:`sj.identification.KEPT_TERMS`);
    - ``grid_rest``: the one-standard-error rule among the grid and the models with
      friction at rest together (the term as one more candidate);
    - ``previous``: 0.5.0's default, the rule among its torque models."""
    cvs = [cv for _, cv in selection.candidates]
    physical = [e.physical for e, _ in selection.options]
    frictions = [m.friction for _, m in selection.options]
    kind = [kinds.get(f, "previous") for f in frictions]
    grid = choice(cvs, physical, [k == "grid" for k in kind])
    estimator, model = selection.options[grid]

    def kept(rule: sj.identification.KeptTerms) -> int:
        found = [next(i for i, (e, m) in enumerate(selection.options)
                      if e == estimator and m.friction == with_terms.friction)
                 for with_terms in rule.models(model)]
        which = rule.kept(cvs[grid], [cvs[i] for i in found])
        return grid if which is None else found[which]

    previous = {m.friction for m in previous_models}
    return {"grid": grid, "kept_fixed": kept(REST_VARIANTS["fixed"]),
            "kept_fit": kept(REST_VARIANTS["fit"]),
            "kept_either": kept(sj.identification.KeptTerms(
                [*REST_VARIANTS["fixed"].alternatives, *REST_VARIANTS["fit"].alternatives])),
            "default": kept(sj.identification.KEPT_TERMS),
            "grid_rest": choice(cvs, physical, [k in ("grid", "rest") for k in kind]),
            "previous": choice(cvs, physical, [f in previous for f in frictions])}


def choice(cvs: list, physical: list[bool], among: list[bool]) -> int:
    """The index the default's one-standard-error rule picks among the candidates
    ``among`` marks."""
    keep = [i for i in range(len(cvs)) if among[i]]
    return keep[simplest_not_worse([cvs[i] for i in keep], [physical[i] for i in keep])]


def summarise(rows: list[dict]) -> dict:
    """Among the grid's candidates, per score: Spearman's rho with the measured error
    on each kind of new motion (and with LOTO where it ran). Per choice
    (:data:`CHOICES`), on each kind of new motion: its predicted / measured error (the
    prediction: the score it was chosen by, the previous default's the default
    validation's; and that score weighed to the motion's speeds), its measured error
    over the best candidate's (of the grid and the models with friction at rest), over
    the grid's choice and over the previous default's choice."""
    out: dict = {}
    default = [r for r in rows if r["kind"] == "grid"]
    candidates = [r for r in rows if r["kind"] in ("grid", "rest")]
    measured = {k: np.array([r[f"new_{k}"] for r in default]) for k in MOTIONS}
    best = {k: min(r[f"new_{k}"] for r in candidates) for k in MOTIONS}
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
    grid = next(r for r in rows if r["grid_chosen"])
    for c in CHOICES:
        pick = next((r for r in rows if r[f"{c}_chosen"]), None)
        if pick is None:  # far's choice without --far
            continue
        score = pick["far" if c == "far" else "pooled"]
        out[c] = {k: {"predicted_over_measured": score / pick[f"new_{k}"],
                      "weighed_over_measured": pick[f"weighed_{k}"] / pick[f"new_{k}"],
                      "chosen_over_best": pick[f"new_{k}"] / best[k],
                      "over_grid": pick[f"new_{k}"] / grid[f"new_{k}"],
                      "over_previous": pick[f"new_{k}"] / previous[f"new_{k}"]}
                  for k in MOTIONS}
        out[c]["friction"] = pick["candidate"]["friction"]
    return out


def format_summary(summary: dict) -> str:
    """Per choice: its torque model, and per motion its error over the best candidate's
    / its weighed prediction over the error."""
    return "; ".join(
        f"{c} {summary[c]['friction'][16:]}: " + ", ".join(
            f"{k} {v['chosen_over_best']:.2f}/{v['weighed_over_measured']:.2f}"
            for k, v in summary[c].items() if k != "friction")
        for c in CHOICES if c in summary)


def table(results: list[dict]) -> list[dict]:
    """Median (min-max) over the plants, separately for those tuned on and held out, and
    for the plants without friction at rest among each: per choice and kind of new
    motion, chosen over best, predicted (and weighed) over measured, over the grid's
    and the previous default's choice; per score, its rank correlations."""
    out = []
    keys = ("chosen_over_best", "predicted_over_measured", "weighed_over_measured",
            "over_grid", "over_previous")
    for held_out in (False, True):
        for without in (False, True):
            group = [r["summary"] for r in results if r["tuned_on"] != held_out
                     and (not without or not r.get("rests", True))]
            if not group:
                continue
            label = ("held out" if held_out else "tuned on") + (
                ", without friction at rest" if without else "")
            for c in (c for c in CHOICES if c in group[0]):
                values = {f"{k} {key}": [g[c][k][key] for g in group] for k in MOTIONS
                          for key in keys}
                out.append({"plants": label, "choice": c, **_spread(values)})
            if without:
                continue
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
