"""SEDSABSO: BSO with simulated annealing on the global best and an exponentially
shrinking population, the paper's Sec. 4.2 (Eq. 14-16).

Each iteration runs BSO's update (:class:`~.bso.BeetleSwarm`), then ``q`` (``n_trials``)
simulated-annealing trials on the swarm's global best ``P_g`` (Eq. 14,
``docs/paper-notes.md`` Sec. 4)::

    cand_k = clip(P_g (1 + s r_k), lower, upper)      # r_k ~ U(0, 1) per dimension; s = 1
    guide <- cand_k  if  min(1, exp(-(f(cand_k) - f(guide)) / T)) > U(0, 1)   # Metropolis

for k = 1..q in turn, then ``T <- decay T``. The guide steers the velocities (Eq. 11's
``g``); it starts each iteration as the better of itself and ``P_g``. The best point ever
evaluated is kept apart and is what is reported: an accepted worse guide never replaces
it. All q candidates perturb the same ``P_g``, so they are evaluated with one product;
only the scalar Metropolis chain is sequential. Candidates are clipped to the search box
(the paper leaves this open).

Population (Eq. 15-16, decreasing form): ``N(t) = round(N_start exp(-(e_start + (e_end -
e_start) t / (K - 1))))`` with the exponents ``e_start = Inf_min``, ``e_end = Inf_max`` of
Eq. 16, from 67 to 37 with the paper's numbers (mean about 50); when N
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

from .. import _deprecation
from .bso import BeetleSwarm
from .swarm import check_population, evaluate, initial_state, uniforms


def metropolis_accept(u, f_new, f_old, temperature):
    """Metropolis criterion: accept with probability ``min(1, exp(-(f_new - f_old) / T))``.

    Drawn as ``exp(-(f_new - f_old) / T) > u`` with ``u ~ U(0, 1)``; a non-finite ``f_new``
    is never accepted (``exp(-inf) = 0``; ``inf - inf`` gives NaN, which compares false).
    """
    return jnp.exp(-(f_new - f_old) / temperature) > u


class SEDSABSO(BeetleSwarm):
    """BSO + simulated annealing on the guide + shrinking population. Defaults: Sec. 5.2."""

    n_start: int = 90  # N_start: population at the first iteration (Eq. 15)
    exponent_start: float = 0.3  # Inf_min: N(t) = N_start exp(-exponent(t)) at t = 0 (Eq. 16)
    exponent_end: float = 0.9  # Inf_max: the exponent at the last iteration (Eq. 16)
    n_trials: int = 3  # q: simulated-annealing trials on the guide per iteration (Eq. 14)
    temperature: float = 1e4  # T_0: initial annealing temperature
    decay: float = 0.93  # T <- decay * T every iteration
    perturbation_scale: float = 1.0  # s in cand = g (1 + s r); 1.0 is Eq. 14 as printed
    n_phases: int = 4  # compiled phases of static population size (see module doc)

    @classmethod
    def paper(cls) -> SEDSABSO:
        """The paper's settings: N_start = 90, Inf_min = 0.3, Inf_max = 0.9, q = 3,
        T = 1e4, decay 0.93, Eq. 14 unscaled, and BSO's c1, c2, w, lambda, delta, c."""
        return cls()

    @property
    def q(self) -> int:
        """Deprecated: :attr:`n_trials` (q in the paper)."""
        _deprecation.warn("SEDSABSO.q", "SEDSABSO.n_trials")
        return self.n_trials

    @property
    def n_slots(self) -> int:
        return self.n_start

    def schedule(self, iterations: int) -> np.ndarray:
        """Eq. 15-16, decreasing: ``round(N_start exp(-e(t)))``, ``e`` linear from
        :attr:`exponent_start` to :attr:`exponent_end` over the iterations, at least 1."""
        t = np.arange(iterations) / max(iterations - 1, 1)
        e = self.exponent_start + (self.exponent_end - self.exponent_start) * t
        return np.maximum(np.round(self.n_start * np.exp(-e)), 1).astype(int)

    def check(self) -> None:
        check_population(self.n_start, "n_start")
        super().check()
        if (isinstance(self.n_trials, bool) or not isinstance(self.n_trials, (int, np.integer))
                or self.n_trials < 0):
            raise ValueError(f"n_trials must be an integer >= 0, got {self.n_trials!r}")
        if not self.temperature > 0:
            raise ValueError(f"temperature must be > 0, got {self.temperature}")
        if not 0.0 < self.decay < 1.0:
            raise ValueError(f"decay must lie in (0, 1), got {self.decay}")
        if not 0.0 <= self.exponent_start <= self.exponent_end:
            raise ValueError(f"need 0 <= exponent_start <= exponent_end, got exponent_start="
                             f"{self.exponent_start}, exponent_end={self.exponent_end}")
        if (isinstance(self.n_phases, bool) or not isinstance(self.n_phases, (int, np.integer))
                or self.n_phases < 1):
            raise ValueError(f"n_phases must be an integer >= 1, got {self.n_phases!r}")

    def evaluations(self, n_active):
        """BSO's three per beetle and the ``q`` annealing candidates (Eq. 14)."""
        return 3 * n_active + self.n_trials

    def init(self, fitness, lower, upper, key):
        return initial_state(fitness, lower, upper, key, self.n_slots,
                             self.vmax_fraction * (upper - lower), self.temperature,
                             antenna=self.antenna)

    def randomness(self, key, dim, dtype):
        """Keys for BSO's ``r1, r2`` (Eq. 11); Eq. 14's ``r`` (q x dim) and the q Metropolis
        uniforms drawn up front."""
        key, sub = jax.random.split(key)
        kr, ku = jax.random.split(key)
        r = jax.random.uniform(kr, (self.n_trials, dim), dtype)
        return (jax.random.split(sub), r,
                uniforms(jax.random.split(ku, self.n_trials), (), dtype))

    def draw(self, randomness, shape, dtype):
        """``(r1 and r2 stacked, r, u)``: BSO's draws of Eq. 11 from their keys, and Eq.
        14's ``r`` and the Metropolis uniforms as drawn up front."""
        k12, r, u = randomness
        return uniforms(k12, shape, dtype), r, u

    def step(self, fitness, s, t, iterations, lower, upper, draws):
        r12, r, u = draws
        r1, r2 = r12[0], r12[1]
        s, (gx, gf) = self.beetle_step(fitness, s, lower, upper, r1, r2)
        swarm_better = gf < s.guide_f
        guide_x = jnp.where(swarm_better, gx, s.guide_x)
        guide_f = jnp.where(swarm_better, gf, s.guide_f)
        if self.n_trials == 0:  # no annealing: BSO with a shrinking population
            return eqx.tree_at(lambda s: (s.guide_x, s.guide_f, s.temperature), s,
                               (guide_x, guide_f, s.temperature * self.decay))
        cand = jnp.clip(gx * (1.0 + self.perturbation_scale * r), lower, upper)  # Eq. 14
        fc, bad = evaluate(fitness, cand)
        # Metropolis against the current guide, the q trials in turn (q is small: unrolled)
        chosen, accepted = jnp.int32(-1), s.sa_accepted
        for k in range(self.n_trials):
            accept = metropolis_accept(u[k], fc[k], guide_f, s.temperature)
            guide_f = jnp.where(accept, fc[k], guide_f)
            chosen = jnp.where(accept, k, chosen)
            accepted = accepted + accept.astype(jnp.int32)
        gx = jnp.where(chosen >= 0, cand[jnp.maximum(chosen, 0)], guide_x)
        i = jnp.argmin(fc)
        better = fc[i] < s.best_f
        bx, bf = jnp.where(better, cand[i], s.best_x), jnp.where(better, fc[i], s.best_f)
        bad = s.n_nonfinite + jnp.sum(bad, dtype=jnp.int32)
        return eqx.tree_at(
            lambda s: (s.guide_x, s.guide_f, s.best_x, s.best_f, s.sa_accepted, s.n_nonfinite,
                       s.n_evaluations, s.temperature),
            s, (gx, guide_f, bx, bf, accepted, bad, s.n_evaluations + self.n_trials,
                s.temperature * self.decay))


_deprecation.renamed_arguments(SEDSABSO, {"q": "n_trials", "f_min": "exponent_start",
                                          "f_max": "exponent_end"})
