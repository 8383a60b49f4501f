"""What a validation costs: the fits of the KUKA LWR4+'s speed splits (7 splits of run 1,
5027 samples, Coulomb + viscous + offset, 64 columns) by ``sj.cross_validate``, which fits
least-squares estimators on the normal equations of each split's rows, against fitting
each split's rows themselves (``estimator.fit(FitProblem(...))``), and the largest
relative difference of the split errors. Each timed twice after a warm-up, best kept;
BLAS limited to one thread as inside a validation.

    python -m benchmarks.validation_speed [--json benchmarks/results/validation_speed.json]
"""

from __future__ import annotations

import argparse
import time

import jax
import numpy as np
from threadpoolctl import threadpool_limits

import sedsabso_jax as sj
from benchmarks.device import device_info
from benchmarks.output import to_json
from sedsabso_jax.dynamics import joint_limits
from sedsabso_jax.identification import FitProblem


def best_of(f, repeats=2):
    f()  # warm-up: the conic programme is built on its first solve
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    robot = sj.robots.kuka_lwr4()
    data = sj.load_kuka_lwr4(1)
    limits = np.asarray(joint_limits("kuka_lwr4", robot).tau_max)
    model = sj.TorqueModel.of(robot, [sj.Offset()])
    Y = model.regressor(data.q, data.qd, data.qdd)
    splits = sj.SpeedSplits().splits([data])
    rows = []

    def on_rows(estimator):
        """Each split's error, its rows fitted as they are."""
        scores = []
        for train, test in zip(splits.train, splits.test):
            x = estimator.fit(FitProblem(model, Y[train], data.tau[train], limits,
                                         warn=False)).x
            scores.append(sj.validation_metrics(data.tau[test], Y[test] @ x,
                                                limits).nrms_limits_percent)
        return np.array(scores)

    with threadpool_limits(limits=1, user_api="blas"):
        for estimator in (sj.OLS(), sj.WLS("residual"), sj.PhysicallyConsistent(sj.OLS())):
            rows_s, by_rows = best_of(lambda: on_rows(estimator))
            normal_s, cv = best_of(lambda: sj.cross_validate(
                robot, data, estimator, model, validation=sj.SpeedSplits(), limits=limits))
            diff = float(np.max(np.abs(cv.fold_scores / by_rows - 1)))
            rows.append({"estimator": repr(estimator), "rows_s": rows_s,
                         "normal_equations_s": normal_s, "ratio": rows_s / normal_s,
                         "max_relative_difference_of_split_errors": diff})
            print(f"{estimator!r}: rows {rows_s:.3f} s, normal equations {normal_s:.3f} s "
                  f"({rows_s / normal_s:.1f}x), split errors differ by {diff:.2g} (relative)",
                  flush=True)
    doc = {"rows": rows, "splits": len(splits), "samples": data.n_samples,
           "columns": model.dim, "device": device_info(),
           "command": "python -m benchmarks.validation_speed"}
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json(doc))


if __name__ == "__main__":
    main()
