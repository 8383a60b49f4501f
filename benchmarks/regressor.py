"""Regressor throughput: sedsabso-jax (batched, jit) against pinocchio in a Python loop.

Same process, same samples, both in float64. sedsabso-jax: the first call (compile + run)
is reported apart; then ``--repeats`` timed calls with ``block_until_ready``. pinocchio:
``computeJointTorqueRegressor`` per sample into a preallocated array (its regressor has no
friction columns, so it writes 10 n instead of 12 n columns). The two are timed in
alternation, so load on this shared machine hits both alike; the ratio uses medians.
Before timing, the two regressors are checked to agree.

A floor: the result is ``samples x n x 12 n`` float64 (47 MB for the KUKA at 10,000
samples); the time to fill a fresh array of that size with numpy is printed beside. The
regressor runs where JAX runs (chunks of 16 / 8 samples on a CPU, all at once on a GPU,
see ``sedsabso_jax.dynamics.chunk_size``); the JSON names the device.

    python -m benchmarks.regressor [--samples 10000] [--repeats 15] [--json out.json]

Typical output (2-core CPU, see docs/results/regressor.md):

    robot    samples  compile_s  jax_ms  pinocchio_ms  speedup  fill_ms
    RS010N     10000       1.9     ...
"""

from __future__ import annotations

import argparse
import json
import time
from importlib import resources

import jax
import numpy as np
import pinocchio as pin

import sedsabso_jax as sj
from benchmarks.device import describe, device_info

PIN_TO_OURS = np.array([4, 6, 9, 5, 7, 8, 0, 1, 2, 3])


def pinocchio_rs010n(robot) -> pin.Model:
    """pinocchio model of the RS010N from its modified-DH table."""
    model = pin.Model()
    parent = 0
    for i, (alpha, a) in enumerate([(0.0, 0.0), (-np.pi / 2, 0.35), (0.0, 1.035)]):
        placement = pin.SE3(pin.utils.rotate("x", alpha), np.array([a, 0.0, 0.0]))
        parent = model.addJoint(parent, pin.JointModelRZ(), placement, f"J{i + 1}")
        p = np.asarray(robot.params[12 * i: 12 * i + 10])[np.argsort(PIN_TO_OURS)]
        model.appendBodyToJoint(parent, pin.Inertia.FromDynamicParameters(p), pin.SE3.Identity())
    return model


def pinocchio_loop(model, data, q, qd, qdd, out):
    for k in range(q.shape[0]):
        out[k] = pin.computeJointTorqueRegressor(model, data, q[k], qd[k], qdd[k])
    return out


def bench(name, robot, model, samples, repeats, rng):
    n = robot.n_joints
    q = rng.uniform(-np.pi, np.pi, (samples, n))
    qd, qdd = rng.standard_normal((2, samples, n))
    data = model.createData()
    out = np.empty((samples, n, 10 * n))

    t0 = time.perf_counter()
    Y = sj.regressor(robot, q, qd, qdd).block_until_ready()
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    sj.regressor(robot, q, qd, qdd).block_until_ready()
    second = time.perf_counter() - t0

    ref = pinocchio_loop(model, data, q, qd, qdd, out)
    ours = np.concatenate([np.asarray(Y)[..., 12 * i: 12 * i + 10] for i in range(n)], -1)
    theirs = np.concatenate([ref[..., 10 * i: 10 * i + 10][..., PIN_TO_OURS] for i in range(n)], -1)
    err = float(np.abs(ours - theirs).max())
    assert err < 1e-9, f"{name}: regressors disagree by {err}"

    t_jax, t_pin, t_fill = [], [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        sj.regressor(robot, q, qd, qdd).block_until_ready()
        t_jax.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        pinocchio_loop(model, data, q, qd, qdd, out)
        t_pin.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        np.full((samples, n, 12 * n), 1.0)
        t_fill.append(time.perf_counter() - t0)
    jax_ms, pin_ms = 1e3 * np.median(t_jax), 1e3 * np.median(t_pin)
    return {
        "robot": name, "joints": n, "samples": samples,
        "compile_s": first - second, "first_call_s": first,
        "jax_ms_median": jax_ms, "jax_ms_min": 1e3 * min(t_jax),
        "pinocchio_ms_median": pin_ms, "pinocchio_ms_min": 1e3 * min(t_pin),
        "speedup_median": pin_ms / jax_ms,
        "fill_fresh_array_ms_median": 1e3 * np.median(t_fill),
        "output_MB": samples * n * 12 * n * 8 / 1e6,
        "max_abs_difference": err,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    jax.config.update("jax_enable_x64", True)
    rng = np.random.default_rng(0)
    rows = []
    rs = sj.robots.rs010n()
    rows.append(bench("RS010N", rs, pinocchio_rs010n(rs), args.samples, args.repeats, rng))
    path = resources.files("sedsabso_jax") / "data" / "kuka_lwr4" / "kuka_lwr4.urdf"
    kuka = sj.robots.from_urdf(str(path))
    rows.append(bench("KUKA LWR4+", kuka, pin.buildModelFromUrdf(str(path)), args.samples,
                      args.repeats, rng))
    info = device_info()
    print(f"device: {describe(info)}, jax {jax.__version__}, pinocchio {pin.__version__}, "
          f"float64, median of {args.repeats}")
    print(f"{'robot':11s} {'samples':>7s} {'compile_s':>9s} {'jax_ms':>7s} {'pin_ms':>7s} "
          f"{'speedup':>7s} {'fill_ms':>7s} {'out_MB':>6s}")
    for r in rows:
        print(f"{r['robot']:11s} {r['samples']:7d} {r['compile_s']:9.2f} {r['jax_ms_median']:7.1f} "
              f"{r['pinocchio_ms_median']:7.1f} {r['speedup_median']:6.1f}x "
              f"{r['fill_fresh_array_ms_median']:7.1f} {r['output_MB']:6.1f}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"device": info, "jax": jax.__version__,
                       "pinocchio": pin.__version__, "rows": rows}, fh, indent=2)


if __name__ == "__main__":
    main()
