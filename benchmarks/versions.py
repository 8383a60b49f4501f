"""Time per run of the swarms in this checkout against another version of the package, in
one process, interleaved seed by seed (so that the shared machine's slow spells hit both
alike), with evosax's PSO beside them for the speed issue's ratios.

The other version's package is taken from git (``git archive REF sedsabso_jax``) into a
temporary directory under the name ``sedsabso_jax_REF`` (its imports are relative), so
both are imported side by side. Problem: the RS010N identification problem of
``benchmarks/swarms.py`` (1000 random states, box true +- max(10 %, 0.1), Eq. 17), 600
iterations, the paper's settings, one run per call compiled once; time per run the
fastest over ``--seeds`` seeds (the machine only ever adds time).

    python -m benchmarks.versions --ref 504fc4a [--seeds 7] [--json out.json]
"""

from __future__ import annotations

import argparse
import importlib
import io
import json
import pathlib
import re
import subprocess
import sys
import tarfile
import tempfile
import time

import jax
import jax.numpy as jnp
import numpy as np

from benchmarks import peers
from benchmarks.device import describe, device_info
from benchmarks.problems import rs010n_problem

jax.config.update("jax_enable_x64", True)

import sedsabso_jax as sj  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]


def import_version(ref: str, where: pathlib.Path):
    """The package as of git ``ref``, imported as ``sedsabso_jax_<ref>``."""
    name = "sedsabso_jax_" + re.sub(r"\W", "_", ref)
    tar = subprocess.run(["git", "-C", str(ROOT), "archive", ref, "sedsabso_jax"],
                         capture_output=True, check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(tar)) as archive:
        archive.extractall(where, filter="data")
    (where / "sedsabso_jax").rename(where / name)
    for path in (where / name).rglob("*.py"):  # absolute self-references, if any
        text = path.read_text()
        path.write_text(re.sub(r"\bsedsabso_jax\b(?=\.|\s|$)", name, text))
    sys.path.insert(0, str(where))
    return importlib.import_module(name)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--ref", required=True, help="git ref of the other version")
    parser.add_argument("--seeds", type=int, default=7)
    parser.add_argument("--iterations", type=int, default=600)
    parser.add_argument("--dtypes", default="float64,float32")
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)

    prob, lo, hi, _ = rs010n_problem()
    W, tau = np.asarray(prob.W), np.asarray(prob.tau)
    with tempfile.TemporaryDirectory() as tmp:
        other = import_version(args.ref, pathlib.Path(tmp))
        other_prob = other.L1Residual(W, tau)
        calls, compile_s = {}, {}
        for name in args.dtypes.split(","):
            dtype = jnp.dtype(name)
            exe, _ = peers.evosax_compiled(W, tau, lo, hi, args.iterations, dtype=name)
            jax.block_until_ready(exe(jax.random.key(0)))

            def evosax_call(seed, exe=exe):
                t0 = time.perf_counter()
                jax.block_until_ready(exe(jax.random.key(seed)))
                return time.perf_counter() - t0

            calls["evosax PSO", "", name] = evosax_call
            for method in ("SEDSABSO", "BSO", "LDWPSO"):
                for version, pkg, p in (("this", sj, prob), (args.ref, other, other_prob)):
                    solver = getattr(pkg, method).paper()
                    first = pkg.minimise(p, solver, lo, hi, key=jax.random.key(0),
                                         iterations=args.iterations, dtype=dtype)
                    compile_s[method, version, name] = first.compile_s
                    calls[method, version, name] = (
                        lambda seed, pkg=pkg, s=solver, p=p, d=dtype: pkg.minimise(
                            p, s, lo, hi, key=jax.random.key(seed),
                            iterations=args.iterations, dtype=d).run_s)
        times = {k: [] for k in calls}
        for seed in range(1, args.seeds + 1):
            for k, call in calls.items():
                times[k].append(call(seed))
    rows = []
    for (method, version, name), t in times.items():
        best = float(min(t))
        row = {"method": method, "version": version, "dtype": name, "seeds": args.seeds,
               "time_per_run_s": best, "time_per_run_median_s": float(np.median(t)),
               "over_evosax": best / min(times["evosax PSO", "", name])}
        if version == "this":
            row["over_" + args.ref] = best / min(times[method, args.ref, name])
            row["compile_s"] = compile_s[method, version, name]
        rows.append(row)
    print(f"{describe(device_info())}; {args.seeds} seeds interleaved, fastest per method")
    print(f"| method | dtype | this [s] | {args.ref} [s] | this / {args.ref} | this x evosax "
          f"| {args.ref} x evosax |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        if r["version"] != "this":
            continue
        o = next(x for x in rows if x["method"] == r["method"] and x["dtype"] == r["dtype"]
                 and x["version"] == args.ref)
        print(f"| {r['method']} | {r['dtype']} | {r['time_per_run_s']:.4f} | "
              f"{o['time_per_run_s']:.4f} | {r['over_' + args.ref]:.3f} | "
              f"{r['over_evosax']:.2f} | {o['over_evosax']:.2f} |")
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(
            {"device": device_info(), "ref": args.ref, "iterations": args.iterations,
             "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
