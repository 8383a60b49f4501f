"""SEDSABSO: BSO with simulated annealing on the global best and an exponentially
shrinking population, the paper's Sec. 4.2 (Eq. 14-16).

Each iteration runs BSO's update (:mod:`sedsabso_jax.bso`), then ``q`` simulated-annealing
trials on the swarm's global best ``P_g`` (Eq. 14, NOTES_ON_THE_PAPER.md Sec. 4)::

    cand_k = clip(P_g (1 + s r_k), lower, upper)      # r_k ~ U(0, 1) per dimension; s = 1
    guide <- cand_k  if  min(1, exp(-(f(cand_k) - f(guide)) / T)) > U(0, 1)   # Metropolis

for k = 1..q in turn, then ``T <- decay T``. The guide steers the velocities (Eq. 11's
``g``); it starts each iteration as the better of itself and ``P_g``. The best point ever
evaluated is kept apart and is what is reported: an accepted worse guide never replaces
it. All q candidates perturb the same ``P_g``, so they are evaluated with one product;
only the scalar Metropolis chain is sequential. Candidates are clipped to the search box
(the paper leaves this open).

Population (Eq. 15-16, decreasing form): ``N(t) = round(N_start exp(-(f_min + (f_max -
f_min) t / (K - 1))))``, from 67 to 37 with the paper's numbers (mean about 50); when N
falls, the beetles with the worst personal best leave first. The iterations run in
``n_phases`` phases of static, shrinking slot counts, so the work follows N(t): each
phase evaluates the largest N of its iterations, so 4 phases waste about 7 % of the ideal
work and 8 about 4 %, while each phase adds one compiled loop body (about 5 s of
compilation each on the 2-core CPU).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .bso import BSO, _check_common
from .swarm import evaluate, initial_state, uniforms


def metropolis_accept(u, f_new, f_old, temperature):
    """Metropolis criterion: accept with probability ``min(1, exp(-(f_new - f_old) / T))``.

    Drawn as ``exp(-(f_new - f_old) / T) > u`` with ``u ~ U(0, 1)``; a non-finite ``f_new``
    is never accepted (``exp(-inf) = 0``; ``inf - inf`` gives NaN, which compares false).
    """
    return jnp.exp(-(f_new - f_old) / temperature) > u


class SEDSABSO(BSO):
    """BSO + simulated annealing on the guide + shrinking population. Defaults: Sec. 5.2."""

    n_start: int = 90  # N_start (Eq. 15)
    f_min: float = 0.3  # Inf_min (Eq. 16)
    f_max: float = 0.9  # Inf_max (Eq. 16)
    q: int = 3  # SA perturbations of the guide per iteration
    temperature: float = 1e4  # initial SA temperature T
    decay: float = 0.93  # T <- decay * T every iteration
    perturbation_scale: float = 1.0  # s in cand = g (1 + s r); 1.0 is Eq. 14 as printed
    n_phases: int = 4  # compiled phases of static population size (see module doc)

    @classmethod
    def paper(cls) -> SEDSABSO:
        """The paper's settings: N_start = 90, f_min = 0.3, f_max = 0.9, q = 3, T = 1e4,
        decay 0.93, Eq. 14 unscaled, and BSO's c1, c2, w, lambda, delta, c."""
        return cls()

    @property
    def n_slots(self) -> int:
        return self.n_start

    def schedule(self, iterations: int) -> np.ndarray:
        t = np.arange(iterations) / max(iterations - 1, 1)
        n = np.round(self.n_start * np.exp(-(self.f_min + (self.f_max - self.f_min) * t)))
        return np.maximum(n, 1).astype(int)

    def check(self) -> None:
        BSO.check(self)
        _check_common(self, self.n_start, "n_start")
        if not isinstance(self.q, (int, np.integer)) or self.q < 0:
            raise ValueError(f"q must be an integer >= 0, got {self.q!r}")
        if not self.temperature > 0:
            raise ValueError(f"temperature must be > 0, got {self.temperature}")
        if not 0.0 < self.decay < 1.0:
            raise ValueError(f"decay must lie in (0, 1), got {self.decay}")
        if not 0.0 <= self.f_min <= self.f_max:
            raise ValueError(
                f"need 0 <= f_min <= f_max, got f_min={self.f_min}, f_max={self.f_max}")
        if not isinstance(self.n_phases, (int, np.integer)) or self.n_phases < 1:
            raise ValueError(f"n_phases must be an integer >= 1, got {self.n_phases!r}")

    def init(self, fitness, lower, upper, key):
        return initial_state(fitness, lower, upper, key, self.n_slots,
                             self.vmax_fraction * (upper - lower), self.temperature)

    def randomness(self, key, dim, dtype):
        """Keys for BSO's ``r1, r2`` (Eq. 11); Eq. 14's ``r`` (q x dim) and the q Metropolis
        uniforms drawn up front."""
        key, sub = jax.random.split(key)
        kr, ku = jax.random.split(key)
        r = jax.random.uniform(kr, (self.q, dim), dtype)
        return jax.random.split(sub), r, uniforms(jax.random.split(ku, self.q), (), dtype)

    def step(self, fitness, s, t, iterations, lower, upper, keys):
        k12, r, u = keys
        r1, r2 = uniforms(k12, s.x.shape, s.x.dtype)
        s, (gx, gf) = self.beetle_step(fitness, s, lower, upper, r1, r2)
        swarm_better = gf < s.guide_f
        guide_x = jnp.where(swarm_better, gx, s.guide_x)
        guide_f = jnp.where(swarm_better, gf, s.guide_f)
        if self.q == 0:  # no annealing: BSO with a shrinking population
            return eqx.tree_at(lambda s: (s.guide_x, s.guide_f, s.temperature), s,
                               (guide_x, guide_f, s.temperature * self.decay))
        cand = jnp.clip(gx * (1.0 + self.perturbation_scale * r), lower, upper)  # Eq. 14
        fc, bad = evaluate(fitness, fitness.embed(cand))
        # Metropolis against the current guide, the q trials in turn (q is small: unrolled)
        chosen, accepted = jnp.int32(-1), s.sa_accepted
        for k in range(self.q):
            accept = metropolis_accept(u[k], fc[k], guide_f, s.temperature)
            guide_f = jnp.where(accept, fc[k], guide_f)
            chosen = jnp.where(accept, k, chosen)
            accepted = accepted + accept.astype(jnp.int32)
        gx = jnp.where(chosen >= 0, cand[jnp.maximum(chosen, 0)], guide_x)
        i = jnp.argmin(fc)
        better = fc[i] < s.best_f
        bx, bf = jnp.where(better, cand[i], s.best_x), jnp.where(better, fc[i], s.best_f)
        bad = s.n_nonfinite + bad
        return eqx.tree_at(
            lambda s: (s.guide_x, s.guide_f, s.best_x, s.best_f, s.sa_accepted, s.n_nonfinite,
                       s.n_evaluations, s.temperature),
            s, (gx, guide_f, bx, bf, accepted, bad, s.n_evaluations + self.q,
                s.temperature * self.decay))
