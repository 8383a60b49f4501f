"""How `sedsabso-jax identify`'s default generalises on three real robots: the KUKA LWR4+
(joint torque sensors; two runs of one trajectory), the Franka Emika Panda (link-side
torque sensors) and the Staubli TX40 (motor side, coupled wrist).

The default chooses method, weighting and torque model by cross-validation over stretches
of the motion's phase (``sj.select_and_identify``). Its generalisation is measured
by NESTED cross-validation: the recording's phase is cut into 5 folds; for each, the whole
choice is made on the other 4 (its own 4-fold cross-validation) and the chosen model,
fitted to them, predicts the held-out stretch, a part of the motion no choice or fit saw.
Beside it, fixed settings are scored on the same outer folds: plain OLS (Coulomb + viscous
friction) and the package's previous default (WLS weighted by 1/limit with offset,
quadratic and smooth-Coulomb terms, chosen on the KUKA's repeat run), and the same
choice among physically consistent fits with the pull to the a-priori parameters also
chosen by the inner cross-validation (``identify --physical --prior-strength cv``;
``--no-physical`` leaves it out, the slow part). The KUKA's second
run repeats the first's trajectory: its figure measures repeatability, not generalisation.

    python -m benchmarks.real_robots [--json benchmarks/results/real_robots.json] [--no-physical]

Figures: NRMS over the joint torque limits [%] (RMS error / (2 limit), mean over joints).
"""

from __future__ import annotations

import argparse
import platform
import time
import warnings
from pathlib import Path

import jax
import numpy as np

import sedsabso_jax as sj
from benchmarks.output import to_json
from data import real_robots
from sedsabso_jax.dynamics import joint_limits
from sedsabso_jax.identification import phase_folds

PHYSICAL = "physical, chosen by cross-validation (model and pull to the prior)"
FIXED = {
    "OLS, Coulomb + viscous": (sj.OLS(), "viscous-coulomb"),
    "previous default: WLS 1/limit, offset+quadratic+smooth":
        (sj.WLS("limits"), "viscous-coulomb+offset+quadratic+smooth"),
}


def datasets(tmp: Path):
    """(name, robot, measurements (joint side), limits, transmission, held-out runs)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the KUKA URDF's duplicate <origin>
        kuka = sj.robots.kuka_lwr4()
    yield ("KUKA LWR4+", kuka, sj.load_kuka_lwr4(1), joint_limits("kuka_lwr4", kuka),
           None, {"run 2 (repeats run 1: repeatability)": sj.load_kuka_lwr4(2)})
    panda = sj.robots.franka_panda()
    data = sj.load_measurements(real_robots.panda_npz(tmp / "panda.npz"), n_joints=7,
                                resample_hz=1000.0)
    yield "Franka Panda", panda, data, joint_limits("franka_panda", panda), None, {}
    tx40 = sj.robots.staubli_tx40()
    data, tr = real_robots.tx40_joint_side(tmp)
    yield ("Staubli TX40 (motor side, 1 kHz)", tx40, data,
           joint_limits("staubli_tx40", tx40), tr, {})


def nrms(ident, data, limits) -> float:
    pred = ident.predict(data.q, data.qd, data.qdd)
    return sj.validation_metrics(data.tau, pred, limits.torque_limits).nrms_limits_percent


def subset(data, mask):
    return (data.times[mask], data.q[mask], data.qd[mask], data.qdd[mask], data.tau[mask])


def fixed(robot, data, estimator, friction, limits, transmission, base):
    """``identify`` with one of :data:`FIXED`."""
    model = sj.TorqueModel.of(robot, friction, transmission=transmission, base=base)
    return sj.identify(robot, data, estimator, model, limits=limits)


def evaluate(name, robot, data, limits, transmission, runs, folds=5, physical=True) -> dict:
    base = sj.base_parameters(robot)
    common = dict(limits=limits.torque_limits, base=base, transmission=transmission)
    labels, period = phase_folds(data.times, data.q, folds)
    t0 = time.perf_counter()
    held = {"default (chosen by cross-validation)": [], **{k: [] for k in FIXED}}
    if physical:
        held[PHYSICAL] = []
    chosen_per_fold, physical_per_fold = [], []
    for k in range(folds):
        train, test = labels != k, labels == k
        inner = np.searchsorted(np.unique(labels[train]), labels[train])  # folds 0..3
        tr = subset(data, train)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            default = sj.select_and_identify(robot, tr, folds=inner, **common)
            fits = {"default (chosen by cross-validation)": default.ident}
            for label, (estimator, friction) in FIXED.items():
                fits[label] = fixed(robot, tr[1:], estimator, friction, **common)
            if physical:  # the whole choice again, among physically consistent fits
                chosen = sj.select_and_identify(robot, tr, folds=inner, physical=True,
                                                prior_strength="cv", **common)
                fits[PHYSICAL] = chosen.ident
                physical_per_fold.append({**chosen.selection.chosen,
                                          "prior_strength": chosen.prior_selection.chosen})
            for label, ident in fits.items():
                pred = ident.predict(data.q[test], data.qd[test], data.qdd[test])
                held[label].append(sj.validation_metrics(
                    data.tau[test], pred, limits.torque_limits).nrms_limits_percent)
        chosen_per_fold.append(default.selection.chosen)
    nested_s = time.perf_counter() - t0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = sj.select_and_identify(robot, data, folds=folds, **common)
        full, final = report.selection, report.ident
        other_runs = {}
        for run, d in runs.items():
            other_runs[run] = {"default": nrms(final, d, limits)}
            for label, (estimator, friction) in FIXED.items():
                other_runs[run][label] = nrms(fixed(robot, data, estimator, friction, **common),
                                              d, limits)
    cv_chosen = full.cross_validation
    return {
        "robot": name, "samples": data.n_samples, "period_s": period,
        "nested_held_out_percent": {k: {"mean": float(np.mean(v)), "folds": v}
                                    for k, v in held.items()},
        "chosen_per_outer_fold": chosen_per_fold,
        "physical_chosen_per_outer_fold": physical_per_fold or None,
        "chosen_on_all_data": full.chosen, "cv_of_chosen_percent": cv_chosen.score,
        "cv_standard_error": cv_chosen.standard_error,
        "fit_percent": final.fit["nrms_limits_percent"], "other_runs": other_runs,
        "candidates": [{"settings": s, "cv": cv.score, "se": cv.standard_error,
                        "n_parameters": cv.n_parameters} for s, cv in full.candidates],
        "nested_seconds": nested_s,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default="benchmarks/results/real_robots.json")
    ap.add_argument("--no-physical", action="store_true",
                    help="leave out the physically consistent choice (the slow part)")
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    import tempfile

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, robot, data, limits, tr, runs in datasets(Path(tmp)):
            rows.append(evaluate(name, robot, data, limits, tr, runs,
                                 physical=not args.no_physical))
            r = rows[-1]
            phys = r["nested_held_out_percent"].get(PHYSICAL)
            print(f"{name}: chosen {r['chosen_on_all_data']}, CV {r['cv_of_chosen_percent']:.4f}"
                  f" %, nested {r['nested_seconds']:.0f} s"
                  + (f"; physical, nested {phys['mean']:.4f} %" if phys else ""), flush=True)
    print("\n| robot | held-out stretch, default (nested CV) | OLS Coulomb + viscous | "
          "previous default | default's choice on all data | its CV | other runs |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        h = r["nested_held_out_percent"]
        c = r["chosen_on_all_data"]
        runs = "; ".join(f"{k}: {v['default']:.4f} (previous default "
                         f"{v[list(FIXED)[1]]:.4f})" for k, v in r["other_runs"].items())
        print(f"| {r['robot']} | **{h['default (chosen by cross-validation)']['mean']:.4f}** | "
              f"{h[list(FIXED)[0]]['mean']:.4f} | {h[list(FIXED)[1]]['mean']:.4f} | "
              f"{c['method']} {c['sigma'] or 'equal'}, {c['friction']} | "
              f"{r['cv_of_chosen_percent']:.4f} | {runs or '-'} |")
    doc = {"machine": platform.processor() or platform.machine(), "rows": rows,
           "versions": {"sedsabso_jax": sj.__version__}}
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(to_json(doc))
    print(f"written: {args.json}")


if __name__ == "__main__":
    main()
