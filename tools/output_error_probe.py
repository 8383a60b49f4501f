"""A probe for issue 44 part 4 (output-error refinement, not in the package): Levenberg-
Marquardt on the open-loop rollouts of the KUKA (48 windows of 0.5 s of run 1), exact
Jacobian by ``jax.jacfwd`` through the rollouts, over 28 joint parameters (viscous and
Coulomb friction, armature, offset; the inertias of the physically consistent fit
fixed); held-out rollouts and torque error on run 2 before and after.

    python tools/output_error_probe.py      # about 5 minutes on 2 cores
"""
import jax; jax.config.update("jax_enable_x64", True)
import time

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import scipy.optimize as so

import sedsabso_jax as sj
from sedsabso_jax.dynamics import joint_limits, rollout
from sedsabso_jax.identification._fit._rollouts import STICKING_VELOCITY, simulated_dynamics, starts

robot = sj.robots.kuka_lwr4(); lim = joint_limits("kuka_lwr4", robot).tau_max
d1, d2 = sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2)
fit = sj.identify(robot, d1, sj.PhysicallyConsistent(sj.OLS()), sj.TorqueModel.of(robot, (sj.Offset(),)), limits=lim)
rb, p0, arm0, extra0 = simulated_dynamics(fit)
p0 = jnp.asarray(p0); n = 7
fv0 = p0.reshape(-1, 12)[:, 11]
dt = 1/d1.rate; steps = int(0.5/dt)
def win(d, count=48):
    f = starts(d.n_samples, steps, count); idx = f[:, None] + np.arange(steps+1)
    return jnp.asarray(d.q[f]), jnp.asarray(d.qd[f]), jnp.asarray(d.tau[idx[:, :-1]]), jnp.asarray(d.q[idx])
class Extra(eqx.Module):
    fc: jax.Array; offset: jax.Array
    def __call__(self, q, qd): return self.fc * jnp.tanh(qd / STICKING_VELOCITY) + self.offset
# theta: log fv, log fc, log arm(+1e-4), offset
def unpack(th):
    fv = jnp.exp(th[:n]); fc = jnp.exp(th[n:2*n]); arm = jnp.exp(th[2*n:3*n]); off = th[3*n:]
    p = p0.reshape(-1, 12).at[:, 11].set(fv).ravel()
    return p, arm, Extra(fc, off)
th0 = jnp.concatenate([jnp.log(jnp.maximum(fv0, 1e-3)), jnp.log(jnp.maximum(extra0.fc, 1e-3)), jnp.log(jnp.full(n, 1e-3)), extra0.offset])
q0, qd0, tau, meas = win(d1)
@jax.jit
def resid(th):
    p, arm, ex = unpack(th)
    q, _ = rollout(rb, p, q0, qd0, tau, dt, armature=arm, extra=ex, integrator="implicit", substeps=2)
    return ((q - meas)[:, 1:]).ravel()
jac = jax.jit(jax.jacfwd(resid))
t = time.perf_counter(); r0 = resid(th0).block_until_ready(); print("compile+run resid", time.perf_counter()-t)
t = time.perf_counter(); J = jac(th0).block_until_ready(); print("jac first", time.perf_counter()-t, J.shape)
t = time.perf_counter(); J = jac(th0).block_until_ready(); print("jac", time.perf_counter()-t)
t0 = time.process_time()
sol = so.least_squares(lambda x: np.asarray(resid(jnp.asarray(x))), np.asarray(th0), jac=lambda x: np.asarray(jac(jnp.asarray(x))), method="lm", max_nfev=15)
print("LM cpu", time.process_time()-t0, "nfev", sol.nfev, "cost", 0.5*float(r0@r0), "->", sol.cost)
p, arm, ex = unpack(jnp.asarray(sol.x))
print("fv", np.round(np.exp(sol.x[:n]),3), "fc", np.round(np.exp(sol.x[n:2*n]),3), "arm", np.round(np.exp(sol.x[2*n:3*n]),4), "off", np.round(sol.x[3*n:],3))
# held-out
for label, (pp, aa, ee) in (("IDIM", unpack(th0)), ("refined", (p, arm, ex))):
    q0b, qd0b, taub, measb = win(d2, 64)
    q, _ = rollout(rb, pp, q0b, qd0b, taub, dt, armature=aa, extra=ee, integrator="implicit", substeps=2)
    e = np.abs(np.asarray(q) - np.asarray(measb)) * 57.2958
    tau_pred = np.asarray(sj.inverse_dynamics(rb, pp, d2.q, d2.qd, d2.qdd)) + aa * d2.qdd + np.asarray(jax.vmap(ee)(jnp.asarray(d2.q), jnp.asarray(d2.qd)))
    nrms = sj.validation_metrics(d2.tau, tau_pred, lim)["nrms_limits_percent"]
    print(label, "held-out rollouts 0.2/0.5", np.median(e[:, 40]), np.median(e[:, 100]), "torque nrms", nrms)
