"""Real robot: identify the KUKA LWR4+ on FloBaRoID's measurements_1, validate on
measurements_2 (held out), with every method and model choice of ``sj.identify``.

Metric: NRMS over the torque limits, per joint ``RMS(tau_pred - tau_meas) / (2 limit)``
in percent, mean over the 7 joints (FloBaRoID's; best published on these files 0.176 %).
Recorded ``q, qd, qdd, tau`` are used as they are (no filtering: low-pass filtering of
either changed the held-out error by less than 0.001 percentage points). Swarms: the L1
objective (Eq. 17) on the same weighted rows, box ``prior +- max(50 % |prior|, 0.5)``
around the URDF's a-priori base parameters (extra terms around 0), 600 iterations,
``--runs`` runs (seed 0, batched); the row is the run with the lowest L1 objective, the
held-out error of every run is in the JSON and its range in the table. Times: wall time
of ``identify`` (building the regressor included, its compile excluded by a warm-up call;
optimistix's and the swarms' compile included, and given apart).

    python -m benchmarks.kuka_real [--json benchmarks/results/kuka_real.json] [--no-swarms]
                                   [--runs 3]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from importlib import resources

import jax
import numpy as np

import sedsabso_jax as sj
from sedsabso_jax.identification import parse_friction

LIMITS = np.array([176.0, 176.0, 100.0, 100.0, 100.0, 38.0, 38.0])
FIELDS = ("positions", "velocities", "accelerations", "torques")
FULL = "viscous-coulomb+offset+quadratic+smooth"
#: The swarms' box, iterations and seed.
BOX = dict(box=(0.5, 0.5), iterations=600, seed=0)


def data_dir() -> str:
    """The KUKA files packaged with sedsabso-jax (sedsabso_jax/data/kuka_lwr4)."""
    return str(resources.files("sedsabso_jax") / "data" / "kuka_lwr4")


def load(path):
    with np.load(path, allow_pickle=False) as z:
        return [np.asarray(z[k], dtype=float) for k in FIELDS]


def configurations(swarms: bool, runs: int):
    """(label, friction, estimator) rows."""
    rows = []
    for friction in ("viscous-coulomb", "viscous-coulomb+offset", FULL):
        rows += [
            ("OLS", friction, sj.OLS()),
            ("WLS (Gautier, residual std)", friction, sj.WLS()),
            ("WLS (1/limit)", friction, sj.WLS("limits")),
            ("L1 optimum (LP)", friction, sj.L1()),
            ("L1 optimum (LP), 1/limit", friction, sj.L1("limits")),
            ("LM (optimistix)", friction, sj.LevenbergMarquardt()),
            ("physical, WLS (1/limit)", friction, sj.PhysicallyConsistent(sj.WLS("limits"))),
            ("physical, OLS, prior weight 1", friction,
             sj.PhysicallyConsistent(sj.OLS(), prior_weight=1.0)),
        ]
    if swarms:
        for friction, weights in (("viscous-coulomb", None),
                                  ("viscous-coulomb+offset", "limits")):
            for name in ("SEDSABSO", "BSO", "LDWPSO"):
                rows.append((f"{name} (paper)", friction,
                             sj.Estimator.named(name, sigma=weights, runs=runs, **BOX)))
        slow = (("SEDSABSO", sj.SEDSABSO(beetle=sj.optim.BeetleStep(vmax_fraction=0.1))),
                ("LDWPSO", sj.LDWPSO(vmax_fraction=0.1)))
        for name, solver in slow:
            rows.append((f"{name}, Vmax = 0.1 (ub - lb)", "viscous-coulomb+offset",
                         sj.BoxSearch(solver, sigma="limits", runs=runs, **BOX)))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default="benchmarks/results/kuka_real.json")
    ap.add_argument("--data", default=data_dir())
    ap.add_argument("--no-swarms", action="store_true")
    ap.add_argument("--runs", type=int, default=3, help="swarm runs (seeds) per setting")
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)

    robot = sj.robots.kuka_lwr4()
    base = sj.base_parameters(robot)
    train = load(os.path.join(args.data, "measurements_1.npz"))
    test = load(os.path.join(args.data, "measurements_2.npz"))
    models = {}  # one model per friction text, built once
    sj.identify(robot, train, sj.OLS(), sj.TorqueModel.of(robot, base=base),
                limits=LIMITS)  # compile the regressor for this sample count

    rows = []
    for label, friction, estimator in configurations(not args.no_swarms, args.runs):
        if friction not in models:
            models[friction] = sj.TorqueModel.of(robot, parse_friction(friction), base=base)
        t0 = time.perf_counter()
        ident = sj.identify(robot, train, estimator, models[friction], limits=LIMITS)
        seconds = time.perf_counter() - t0
        tau_pred = ident.predict(*test[:3])
        metrics = sj.validation_metrics(test[3], tau_pred, LIMITS)
        held, per_joint = metrics.nrms_limits_percent, metrics.nrms_limits_percent_per_joint
        row = {"label": label, "friction": friction, "method": ident.method,
               "weights": ident.settings["weights"], "physical": ident.settings["physical"],
               "heldout_nrms_limits_percent": held,
               "heldout_per_joint_percent": [float(v) for v in per_joint],
               "fit_nrms_limits_percent": ident.fit["nrms_limits_percent"],
               "fit_l1_weighted": ident.fit["l1"], "seconds": seconds,
               "n_parameters": len(ident.names)}
        if ident.full_params is not None:
            row["physically_consistent"] = sj.is_physically_consistent(ident.full_params)
            row["physical_fit"] = ident.settings["physical_fit"]
        if "compile_s" in ident.settings:  # LM and swarms: compile time apart
            row.update(compile_s=ident.settings["compile_s"], run_s=ident.settings["run_s"])
        if "solver" in ident.settings:
            X = np.atleast_2d(np.asarray(ident.result.x, dtype=float))
            Yt = ident.model.regressor(*test[:3])
            runs_held = [sj.validation_metrics(test[3], Yt @ x, LIMITS).nrms_limits_percent
                         for x in X]
            row.update(solver=ident.settings["solver"], box=ident.settings["box"],
                       runs=len(runs_held), heldout_runs_percent=runs_held,
                       f_runs=ident.settings["f_runs"])
        rows.append(row)
        print(f"{label:34s} {friction:40s} held-out {held:.4f} %  ({seconds:.1f} s)",
              flush=True)

    # L1 objective floors, for the swarms' gap
    floors = {(r["friction"], r["weights"]): r["fit_l1_weighted"] for r in rows
              if r["method"] == "L1"}
    for r in rows:
        key = (r["friction"], r["weights"])
        if "solver" in r and key in floors:
            r["l1_gap_to_optimum"] = (r["fit_l1_weighted"] - floors[key]) / floors[key]

    best = min(rows, key=lambda r: r["heldout_nrms_limits_percent"])
    out = {
        "what": "KUKA LWR4+ (FloBaRoID): identify on measurements_1, NRMS over torque limits "
                "on measurements_2 (held out)",
        "limits_Nm": LIMITS.tolist(), "published_best_percent": 0.176,
        "machine": {"platform": platform.platform(), "cpus": os.cpu_count(),
                    "jax": jax.__version__, "device": str(jax.devices()[0])},
        "best": {k: best[k] for k in ("label", "friction", "heldout_nrms_limits_percent")},
        "rows": rows,
    }
    if args.json:
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1)

    print()
    print("| method | model | held-out NRMS (%) | per joint (%) | fit (%) | time (s) |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        pj = " ".join(f"{v:.3f}" for v in r["heldout_per_joint_percent"])
        extra = ""
        if "l1_gap_to_optimum" in r:
            lo, hi = min(r["heldout_runs_percent"]), max(r["heldout_runs_percent"])
            extra = (f" (L1 gap {100 * r['l1_gap_to_optimum']:.0f} %; {r['runs']} runs: "
                     f"{lo:.3f}-{hi:.3f})")
        secs = f"{r['seconds']:.2f}"
        if r.get("compile_s"):
            secs += f" (compile {r['compile_s']:.1f})"
        print(f"| {r['label']}{extra} | {r['friction']} | "
              f"**{r['heldout_nrms_limits_percent']:.4f}** | {pj} | "
              f"{r['fit_nrms_limits_percent']:.4f} | {secs} |")
    print(f"\nbest held-out: {best['label']}, {best['friction']}: "
          f"{best['heldout_nrms_limits_percent']:.4f} %")


if __name__ == "__main__":
    main()
