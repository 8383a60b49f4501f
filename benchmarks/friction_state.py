"""Friction at rest (issue 30, part 3): Dahl's presliding state (``sj.Presliding``),
its displacements recovered from simulated noisy data, and the optimisers on its search
problem (``sj.identification.PreslidingProblem``: the displacements ``u = log q_c``, one
per joint, searched; the linear values solved for each trial) with the same budget of
fitness evaluations: SEDSABSO, LDWPSO, CMA-ES (evosax), optimistix's Levenberg-Marquardt
through the scan's Jacobian, and scipy (Powell on the loss, as ``identify`` does; TRF
least squares with the JAX Jacobian). Each is judged by the error its displacements
give on held-out data (the linear values fitted on the fit data with them): the KUKA
LWR4+'s run 2 (a repeat of run 1's trajectory, which never stands still) and the Staubli
TX40's last 30 % (point to point, a fifth of its samples at rest; the state integrated
along the whole recording). NRMS over the joint torque limits, %; seconds: compile and
run apart (the swarms' compile from ``minimise``, the others' first call less a warm
one).

    python -m benchmarks.friction_state [--json benchmarks/results/friction_state.json]
    python -m benchmarks.friction_state --population-speed   # the population fitness only

Typical output (2-core AMD EPYC, 2026-11-26; see the JSON for every seed)::

    | data | optimiser | seed | evaluations | fit [%] | validated [%] | compile s | run s |
    | TX40 | no presliding term (OLS) | None | 1 | 1.6546 | 2.1155 | 0.00 | 0.00 |
    | TX40 | LDWPSO | 0 | 1200 | 1.5326 | 1.3610 | 5.60 | 1.40 |
    | TX40 | scipy TRF (JAX Jacobian) | None | 98 | 1.5325 | 1.3707 | 2.71 | 1.55 |
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import time
import warnings
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import sedsabso_jax as sj
from benchmarks.output import to_json
from data import real_robots
from sedsabso_jax.dynamics import joint_limits
from sedsabso_jax.identification import PreslidingProblem, parse_friction

BUDGET = 1200  # fitness evaluations per optimiser and seed
SEEDS = (0, 1, 2)
SIZES = (64, 256, 1024, 4096)


def nrms(pred, tau, limits) -> float:
    return float(np.mean(np.sqrt(np.mean((pred - tau) ** 2, 0)) / (2 * limits)) * 100)


# ---------------------------------------------------------------- simulation: recovery
def point_to_point(n, moves=30, rate=100.0, seed=0, fine=10):
    """Minimum-jerk moves between random targets, each followed by a rest (0.3-0.8 s),
    at ``fine`` times ``rate``: (q, qd, qdd, dt)."""
    rng = np.random.default_rng(seed)
    pieces, here = [], np.zeros(n)
    for _ in range(moves):
        target = rng.uniform(-1.0, 1.0, n)
        s = np.linspace(0.0, 1.0, int(rng.uniform(0.8, 1.6) * rate * fine))
        pieces.append(here + (target - here) * (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)[:, None])
        pieces.append(np.repeat(target[None], int(rng.uniform(0.3, 0.8) * rate * fine), 0))
        here = target
    q = np.concatenate(pieces)
    dt = 1.0 / (rate * fine)
    qd = np.gradient(q, dt, axis=0)
    qd[np.abs(qd) < 1e-12] = 0.0
    return q, qd, np.gradient(qd, dt, axis=0), dt


def dahl_loop(q, q_c):
    """Dahl's state along ``q`` by a plain loop (the plant's, on the fine grid)."""
    z = np.zeros_like(q)
    for k in range(1, len(q)):
        s = np.sign(q[k] - q[k - 1])
        z[k] = s + (z[k - 1] - s) * np.exp(-np.abs(q[k] - q[k - 1]) / q_c)
    return z


def recovery(robot, name, noise, seed) -> dict:
    """A point-to-point plant with presliding friction (displacements 5-40 mrad, FP 1-4
    N m), state integrated at 1 kHz, sampled at 100 Hz, ``noise`` of each joint's RMS
    torque; ``identify`` with presliding:fit (OLS)."""
    n = robot.n_joints
    rng = np.random.default_rng(100 + seed)
    q_c, fp = rng.uniform(0.005, 0.04, n), rng.uniform(1.0, 4.0, n)
    qf, qdf, qddf, dt = point_to_point(n, seed=seed)
    z = dahl_loop(qf, q_c)[::10]
    q, qd, qdd = qf[::10], qdf[::10], qddf[::10]
    t = np.arange(len(q)) * dt * 10
    tau = sj.simulate_measurements(robot, q, qd, qdd, t).tau + fp * z
    tau = tau + noise * np.sqrt(np.mean(tau ** 2, 0)) * rng.standard_normal(tau.shape)
    data = sj.Measurements(t, q, qd, qdd, tau)
    model = sj.TorqueModel.of(robot, parse_friction("presliding:fit"))
    t0 = time.perf_counter()
    fit = sj.identify(robot, data, sj.OLS(), model)
    seconds = time.perf_counter() - t0
    shapes = fit.settings["shapes"]
    found = np.array([shapes[f"q_c{j + 1}"]["value"] for j in range(n)])
    fp_found = fit.values[[fit.names.index(f"FP{j + 1}") for j in range(n)]]
    return {"robot": name, "noise": noise, "seed": seed, "samples": len(t),
            "rest_fraction": float(np.mean(np.all(np.diff(q, axis=0) == 0, 1))),
            "q_c": q_c.tolist(), "q_c_found": found.tolist(), "FP": fp.tolist(),
            "FP_found": fp_found.tolist(),
            "q_c_max_error_percent": float(np.max(np.abs(found / q_c - 1)) * 100),
            "FP_max_error_percent": float(np.max(np.abs(fp_found / fp - 1)) * 100),
            "seconds": seconds}


# ---------------------------------------------------------------- the optimisers' table
def cases():
    """(name, model, fit problem, held-out problem, held-out torques, limits)."""
    kuka = sj.robots.kuka_lwr4()
    limits = joint_limits("kuka_lwr4", kuka).torque_limits
    model = sj.TorqueModel.of(kuka, parse_friction("offset+presliding:fit"))
    run1, run2 = sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2)
    yield ("KUKA LWR4+ (run 1 -> run 2)", model, PreslidingProblem.of(model, run1,
                                                                      weights=1 / limits),
           PreslidingProblem.of(model, run2, weights=1 / limits), run2.tau, limits)
    tx40 = sj.robots.staubli_tx40()
    limits = joint_limits("staubli_tx40", tx40).torque_limits
    with tempfile.TemporaryDirectory() as tmp:
        data, tr = real_robots.tx40_joint_side(Path(tmp))
    model = sj.TorqueModel.of(tx40, parse_friction("offset+coupling+presliding:fit"),
                              transmission=tr)
    cut = int(0.7 * data.n_samples)
    first, last = np.arange(cut), np.arange(cut, data.n_samples)
    yield ("Staubli TX40 (first 70 % -> last 30 %)", model,
           PreslidingProblem.of(model, data, first, weights=1 / limits),
           PreslidingProblem.of(model, data, last, weights=1 / limits), data.tau[last], limits)


def judged(train, held, tau, limits, u) -> tuple[float, float]:
    """(fit loss as NRMS %, held-out NRMS %) of the displacements ``exp(u)``."""
    u = jnp.asarray(u)
    values = train.solve(u)
    fit = float(np.sqrt(np.mean(np.asarray(train.residual(u)).reshape(-1, len(limits)) ** 2,
                                0)).mean() / 2 * 100)
    return fit, nrms(np.asarray(held.predict(u, values)), tau, limits)


def swarms(train, lo, hi, seed):
    """(name, u, evaluations, compile s, run s) of each swarm's run with ``seed``."""
    d = lo.size
    for name, solver in (("SEDSABSO", sj.SEDSABSO()), ("LDWPSO", sj.LDWPSO()),
                         ("CMA-ES (evosax)", sj.Evosax("CMA_ES"))):
        iterations = sj.iterations_for_budget(solver, BUDGET, d)
        res = sj.minimise(PreslidingProblem.fitness, solver, lo, hi,
                          key=jax.random.key(seed), iterations=iterations, args=train)
        yield name, np.asarray(res.x), int(res.n_evaluations), res.compile_s, res.run_s


def gradient_based(train, lo, hi, u0):
    """(name, u, evaluations, compile s, run s) of optimistix's LM and scipy's Powell
    and TRF from ``u0`` (each Jacobian counted as ``d + 1`` evaluations)."""
    import optimistix as optx
    from scipy.optimize import least_squares, minimize

    d = lo.size

    def clipped(u, problem):
        return problem.residual(jnp.clip(u, lo, hi))

    steps = BUDGET // (d + 1)

    @jax.jit
    def lm(u, problem):
        sol = optx.least_squares(clipped, optx.LevenbergMarquardt(rtol=1e-8, atol=1e-8), u,
                                 args=problem, max_steps=steps, throw=False)
        return jnp.clip(sol.value, lo, hi), sol.stats["num_steps"]

    t0 = time.perf_counter()
    jax.block_until_ready(lm(jnp.asarray(u0), train))
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    u, k = jax.block_until_ready(lm(jnp.asarray(u0), train))
    run = time.perf_counter() - t0
    yield "LM (optimistix)", np.asarray(u), int(k) * (d + 1), first - run, run

    fitness = jax.jit(PreslidingProblem.fitness)
    jacobian = jax.jit(jax.jacfwd(lambda u, p: p.residual(u)))
    residuals = jax.jit(lambda u, p: p.residual(u))

    def loss(u):
        return fitness(u, train)

    def jac(u):
        return jacobian(u, train)

    def residual(u):
        return residuals(u, train)

    t0 = time.perf_counter()
    loss(jnp.asarray(u0)).block_until_ready()
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    best = minimize(lambda u: float(loss(jnp.asarray(u))), u0, method="Powell",
                    bounds=list(zip(lo, hi)), options={"maxfev": BUDGET, "xtol": 1e-3,
                                                       "ftol": 1e-10})
    yield "scipy Powell", best.x, int(best.nfev), compile_s, time.perf_counter() - t0
    t0 = time.perf_counter()
    jac(jnp.asarray(u0)).block_until_ready()
    residual(jnp.asarray(u0)).block_until_ready()
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    best = least_squares(lambda u: np.asarray(residual(jnp.asarray(u))), u0,
                         jac=lambda u: np.asarray(jac(jnp.asarray(u))), bounds=(lo, hi),
                         method="trf", max_nfev=steps)
    yield ("scipy TRF (JAX Jacobian)", best.x, int(best.nfev) * (d + 1), compile_s,
           time.perf_counter() - t0)


def table() -> list[dict]:
    rows = []
    print("| data | optimiser | seed | evaluations | fit [%] | validated [%] | "
          "compile [s] | run [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for name, model, train, held, tau, limits in cases():
        term = next(t for t in model.terms if t.name == "presliding")
        lo, hi = (np.full(train.dq.shape[1], np.log(b)) for b in term.bounds)
        u0 = np.full(lo.size, np.log(sj.Presliding().displacement))

        def show(row):
            rows.append(row)
            print(f"| {name} | {row['optimiser']} | {row['seed']} | {row['evaluations']} | "
                  f"{row['fit']:.4f} | {row['validated']:.4f} | {row['compile_s']:.2f} | "
                  f"{row['run_s']:.2f} |", flush=True)

        # the same model without the state (OLS), and with the default displacement fixed
        A, w = np.asarray(train.A), np.asarray(train.weights)
        x = np.linalg.lstsq(A.reshape(-1, A.shape[-1]), np.asarray(train.tau).reshape(-1),
                            rcond=None)[0] / np.asarray(train.scale)
        fit_res = A @ (x * np.asarray(train.scale)) - np.asarray(train.tau)
        pred = (np.asarray(held.A) @ (x * np.asarray(held.scale))) / w
        show({"data": name, "optimiser": "no presliding term (OLS)", "seed": None,
              "evaluations": 1, "fit": float(np.mean(np.sqrt(np.mean(fit_res ** 2, 0)))
                                             / 2 * 100),
              "validated": nrms(pred, tau, limits), "compile_s": 0.0, "run_s": 0.0,
              "q_c": None})
        fit0, val0 = judged(train, held, tau, limits, u0)
        show({"data": name, "optimiser": "presliding, q_c = 2 mrad fixed", "seed": None,
              "evaluations": 1, "fit": fit0, "validated": val0, "compile_s": 0.0,
              "run_s": 0.0, "q_c": np.exp(u0).tolist()})
        found = [*((s, r) for s in SEEDS for r in swarms(train, lo, hi, s)),
                 *((None, r) for r in gradient_based(train, lo, hi, u0))]
        for seed, (optimiser, u, evaluations, compile_s, run_s) in found:
            fit, val = judged(train, held, tau, limits, u)
            show({"data": name, "optimiser": optimiser, "seed": seed,
                  "evaluations": evaluations, "fit": fit, "validated": val,
                  "compile_s": float(compile_s or 0.0), "run_s": float(run_s),
                  "q_c": np.exp(u).tolist()})
    return rows


# ---------------------------------------------------------------- the package's validation
def validation(fitted: bool) -> list[dict]:
    """Each real robot's default candidate with most friction (offset + qd|qd| + smooth
    Coulomb, + coupling on the TX40) with and without the presliding state, OLS, judged by
    the default's own validation (phase folds and speed splits pooled, fold by fold):
    what would decide whether the state joins the candidates."""
    rows = []
    print("| robot | friction | validation [%] | folds better | seconds |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, robot, data, limits, tr, _ in real_robots_datasets(Path(tmp)):
            base = sj.base_parameters(robot)
            coupled = "+coupling" if tr is not None else ""
            texts = [f"offset+quadratic+smooth{coupled}",
                     f"offset+quadratic+smooth{coupled}+presliding"]
            if fitted:
                texts.append(f"offset+quadratic+smooth{coupled}+presliding:fit")
            first = None
            for text in texts:
                model = sj.TorqueModel.of(robot, parse_friction(text), transmission=tr,
                                          base=base)
                t0 = time.perf_counter()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    cv = sj.cross_validate(robot, data, sj.OLS(), model, limits=limits,
                                           validation=sj.Pooled((sj.PhaseFolds(),
                                                                 sj.SpeedSplits())))
                first = cv if first is None else first
                better = int(np.sum(cv.fold_scores < first.fold_scores))
                rows.append({"robot": name, "friction": text, "score": cv.score,
                             "fold_scores": cv.fold_scores.tolist(), "folds_better": better,
                             "seconds": time.perf_counter() - t0})
                print(f"| {name} | {text} | {cv.score:.4f} | {better}/{len(cv.fold_scores)} | "
                      f"{rows[-1]['seconds']:.0f} |", flush=True)
    return rows


def real_robots_datasets(tmp: Path):
    """(name, robot, data, limits, transmission, None) of the three shipped robots."""
    from benchmarks.real_robots import datasets

    for name, robot, data, limits, tr, _ in datasets(tmp):
        yield name, robot, data, limits.torque_limits, tr, None


# ---------------------------------------------------------------- population speed
def population_speed() -> list[dict]:
    """The KUKA run 1 problem's fitness of a population in one vmapped call: compile
    (ahead of time) and run (median of 3, ``block_until_ready``) apart."""
    _, _, train, _, _, _ = next(cases())
    rows = []
    print(f"device: {jax.devices()[0].device_kind}")
    print("| population | compile [s] | run [s] | evaluations/s |")
    print("|---|---|---|---|")
    rng = np.random.default_rng(0)
    for size in SIZES:
        u = jnp.asarray(rng.uniform(np.log(1e-4), np.log(0.1), (size, train.dq.shape[1])))
        t0 = time.perf_counter()
        compiled = jax.jit(jax.vmap(PreslidingProblem.fitness, (0, None))).lower(
            u, train).compile()
        compile_s = time.perf_counter() - t0
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            compiled(u, train).block_until_ready()
            times.append(time.perf_counter() - t0)
        run_s = float(np.median(times))
        rows.append({"population": size, "compile_s": compile_s, "run_s": run_s,
                     "evaluations_per_s": size / run_s})
        print(f"| {size} | {compile_s:.2f} | {run_s:.4f} | {size / run_s:.0f} |", flush=True)
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    ap.add_argument("--validation", choices=("fixed", "fitted"), default=None,
                    help="only the real robots' validation with and without the state")
    ap.add_argument("--population-speed", action="store_true",
                    help="only time the state model's population fitness (under 2 minutes)")
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    out: dict = {"machine": {"platform": platform.platform(), "processor": platform.processor(),
                             "device": jax.devices()[0].device_kind}, "budget": BUDGET}
    if args.population_speed:
        out["population_speed"] = population_speed()
    elif args.validation:
        out["validation"] = validation(args.validation == "fitted")
    else:
        print("| robot | noise | seed | rest | q_c max error [%] | FP max error [%] | s |")
        print("|---|---|---|---|---|---|---|")
        out["recovery"] = []
        for robot, name in ((sj.robots.rs010n(), "rs010n"), (sj.robots.kuka_lwr4(), "KUKA")):
            for noise in (0.01, 0.05):
                for seed in (0, 1):
                    row = recovery(robot, name, noise, seed)
                    out["recovery"].append(row)
                    print(f"| {name} | {noise:.2f} | {seed} | {row['rest_fraction']:.2f} | "
                          f"{row['q_c_max_error_percent']:.1f} | "
                          f"{row['FP_max_error_percent']:.1f} | {row['seconds']:.1f} |",
                          flush=True)
        out["optimisers"] = table()
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json(out))


if __name__ == "__main__":
    main()
