"""A candidate for a cheaper end of the coordinate search (issue 45: the smooth Coulomb's
scales searched beside friction at rest cost 7-9 s a search on the KUKA LWR4+): Gauss-Newton
steps on the projected residual's Jacobian (forward mode through the columns, one call of
``k`` directions) until a step's predicted gain is below 1e-8 of the loss, then the
package's finite-difference Newton (:func:`~sedsabso_jax.identification._search._newton.polish`)
to its own end, so that where the search ends is decided as before. Not the package's
method: a measurement for the step before offering the scales to the validation.

On the KUKA LWR4+'s run 1 and the default's model (offset, smooth Coulomb, load friction),
friction at rest searched up to 20 mrad alone (7 parameters) and with the smooth scales (14),
it times the package's search and the candidate (the same sweeps first), twice each, and
prints the two ends' loss and parameter differences:

    python tools/gauss_newton_polish.py
"""

from __future__ import annotations

import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

import sedsabso_jax as sj  # noqa: E402
from sedsabso_jax.identification import KeptTerms, Projection, candidate_models  # noqa: E402
from sedsabso_jax.identification._search._methods import CoordinateSearch  # noqa: E402
from sedsabso_jax.identification._search._newton import (  # noqa: E402
    FTOL,
    HALVINGS,
    STEP,
    newton_step,
    polish,
)
from sedsabso_jax.identification._search._problem import losses  # noqa: E402


@eqx.filter_jit
def _residual_and_jacobian(u, problem):
    return problem.residual(u), jax.jacfwd(problem.residual)(u)


def gauss_newton(problem, u, loss, lower, upper, held, gain=1e-8, max_steps=20, rtol=1e-10):
    """Gauss-Newton steps from ``u`` until the predicted gain is below ``gain`` of the
    loss (a step the loss does not confirm halved, as the polish does)."""
    scale, steps = abs(loss), 0
    for steps in range(1, max_steps + 1):
        r, J = (np.asarray(x) for x in _residual_and_jacobian(jnp.asarray(u), problem))
        g, H = 2 * J.T @ r / r.size, 2 * J.T @ J / r.size
        at_bound = ((u <= lower) & (g > 0)) | ((u >= upper) & (g < 0))
        floor = 4 * FTOL * scale / STEP ** 2  # the polish's: what rounding hides
        d = newton_step(g, H, ~(at_bound | held), u, lower, upper, floor)
        if -0.5 * float(g @ d) <= gain * scale:
            break
        for _ in range(HALVINGS + 1):
            f_new = float(losses(problem, (u + d)[None])[0])
            if f_new <= loss + rtol * scale:
                break
            d = d / 2
        else:
            break
        u, loss = u + d, f_new
    return u, loss, steps


def main() -> None:
    robot, data = sj.robots.kuka_lwr4(), sj.load_kuka_lwr4(1)
    chosen = next(m for m in candidate_models(robot)
                  if m.friction == "viscous-coulomb+offset+smooth+load")
    chosen = chosen.reading(chosen.prior_values)
    at_rest = sj.Presliding(fitted=True, largest=0.02)
    for label, terms in (("friction at rest", (at_rest,)),
                         ("and the smooth scales", (at_rest, sj.SmoothCoulomb(fitted=True)))):
        model = KeptTerms([terms]).models(chosen)[0]
        problem = Projection.of(model, data)
        found = [f for _, f in model.nonlinear()]
        u0, lower, upper = (np.log(np.concatenate([getattr(f, a) for f in found]))
                            for a in ("values", "lower", "upper"))
        k = u0.size
        losses(problem, np.repeat(u0[None], 7 * k, 0))  # compiled before timing
        _residual_and_jacobian(jnp.asarray(u0), problem)
        for _ in range(2):
            t0 = time.perf_counter()
            package = CoordinateSearch().search(problem, u0, lower, upper)
            t_package = time.perf_counter() - t0
            t0 = time.perf_counter()
            swept = CoordinateSearch(newton=0).search(problem, u0, lower, upper)
            u, loss, steps = gauss_newton(problem, swept.u, swept.loss, lower, upper,
                                          swept.held)
            end = polish(problem, u, loss, lower, upper, 1e-10, 10, 7 * k, swept.held)
            t_candidate = time.perf_counter() - t0
            print(f"{label} ({k} parameters): package {package.evaluations} trials, "
                  f"{package.newton_steps} Newton steps, {t_package:.2f} s; candidate "
                  f"{steps} Gauss-Newton + {end.steps} Newton steps (converged "
                  f"{end.converged}), {t_candidate:.2f} s; loss (candidate - package) / "
                  f"package {(end.loss - package.loss) / package.loss:.1e}, parameters "
                  f"apart by {np.abs(end.u - package.u).max():.1e} (log)", flush=True)


if __name__ == "__main__":
    main()
