"""The delay of the torques behind the motion on the three shipped robots
(``sj.identification.estimate_delay``), for several torque models, and on the KUKA what
fitting run 1 re-timed by it does to the prediction of run 2 (re-timed alike): OLS, NRMS
over the torque limits [%]. The KUKA's run 2 repeats run 1's trajectory (repeatability).

    python -m benchmarks.delay
"""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import jax

import sedsabso_jax as sj
from benchmarks.real_robots import datasets
from sedsabso_jax.identification import estimate_delay, parse_friction

MODELS = ("viscous-coulomb", "viscous-coulomb+offset", "viscous-coulomb+offset+smooth",
          "viscous-coulomb+offset+smooth+presliding:0.001")


def main() -> None:
    jax.config.update("jax_enable_x64", True)
    print("| robot | model | delay [ms] | [samples] | held out, as recorded [%] | "
          "held out, re-timed [%] |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, robot, data, limits, tr, runs in datasets(Path(tmp)):
            for friction in MODELS:
                if tr is not None and "presliding" in friction:
                    continue  # the motor side's coupled wrist: shown with the plain models
                model = sj.TorqueModel.of(robot, parse_friction(friction), transmission=tr)
                found = estimate_delay(robot, data, model, limits=limits.torque_limits)
                held = ["-", "-"]
                for run in runs.values():
                    for i, d in enumerate((0.0, found.seconds)):
                        fit = sj.identify(robot, data.delayed(d), sj.OLS(), model,
                                          limits=limits.torque_limits)
                        h = run.delayed(d)
                        error = sj.validation_metrics(h.tau, fit.predict(h.q, h.qd, h.qdd),
                                                      limits.torque_limits)
                        held[i] = f"{error.nrms_limits_percent:.4f}"
                print(f"| {name} | {friction} | {1e3 * found.seconds:.2f} | "
                      f"{found.samples:.2f}{' (at bound)' if found.at_bound else ''} | "
                      f"{held[0]} | {held[1]} |", flush=True)


if __name__ == "__main__":
    main()
