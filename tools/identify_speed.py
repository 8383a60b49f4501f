"""One process's wall time of the default identification (``sj.select_and_identify``) of
the shipped KUKA LWR4+ run 1, run 2 held out, for comparing two checkouts of the package
(a refactor that must not slow the default down). Compilation is part of what a user
waits for, so nothing is warmed up. Prints one JSON line: the package's path, the
seconds, the choice and the held-out NRMS over the limits. Alternate the checkouts,
several processes each, and compare medians:

    for i in 1 2 3; do PYTHONPATH=OLD python tools/identify_speed.py; \\
        python tools/identify_speed.py; done

``--smooth``: the smooth Coulomb's velocity scales searched as a second alternative to
friction at rest (the nested benchmark's ``--kept smooth``).
"""

from __future__ import annotations

import json
import sys
import time
import warnings

import jax

jax.config.update("jax_enable_x64", True)
import sedsabso_jax as sj  # noqa: E402
from sedsabso_jax.dynamics import joint_limits  # noqa: E402


def main() -> None:
    robot = sj.robots.kuka_lwr4()
    limits = joint_limits("kuka_lwr4", robot).torque_limits
    data, held_out = sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        validation = sj.identification.DefaultValidation()
        if "--smooth" in sys.argv[1:]:
            at_rest = sj.Presliding(fitted=True, largest=0.02)
            validation = sj.identification.DefaultValidation(kept=sj.identification.KeptTerms(
                [(at_rest,), (at_rest, sj.SmoothCoulomb(fitted=True))]))
        report = sj.select_and_identify(robot, data, held_out=held_out, limits=limits,
                                        validation=validation)
    seconds = time.perf_counter() - t0
    print(json.dumps({"package": sj.__file__, "seconds": round(seconds, 1),
                      "friction": report.selection.chosen["friction"],
                      "held_out_percent": report.validation.nrms_limits_percent}))


if __name__ == "__main__":
    main()
