"""Friction beyond the default's candidates on the real KUKA LWR4+ (issue 30, parts 1 and
4): fixed and fitted velocity scales (smooth Coulomb, Stribeck) and Coulomb friction
growing with the transmitted torque, each fitted on run 1 by OLS and by the physically
consistent OLS fit, judged on run 2 (NRMS over the torque limits, %). Run 2 repeats run
1's trajectory: the figures measure repeatability, not how the terms extrapolate to new
motions (what the simulation study, ``benchmarks.extrapolation``, weighs). Of these terms
smooth Coulomb friction and load-dependent friction (two stages) are among the
default's candidates.

    python -m benchmarks.friction_terms [--json benchmarks/results/friction_terms.json]

Typical output (2-core AMD EPYC, 2026-11-26)::

    | friction | estimator | parameters | fit [%] | run 2 [%] | seconds | note |
    | viscous-coulomb+offset | OLS | 64 | 0.1281 | 0.1332 | 0.3 | |
    ...
"""

from __future__ import annotations

import argparse
import time
import warnings

import jax
import numpy as np

import sedsabso_jax as sj
from benchmarks.output import to_json
from sedsabso_jax.dynamics import joint_limits
from sedsabso_jax.identification import parse_friction

FRICTIONS = ("offset", "offset+smooth", "offset+smooth:fit", "offset+stribeck:fit",
             "offset+smooth:fit+stribeck:fit", "offset+load", "offset+smooth+load",
             "offset+smooth+load:fixed-point")


def nrms(pred: np.ndarray, tau: np.ndarray, limits: np.ndarray) -> float:
    return float(np.mean(np.sqrt(np.mean((pred - tau) ** 2, 0)) / (2 * limits)) * 100)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    robot = sj.robots.kuka_lwr4()
    limits = joint_limits("kuka_lwr4", robot).torque_limits
    fit_data, held = sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2)
    base = sj.base_parameters(robot)
    rows = []
    print("| friction | estimator | parameters | fit [%] | run 2 [%] | seconds | note |")
    print("|---|---|---|---|---|---|---|")
    for text in FRICTIONS:
        model = sj.TorqueModel.of(robot, parse_friction(text), base=base)
        for estimator in (sj.OLS(), sj.PhysicallyConsistent(sj.OLS())):
            t0 = time.perf_counter()
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                ident = sj.identify(robot, fit_data, estimator, model, limits=limits)
            seconds = time.perf_counter() - t0
            load = ident.settings.get("load")
            note = "" if not load else (
                f"load after {load['iterations']} fits" + (
                    "" if "settled" not in load else
                    f", {'settled' if load['settled'] else 'NOT settled'}"))
            shapes = ident.settings.get("shapes", {})
            on_bound = [k for k, s in shapes.items() if s["at_bound"]]
            if on_bound:
                note += f" on a bound: {', '.join(on_bound)}"
            row = {"friction": ident.model.friction, "estimator": estimator.name
                   + (" physical" if estimator.physical else ""),
                   "parameters": len(ident.names),
                   "fit": ident.fit["nrms_limits_percent"],
                   "run_2": nrms(ident.predict(held.q, held.qd, held.qdd), held.tau, limits),
                   "seconds": seconds, "shapes": shapes, "load": load,
                   "warnings": sorted({str(w.message)[:80] for w in caught})}
            rows.append(row)
            print(f"| {row['friction']} | {row['estimator']} | {row['parameters']} | "
                  f"{row['fit']:.4f} | {row['run_2']:.4f} | {seconds:.1f} | {note.strip()} |",
                  flush=True)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json({"robot": "kuka_lwr4", "fit": "run 1", "judged": "run 2",
                             "rows": rows}))


if __name__ == "__main__":
    main()
