"""Are the identified parameters' standard deviations right on real data? The KUKA LWR4+'s
two runs of one trajectory, each identified alone (OLS, Coulomb + viscous + offset +
armature): if the standard deviations held, the runs' estimates would differ by a median
of 0.674 of their combined standard deviation, and 68.3 % of them by less than one.

    python -m benchmarks.uncertainty [--json benchmarks/results/uncertainty.json]
"""

from __future__ import annotations

import argparse
import warnings

import jax
import numpy as np

import sedsabso_jax as sj
from benchmarks.device import device_info
from benchmarks.output import to_json
from sedsabso_jax.dynamics import joint_limits

MODEL = (sj.Offset(), sj.Armature())


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # IA1, IA2
        robot = sj.robots.kuka_lwr4()
        limits = joint_limits("kuka_lwr4", robot).tau_max
        model = sj.TorqueModel.of(robot, MODEL)
        fits = [sj.identify(robot, sj.load_kuka_lwr4(run), sj.OLS(), model, limits=limits)
                for run in (1, 2)]
    z = (fits[0].values - fits[1].values) / np.sqrt(fits[0].std ** 2 + fits[1].std ** 2)
    relative = fits[0].relative_std_percent
    worst = int(np.argmax(relative))
    found = {"model": model.friction, "parameters": len(z),
             "median_abs_z": float(np.median(np.abs(z))),
             "fraction_within_one": float(np.mean(np.abs(z) < 1)),
             "expected": {"median_abs_z": 0.674, "fraction_within_one": 0.683},
             "run1_relative_std_percent": {"median": float(np.median(relative)),
                                           "max": float(relative[worst]),
                                           "max_name": fits[0].names[worst]},
             "device": device_info()}
    print(f"{len(z)} parameters: median |difference| / combined std {found['median_abs_z']:.2f} "
          f"(0.67 if the std held), within one std {100 * found['fraction_within_one']:.0f} % "
          f"(68 %); run 1 relative std median {np.median(relative):.1f} %, largest "
          f"{relative[worst]:.0f} % ({fits[0].names[worst]})")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json(found))


if __name__ == "__main__":
    main()
