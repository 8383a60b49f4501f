"""Published models of two of the repository's real robots, on the same recordings, folds
and measure as :mod:`benchmarks.real_robots`:

- Franka Emika Panda: the model of Gaz et al. (IEEE RA-L 4(4), 2019; link parameters of
  the supplementary material's tables and the sigmoid joint friction,
  ``data/franka_panda/gaz2019_parameters.json``). Its torques on the Panda recording come
  from the package's inverse dynamics with those parameters plus the friction; scored on
  the whole run and on the 5 held-out stretches of the nested cross-validation, beside the
  default's figures read from ``benchmarks/results/real_robots.json``. Their repository's
  closed-form model (generated from slightly different coefficients) is scored too, with
  its gravity vector in place of the tables'.
- Staubli TX40: FIGAROH's identified base parameters (``data/staubli_tx40/TX40_bp_5.csv``)
  scored the same way, and the friction, armature, offset and motor-6 terms, joint side
  in FIGAROH's convention, of ``T40X_config.yaml``, of that file, and of this package's
  fits (the model with FIGAROH's terms, and the default's choice).

Gaz et al.'s identification used this very run among its data, and FIGAROH's this very
recording: for them nothing is held out. NRMS over the joint torque limits [%].

    python -m benchmarks.published [--json benchmarks/results/published.json]
                                   [--nested benchmarks/results/real_robots.json]
"""

from __future__ import annotations

import argparse
import csv
import json
import platform
import re
import tempfile
import time
import warnings
from pathlib import Path

import jax
import numpy as np

import sedsabso_jax as sj
from benchmarks.output import to_json
from data import real_robots
from sedsabso_jax.dynamics import joint_limits, params_from_com, pseudo_inertia
from sedsabso_jax.identification import parse_friction, phase_folds
from sedsabso_jax.robots import FRANKA_PANDA_MDH, from_mdh

GAZ = real_robots.PANDA / "gaz2019_parameters.json"
FIGAROH_BASE = real_robots.TX40 / "TX40_bp_5.csv"
FIGAROH_CONFIG = real_robots.TX40 / "T40X_config.yaml"
FOLDS = 5
#: This package's fit with FIGAROH's terms (per-joint friction, offset, armature, motor-6
#: coupling) and weighting (WLS by each joint's OLS residual, Gautier's).
FIGAROH_LIKE = dict(method="WLS", sigma="residual",
                    friction="viscous-coulomb+offset+armature+coupling")


# ----------------------------------------------------------------------- Gaz et al.
def load_gaz(path=GAZ) -> dict:
    return json.loads(Path(path).read_text())


def gaz_params(doc: dict) -> np.ndarray:
    """The package's full parameters (12 per link, modified-DH link frames) of the
    tables: inertia moved from the centre of mass to the frame origin; no Coulomb or
    viscous friction (Gaz et al.'s friction is the sigmoid of :func:`gaz_friction`)."""
    links = doc["links"]
    assert links["inertia_at_com_order"] == ["Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"]
    out = []
    for m, c, (xx, xy, xz, yy, yz, zz) in zip(links["mass_kg"], links["com_m"],
                                              links["inertia_at_com_kg_m2"]):
        I_c = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        out += [*params_from_com(m, c, I_c), 0.0, 0.0]
    return np.array(out)


def gaz_robot(doc: dict, params=None) -> sj.Robot:
    """The Panda (modified DH) with Gaz et al.'s parameters and their gravity (9.80665)."""
    t = FRANKA_PANDA_MDH
    return from_mdh(t["alpha"], t["a"], t["d"], gravity=(0.0, 0.0, -9.80665),
                    params=gaz_params(doc) if params is None else params,
                    name="franka_panda (Gaz et al. 2019)")


def gaz_friction(doc: dict, qd) -> np.ndarray:
    """``phi1 / (1 + exp(-phi2 (qd + phi3))) - phi1 / (1 + exp(-phi2 phi3))`` per joint."""
    f = doc["friction"]
    p1, p2, p3 = (np.asarray(f[k]) for k in ("phi1", "phi2", "phi3"))
    return p1 / (1 + np.exp(-p2 * (np.asarray(qd) + p3))) - p1 / (1 + np.exp(-p2 * p3))


def gaz_repository_gravity_params(doc: dict) -> np.ndarray:
    """Full parameters whose gravity torques are those of the repository's closed-form
    ``get_GravityVector`` (its first moments only; not physical)."""
    g = np.asarray(doc["repository_code_model"]["gravity_equivalent_first_moments"]["values"])
    p = np.zeros((7, 12))
    p[:, 6:10] = g
    return p.ravel()


def gaz_torques(doc: dict, q, qd, qdd, *, gravity: str = "tables") -> np.ndarray:
    """Gaz et al.'s model's joint torques: rigid body (tables) plus sigmoid friction;
    ``gravity="repository"`` swaps the tables' gravity for the repository's closed form."""
    robot = gaz_robot(doc)
    tau = np.array(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    if gravity == "repository":
        zero = np.zeros_like(np.asarray(q))
        tau -= np.asarray(sj.inverse_dynamics(robot, robot.params, q, zero, zero))
        tau += np.asarray(sj.inverse_dynamics(robot, gaz_repository_gravity_params(doc),
                                              q, zero, zero))
    elif gravity != "tables":
        raise ValueError(f"gravity must be 'tables' or 'repository', got {gravity!r}")
    return tau + gaz_friction(doc, qd)


def gaz_consistency(doc: dict) -> dict:
    """Physical consistency of the tables' links: the smallest eigenvalue of each link's
    pseudo-inertia (> 0: positive mass, positive-definite inertia, triangle inequalities)
    and each link's triangle-inequality margin at the centre of mass."""
    p = gaz_params(doc).reshape(7, 12)
    eig_min = np.linalg.eigvalsh(pseudo_inertia(p[:, :10])).min(axis=1)
    margins = []
    for xx, xy, xz, yy, yz, zz in doc["links"]["inertia_at_com_kg_m2"]:
        e = np.linalg.eigvalsh(np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]))
        margins.append(float(e[0] + e[1] - e[2]))
    return {"consistent": bool(np.all(eig_min > 0)),
            "pseudo_inertia_min_eigenvalue": eig_min, "triangle_margin_at_com": margins,
            "mass_kg": float(np.sum(doc["links"]["mass_kg"]))}


# ----------------------------------------------------------------------- FIGAROH, TX40
def figaroh_base(path=FIGAROH_BASE) -> list[dict]:
    """FIGAROH's results file: per base parameter its expression (standard parameters,
    joints from 1) and its OLS and WLS values with relative standard deviations [%]."""
    rows = []
    with open(path, newline="") as f:
        for expr, ols, ols_std, wls, wls_std in csv.reader(f):
            rows.append({"expression": expr, "ols": float(ols), "ols_std_percent": float(ols_std),
                         "wls": float(wls), "wls_std_percent": float(wls_std)})
    return rows


_FIGAROH_TO_OURS = {"Ixx": "XX", "Iyy": "YY", "Izz": "ZZ", "Ixy": "XY", "Ixz": "XZ",
                    "Iyz": "YZ", "m": "M", "mx": "MX", "my": "MY", "mz": "MZ", "fv": "FV",
                    "fs": "FC"}


def figaroh_torques(robot: sj.Robot, rows, q, qd, qdd, column: str = "wls") -> np.ndarray:
    """The joint torques of FIGAROH's identified TX40 model (its regressor: link
    parameters about the URDF joint frames, ``fv qd + fs sign(qd)``, a torque offset
    ``off``, actuator inertia ``Ia qdd`` on joints 3-5, and on joints 5 and 6 the motor-6
    terms ``Iam6 qdd_other + fvm6 qd_other + fsm6 sign(qd5 + qd6)``). Each base parameter's
    value goes to the first standard parameter of its expression, the others stay 0: that
    reproduces every base combination."""
    params, extra = np.zeros(robot.n_params), {}
    names = robot.param_names
    for r in rows:
        kind, joint = re.fullmatch(r"([A-Za-z]+?)(\d+)", r["expression"].split()[0]).groups()
        if kind in _FIGAROH_TO_OURS:
            params[names.index(_FIGAROH_TO_OURS[kind] + joint)] = r[column]
        else:
            extra[kind + joint] = r[column]
    q, qd, qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
    tau = np.array(sj.inverse_dynamics(robot, params, q, qd, qdd))
    for j in range(robot.n_joints):
        tau[:, j] += extra.pop(f"off{j + 1}", 0.0) + extra.pop(f"Ia{j + 1}", 0.0) * qdd[:, j]
    s = np.sign(qd[:, 4] + qd[:, 5])
    iam, fvm, fsm = extra.pop("Iam6"), extra.pop("fvm6"), extra.pop("fsm6")
    tau[:, 4] += iam * qdd[:, 5] + fvm * qd[:, 5] + fsm * s
    tau[:, 5] += iam * qdd[:, 4] + fvm * qd[:, 4] + fsm * s
    if extra:
        raise ValueError(f"FIGAROH terms not understood: {sorted(extra)}")
    return tau


def figaroh_config(path=FIGAROH_CONFIG) -> dict:
    """``fv, fs, Ia, offset, Iam6, fvm6, fsm6, N, dq_lim_def`` of ``T40X_config.yaml``
    (read as text: plain ``key : value`` lines)."""
    out = {}
    for line in Path(path).read_text().splitlines():
        m = re.match(r"\s*-?\s*(fv|fs|Ia|offset|Iam6|fvm6|fsm6|N|dq_lim_def)\s*:\s*(.+?)\s*$",
                     line)
        if m:
            out[m[1]] = json.loads(m[2]) if m[2].startswith("[") else float(m[2])
    return out


def figaroh_terms(names, values, K) -> dict:
    """Joint-side terms in FIGAROH's convention from this package's fit (``names``,
    ``values``; ``K`` the transmission, motor angles ``K q``).

    The package's armature ``IA_m`` and coupled-motor friction ``FVM_m, FCM_m`` are motor
    side: they add ``K^T diag(IA) K qdd`` and ``K_m^T (FVM_m K_m.qd + FCM_m sign(K_m.qd))``.
    FIGAROH's ``Ia_j``, ``fv_j`` are the coefficients of ``qdd_j``, ``qd_j`` in joint
    ``j``'s torque, its ``Iam6``, ``fvm6`` those of ``qdd_6``, ``qd_6`` in joint 5's (and of
    ``qdd_5``, ``qd_5`` in joint 6's), ``fsm6`` that of ``sign(qd5 + qd6)``: so ``Ia_j =
    (K^T diag(IA) K)_jj``, ``Iam6 = (K^T diag(IA) K)_56``, ``fv_j = FV_j + (K^T diag(FVM)
    K)_jj``, ``fvm6 = (K^T diag(FVM) K)_56`` and ``fsm6 = K_65 FCM6``. ``Ia`` is None for a
    joint whose armature regroups with the link inertias (as in FIGAROH's base)."""
    v = dict(zip(names, np.asarray(values, dtype=float)))
    K = np.asarray(K, dtype=float)
    n = K.shape[0]
    ia = np.array([v.get(f"IA{m + 1}", 0.0) for m in range(n)])
    fvm = np.array([v.get(f"FVM{m + 1}", 0.0) for m in range(n)])
    A, V = K.T @ np.diag(ia) @ K, K.T @ np.diag(fvm) @ K
    known = [j for j in range(n) if f"IA{j + 1}" in v]
    if K[5, 4] <= 0 or any(k[:3] in ("FVM", "FCM") and k[3:] != "6" for k in v):
        raise ValueError("FIGAROH's motor-6 terms are those of the TX40's wrist")
    return {"fv": [v[f"FV{j + 1}"] + V[j, j] for j in range(n)],
            "fs": [v[f"FC{j + 1}"] for j in range(n)],
            "Ia": [float(A[j, j]) if j in known else None for j in range(n)],
            "offset": [v.get(f"OFF{j + 1}") for j in range(n)],
            "Iam6": float(A[4, 5]) if "IA6" in v else None, "fvm6": float(V[4, 5]),
            "fsm6": float(K[5, 4] * v.get("FCM6", 0.0))}


def figaroh_identified_terms(rows) -> dict:
    """The same terms from FIGAROH's results file (WLS values; None where regrouped)."""
    v = {r["expression"]: r["wls"] for r in rows}
    return {"fv": [v[f"fv{j}"] for j in range(1, 7)], "fs": [v[f"fs{j}"] for j in range(1, 7)],
            "Ia": [v.get(f"Ia{j}") for j in range(1, 7)],
            "offset": [v[f"off{j}"] for j in range(1, 7)],
            "Iam6": v["Iam6"], "fvm6": v["fvm6"], "fsm6": v["fsm6"]}


def fit_without_slow_samples(model, data, dq_lim):
    """OLS of ``model`` (a :class:`~sedsabso_jax.identification.TorqueModel`) on each
    joint's equations where ``|qd_j| >= dq_lim[j]``, as FIGAROH's script selects them
    (it drops a joint's samples near zero velocity): ``(names, values)``."""
    Y = model.regressor(data.q, data.qd, data.qdd)
    keep = np.abs(data.qd) >= np.asarray(dq_lim)
    A = np.concatenate([Y[keep[:, j], j] for j in range(Y.shape[1])])
    b = np.concatenate([data.tau[keep[:, j], j] for j in range(Y.shape[1])])
    return model.names, np.linalg.lstsq(A, b, rcond=None)[0]


# ----------------------------------------------------------------------- the benchmark
def scores(tau, pred, limits, labels) -> dict:
    whole = sj.validation_metrics(tau, pred, limits)
    folds = [sj.validation_metrics(tau[labels == k], pred[labels == k],
                                   limits).nrms_limits_percent for k in range(FOLDS)]
    return {"whole_run": whole.nrms_limits_percent,
            "whole_run_per_joint": whole.nrms_limits_percent_per_joint,
            "held_out_stretches": {"mean": float(np.mean(folds)), "folds": folds}}


def nested_row(nested: dict, prefix: str, data, period) -> dict:
    row = next(r for r in nested["rows"] if r["robot"].startswith(prefix))
    if row["samples"] != data.n_samples or not np.isclose(row["period_s"] or 0, period or 0):
        raise RuntimeError(f"{prefix}: the nested benchmark's data differ from these "
                           f"(samples {row['samples']} vs {data.n_samples}); rerun "
                           "python -m benchmarks.real_robots")
    h = row["nested_held_out_percent"]["phase"]["default"]
    return {"held_out_stretches": {"mean": h["mean"], "folds": h["splits"]},
            "whole_run_fit": row["fit_percent"],
            "chosen_on_all_data": row["chosen_on_all_data"]}


def panda(tmp: Path, nested: dict) -> dict:
    doc = load_gaz()
    robot = sj.robots.franka_panda()
    data = sj.load_measurements(real_robots.panda_npz(tmp / "panda.npz"), n_joints=7,
                                resample_hz=1000.0)
    limits = joint_limits("franka_panda", robot).torque_limits
    labels, period = phase_folds(data.times, data.q, FOLDS)
    tab = gaz_torques(doc, data.q, data.qd, data.qdd)
    rep = gaz_torques(doc, data.q, data.qd, data.qdd, gravity="repository")
    zero = np.zeros_like(data.q)
    g = gaz_robot(doc)
    g_tab = np.asarray(sj.inverse_dynamics(g, g.params, data.q, zero, zero))
    g_rep = np.asarray(sj.inverse_dynamics(g, gaz_repository_gravity_params(doc), data.q,
                                           zero, zero))
    return {
        "robot": "Franka Panda", "samples": data.n_samples, "period_s": period,
        "gaz2019_tables_sigmoid_friction": scores(data.tau, tab, limits, labels),
        "gaz2019_repository_gravity": scores(data.tau, rep, limits, labels),
        "gaz2019_rigid_body_only": scores(data.tau, tab - gaz_friction(doc, data.qd),
                                          limits, labels),
        "gravity_tables_vs_repository_max_abs_Nm": np.abs(g_tab - g_rep).max(axis=0),
        "gaz2019_consistency": gaz_consistency(doc),
        "this_package_default": nested_row(nested, "Franka Panda", data, period),
    }


def tx40(tmp: Path, nested: dict) -> dict:
    robot = sj.robots.staubli_tx40()
    data, tr = real_robots.tx40_joint_side(tmp)
    limits = joint_limits("staubli_tx40", robot).torque_limits
    labels, period = phase_folds(data.times, data.q, FOLDS)
    rows = figaroh_base()
    ours = nested_row(nested, "Staubli TX40", data, period)
    base = sj.base_parameters(robot)
    fits = {}
    for label, settings in (("figaroh_terms", FIGAROH_LIKE),
                            ("default_choice", ours["chosen_on_all_data"])):
        estimator = sj.Estimator.named(settings["method"], sigma=settings["sigma"])
        if settings.get("physical"):
            estimator = sj.PhysicallyConsistent(estimator)
        model = sj.TorqueModel.of(robot, parse_friction(settings["friction"]), base=base,
                                  transmission=tr)
        ident = sj.identify(robot, data, estimator, model, limits=limits)
        extra = {n: v for n, v in zip(ident.names, ident.values)
                 if re.fullmatch(r"(FV|FC|OFF|FQ|IA|FVM|FCM)\d+", n)}
        fits[label] = {"settings": settings, "fit_whole_run": ident.fit["nrms_limits_percent"],
                       "motor_side_and_joint_values": extra,
                       "figaroh_convention": figaroh_terms(ident.names, ident.values,
                                                           tr.matrix),
                       "regrouped": ident.settings.get("regrouped", [])}
        if label == "figaroh_terms":
            names, x = fit_without_slow_samples(ident.model, data,
                                                figaroh_config()["dq_lim_def"])
            pred = ident.model.predict(x, data.q, data.qd, data.qdd)
            fits["figaroh_terms_slow_samples_dropped"] = {
                "settings": {"method": "OLS", "friction": FIGAROH_LIKE["friction"],
                             "rows": "joint j's where |qd_j| >= T40X_config.yaml's dq_lim_def"},
                "fit_whole_run": sj.validation_metrics(data.tau, pred,
                                                       limits).nrms_limits_percent,
                "figaroh_convention": figaroh_terms(names, x, tr.matrix)}
    slow = np.abs(data.qd) < np.asarray(figaroh_config()["dq_lim_def"])
    return {
        "robot": "Staubli TX40 (motor side, 1 kHz)", "samples": data.n_samples,
        "slow_sample_fraction_per_stretch": [float(slow[labels == k].mean())
                                             for k in range(FOLDS)],
        "figaroh_identified_wls": scores(data.tau, figaroh_torques(
            robot, rows, data.q, data.qd, data.qdd), limits, labels),
        "figaroh_identified_ols": scores(data.tau, figaroh_torques(
            robot, rows, data.q, data.qd, data.qdd, "ols"), limits, labels),
        "terms_joint_side": {"T40X_config.yaml": {k: v for k, v in figaroh_config().items()
                                                  if k not in ("N", "dq_lim_def")},
                             "FIGAROH identified (TX40_bp_5.csv, WLS)":
                                 figaroh_identified_terms(rows),
                             **{f"this package, {k}": f["figaroh_convention"]
                                for k, f in fits.items() if k != "default_choice"}},
        "this_package_fits": fits, "this_package_default": ours,
    }


def _fmt(v, digits=3):
    return "-" if v is None else f"{v:.{digits}g}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default="benchmarks/results/published.json")
    ap.add_argument("--nested", default="benchmarks/results/real_robots.json",
                    help="the nested benchmark's JSON, for the default's held-out figures")
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    nested = json.loads(Path(args.nested).read_text())
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # rank and conditioning notes of the fits
        rows = [panda(Path(tmp), nested), tx40(Path(tmp), nested)]
    p, t = rows
    print("\n| Panda | whole run | held-out stretches (mean) | per stretch |\n|---|---|---|---|")
    for label, s in (("this package's default (nested CV; whole run: in-sample fit)",
                      p["this_package_default"]),
                     ("Gaz et al. 2019, tables + sigmoid friction",
                      p["gaz2019_tables_sigmoid_friction"]),
                     ("Gaz et al., repository gravity", p["gaz2019_repository_gravity"]),
                     ("Gaz et al., rigid body only", p["gaz2019_rigid_body_only"])):
        w = s.get("whole_run", s.get("whole_run_fit"))
        h = s["held_out_stretches"]
        print(f"| {label} | {w:.4f} | {h['mean']:.4f} | "
              f"{', '.join(f'{x:.3f}' for x in h['folds'])} |")
    c = p["gaz2019_consistency"]
    print(f"Gaz links physically consistent: {c['consistent']} (smallest pseudo-inertia "
          f"eigenvalue {min(c['pseudo_inertia_min_eigenvalue']):.3g})")
    print("\n| TX40 | whole run | held-out stretches (mean) |\n|---|---|---|")
    d = t["this_package_default"]
    print(f"| this package's default | {d['whole_run_fit']:.4f} (in-sample) | "
          f"{d['held_out_stretches']['mean']:.4f} (nested) |")
    for k, f in t["this_package_fits"].items():
        if k == "default_choice":  # the default's row above
            continue
        print(f"| this package, {k} | {f['fit_whole_run']:.4f} (in-sample) | - |")
    for k in ("figaroh_identified_wls", "figaroh_identified_ols"):
        print(f"| {k} | {t[k]['whole_run']:.4f} | {t[k]['held_out_stretches']['mean']:.4f} |")
    srcs = list(t["terms_joint_side"])
    print(f"\n| term, joint side: {' / '.join(srcs)} | J1 | J2 | J3 | J4 | J5 | J6 |\n"
          "|---|---|---|---|---|---|---|")
    for term in ("fv", "fs", "Ia", "offset"):
        cells = [" / ".join(_fmt(t["terms_joint_side"][src][term][j]) for src in srcs)
                 for j in range(6)]
        print(f"| {term} | " + " | ".join(cells) + " |")
    for k in ("Iam6", "fvm6", "fsm6"):
        print(f"| {k} | " + " / ".join(_fmt(t["terms_joint_side"][src][k]) for src in srcs)
              + " |")
    doc = {"machine": platform.processor() or platform.machine(), "rows": rows,
           "seconds": time.perf_counter() - t0, "versions": {"sedsabso_jax": sj.__version__}}
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(to_json(doc))
    print(f"written: {args.json}")


if __name__ == "__main__":
    main()
