"""A probe for issue 44 part 4 (output-error refinement, not in the package): Levenberg-
Marquardt on the open-loop rollouts of the KUKA (48 windows of 0.5 s of run 1), exact
Jacobian by ``jax.jacfwd`` through the rollouts, over 28 joint parameters (viscous and
Coulomb friction, armature, offset; the inertias of the physically consistent fit
fixed); held-out rollouts and torque error on run 2 before and after.

    python tools/output_error_probe.py      # about 5 minutes on 2 cores
"""

from __future__ import annotations

import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize as so

import sedsabso_jax as sj
from sedsabso_jax.dynamics import joint_limits, rollout
from sedsabso_jax.identification._fit._rollouts import (
    STICKING_VELOCITY,
    simulated_dynamics,
    starts,
)

jax.config.update("jax_enable_x64", True)
N = 7
DEG = 180.0 / np.pi


class Extra(eqx.Module):
    fc: jax.Array
    offset: jax.Array

    def __call__(self, q, qd):
        return self.fc * jnp.tanh(qd / STICKING_VELOCITY) + self.offset


def windows(d, steps, count):
    first = starts(d.n_samples, steps, count)
    idx = first[:, None] + np.arange(steps + 1)
    return (jnp.asarray(d.q[first]), jnp.asarray(d.qd[first]),
            jnp.asarray(d.tau[idx[:, :-1]]), jnp.asarray(d.q[idx]))


def main() -> None:
    robot = sj.robots.kuka_lwr4()
    limits = joint_limits("kuka_lwr4", robot).tau_max
    d1, d2 = sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2)
    fit = sj.identify(robot, d1, sj.PhysicallyConsistent(sj.OLS()),
                      sj.TorqueModel.of(robot, (sj.Offset(),)), limits=limits)
    chain, p0, _, extra0 = simulated_dynamics(fit)
    p0 = jnp.asarray(p0)
    dt = 1.0 / d1.rate
    steps = int(round(0.5 / dt))

    def unpack(theta):  # log FV, log FC, log armature, offset
        p = p0.reshape(-1, 12).at[:, 11].set(jnp.exp(theta[:N])).ravel()
        return p, jnp.exp(theta[2 * N:3 * N]), Extra(jnp.exp(theta[N:2 * N]), theta[3 * N:])

    fv0 = p0.reshape(-1, 12)[:, 11]
    theta0 = jnp.concatenate([jnp.log(jnp.maximum(fv0, 1e-3)),
                              jnp.log(jnp.maximum(extra0.fc, 1e-3)),
                              jnp.log(jnp.full(N, 1e-3)), extra0.offset])
    q0, qd0, tau, measured = windows(d1, steps, 48)

    @jax.jit
    def residual(theta):
        p, armature, extra = unpack(theta)
        q, _ = rollout(chain, p, q0, qd0, tau, dt, armature=armature, extra=extra,
                       integrator="implicit", substeps=2)
        return (q - measured)[:, 1:].ravel()

    jacobian = jax.jit(jax.jacfwd(residual))
    r0 = residual(theta0).block_until_ready()
    jacobian(theta0).block_until_ready()
    start = time.perf_counter()
    jacobian(theta0).block_until_ready()
    print(f"one Jacobian ({r0.size} x {theta0.size}): {time.perf_counter() - start:.1f} s")
    start = time.process_time()
    sol = so.least_squares(lambda x: np.asarray(residual(jnp.asarray(x))), np.asarray(theta0),
                           jac=lambda x: np.asarray(jacobian(jnp.asarray(x))), method="lm",
                           max_nfev=15)
    print(f"LM: {time.process_time() - start:.0f} s CPU, {sol.nfev} evaluations, cost "
          f"{0.5 * float(r0 @ r0):.6g} -> {sol.cost:.6g}")
    q0b, qd0b, taub, measured_b = windows(d2, steps, 64)
    for label, theta in (("inverse-dynamics fit", theta0), ("refined", jnp.asarray(sol.x))):
        p, armature, extra = unpack(theta)
        q, _ = rollout(chain, p, q0b, qd0b, taub, dt, armature=armature, extra=extra,
                       integrator="implicit", substeps=2)
        e = np.abs(np.asarray(q) - np.asarray(measured_b)) * DEG
        predicted = (np.asarray(sj.inverse_dynamics(chain, p, d2.q, d2.qd, d2.qdd))
                     + np.asarray(armature) * d2.qdd
                     + np.asarray(jax.vmap(extra)(jnp.asarray(d2.q), jnp.asarray(d2.qd))))
        nrms = sj.validation_metrics(d2.tau, predicted, limits)["nrms_limits_percent"]
        print(f"{label}: held-out rollouts 0.2 / 0.5 s {np.median(e[:, 40]):.3g} / "
              f"{np.median(e[:, 100]):.3g} deg, torque {nrms:.4f} %")


if __name__ == "__main__":
    main()
