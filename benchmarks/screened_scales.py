"""The smooth Coulomb's scales searched where they validate better (the default's screen,
``sj.identification.SCREENED_TERMS``), against the default without it, on simulated
plants judged on motions no choice or fit saw (issue 45).

The plants are :mod:`benchmarks.extrapolation`'s: a simulated KUKA LWR4+ with Stribeck
friction (static above Coulomb, decaying over 0.03-0.15 rad/s), load-dependent and
saturating friction, a drifting offset, friction at rest on most joints, torque and
position noise, velocities and accelerations derived from the positions. Each is
identified from one excitation by ``select_and_identify`` (the default's candidates and
validation, the signals as recorded) with and without the screen, and judged on the new
motions of that study (three other trajectories at 1x, 1.5x and 2x the speed, point to
point with dwells, pick and place, slow reversals; each the mean over three). Held-out
plants by default (8-15: the screen has no constant of its own, and the default's were
chosen on plants 0-7).

    python -m benchmarks.screened_scales [--plants 8-15] [--position-noise RAD] [--json PATH]

Figures: NRMS over the joint torque limits [%], per plant and kind of motion, with and
without the screen, and their ratio; whether the screen passed and the scales were
kept; the seconds of each identification.
"""

from __future__ import annotations

import argparse
import time
import warnings

import jax
import numpy as np

import sedsabso_jax as sj
from benchmarks.extrapolation import DURATION, MOTIONS, RATE, Plant, _nrms, new_motions
from benchmarks.output import to_json
from sedsabso_jax.dynamics import joint_limits
from sedsabso_jax.identification import DefaultValidation, candidate_models


def plant_rows(p: int, designs: list, robot, tau_max, models,
               position_noise: float | None = None) -> dict:
    """Plant ``p`` identified with and without the screen, judged on its new motions
    (``position_noise``: the recorded positions' [rad], None: the plant's own)."""
    plant = Plant(robot, tau_max, seed=p)
    if position_noise is not None:
        plant.position_noise = position_noise
    data = plant.record(designs[0], 1.0, seed=0)
    new = new_motions(plant, designs, range(1, 4))
    out: dict = {"plant": p, "position_noise": plant.position_noise}
    for name, screened in (("with", sj.identification.SCREENED_TERMS), ("without", None)):
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            report = sj.select_and_identify(
                robot, data, limits=tau_max, models=models,
                validation=DefaultValidation(signals=None, screened=screened))
        seconds = time.perf_counter() - t0
        screen = report.selection.screen
        out[name] = {"friction": report.ident.model.friction, "seconds": seconds,
                     "validated": report.cross_validation.score,
                     **{k: float(np.mean([_nrms(report.ident, m, tau_max)
                                          for (kind, _), m in new.items() if kind == k]))
                        for k in MOTIONS}}
        if screen is not None:
            out[name].update(passed=screen.passed, kept=screen.kept,
                             scales=screen.scales(), smallest=screen.smallest(),
                             noise=screen.noise)
    out["ratio"] = {k: out["with"][k] / out["without"][k] for k in MOTIONS}
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plants", default="8-15", help="first-last plant seeds (8-15)")
    ap.add_argument("--json", default=None)
    ap.add_argument("--position-noise", type=float, default=None,
                    help="the recorded positions' noise [rad] (default: the plants' 2e-4)")
    args = ap.parse_args(argv)
    first, last = (int(x) for x in args.plants.split("-"))
    jax.config.update("jax_enable_x64", True)
    robot = sj.robots.kuka_lwr4()
    limits = joint_limits("kuka_lwr4", robot)
    tau_max = np.asarray(limits.tau_max)
    base = sj.base_parameters(robot)
    models = candidate_models(robot, base=base)
    rows = []
    for p in range(first, last + 1):
        # the plant's excitation and three other trajectories (the study's designs)
        designs = [sj.design_excitation(robot, limits, key=seed, base=base,
                                        search=sj.excitation.DesignSearch(iterations=30),
                                        duration=DURATION, rate=RATE).trajectory
                   for seed in (p, 16, 17, 18)]
        row = plant_rows(p, designs, robot, tau_max, models, args.position_noise)
        rows.append(row)
        w = row["with"]
        print(f"plant {p}: screen from {w.get('smallest', 0):.3g} rad/s, "
              f"{'passed' if w.get('passed') else 'not passed'}"
              f"{', kept' if w.get('kept') else ''}; "
              + ", ".join(f"{k} {w[k]:.3f}/{row['without'][k]:.3f}" for k in MOTIONS)
              + f"; {w['seconds']:.0f} s / {row['without']['seconds']:.0f} s", flush=True)
    ratios = {k: [r["ratio"][k] for r in rows] for k in MOTIONS}
    summary = {k: {"median": float(np.median(v)), "min": float(np.min(v)),
                   "max": float(np.max(v))} for k, v in ratios.items()}
    print("ratio with / without the screen (median, min, max): " + "; ".join(
        f"{k} {s['median']:.3f} ({s['min']:.3f}-{s['max']:.3f})" for k, s in summary.items()))
    if args.json:
        with open(args.json, "w") as f:
            f.write(to_json({"plants": rows, "summary": summary}))


if __name__ == "__main__":
    main()
