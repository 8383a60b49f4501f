"""What searching the smooth Coulomb's velocity scales beside friction at rest costs
(issue 45): on the KUKA LWR4+'s run 1 and the default's model (offset, smooth Coulomb,
load friction), friction at rest searched up to 20 mrad alone, and with the smooth
scales searched too. For each: the columns a trial moves, one compiled call's seconds per
trial (98 trials, warmed up, the median of 10 calls), and the search on all the data
(evaluations, Newton steps, seconds; OLS, the second fit timed).

    python -m benchmarks.kept_search_cost [--json PATH]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import equinox as eqx
import jax
import numpy as np

import sedsabso_jax as sj
from benchmarks.output import write_json
from sedsabso_jax.identification import KeptTerms, Projection, candidate_models

TRIALS = 98
AT_REST = sj.Presliding(fitted=True, largest=0.02)
KEPT = {"friction at rest": (AT_REST,),
        "friction at rest and the smooth scales": (AT_REST, sj.SmoothCoulomb(fitted=True))}


def main(argv=None) -> dict:
    jax.config.update("jax_enable_x64", True)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)
    robot = sj.robots.kuka_lwr4()
    data = sj.load_kuka_lwr4(1)
    chosen = next(m for m in candidate_models(robot)
                  if m.friction == "viscous-coulomb+offset+smooth+load")
    chosen = chosen.reading(chosen.prior_values)  # the load read at the robot's own
    losses = eqx.filter_jit(jax.vmap(lambda u, p: p.loss(u), (0, None)))
    out: dict = {}
    for label, terms in KEPT.items():
        model = KeptTerms([terms]).models(chosen)[0]
        problem = Projection.of(model, data)
        u0 = np.log(np.concatenate([f.values for _, f in model.nonlinear()]))
        U = u0 + 0.01 * np.random.default_rng(0).standard_normal((TRIALS, u0.size))
        jax.block_until_ready(losses(U, problem))
        calls = []
        for _ in range(10):
            t0 = time.perf_counter()
            jax.block_until_ready(losses(U, problem))
            calls.append(time.perf_counter() - t0)
        fits = []
        for _ in range(2):
            t0 = time.perf_counter()
            ident = sj.identify(robot, data, sj.OLS(), model)
            fits.append(time.perf_counter() - t0)
        searched = ident.settings["searched"]
        out[label] = {"friction": model.friction, "parameters": int(u0.size),
                      "moved_columns": problem.recipe.moved_columns,
                      "seconds_per_trial": float(np.median(calls)) / TRIALS,
                      "evaluations": searched["evaluations"],
                      "newton_steps": searched.get("newton_steps"),
                      "search_seconds": searched["seconds"], "identify_seconds": fits[-1]}
        r = out[label]
        print(f"{label}: {r['parameters']} parameters, {r['moved_columns']} moved columns, "
              f"{1e3 * r['seconds_per_trial']:.2f} ms a trial; the search on all the data "
              f"{r['evaluations']} trials, {r['newton_steps']} Newton steps, "
              f"{r['search_seconds']:.2f} s (identify {r['identify_seconds']:.2f} s)")
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
