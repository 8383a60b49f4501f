"""COCO's bbob functions: evaluations per second of sedsabso-jax's JAX suite
(``sj.compare.coco_function``) against COCO's own C code through ``cocoex``.

Same process, same points: a population of 100 points uniform in [-5, 5]^d (seed 0),
float64, instance 1 of f1 (sphere, the cheapest), f10 (rotated ellipsoid: a rotation and
T_osz), f16 (Weierstrass: 12 cosines a coordinate), f21 (Gallagher, 101 peaks) and f23
(Katsuura: 32 terms a coordinate, a product), d = 10 and 40. Before timing, the values
are checked to agree with cocoex's (relative 1e-10, as tests/test_coco.py).

- sedsabso-jax: ``f(X)``, the population in one call, ``block_until_ready``; the first
  call of a dimension compiles (reported apart: one compilation serves every function and
  instance of the dimension, so the other functions' first calls compile nothing). At
  100 points a call costs mostly its dispatch (about 50 us on this CPU); so also
  ``jax.lax.map(f, Xs)`` over 50 populations in one compiled call, as an optimiser's
  compiled loop evaluates its populations (column ``in_jit``).
- cocoex, Python loop: ``problem(x)`` for each point (a ``cocoex.Suite`` problem, as an
  experiment calls it).
- cocoex, BareProblem: ``BareProblem(X)`` on the (100, d) array (the loop in Cython).

All are timed in alternation for ``--repeats`` rounds (a timing: as many calls as take
about 20 ms) and the fastest round kept (load on this shared machine only ever adds
time); the ratios are evaluations per second of sedsabso-jax over cocoex's.

    python -m benchmarks.coco_speed [--repeats 7]
        [--json benchmarks/results/coco_speed_cpu_2core.json]

Typical output (2-core AMD EPYC, shared, float64; benchmarks/results/
coco_speed_cpu_2core.json; figures vary by up to 2x between runs on this machine):

      d    f compile_s  first_s  jax_evals/s in_jit_evals/s loop_evals/s bare_evals/s
     10   f1       2.1   2.0965     1.18e+06       7.75e+07     1.04e+06     6.75e+06
     10  f23             0.0025     5.78e+05       2.74e+06     1.62e+05        2e+05
     40  f16             0.0098      4.4e+04       5.75e+04     5.09e+04     5.91e+04
     40  f21             0.0086     2.52e+05       3.46e+05     1.83e+05     1.89e+05

At 100 points a call, ``f(X)`` is about as fast as cocoex's Python loop and slower than
its C loop on cheap functions (the call's dispatch dominates); inside compiled code the
cheap functions run 10-75x faster than cocoex, the transcendental-heavy ones (f10, f16,
f21: libm's ``exp``, ``log``, ``sin``, ``cos`` element by element, as in C) 1-2.5x, and
f23 13-17x (COCO computes ``pow(2, j)`` 32 times a coordinate).
"""

from __future__ import annotations

import argparse
import time

import jax
import numpy as np

import sedsabso_jax as sj
from benchmarks.device import describe, device_info
from benchmarks.output import to_json

FUNCTIONS = (1, 10, 16, 21, 23)
DIMENSIONS = (10, 40)
POPULATION = 100
#: populations evaluated in one compiled call (``lax.map``)
MAPPED = 50


def timed(run, calls: int) -> float:
    """Seconds per call of ``run``, over ``calls`` calls."""
    t0 = time.perf_counter()
    for _ in range(calls):
        run()
    return (time.perf_counter() - t0) / calls


def calls_for(run, seconds: float = 0.02) -> int:
    """How many calls of ``run`` take about ``seconds`` (one timing)."""
    return max(1, round(seconds / timed(run, 1)))


def bench(function: int, dim: int, X: np.ndarray, suite, repeats: int, compiled: set) -> dict:
    import cocoex

    f, f_opt, _ = sj.compare.coco_function(function, 1, dim)
    Xj = jax.device_put(X)
    t0 = time.perf_counter()
    got = np.asarray(f(Xj).block_until_ready())  # compiles once per dimension
    first_s = time.perf_counter() - t0
    compile_s = first_s if dim not in compiled else None
    compiled.add(dim)
    Xs = jax.device_put(np.broadcast_to(X, (MAPPED,) + X.shape).copy())
    in_jit = jax.jit(lambda Xs: jax.lax.map(f, Xs))
    np.testing.assert_array_equal(np.asarray(in_jit(Xs))[-1], got)
    problem = suite.get_problem_by_function_dimension_instance(function, dim, 1)
    bare = cocoex.BareProblem("bbob", function, dim, 1)
    want = np.array([problem(x) for x in X])
    scale = np.maximum(np.abs(want), np.abs(want - f_opt))
    rel = float(np.max(np.abs(got - want) / scale))
    assert rel <= 1e-10 and np.array_equal(bare(X), want), (function, dim, rel)

    runs = {"jax": lambda: f(Xj).block_until_ready(),
            "in_jit": lambda: in_jit(Xs).block_until_ready(),
            "loop": lambda: [problem(x) for x in X],
            "bare": lambda: bare(X)}
    for run in runs.values():  # warm-up
        run()
    calls = {k: calls_for(run) for k, run in runs.items()}
    points = {"jax": POPULATION, "in_jit": MAPPED * POPULATION, "loop": POPULATION,
              "bare": POPULATION}
    best = {k: np.inf for k in runs}
    for _ in range(repeats):
        for k, run in runs.items():
            best[k] = min(best[k], timed(run, calls[k]))
    rate = {k: points[k] / best[k] for k in runs}
    return {"function": function, "dimension": dim, "population": POPULATION,
            "compile_s": compile_s, "first_call_s": first_s,
            "jax_s_per_population": best["jax"],
            "in_jit_s_per_population": best["in_jit"] / MAPPED,
            "loop_s_per_population": best["loop"], "bare_s_per_population": best["bare"],
            **{f"{k}_evals_per_s": v for k, v in rate.items()},
            "ratio_jax_vs_loop": rate["jax"] / rate["loop"],
            "ratio_jax_vs_bare": rate["jax"] / rate["bare"],
            "ratio_in_jit_vs_loop": rate["in_jit"] / rate["loop"],
            "ratio_in_jit_vs_bare": rate["in_jit"] / rate["bare"],
            "max_relative_difference": rel}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    import cocoex

    suite = cocoex.Suite("bbob", "instances: 1", "dimensions: 10,40")
    rows, compiled = [], set()
    info = device_info()
    print(f"device: {describe(info)}, jax {jax.__version__}, cocoex {cocoex.__version__}, "
          f"float64, {POPULATION} points, fastest of {args.repeats} rounds", flush=True)
    print(f"{'d':>3s} {'f':>4s} {'compile_s':>9s} {'first_s':>8s} {'jax_evals/s':>12s} "
          f"{'in_jit_evals/s':>14s} {'loop_evals/s':>12s} {'bare_evals/s':>12s}", flush=True)
    for dim in DIMENSIONS:
        X = np.random.default_rng(0).uniform(-5, 5, (POPULATION, dim))
        for function in FUNCTIONS:
            r = bench(function, dim, X, suite, args.repeats, compiled)
            rows.append(r)
            compile_s = "" if r["compile_s"] is None else f"{r['compile_s']:.1f}"
            print(f"{dim:3d} {'f' + str(function):>4s} {compile_s:>9s} "
                  f"{r['first_call_s']:8.4f} {r['jax_evals_per_s']:12.3g} "
                  f"{r['in_jit_evals_per_s']:14.3g} {r['loop_evals_per_s']:12.3g} "
                  f"{r['bare_evals_per_s']:12.3g}", flush=True)
    print("ratios (evaluations per second over cocoex's): jax / loop, jax / bare, "
          "in_jit / loop, in_jit / bare")
    for r in rows:
        print(f"{r['dimension']:3d} {'f' + str(r['function']):>4s} "
              f"{r['ratio_jax_vs_loop']:6.2f} {r['ratio_jax_vs_bare']:6.2f} "
              f"{r['ratio_in_jit_vs_loop']:6.2f} {r['ratio_in_jit_vs_bare']:6.2f}")
    doc = {"rows": rows, "device": info, "cocoex": cocoex.__version__,
           "command": "python -m benchmarks.coco_speed"
                      + (f" --repeats {args.repeats}" if args.repeats != 7 else "")}
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            fh.write(to_json(doc))


if __name__ == "__main__":
    main()
