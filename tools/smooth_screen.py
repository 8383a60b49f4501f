"""Would the smooth Coulomb's velocity scales validate better on a robot's data? A cheap
screen, measured for a later default (issue 45: the scales searched where they validate
better), not part of the package.

For each shipped robot: the default's choice on all its data (signals as loaded), its
nonlinear parameters held where that fit put them (model ``A``); the same model with
friction at rest held there and the smooth Coulomb's scales searched on all the data,
then held (model ``B``). Both are validated by the default's splits with nothing
searched in them, and the screen passes where ``B`` beats ``A`` by the default's rule
(``DEFAULT.not_worse``, one standard error of the paired excess). Holding values
searched on all the data makes both validations optimistic, ``B``'s by its extra
parameters more; and it holds friction at rest where the fit without the scales put
it, where the full validation (each split's own search of both, ``python -m
benchmarks.real_robots --kept smooth``) searches them together. Measured on the shipped
robots, it agrees with the full validation on the TX40 (passes) and not on the KUKA (does
not pass, where the full validation on all its data prefers the scales):
docs/explanation/identification-defaults.md.

    python tools/smooth_screen.py [--robots kuka,panda,tx40]

prints, per robot, the default's choice and seconds, the scales found and the seconds
of their search, both validations and whether the screen passes.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import time
import warnings
from pathlib import Path

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
import sedsabso_jax as sj  # noqa: E402
from benchmarks.real_robots import ROBOTS, datasets  # noqa: E402
from sedsabso_jax.identification import DEFAULT, DefaultValidation, candidate_models  # noqa: E402


def screened(model: sj.TorqueModel) -> sj.TorqueModel:
    """``model`` (its searched values held) with friction at rest fixed at its values and
    the smooth Coulomb's scales searched."""
    terms = tuple(sj.Presliding(displacement=t.displacement) if isinstance(t, sj.Presliding)
                  else sj.SmoothCoulomb(fitted=True) if isinstance(t, sj.SmoothCoulomb)
                  else t for t in model.terms)
    return dataclasses.replace(model, terms=terms, search=None)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", default=",".join(ROBOTS))
    robots = parser.parse_args().robots.split(",")
    if unknown := sorted(set(robots) - set(ROBOTS)):
        parser.error(f"--robots: unknown {', '.join(unknown)}; expected words of "
                     f"{', '.join(ROBOTS)}")
    warnings.simplefilter("ignore")
    for name, robot, data, limits, tr, _ in datasets(Path(tempfile.mkdtemp()), robots):
        tau_limits = limits.torque_limits
        validation = DefaultValidation(signals=None)
        t0 = time.perf_counter()
        report = sj.select_and_identify(
            robot, data, validation=validation, limits=tau_limits,
            models=candidate_models(robot, transmission=tr, base=sj.base_parameters(robot)))
        print(f"{name}: default {time.perf_counter() - t0:.1f} s, "
              f"{report.selection.chosen}", flush=True)
        estimator, held = report.ident.estimator, report.ident.model
        t0 = time.perf_counter()
        smooth = sj.identify(robot, data, estimator, screened(held), limits=tau_limits).model
        scales = next(np.atleast_1d(t.velocity) for t in smooth.terms
                      if isinstance(t, sj.SmoothCoulomb))
        print(f"  scales searched on all the data in {time.perf_counter() - t0:.1f} s: "
              f"{np.array2string(scales, precision=4)} rad/s", flush=True)
        splits = validation.of([data])
        a, b = (sj.cross_validate(robot, data, estimator, m, validation=splits,
                                  limits=tau_limits) for m in (held, smooth))
        print(f"  held: {a.score:.5f} +- {a.standard_error:.5f} %, with the scales "
              f"{b.score:.5f} +- {b.standard_error:.5f} %: screen "
              f"{'passes' if not DEFAULT.not_worse(a, b) else 'does not pass'}", flush=True)


if __name__ == "__main__":
    main()
