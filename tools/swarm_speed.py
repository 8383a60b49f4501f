"""One process's run time of each swarm on the paper's problem, for comparing two
checkouts of the package (a refactor that must not slow the swarms down).

RS010N, Eq. 17 over 1000 random states (seed 0), the paper's settings and search box, 600
iterations; each swarm compiled first, then the fastest of ``--seeds`` seeded runs (the
shared machine only ever adds time). Prints one JSON line: the package's path and the
seconds per swarm. Alternate the checkouts, several processes each, and compare medians:

    for i in 1 2 3 4 5 6; do PYTHONPATH=OLD python tools/swarm_speed.py; \\
        python tools/swarm_speed.py; done
"""

from __future__ import annotations

import argparse
import json
import time

import jax

jax.config.update("jax_enable_x64", True)
import numpy as np  # noqa: E402

import sedsabso_jax as sj  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=19, help="timed runs per swarm (19)")
    args = ap.parse_args()
    robot = sj.robots.rs010n()
    q, qd, qdd = np.random.default_rng(0).normal(size=(3, 1000, robot.n_joints))
    base = sj.base_parameters(robot)
    tau = sj.inverse_dynamics(robot, robot.params, q, qd, qdd)
    problem = sj.L1Residual.from_base(base, q, qd, qdd, tau)
    lo, hi = sj.box_around(np.asarray(base.values), 0.1, 0.1)
    out: dict = {"package": sj.__file__}
    for name in ("SEDSABSO", "BSO", "LDWPSO"):
        solver = getattr(sj, name).paper()
        jax.block_until_ready(sj.minimise(problem, solver, lo, hi, key=jax.random.key(0),
                                          iterations=600).f)
        best = np.inf
        for seed in range(1, args.seeds + 1):
            t0 = time.perf_counter()
            jax.block_until_ready(sj.minimise(problem, solver, lo, hi,
                                              key=jax.random.key(seed), iterations=600).f)
            best = min(best, time.perf_counter() - t0)
        out[name] = best
    print(json.dumps(out))


if __name__ == "__main__":
    main()
