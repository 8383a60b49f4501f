"""Identification by simulation error (issue 44 part 4): does the output-error refinement
of a physical fit (``sj.identification.refine``, DIDIM's idea with open-loop windows and an
exact Jacobian) predict new data better than the inverse-dynamics fit it starts from?

Two robots, each fitted on one part and judged on another: the KUKA LWR4+ (run 1 fitted,
run 2 held out: the same trajectory again) and the Franka Panda (its one run, the first
70 % fitted, the last 30 % held out: a new stretch of motion). The start is the physically
consistent least-squares fit with torque offsets; rows refine it with
``OutputError(torque_weight=w)`` for the weights given (0: positions only). The torque
weight's default was chosen on the KUKA; the Panda was not looked at to choose it.

Columns: held-out torque NRMS over the limits [%] (inverse dynamics of the model); the
median end error [deg] of open-loop rollouts of 0.2 s and 0.5 s from 64 measured states of
the held-out data, in JAX (linearly implicit Euler, 1 ms steps: finer than the
refinement's own) and in MuJoCo (the model's MJCF, its timestep the sample period);
the refinement's cost before and after, its Levenberg-Marquardt steps and CPU seconds
(compilation included).

    python -m benchmarks.output_error [--weights 0 10] [--steps 10] [--robots both]
        [--json benchmarks/results/output_error.json]
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import warnings
from pathlib import Path

import jax

import sedsabso_jax as sj
from benchmarks.output import to_json
from data import real_robots
from sedsabso_jax.dynamics import joint_limits
from sedsabso_jax.identification import OutputError, refine, rollout_errors


def cases(robots: str = "both"):
    """``(name, robot, fitted, held_out, limits, length)`` per robot; the Panda's
    windows are half as long (1 kHz: a step per millisecond, 2.5 times the KUKA's steps)."""
    kuka = sj.robots.kuka_lwr4()
    if robots in ("kuka", "both"):
        yield ("KUKA LWR4+ run 1 -> run 2", kuka, sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2),
               joint_limits("kuka_lwr4", kuka).tau_max, 0.2)
    if robots == "kuka":
        return
    with tempfile.TemporaryDirectory() as tmp:
        data = sj.load_measurements(real_robots.panda_npz(Path(tmp) / "panda.npz"),
                                    n_joints=7, resample_hz=1000.0)
    panda = sj.robots.franka_panda()
    cut = int(0.7 * data.n_samples)
    yield ("Franka Panda first 70 % -> last 30 %", panda, data.slice(0, cut),
           data.slice(cut, None), joint_limits("franka_panda", panda).torque_limits, 0.1)


def judged(model, held_out, limits) -> dict:
    """Held-out torque error, and rollouts in JAX and in MuJoCo (its written MJCF, the
    sample period its timestep, MuJoCo's implicitfast)."""
    tau = model.predict(held_out.q, held_out.qd, held_out.qdd)
    xml = model.mjcf(timestep=1.0 / held_out.rate)
    medians = rollout_errors(model, held_out, xml).medians()
    return {"held_out_nrms_percent":
            sj.validation_metrics(held_out.tau, tau, limits).nrms_limits_percent,
            "rollout_median_deg": medians["own"],
            "rollout_median_deg_mujoco": medians["mujoco"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--weights", type=float, nargs="+", default=[0.0, 10.0])
    ap.add_argument("--steps", type=int, default=OutputError().steps,
                    help="Levenberg-Marquardt steps (default: the OutputError default)")
    ap.add_argument("--robots", choices=["kuka", "panda", "both"], default="both")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    rows = []
    for name, robot, fitted, held_out, limits, length in cases(args.robots):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = sj.identify(robot, fitted, sj.PhysicallyConsistent(sj.OLS()),
                              sj.TorqueModel.of(robot, (sj.Offset(),)), limits=limits)
        rows.append({"robot": name, "model": "inverse-dynamics fit (start)",
                     **judged(fit, held_out, limits)})
        for w in args.weights:
            method = OutputError(length=length, torque_weight=w, steps=args.steps)
            r = refine(fit, fitted, method, limits=limits)
            rows.append({"robot": name, "model": f"refined, torque_weight {w:g}",
                         **judged(r, held_out, limits), "cost": list(r.cost),
                         "steps": r.steps, "cpu_s": r.seconds, "length_s": length,
                         "windows": method.windows})
            print(rows[-1], flush=True)
    print("| robot | model | held-out torque [%] | rollout 0.2 / 0.5 s [deg] | in MuJoCo "
          "[deg] | cost before -> after | steps | CPU [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        cost = f"{r['cost'][0]:.4g} -> {r['cost'][1]:.4g}" if "cost" in r else ""
        print(f"| {r['robot']} | {r['model']} | {r['held_out_nrms_percent']:.4f} | "
              + " / ".join(f"{e:.3g}" for e in r["rollout_median_deg"]) + " | "
              + " / ".join(f"{e:.3g}" for e in r["rollout_median_deg_mujoco"])
              + f" | {cost} | {r.get('steps', '')} | "
              + (f"{r['cpu_s']:.0f}" if "cpu_s" in r else "") + " |")
    if args.json:
        with open(args.json, "w") as f:
            f.write(to_json({"rows": rows, "jax": jax.__version__,
                             "machine": platform.processor() or platform.machine(),
                             "command": "python -m benchmarks.output_error"}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
