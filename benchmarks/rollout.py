"""Rollout speed: every window of a recording simulated at once (``sedsabso_jax.dynamics.rollout``).

The KUKA LWR4+ (7 joints), ``--windows`` random windows of ``--steps`` steps of 2 ms, RK4,
float64; the first call (compile + run) apart, then the median of ``--repeats`` calls with
``block_until_ready``.

    python -m benchmarks.rollout [--windows 250] [--steps 100] [--repeats 3]
"""

from __future__ import annotations

import argparse
import time

import jax
import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--windows", type=int, default=250)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--integrator", default="rk4", choices=("rk4", "euler"))
    args = parser.parse_args()
    jax.config.update("jax_enable_x64", True)
    import sedsabso_jax as sj
    from sedsabso_jax.dynamics import rollout

    robot = sj.robots.kuka_lwr4()
    rng = np.random.default_rng(0)
    n = robot.n_joints
    q0 = rng.uniform(-1, 1, (args.windows, n))
    qd0 = rng.uniform(-0.5, 0.5, (args.windows, n))
    tau = rng.standard_normal((args.windows, args.steps, n))

    def run():
        return jax.block_until_ready(rollout(robot, None, q0, qd0, tau, 0.002,
                                             integrator=args.integrator))

    t = time.perf_counter()
    run()
    first = time.perf_counter() - t
    times = []
    for _ in range(args.repeats):
        t = time.perf_counter()
        run()
        times.append(time.perf_counter() - t)
    run_s = float(np.median(times))
    print(f"KUKA LWR4+, {args.windows} windows x {args.steps} steps, {args.integrator}, "
          f"{jax.default_backend()}: first call (compile + run) {first:.2f} s, "
          f"run {run_s:.2f} s (median of {args.repeats}), compile ~{first - run_s:.2f} s, "
          f"{run_s / (args.windows * args.steps) * 1e6:.1f} us per window-step")


if __name__ == "__main__":
    main()
