"""SEDSABSO: BSO with simulated annealing on the global best and an exponentially
shrinking population, the paper's Sec. 4.2 (Eq. 14-16).

Each iteration runs BSO's update (:class:`~._bso.BeetleStep`), then ``q`` (``n_trials``)
simulated-annealing trials on the swarm's global best ``P_g`` (Eq. 14,
``docs/explanation/paper-notes.md`` Sec. 4)::

    cand_k = clip(P_g (1 + s r_k), lower, upper)      # r_k ~ U(0, 1) per dimension; s = 1
    guide <- cand_k  if  min(1, exp(-(f(cand_k) - f(guide)) / T)) > U(0, 1)   # Metropolis

for k = 1..q in turn, then ``T <- decay T``. The guide steers the velocities (Eq. 11's
``g``); it starts each iteration as the better of itself and ``P_g``. The best point ever
evaluated is kept apart and is what is reported: an accepted worse guide never replaces
it. All q candidates perturb the same ``P_g``, so they are evaluated with one product;
only the scalar Metropolis chain is sequential. Candidates are clipped to the search box
(the paper leaves this open). An iteration is two rounds (:mod:`._swarm`): the beetles'
``3 N(t)`` points, then the ``q`` candidates around the new ``P_g``.

Population (Eq. 15-16, decreasing form): ``N(t) = round(N_start exp(-(e_start + (e_end -
e_start) t / (K - 1))))`` with the exponents ``e_start = Inf_min``, ``e_end = Inf_max`` of
Eq. 16, from 67 to 37 with the paper's numbers (mean about 50); when N
falls, the beetles with the worst personal best leave first. The iterations run in
``n_phases`` phases of static, shrinking slot counts, so the work follows N(t): each
phase evaluates the largest N of its iterations, and each phase adds one compiled loop
body (the trade, measured: ``docs/explanation/swarms-kernels.md``).
"""

from __future__ import annotations

import dataclasses
from typing import Any, ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import DTypeLike
from jaxtyping import Array, Bool, Float, Int, PRNGKeyArray

from .. import _deprecation
from ._bso import AbstractBeetles, BeetleState, BeetleStep, absorb_beetles, beetle_state
from ._checks import check_integer, check_population, is_concrete
from ._population import INITIAL, SwarmState, evaluate, extend, replace, swarm_best
from ._random import uniforms
from ._result import Result
from ._solver import Bounds


def metropolis_accept(u: Float[Array, "*shape"] | float, f_new: Float[Array, "*shape"] | float,
                      f_old: Float[Array, "*shape"] | float,
                      temperature: Float[Array, "*shape"] | float
                      ) -> Bool[Array, "*shape"]:
    """Metropolis criterion: accept with probability ``min(1, exp(-(f_new - f_old) / T))``.

    Drawn as ``exp(-(f_new - f_old) / T) > u`` with ``u ~ U(0, 1)``; a non-finite ``f_new``
    is never accepted (``exp(-inf) = 0``; ``inf - inf`` gives NaN, which compares false).
    """
    return jnp.exp(-(f_new - f_old) / temperature) > u


class SEDSABSOState(BeetleState):
    """:class:`~._bso.BeetleState` and the annealing's: the temperature, the moves
    accepted, and the iteration's draws and candidates for its annealing round."""

    temperature: Float[Array, ""]  # T
    sa_accepted: Int[Array, ""]  # Metropolis moves accepted so far
    trial_r: Float[Array, "q d"]  # r_k of Eq. 14, drawn with the iteration
    trial_u: Float[Array, " q"]  # the Metropolis uniforms, drawn with the iteration
    candidates: Float[Array, "q d"]  # cand_k of Eq. 14, once proposed


class SEDSABSO(AbstractBeetles[SEDSABSOState]):
    """BSO + simulated annealing on the guide + shrinking population. Defaults: Sec. 5.2."""

    population_size: int = 90  # N_start: the initial population (Eq. 15)
    exponent_start: float = 0.3  # Inf_min: N(t) = N_start exp(-exponent(t)) at t = 0 (Eq. 16)
    exponent_end: float = 0.9  # Inf_max: the exponent at the last iteration (Eq. 16)
    n_trials: int = 3  # q: simulated-annealing trials on the guide per iteration (Eq. 14)
    temperature: float = 1e4  # T_0: initial annealing temperature
    decay: float = 0.93  # T <- decay * T every iteration
    perturbation_scale: float = 1.0  # s in cand = g (1 + s r); 1.0 is Eq. 14 as printed
    n_phases: int = 4  # compiled phases of static population size (see module doc)
    beetle: BeetleStep = BeetleStep()  # Eq. 10-13's hyperparameters
    registry_order: ClassVar[int] = 1

    def __check_init__(self) -> None:
        check_population(self.population_size)
        check_integer(self.n_trials, "n_trials", 0)
        check_integer(self.n_phases, "n_phases", 1)
        if not is_concrete(self.temperature, self.decay, self.exponent_start,
                           self.exponent_end):
            return
        if not self.temperature > 0:
            raise ValueError(f"temperature must be > 0, got {self.temperature}")
        if not 0.0 < self.decay < 1.0:
            raise ValueError(f"decay must lie in (0, 1), got {self.decay}")
        if not 0.0 <= self.exponent_start <= self.exponent_end:
            raise ValueError(f"need 0 <= exponent_start <= exponent_end, got exponent_start="
                             f"{self.exponent_start}, exponent_end={self.exponent_end}")

    @classmethod
    def paper(cls) -> SEDSABSO:
        """The paper's settings: N_start = 90, Inf_min = 0.3, Inf_max = 0.9, q = 3,
        T = 1e4, decay 0.93, Eq. 14 unscaled, and BSO's c1, c2, w, lambda, delta, c."""
        return cls()

    @property
    def asks_per_iteration(self) -> int:
        return 2 if self.n_trials else 1

    def schedule(self, iterations: int) -> np.ndarray:
        """Eq. 15-16, decreasing: ``round(N_start exp(-e(t)))``, ``e`` linear from
        :attr:`exponent_start` to :attr:`exponent_end` over the iterations, at least 1."""
        t = np.arange(iterations) / max(iterations - 1, 1)
        e = self.exponent_start + (self.exponent_end - self.exponent_start) * t
        return np.maximum(np.round(self.population_size * np.exp(-e)), 1).astype(int)

    def evaluations(self, n_active: int | Int[np.ndarray, " t"]
                    ) -> int | Int[np.ndarray, " t"]:
        """BSO's three per beetle and the ``q`` annealing candidates (Eq. 14)."""
        return 3 * n_active + self.n_trials

    def own_state(self, state: SwarmState) -> SEDSABSOState:
        """The beetles' state, the temperature at ``T_0``, and zeros for the annealing
        round's draws and candidates (q x dim)."""
        dim, dtype = state.x.shape[1], state.x.dtype
        trials = jnp.zeros((self.n_trials, dim), dtype)
        return extend(SEDSABSOState, beetle_state(state),
                      temperature=jnp.asarray(self.temperature, dtype),
                      sa_accepted=jnp.int32(0), trial_r=trials,
                      trial_u=jnp.zeros(self.n_trials, dtype), candidates=trials)

    def result(self, state: SEDSABSOState, history_f: Float[Array, " iterations"], dim: int
               ) -> Result:
        return dataclasses.replace(super().result(state, history_f, dim),
                                   sa_accepted=state.sa_accepted)

    def randomness(self, key: PRNGKeyArray, dim: int, dtype: DTypeLike
                   ) -> tuple[PRNGKeyArray, Float[Array, "q d"], Float[Array, " q"]]:
        """Keys for BSO's ``r1, r2`` (Eq. 11); Eq. 14's ``r`` (q x dim) and the q Metropolis
        uniforms drawn up front."""
        key, sub = jax.random.split(key)
        kr, ku = jax.random.split(key)
        r = jax.random.uniform(kr, (self.n_trials, dim), dtype)
        return (jax.random.split(sub), r,
                uniforms(jax.random.split(ku, self.n_trials), (), dtype))

    def draw(self, randomness: Any, shape: tuple[int, ...], dtype: DTypeLike
             ) -> tuple[Float[Array, "2 slots d"], Float[Array, "q d"], Float[Array, " q"]]:
        """``(r1 and r2 stacked, r, u)``: BSO's draws of Eq. 11 from their keys, and Eq.
        14's ``r`` and the Metropolis uniforms as drawn up front."""
        k12, r, u = randomness
        return uniforms(k12, shape, dtype), r, u

    # ------------------------------------------------------- round 0: the beetles
    def propose(self, k: int, s: SEDSABSOState, draws: Any, lower: Bounds, upper: Bounds
                ) -> SEDSABSOState:
        """Round 0: Eq. 10-13, the annealing round's draws kept for it. Round 1: Eq. 14's
        candidates around the swarm's best ``P_g`` after the beetles moved."""
        if k == 0:
            r12, r, u = draws
            x, v = self.beetle.move(s, r12[0], r12[1], lower, upper)
            return replace(s, x=x, v=v, trial_r=r, trial_u=u, candidates=jnp.zeros_like(r))
        return replace(s, candidates=self.candidates(swarm_best(s)[0], s.trial_r, lower,
                                                     upper))

    def points(self, k: int, s: SEDSABSOState) -> Float[Array, "m d"]:
        return s.candidates if k > 0 else super().points(k, s)

    def absorb(self, k: int, s: SEDSABSOState, evaluation: Any) -> SEDSABSOState:
        """Round 0: the beetles' update; the guide becomes the swarm's best ``P_g`` if
        that is better (without annealing trials, the temperature then cools). Round 1:
        :meth:`anneal`."""
        if k > 0:
            return self.anneal(s, evaluation)
        s, (gx, gf) = absorb_beetles(k, s, evaluation)
        if k == INITIAL:
            return s
        swarm_better = gf < s.guide_f
        s = replace(s, guide_x=jnp.where(swarm_better, gx, s.guide_x),
                    guide_f=jnp.where(swarm_better, gf, s.guide_f))
        if self.n_trials == 0:  # no annealing: BSO with a shrinking population
            s = replace(s, temperature=s.temperature * self.decay)
        return s

    # ------------------------------------------------ round 1: the annealing trials
    def candidates(self, gx: Float[Array, " d"], r: Float[Array, "q d"], lower: Bounds,
                   upper: Bounds) -> Float[Array, "q d"]:
        """Eq. 14: ``clip(P_g (1 + s r_k), lower, upper)`` for the q rows of ``r``."""
        return jnp.clip(gx * (1.0 + self.perturbation_scale * r), lower, upper)

    def anneal(self, s: SEDSABSOState, raw: Float[Array, " q"]) -> SEDSABSOState:
        """The q candidates' Metropolis trials against the current guide, in turn (q is
        small: unrolled); the best ever kept apart; counts; the temperature cools."""
        u, cand = s.trial_u, s.candidates
        fc, bad = evaluate(None, cand, raw=raw)
        guide_f, chosen, accepted = s.guide_f, jnp.int32(-1), s.sa_accepted
        for j in range(self.n_trials):
            ok = metropolis_accept(u[j], fc[j], guide_f, s.temperature)
            guide_f = jnp.where(ok, fc[j], guide_f)
            chosen = jnp.where(ok, j, chosen)
            accepted = accepted + ok.astype(jnp.int32)
        gx = jnp.where(chosen >= 0, cand[jnp.maximum(chosen, 0)], s.guide_x)
        i = jnp.argmin(fc)
        better = fc[i] < s.best_f
        return replace(
            s, guide_x=gx, guide_f=guide_f, best_x=jnp.where(better, cand[i], s.best_x),
            best_f=jnp.where(better, fc[i], s.best_f), sa_accepted=accepted,
            n_nonfinite=s.n_nonfinite + jnp.sum(bad, dtype=jnp.int32),
            n_evaluations=s.n_evaluations + self.n_trials,
            temperature=s.temperature * self.decay)


#: The population argument of 0.4 and before, kept through 0.5.x.
_deprecation.renamed(SEDSABSO, {"n_start": "population_size"}, removed_after="0.5")
