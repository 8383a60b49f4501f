"""The paper's identification problem: SEDSABSO, BSO and LDWPSO against the baselines
and pyswarms, same process, same fitness (Eq. 17), same budget.

RS010N (3 joints, 21 base parameters), 1000 random states (seed 0), noise-free torques
from the paper's Table 2, search box ``true +- max(10 % |true|, 0.1)`` (the paper's own
scenario: a box around the true values), 600 iterations, the paper's settings. Per swarm:
compile time apart; one run timed on its own after compilation (fastest of 5 seeds,
median in the JSON), float64 and float32; 10 runs batched in one compiled call; mean
final fitness and mean largest absolute base-parameter error over the 10 runs; SEDSABSO /
BSO time from alternating pairs. Also: BSO with the authors' literal sign, all three with
Vmax = 0.1 (ub - lb) and SEDSABSO with 0.05, OLS / LM / GN / L1-LP, and pyswarms'
GlobalBestPSO (50 particles, w = 0.8, c1 = c2 = 2, numpy fitness over the swarm), mealpy's
OriginalPSO and evosax's PSO (:mod:`benchmarks.peers`; same fitness, same budget; float32
computed in float32 throughout).

Speed against evosax's PSO: the three swarms and evosax's PSO, float64 and float32,
compiled first, then one run each in turn for ``--ratio-seeds`` seeds in the same
process; time per run the fastest over the seeds (the shared machine only ever adds
time), ratio to evosax's in the same dtype. Runs per call: ``--runs-per-call`` runs in
one compiled call (``minimise(runs=k)``, ``batch="auto"``: in sequence on a CPU, vmapped
on an accelerator; evosax's run vmapped over keys), one call timed after compilation.
The JSON names the device (platform, kind, CPU model).

    python -m benchmarks.swarms [--json out.json] [--quick] [--runs-per-call 1,10,100,1000]

About 20 minutes on the 2-core CPU, most of it the 1000-run calls.
"""

from __future__ import annotations

import argparse
import json
import time

import jax
import jax.numpy as jnp
import numpy as np

import sedsabso_jax as sj
from benchmarks import peers
from benchmarks.device import describe, device_info
from benchmarks.problems import rs010n_problem
from sedsabso_jax import baselines
from sedsabso_jax.optim import BeetleStep


def batch_label() -> str:
    """How ``minimise(runs=k)`` with ``batch="auto"`` shares a call here (its docstring):
    in sequence on a single CPU device, else vmapped (on one accelerator, in chunks that
    fit its memory when all runs at once would not)."""
    if jax.default_backend() == "cpu" and jax.device_count() == 1:
        return "in sequence"
    return "vmap"


def swarm_row(name, solver, prob, lo, hi, true, iterations, dtype, runs=10):
    first = sj.minimise(prob, solver, lo, hi, key=jax.random.key(0), iterations=iterations,
                        dtype=dtype)
    singles = [sj.minimise(prob, solver, lo, hi, key=jax.random.key(s), iterations=iterations,
                           dtype=dtype).run_s for s in peers.SEEDS]
    sj.minimise(prob, solver, lo, hi, key=jax.random.key(0), iterations=iterations,
                dtype=dtype, runs=runs)  # compile the batched call
    many = sj.minimise(prob, solver, lo, hi, key=jax.random.key(7), iterations=iterations,
                       dtype=dtype, runs=runs)
    x = np.asarray(many.x, dtype=float)
    return {
        "method": name, "dtype": jnp.dtype(dtype).name, "compile_s": first.compile_s,
        **peers.timing(singles), "batched_runs": runs,
        "batched_time_s": many.run_s, "fitness_mean": float(np.mean(many.f)),
        "fitness_std": float(np.std(many.f)),
        "max_abs_error_mean": float(np.abs(x - true).max(-1).mean()),
        "sa_accepted_mean": float(np.mean(many.sa_accepted)),
    }


def paired_ratio(prob, lo, hi, iterations, dtype, pairs=9):
    """SEDSABSO / BSO time per run, from runs alternated in pairs (same seeds), so that the
    shared machine's slow spells hit both alike: the ratio of the fastest runs of each
    (the machine only ever adds time) and the median of the pairwise ratios."""
    sed, bso = sj.SEDSABSO.paper(), sj.BSO.paper()
    times = np.array([[sj.minimise(prob, s, lo, hi, key=jax.random.key(100 + seed),
                                   iterations=iterations, dtype=dtype).run_s for s in (sed, bso)]
                      for seed in range(pairs)])
    ratios = times[:, 0] / times[:, 1]
    return {"dtype": jnp.dtype(dtype).name, "pairs": pairs,
            "fastest": float(times[:, 0].min() / times[:, 1].min()),
            "median": float(np.median(ratios)), "min": float(ratios.min()),
            "max": float(ratios.max())}


def speed_vs_evosax(prob, lo, hi, iterations, dtypes, seeds):
    """Time per run of SEDSABSO, BSO, LDWPSO and evosax's PSO, interleaved seeds in one
    process; fastest and median over the seeds, ratio (fastest) to evosax's PSO in the
    same dtype."""
    W, tau = np.asarray(prob.W), np.asarray(prob.tau)
    calls = {}
    for dtype in dtypes:
        name = jnp.dtype(dtype).name
        exe, _ = peers.evosax_compiled(W, tau, lo, hi, iterations, dtype=name)
        jax.block_until_ready(exe(jax.random.key(0)))

        def evosax_call(seed, exe=exe):
            t0 = time.perf_counter()
            jax.block_until_ready(exe(jax.random.key(seed)))
            return time.perf_counter() - t0

        calls["evosax PSO", name] = evosax_call
        for method in ("SEDSABSO", "BSO", "LDWPSO"):
            solver = getattr(sj, method).paper()
            sj.minimise(prob, solver, lo, hi, key=jax.random.key(0), iterations=iterations,
                        dtype=dtype)  # compile
            calls[method, name] = (lambda seed, s=solver, d=dtype: sj.minimise(
                prob, s, lo, hi, key=jax.random.key(seed), iterations=iterations,
                dtype=d).run_s)
    times = {k: [] for k in calls}
    for seed in range(1, seeds + 1):
        for k, call in calls.items():
            times[k].append(call(seed))
    rows = []
    for (method, name), t in times.items():
        ref = min(times["evosax PSO", name])
        rows.append({"method": method, "dtype": name, "seeds": seeds,
                     "time_per_run_s": float(min(t)), "time_per_run_median_s": float(np.median(t)),
                     "over_evosax": float(min(t) / ref)})
    return rows


def runs_per_call(prob, lo, hi, iterations, dtypes, counts):
    """Seconds of one compiled call of ``k`` runs, for each ``k`` in ``counts`` (timed
    after the compiling call), per method and dtype; evosax's PSO vmapped over keys."""
    W, tau = np.asarray(prob.W), np.asarray(prob.tau)
    rows = []
    batch = batch_label()
    for dtype in dtypes:
        name = jnp.dtype(dtype).name
        for k in counts:
            for method in ("SEDSABSO", "BSO", "LDWPSO"):
                solver = getattr(sj, method).paper()
                first = sj.minimise(prob, solver, lo, hi, key=jax.random.key(0),
                                    iterations=iterations, dtype=dtype, runs=k)
                r = sj.minimise(prob, solver, lo, hi, key=jax.random.key(1),
                                iterations=iterations, dtype=dtype, runs=k)
                rows.append({"method": method, "dtype": name, "runs": k,
                             "batch": batch, "compile_s": first.compile_s,
                             "call_s": r.run_s, "per_run_s": r.run_s / k})
                print(f"  {method:8s} {name} {k:5d} runs: {r.run_s:8.2f} s", flush=True)
            compile_s, call_s = peers.evosax_many(W, tau, lo, hi, iterations, k, name)
            rows.append({"method": "evosax PSO", "dtype": name, "runs": k, "batch": "vmap",
                         "compile_s": compile_s, "call_s": call_s, "per_run_s": call_s / k})
            print(f"  evosax   {name} {k:5d} runs: {call_s:8.2f} s", flush=True)
    return rows


def pyswarms_row(prob, lo, hi, true, iterations):
    import pyswarms as ps

    W, tau = np.asarray(prob.W), np.asarray(prob.tau)
    f = lambda X: np.abs(X @ W.T - tau).sum(1)  # noqa: E731
    times, fs, errs = [], [], []
    for seed in peers.SEEDS:
        np.random.seed(seed)
        opt = ps.single.GlobalBestPSO(n_particles=50, dimensions=len(lo),
                                      options={"c1": 2.0, "c2": 2.0, "w": 0.8}, bounds=(lo, hi))
        t0 = time.perf_counter()
        cost, pos = opt.optimize(f, iters=iterations, verbose=False)
        times.append(time.perf_counter() - t0)
        fs.append(cost)
        errs.append(np.abs(pos - true).max())
    return {"method": "pyswarms GlobalBestPSO", "dtype": "float64", "compile_s": 0.0,
            **peers.timing(times), "fitness_mean": float(np.mean(fs)),
            "max_abs_error_mean": float(np.mean(errs))}


def baseline_rows(prob, true):
    rows = []
    for name, fn in (("OLS", baselines.ols), ("LM", lambda p: baselines.least_squares(p, "LM")),
                     ("GN", lambda p: baselines.least_squares(p, "GN")),
                     ("L1-LP", baselines.l1_optimum)):
        first = fn(prob)
        r = fn(prob)  # timed after compilation
        rows.append({"method": name, "dtype": "float64", "compile_s": first.compile_s,
                     "time_per_run_s": r.run_s, "fitness_mean": float(r.f),
                     "max_abs_error_mean": float(np.abs(np.asarray(r.x) - true).max())})
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--json", default=None)
    parser.add_argument("--quick", action="store_true", help="100 iterations, float64 only")
    parser.add_argument("--ratio-seeds", type=int, default=7)
    parser.add_argument("--runs-per-call", default="1,10,100,1000",
                        help="comma-separated run counts per compiled call ('' to skip)")
    args = parser.parse_args()
    jax.config.update("jax_enable_x64", True)
    iterations = 100 if args.quick else 600
    info = device_info()
    print(f"device: {describe(info)}, jax {info['jax']}", flush=True)
    prob, lo, hi, true = rs010n_problem()
    rows = []
    dtypes = (jnp.float64,) if args.quick else (jnp.float64, jnp.float32)
    paper = {"SEDSABSO": sj.SEDSABSO.paper(), "BSO": sj.BSO.paper(), "LDWPSO": sj.LDWPSO.paper()}
    for dtype in dtypes:
        for name, solver in paper.items():
            rows.append(swarm_row(name, solver, prob, lo, hi, true, iterations, dtype))
    if not args.quick:
        literal = sj.BSO(beetle=BeetleStep(literal_sign=True))
        rows.append(swarm_row("BSO literal sign", literal, prob, lo, hi, true, iterations,
                              jnp.float64))
        for name, solver in (
                ("SEDSABSO Vmax 0.1", sj.SEDSABSO(beetle=BeetleStep(vmax_fraction=0.1))),
                ("SEDSABSO Vmax 0.05", sj.SEDSABSO(beetle=BeetleStep(vmax_fraction=0.05))),
                ("BSO Vmax 0.1", sj.BSO(beetle=BeetleStep(vmax_fraction=0.1))),
                ("LDWPSO Vmax 0.1", sj.LDWPSO(vmax_fraction=0.1))):
            rows.append(swarm_row(name, solver, prob, lo, hi, true, iterations, jnp.float64))
    ratios = [paired_ratio(prob, lo, hi, iterations, dtype) for dtype in dtypes]
    speed = speed_vs_evosax(prob, lo, hi, iterations, dtypes, args.ratio_seeds)
    rows += baseline_rows(prob, true)
    W, tau = np.asarray(prob.W), np.asarray(prob.tau)
    peers_rows = (("pyswarms", lambda: pyswarms_row(prob, lo, hi, true, iterations)),
                  ("mealpy", lambda: peers.mealpy_row(W, tau, lo, hi, true, iterations)),
                  ("evosax", lambda: peers.evosax_row(W, tau, lo, hi, true, iterations)),
                  ("evosax float32", lambda: peers.evosax_row(W, tau, lo, hi, true, iterations,
                                                              dtype="float32")))
    for label, make in peers_rows:
        try:
            rows.append(make())
        except ImportError:
            print(f"{label} not installed: pip install -e '.[bench]' "
                  "(mealpy: see benchmarks/peers.py)")
    floor = next(r["fitness_mean"] for r in rows if r["method"] == "L1-LP")
    counts = [int(k) for k in args.runs_per_call.split(",") if k.strip()]
    many = runs_per_call(prob, lo, hi, iterations, dtypes, counts) if counts else []
    print(f"RS010N, 1000 samples, 21 base parameters, {iterations} iterations, "
          f"device {describe(info)}; L1 floor f = {floor:.3g}")
    print(f"{'method':24s} {'dtype':7s} {'compile_s':>9s} {'run_s':>7s} {'10 runs_s':>9s} "
          f"{'f mean':>9s} {'max|err|':>8s}")
    for r in rows:
        batched = f"{r['batched_time_s']:9.2f}" if "batched_time_s" in r else f"{'':9s}"
        print(f"{r['method']:24s} {r['dtype']:7s} {r['compile_s']:9.2f} {r['time_per_run_s']:7.3f} "
              f"{batched} {r['fitness_mean']:9.3g} {r['max_abs_error_mean']:8.3g}")
    by = {(r["method"], r["dtype"]): r for r in rows}
    for r in ratios:
        print(f"SEDSABSO / BSO time per run ({r['dtype']}, {r['pairs']} alternating pairs): "
              f"fastest runs {r['fastest']:.2f}; pairwise median {r['median']:.2f} "
              f"(min {r['min']:.2f}, max {r['max']:.2f})")
    if ("SEDSABSO", "float64") in by:
        peer_rows = [r for r in rows if r["method"].split()[0] in ("pyswarms", "mealpy",
                                                                   "evosax")
                     and r["dtype"] == "float64"]
        if peer_rows:
            fastest = min(peer_rows, key=lambda r: r["time_per_run_s"])
            ratio = fastest["time_per_run_s"] / by["SEDSABSO", "float64"]["time_per_run_s"]
            print(f"fastest peer: {fastest['method']} ({fastest['dtype']}), "
                  f"{fastest['time_per_run_s']:.3f} s/run; SEDSABSO float64 is {ratio:.2f}x "
                  f"its speed")
    print(f"time per run against evosax's PSO, same process, fastest of {args.ratio_seeds} "
          f"interleaved seeds:")
    for r in speed:
        print(f"  {r['method']:10s} {r['dtype']:7s} {r['time_per_run_s']:7.3f} s "
              f"(median {r['time_per_run_median_s']:.3f})  {r['over_evosax']:.2f}x evosax")
    if many:
        print("runs per call (batch='auto'; evosax vmapped): seconds per call / per run")
        for r in many:
            print(f"  {r['method']:10s} {r['dtype']:7s} {r['runs']:5d} runs "
                  f"[{r['batch']}]: {r['call_s']:8.2f} s / {r['per_run_s']:.4f} s")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"device": info, "iterations": iterations, "l1_floor": floor,
                       "rows": rows, "sedsabso_over_bso": ratios, "speed_vs_evosax": speed,
                       "runs_per_call": many}, fh, indent=2)


if __name__ == "__main__":
    main()
