"""Friction at rest (``sj.Presliding``) and the search of a model's nonlinear parameters:
Dahl's displacements recovered from simulated noisy data, the search methods on the
shipped robots (the time of a fit and the error on data it did not see), the compiled
population loss's speed, and the target of issue 35: ``presliding:fit`` against a fixed
displacement, each chosen and judged as ``sedsabso-jax identify`` does.

    python -m benchmarks.friction_state [--json benchmarks/results/friction_state.json]
    python -m benchmarks.friction_state --population-speed  # the population loss only
    python -m benchmarks.friction_state --versus-fixed      # KUKA: fitted vs fixed q_c
    python -m benchmarks.friction_state --validation fitted # the robots' own validation

The search methods (``sj.identification``): ``CoordinateSearch`` (the default), the
package's swarms and CMA-ES through ``PopulationSearch`` with 1200 evaluations, and
optimistix's Levenberg-Marquardt (``LeastSquaresSearch``), each in ``sj.identify`` with
OLS (equal weights) and the model offset + smooth Coulomb + presliding:fit (+ coupling on
the TX40): the KUKA LWR4+'s run 1 fitted, run 2 held out (a repeat of run 1's trajectory,
which never stands still); the Franka Panda's and the Staubli TX40's first 70 % fitted,
the last 30 % held out (the TX40 moves point to point, a fifth of its samples at rest).
Errors: NRMS over the joint torque limits, %; seconds: the first fit in the process
(compilation included) and a repeat.
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
from sedsabso_jax.identification import (
    CoordinateSearch,
    LeastSquaresSearch,
    PopulationSearch,
    Projection,
    parse_friction,
)

SIZES = (64, 256, 1024, 4096)
BUDGET = 1200  # evaluations of a population search


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
    found_ = fit.settings["searched"]["parameters"]
    found = np.array([found_[f"q_c{j + 1}"]["value"] for j in range(n)])
    fp_found = fit.values[[fit.names.index(f"FP{j + 1}") for j in range(n)]]
    return {"robot": name, "noise": noise, "seed": seed, "samples": len(t),
            "rest_fraction": float(np.mean(np.all(np.diff(q, axis=0) == 0, 1))),
            "q_c": q_c.tolist(), "q_c_found": found.tolist(), "FP": fp.tolist(),
            "FP_found": fp_found.tolist(),
            "q_c_max_error_percent": float(np.max(np.abs(found / q_c - 1)) * 100),
            "FP_max_error_percent": float(np.max(np.abs(fp_found / fp - 1)) * 100),
            "seconds": seconds}


# ---------------------------------------------------------------- the search methods
def part(data: sj.Measurements, keep: np.ndarray) -> sj.Measurements:
    return sj.Measurements(data.times[keep], data.q[keep], data.qd[keep], data.qdd[keep],
                           data.tau[keep], source=data.source)


def cases(tmp: Path):
    """(name, robot, friction, transmission, fitted data, held-out data, limits)."""
    kuka = sj.robots.kuka_lwr4()
    yield ("KUKA LWR4+ (run 1 -> run 2)", kuka, "offset+smooth+presliding:fit", None,
           sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2),
           joint_limits("kuka_lwr4", kuka).torque_limits)
    panda = sj.robots.franka_panda()
    data = sj.load_measurements(real_robots.panda_npz(tmp / "panda.npz"), n_joints=7,
                                resample_hz=1000.0)
    cut = np.arange(data.n_samples) < int(0.7 * data.n_samples)
    yield ("Franka Panda (first 70 % -> last 30 %)", panda, "offset+smooth+presliding:fit",
           None, part(data, cut), part(data, ~cut),
           joint_limits("franka_panda", panda).torque_limits)
    tx40 = sj.robots.staubli_tx40()
    data, tr = real_robots.tx40_joint_side(tmp)
    cut = np.arange(data.n_samples) < int(0.7 * data.n_samples)
    yield ("Staubli TX40 (first 70 % -> last 30 %)", tx40,
           "offset+smooth+coupling+presliding:fit", tr, part(data, cut), part(data, ~cut),
           joint_limits("staubli_tx40", tx40).torque_limits)


METHODS = (("coordinate search (default)", CoordinateSearch()),
           ("LDWPSO", PopulationSearch(sj.LDWPSO(), BUDGET)),
           ("SEDSABSO", PopulationSearch(sj.SEDSABSO(), BUDGET)),
           ("CMA-ES (evosax)", PopulationSearch(sj.Evosax("CMA_ES"), BUDGET)),
           ("Levenberg-Marquardt (optimistix)", LeastSquaresSearch()))


def table() -> list[dict]:
    rows = []
    print("| data | search | trials | fit [%] | held out [%] | first CPU s | repeat CPU s | "
          "q_c [mrad] |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, robot, friction, tr, fitted, held, limits in cases(Path(tmp)):
            base = sj.base_parameters(robot)
            fixed = sj.TorqueModel.of(robot, parse_friction(friction.replace(":fit", "")),
                                      transmission=tr, base=base)
            trials = [("a fixed displacement (2 mrad)", fixed)] + [
                (label, sj.TorqueModel.of(robot, parse_friction(friction), transmission=tr,
                                          base=base, search=method))
                for label, method in METHODS]
            for label, model in trials:
                seconds = []  # this process's CPU: other work on the machine moves it less
                for _ in range(2):
                    t0 = time.process_time()
                    fit = sj.identify(robot, fitted, sj.OLS(), model, limits=limits)
                    seconds.append(time.process_time() - t0)
                searched = fit.settings.get("searched", {})
                q_c = [v["value"] * 1e3 for v in searched.get("parameters", {}).values()]
                row = {"data": name, "search": label, "trials": searched.get("evaluations", 1),
                       "fit": fit.fit["nrms_limits_percent"],
                       "held_out": nrms(fit.predict(held.q, held.qd, held.qdd), held.tau,
                                        limits),
                       "first_s": seconds[0], "repeat_s": seconds[1], "q_c_mrad": q_c}
                rows.append(row)
                print(f"| {name} | {label} | {row['trials']} | {row['fit']:.4f} | "
                      f"{row['held_out']:.4f} | {seconds[0]:.1f} | {seconds[1]:.1f} | "
                      f"{', '.join(f'{v:.3g}' for v in q_c)} |", flush=True)
    return rows


# ---------------------------------------------------------------- the target
def versus_fixed(repeats: int = 5) -> list[dict]:
    """The KUKA's run 1, OLS with equal weights, physically consistent, offset + smooth
    Coulomb + load friction + presliding, the displacement fixed (2 mrad) or searched:
    chosen and judged as ``sedsabso-jax identify`` does (the default validation's 12
    splits and the fit on all the data; run 2 held out), both in one process,
    alternating; seconds of each whole call, wall and this process's CPU (less moved by
    other work on a shared machine), the first call of each with its compilation."""
    kuka = sj.robots.kuka_lwr4()
    limits = joint_limits("kuka_lwr4", kuka).torque_limits
    run1, run2 = sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2)
    base = sj.base_parameters(kuka)
    rows = []
    print("| presliding | call | wall [s] | CPU [s] | validated [%] | held out [%] |")
    print("|---|---|---|---|---|---|")
    for k in range(repeats):
        for text in ("offset+smooth+load+presliding", "offset+smooth+load+presliding:fit"):
            model = sj.TorqueModel.of(kuka, parse_friction(text), base=base)
            t0, c0 = time.perf_counter(), time.process_time()
            report = sj.select_and_identify(kuka, run1, held_out=run2, limits=limits,
                                            models=model, estimators=sj.OLS(),
                                            physical=True)
            seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
            row = {"friction": text, "call": k + 1, "seconds": seconds, "cpu_seconds": cpu,
                   "validated": report.cross_validation.score,
                   "held_out": report.validation.nrms_limits_percent,
                   "searched": report.ident.settings.get("searched")}
            rows.append(row)
            print(f"| {text.rpartition('+')[2]} | {k + 1} | {seconds:.1f} | {cpu:.1f} | "
                  f"{row['validated']:.4f} | {row['held_out']:.4f} |", flush=True)
    return rows


# ---------------------------------------------------------------- the package's validation
def validation(fitted: bool) -> list[dict]:
    """Each real robot's default candidate with most friction (offset + smooth Coulomb +
    load, + coupling on the TX40) with and without the presliding state, OLS, judged by
    the default's own validation (phase folds and speed splits pooled, split by split):
    what would decide whether the state joins the candidates."""
    from benchmarks.real_robots import datasets

    rows = []
    print("| robot | friction | validation [%] | splits better | seconds |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, robot, data, limits, tr, _ in datasets(Path(tmp)):
            base = sj.base_parameters(robot)
            coupled = "+coupling" if tr is not None else ""
            texts = [f"offset+smooth+load{coupled}", f"offset+smooth+load{coupled}+presliding"]
            if fitted:
                texts.append(f"offset+smooth+load{coupled}+presliding:fit")
            first = None
            for text in texts:
                model = sj.TorqueModel.of(robot, parse_friction(text), transmission=tr,
                                          base=base)
                t0 = time.perf_counter()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    cv = sj.cross_validate(robot, data, sj.OLS(), model,
                                           limits=limits.torque_limits,
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


# ---------------------------------------------------------------- population speed
def population_speed() -> list[dict]:
    """The KUKA run 1 problem's loss (offset + smooth Coulomb + presliding:fit) for a
    population in one vmapped call: compile (ahead of time) and run (median of 3,
    ``block_until_ready``) apart, the state by the sequential and by the associative
    scan (``sj.Presliding(scan=...)``)."""
    kuka = sj.robots.kuka_lwr4()
    run1 = sj.load_kuka_lwr4(1)
    base = sj.base_parameters(kuka)
    rows = []
    print(f"device: {jax.devices()[0].device_kind}")
    print("| state | population | compile [s] | run [s] | evaluations/s |")
    print("|---|---|---|---|---|")
    rng = np.random.default_rng(0)
    for scan in ("sequential", "associative"):
        model = sj.TorqueModel.of(kuka, (sj.Offset(), sj.SmoothCoulomb(),
                                         sj.Presliding(fitted=True, scan=scan)), base=base)
        problem = Projection.of(model, run1)
        for size in SIZES:
            u = jnp.asarray(rng.uniform(np.log(1e-4), np.log(0.1), (size, 7)))
            f = jax.jit(jax.vmap(lambda v, p: p.loss(v), (0, None)))
            t0 = time.perf_counter()
            compiled = f.lower(u, problem).compile()
            compile_s = time.perf_counter() - t0
            times = []
            for _ in range(3):
                t0 = time.perf_counter()
                compiled(u, problem).block_until_ready()
                times.append(time.perf_counter() - t0)
            run_s = float(np.median(times))
            rows.append({"state": scan, "population": size, "compile_s": compile_s,
                         "run_s": run_s, "evaluations_per_s": size / run_s})
            print(f"| {scan} | {size} | {compile_s:.2f} | {run_s:.4f} | {size / run_s:.0f} |",
                  flush=True)
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    ap.add_argument("--validation", choices=("fixed", "fitted"), default=None,
                    help="only the real robots' validation with and without the state")
    ap.add_argument("--population-speed", action="store_true",
                    help="only time the population loss (a few minutes)")
    ap.add_argument("--versus-fixed", action="store_true",
                    help="only the KUKA's fitted against fixed displacement (issue 35)")
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    out: dict = {"machine": {"platform": platform.platform(), "processor": platform.processor(),
                             "device": jax.devices()[0].device_kind}}
    if args.population_speed:
        out["population_speed"] = population_speed()
    elif args.versus_fixed:
        out["versus_fixed"] = versus_fixed()
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
        out["searches"] = table()
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json(out))


if __name__ == "__main__":
    main()
