"""The identified KUKA LWR4+ written for MuJoCo (issue 44): run 1 fitted, run 2 held out.

Rows, each the command's choice made on run 1 alone (``sj.select_and_identify``, physically
consistent, as ``identify --mjcf-out``) and written with ``report.with_mjcf``:

- ``default``: the default's choice (its terms MuJoCo cannot hold left out of the file);
- ``--mujoco-terms``: the choice among the default's candidates with only the terms
  MuJoCo holds in full, no friction at rest;
- the latter driven by its own predicted torques instead of the measured ones (the
  rollouts then check the simulation, not the model);
- the latter's file with MuJoCo's default dry-friction impedance (``solimpfriction``
  unset), which the writer replaces.

Columns: the torque error of the package's own model and of the file in MuJoCo
(``mj_inverse``), NRMS over the torque limits [%] on run 2; the median end error [deg] of
open-loop rollouts of 0.2 s and 0.5 s from 64 measured states of run 2, in JAX (the
package's model) and in MuJoCo (the file); CPU seconds of the choice and fit.

A second table judges the writer's dry-friction impedance on a robot it was not chosen on:
the Franka Panda (its one run, the first 70 % fitted with offsets, physically consistent,
the last 30 % held out), the package's own torque error against its file's in MuJoCo, with
the writer's impedance and with MuJoCo's default.

    python -m benchmarks.mujoco [--json benchmarks/results/mujoco.json] [--mjcf-dir DIR]

``--mjcf-dir`` keeps the files (``benchmarks.mujoco_sysid --mjcf DIR/mujoco-terms.xml``
starts MuJoCo's own identification from the second).
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import tempfile
import time
import warnings
from pathlib import Path

import jax

import sedsabso_jax as sj
from benchmarks.output import to_json
from data import real_robots
from sedsabso_jax.dynamics import joint_limits
from sedsabso_jax.identification import (
    DEFAULT,
    DefaultValidation,
    candidate_models,
    held_frictions,
    mujoco_torques,
    rollout_errors,
)


def choose(robot, data, held_out, limits, mujoco_terms: bool):
    """The command's choice and fit on ``data`` (``--mjcf-out``, with or without
    ``--mujoco-terms``), its MJCF and the CPU seconds they took."""
    frictions = held_frictions(DEFAULT.frictions) if mujoco_terms else DEFAULT.frictions
    validation = DefaultValidation(kept=None) if mujoco_terms else DefaultValidation()
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = sj.select_and_identify(robot, data, held_out=held_out, limits=limits,
                                        models=candidate_models(robot, frictions),
                                        validation=validation, physical=True)
    cpu = time.process_time() - start
    return report.with_mjcf(limits=joint_limits("kuka_lwr4", robot),
                            timestep=1.0 / data.rate), cpu


def row(name, report, xml, held_out, limits, cpu=None):
    ident = report.ident
    nrms = {
        "own": sj.validation_metrics(held_out.tau, ident.predict(held_out.q, held_out.qd,
                                                              held_out.qdd), limits),
        "mujoco": sj.validation_metrics(held_out.tau, mujoco_torques(
            xml, held_out.q, held_out.qd, held_out.qdd), limits)}
    r = rollout_errors(ident, held_out, xml)
    medians = r.medians()
    return {"model": name, "friction": ident.model.friction,
            "held_out_nrms_own_percent": nrms["own"]["nrms_limits_percent"],
            "held_out_nrms_mujoco_percent": nrms["mujoco"]["nrms_limits_percent"],
            "rollout_median_deg_own": medians["own"],
            "rollout_median_deg_mujoco": medians["mujoco"],
            "rollout_lengths_s": list(r.lengths), "left_out": list(report.simulator.left_out),
            "cpu_s": cpu}


def panda_impedance() -> dict[str, float]:
    """The Panda's held-out torque error [%]: own, written, MuJoCo's default impedance."""
    with tempfile.TemporaryDirectory() as tmp:
        data = sj.load_measurements(real_robots.panda_npz(Path(tmp) / "panda.npz"),
                                    n_joints=7, resample_hz=1000.0)
    panda = sj.robots.franka_panda()
    limits = joint_limits("franka_panda", panda).torque_limits
    cut = int(0.7 * data.n_samples)
    fitted, held_out = data.slice(0, cut), data.slice(cut, None)
    fit = sj.identify(panda, fitted, sj.PhysicallyConsistent(sj.OLS()),
                      sj.TorqueModel.of(panda, (sj.Offset(),)))
    xml = fit.mjcf(timestep=1.0 / data.rate)
    soft = re.sub(r'<joint solimpfriction="[^"]*"/>', "", xml)
    q, qd, qdd = held_out.q, held_out.qd, held_out.qdd
    return {name: sj.validation_metrics(held_out.tau, tau, limits).nrms_limits_percent
            for name, tau in (("own", fit.predict(q, qd, qdd)),
                              ("written", mujoco_torques(xml, q, qd, qdd)),
                              ("MuJoCo's default impedance", mujoco_torques(soft, q, qd,
                                                                            qdd)))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    ap.add_argument("--mjcf-dir", default=None)
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    robot = sj.robots.kuka_lwr4()
    limits = joint_limits("kuka_lwr4", robot).tau_max
    data, held_out = sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2)
    rows = []
    for name, mujoco_terms in (("default", False), ("--mujoco-terms", True)):
        report, cpu = choose(robot, data, held_out, limits, mujoco_terms)
        rows.append(row(name, report, report.mjcf, held_out, limits, cpu))
        if args.mjcf_dir:
            os.makedirs(args.mjcf_dir, exist_ok=True)
            with open(os.path.join(args.mjcf_dir, f"{name.strip('-')}.xml"), "w") as f:
                f.write(report.mjcf)
    own = sj.Measurements(held_out.times, held_out.q, held_out.qd, held_out.qdd,
                          report.ident.predict(held_out.q, held_out.qd, held_out.qdd))
    rows.append(row("--mujoco-terms, driven by its own predicted torques (checks the "
                    "simulation)", report, report.mjcf, own, limits))
    soft = re.sub(r'<joint solimpfriction="[^"]*"/>', "", report.mjcf)
    rows.append(row("--mujoco-terms, MuJoCo's default friction impedance", report, soft,
                    held_out, limits))
    print("| model | friction | held-out own [%] | held-out MuJoCo [%] | rollout 0.2 / 0.5 s "
          "own [deg] | rollout 0.2 / 0.5 s MuJoCo [deg] | CPU [s] |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        cpu = "" if r["cpu_s"] is None else f"{r['cpu_s']:.0f}"
        print(f"| {r['model']} | {r['friction']} | {r['held_out_nrms_own_percent']:.4f} | "
              f"{r['held_out_nrms_mujoco_percent']:.4f} | "
              + " / ".join(f"{e:.3g}" for e in r["rollout_median_deg_own"]) + " | "
              + " / ".join(f"{e:.3g}" for e in r["rollout_median_deg_mujoco"])
              + f" | {cpu} |")
    panda = panda_impedance()
    print("\n| Franka Panda, last 30 % held out | " + " | ".join(panda) + " |")
    print("|---|" + "---|" * len(panda))
    print("| torque NRMS over the limits [%] | "
          + " | ".join(f"{v:.4f}" for v in panda.values()) + " |")
    if args.json:
        with open(args.json, "w") as f:
            f.write(to_json({"rows": rows, "panda_impedance": panda, "jax": jax.__version__,
                             "machine": platform.processor() or platform.machine(),
                             "command": "python -m benchmarks.mujoco"}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
