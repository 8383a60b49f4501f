"""The physically consistent fit's conic solve: the package's (the programme built for
Clarabel as cvxpy would state it, :mod:`sedsabso_jax.identification`) against the same
programme stated in cvxpy and canonicalised once with its data as parameters (how the
package solved it before 0.21, a DPP problem), both solved by Clarabel, in one process: on
the KUKA LWR4+'s run 1 and the default's candidate models without a load term.

For each model: cvxpy's one-off canonicalisation, the median of ``REPEATS`` solves each way
(the package's time is its own report's, from the factor to the values; cvxpy's is
``problem.solve``), their ratio, whether the two give the same bytes (they should: Clarabel
gets the same data and keeps the same equilibration), and how far the full parameters move
(relative to the largest) when the torques change by 1e-15 (relative, random): the
package's, and Clarabel's with an equilibration of each fit's own data (cvxpy's
``warm_start=False``). A default identification makes about 240 such solves.

    python -m benchmarks.physical_fit [--json PATH]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import jax
import numpy as np
from threadpoolctl import threadpool_limits

import sedsabso_jax as sj
from benchmarks.output import write_json
from sedsabso_jax.identification import FitProblem, candidate_models

REPEATS = 9
#: The package's pull to the prior with prior_strength 0: 1e-9 of the mean curvature.
RIDGE = 1e-9
#: The package's smallest eigenvalue of a pseudo-inertia.
MARGIN = 1e-6


def _inertial(J):
    """A link's ``[Ixx Iyy Izz Ixy Ixz Iyz m mx my mz]`` from its pseudo-inertia."""
    return [J[1, 1] + J[2, 2], J[0, 0] + J[2, 2], J[0, 0] + J[1, 1],
            -J[0, 1], -J[0, 2], -J[1, 2], J[3, 3], J[0, 3], J[1, 3], J[2, 3]]


def cvxpy_programme(n: int, dim: int, n_extra: int, nonneg: tuple[int, ...] = (),
                    bodies: tuple[int, ...] = ()):
    """The programme as cvxpy states it (the statement the package's docstring gives):
    every link's pseudo-inertia ``- MARGIN 1`` positive semidefinite, friction ``>= 0``,
    ``extras[nonneg] >= 0``, each body's 10 extras its own pseudo-inertia's; the data
    and the prior as parameters; canonicalised by a first solve of the trivial instance.
    Returns ``(problem, (M, c, root_lambda, pulled), p, extras)``."""
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
    constraints = [Ji - MARGIN * np.eye(4) >> 0 for Ji in J] + [friction >= 0]
    if nonneg and extras is not None:
        constraints.append(extras[list(nonneg)] >= 0)
    for start in bodies:
        assert extras is not None
        B = cp.Variable((4, 4), symmetric=True)
        constraints += [B - MARGIN * np.eye(4) >> 0,
                        extras[start:start + 10] == cp.hstack(_inertial(B))]
    problem = cp.Problem(cp.Minimize(cp.norm(cp.hstack([M @ pe - c, root_lam * p - pulled]))),
                         constraints)
    for v in (M, c, pulled):
        v.value = np.zeros(v.shape)
    root_lam.value = 1.0
    problem.solve(solver=cp.CLARABEL)
    return problem, (M, c, root_lam, pulled), p, extras


def one_model(model, data) -> dict:
    """The two ways on one candidate model (see the module docstring), with one BLAS
    thread (as the default's validations fit: OpenBLAS's idle threads would otherwise
    take the CPU from the solver after each factorisation)."""
    with threadpool_limits(limits=1, user_api="blas"):
        return _one_model(model, data)


def _one_model(model, data) -> dict:
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
    # as the package computes them, to the last bit
    scale, lam = np.linalg.norm(factor.c), RIDGE * (float(np.sum(M ** 2)) / C.shape[1])
    prior = np.asarray(model.robot.params, dtype=float)
    nonneg = tuple(int(k) for k in np.flatnonzero(np.asarray(model.nonnegative)[K.shape[0]:]))
    t0 = time.perf_counter()
    problem, (Mp, cp_, root_lam, pulled), p, extras = cvxpy_programme(n, dim, n_extra, nonneg)
    build = time.perf_counter() - t0
    Mp.value, cp_.value = M / scale, factor.c / scale
    root_lam.value, pulled.value = np.sqrt(lam) / scale, np.sqrt(lam) / scale * prior
    seconds = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        problem.solve(solver=cp.CLARABEL)
        seconds.append(time.perf_counter() - t0)
    theirs = np.concatenate([p.value, extras.value if extras is not None else []])
    ours = np.concatenate([fit.full, fit.x[model.base.rank:]])
    mine = float(np.median([f.extra["physical_fit"]["seconds"] for f in package]))
    # the torques' last bits shaken: the package's fit, and a fresh equilibration's
    tau = data.tau * (1 + 1e-15 * np.random.default_rng(0).standard_normal(data.tau.shape))
    shaken = estimator.fit(FitProblem(model, Y, tau, warn=False))
    moved = {"package": np.abs(shaken.full - fit.full).max() / np.abs(fit.full).max()}
    fresh = []
    for f in (fit, shaken):
        factor = sj.optim.factorize(f.W, f.b)
        Mp.value = factor.R @ C[factor.perm] / np.linalg.norm(factor.c)
        cp_.value = factor.c / np.linalg.norm(factor.c)
        problem.solve(solver=cp.CLARABEL, warm_start=False)
        fresh.append(np.asarray(p.value))
    moved["own_equilibration"] = np.abs(fresh[1] - fresh[0]).max() / np.abs(fresh[0]).max()
    return {"model": model.friction, "columns": dim,
            "cvxpy_canonicalisation_s": build,
            "cvxpy_solve_s": float(np.median(seconds)), "package_solve_s": mine,
            "ratio": float(np.median(seconds)) / mine,
            "same_bytes": ours.tobytes() == theirs.tobytes(),
            "moved_by_1e-15": {k: float(v) for k, v in moved.items()},
            "status": [fit.extra["physical_fit"]["status"], str(problem.status)]}


def main(argv=None) -> dict:
    jax.config.update("jax_enable_x64", True)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)
    robot, data = sj.robots.kuka_lwr4(), sj.load_kuka_lwr4(1)
    models = [m for m in candidate_models(robot) if "load" not in m.friction]
    rows = [one_model(m, data) for m in models]
    print("| model | columns | cvxpy canonicalisation [s] | cvxpy solve [ms] | package [ms] "
          "| ratio | same bytes | moved by 1e-15: package | own equilibration |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        moved = r["moved_by_1e-15"]
        print(f"| {r['model']} | {r['columns']} | {r['cvxpy_canonicalisation_s']:.2f} | "
              f"{1e3 * r['cvxpy_solve_s']:.1f} | {1e3 * r['package_solve_s']:.1f} | "
              f"{r['ratio']:.2f} | {r['same_bytes']} | {moved['package']:.1e} | "
              f"{moved['own_equilibration']:.1e} |")
    out = {"robot": "kuka_lwr4 run 1", "estimator": "PhysicallyConsistent(OLS())",
           "repeats": REPEATS, "models": rows}
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
