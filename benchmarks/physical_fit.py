"""The physically consistent fit's conic solve, built for Clarabel directly (the
package's) against the same programme stated in cvxpy and canonicalised once with its data
as parameters (how the package solved it before, a DPP problem), both solved by Clarabel,
in one process: on the KUKA LWR4+'s run 1 and the default's candidate models (OLS, the
unconstrained viscous and Coulomb friction, an offset, the smooth Coulomb shape).

For each model: cvxpy's one-off canonicalisation, the median of ``REPEATS`` solves each way
(the package's time is its own report's, from the factor to the values), their ratio, and
how far apart the answers are (objective, relative; the base values, relative to the
largest). A default identification makes about 240 such solves.

    python -m benchmarks.physical_fit [--json PATH]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import jax
import numpy as np

import sedsabso_jax as sj
from benchmarks.output import write_json
from sedsabso_jax.identification import FitProblem, candidate_models

REPEATS = 9
#: The package's pull to the prior with prior_strength 0: 1e-9 of the mean curvature.
RIDGE = 1e-9
MARGIN = 1e-6


def _inertial(J):
    return [J[1, 1] + J[2, 2], J[0, 0] + J[2, 2], J[0, 0] + J[1, 1],
            -J[0, 1], -J[0, 2], -J[1, 2], J[3, 3], J[0, 3], J[1, 3], J[2, 3]]


def cvxpy_programme(n: int, dim: int, n_extra: int):
    """The programme as cvxpy states it: every link's pseudo-inertia >= MARGIN, friction
    >= 0, the data and the prior as parameters; canonicalised by a first solve."""
    import cvxpy as cp

    d_full = 12 * n
    M = cp.Parameter((dim, d_full + n_extra))
    c, root_lam, pulled = cp.Parameter(dim), cp.Parameter(nonneg=True), cp.Parameter(d_full)
    J = [cp.Variable((4, 4), symmetric=True) for _ in range(n)]
    friction = cp.Variable(2 * n)
    extras = cp.Variable(n_extra) if n_extra else None
    p = cp.hstack([e for i in range(n)
                   for e in (*_inertial(J[i]), friction[2 * i], friction[2 * i + 1])])
    pe = cp.hstack([p, extras]) if extras is not None else p
    problem = cp.Problem(cp.Minimize(cp.norm(cp.hstack([M @ pe - c, root_lam * p - pulled]))),
                         [Ji - MARGIN * np.eye(4) >> 0 for Ji in J] + [friction >= 0])
    for v in (M, c, pulled):
        v.value = np.zeros(v.shape)
    root_lam.value = 1.0
    problem.solve(solver=cp.CLARABEL)
    return problem, (M, c, root_lam, pulled), p, extras


def one_model(model, data) -> dict:
    import cvxpy as cp

    Y = np.asarray(model.regressor(data.q, data.qd, data.qdd))
    fit_problem = FitProblem(model, Y, data.tau, warn=False)
    estimator = sj.PhysicallyConsistent(sj.OLS())
    package = [estimator.fit(fit_problem) for _ in range(REPEATS + 1)][1:]
    fit = package[-1]
    factor = sj.optim.factorize(fit.W, fit.b)
    n, dim = model.robot.n_joints, model.dim
    n_extra, K = dim - model.base.rank, np.asarray(model.base.matrix)
    C = np.zeros((dim, 12 * n + n_extra))
    C[:K.shape[0], :12 * n], C[K.shape[0]:, 12 * n:] = K, np.eye(n_extra)
    M = factor.R @ C[factor.perm]
    scale, lam = np.linalg.norm(factor.c), RIDGE * np.sum(M ** 2) / C.shape[1]
    prior = np.asarray(model.robot.params, dtype=float)
    t0 = time.perf_counter()
    problem, (Mp, cp_, root_lam, pulled), p, extras = cvxpy_programme(n, dim, n_extra)
    build = time.perf_counter() - t0
    Mp.value, cp_.value = M / scale, factor.c / scale
    root_lam.value, pulled.value = np.sqrt(lam) / scale, np.sqrt(lam) / scale * prior
    seconds = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        problem.solve(solver=cp.CLARABEL)
        seconds.append(time.perf_counter() - t0)
    pe = np.concatenate([p.value, extras.value if extras is not None else []])

    def objective(x_full):
        return float(np.sum((M @ x_full - factor.c) ** 2)
                     + lam * np.sum((x_full[:12 * n] - prior) ** 2))

    ours = np.concatenate([fit.full, fit.x[model.base.rank:]])
    base = np.asarray(fit.x)
    theirs = C @ pe
    mine = float(np.median([f.extra["physical_fit"]["seconds"] for f in package]))
    return {"model": model.friction, "columns": dim,
            "cvxpy_canonicalisation_s": build,
            "cvxpy_solve_s": float(np.median(seconds)), "direct_solve_s": mine,
            "ratio": float(np.median(seconds)) / mine,
            "objective_relative_difference": (objective(ours) - objective(pe)) / objective(pe),
            "values_difference": float(np.abs(base - theirs).max() / np.abs(theirs).max()),
            "status": [fit.extra["physical_fit"]["status"], str(problem.status)]}


def main(argv=None) -> dict:
    jax.config.update("jax_enable_x64", True)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)
    robot, data = sj.robots.kuka_lwr4(), sj.load_kuka_lwr4(1)
    models = [m for m in candidate_models(robot) if "load" not in m.friction
              and "armature" not in m.friction]
    rows = [one_model(m, data) for m in models]
    print("| model | columns | cvxpy build [s] | cvxpy solve [ms] | direct [ms] | ratio "
          "| objective diff | values diff |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['model']} | {r['columns']} | {r['cvxpy_canonicalisation_s']:.2f} | "
              f"{1e3 * r['cvxpy_solve_s']:.1f} | {1e3 * r['direct_solve_s']:.1f} | "
              f"{r['ratio']:.2f} | {r['objective_relative_difference']:.1e} | "
              f"{r['values_difference']:.1e} |")
    out = {"robot": "kuka_lwr4 run 1", "estimator": "PhysicallyConsistent(OLS())",
           "repeats": REPEATS, "models": rows}
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
