"""Beetle Swarm Optimisation (BSO): T. Wang, L. Yang, Q. Liu, "Beetle Swarm Optimization
Algorithm: Theory and Application", arXiv:1808.00206 (2018); the paper's Eq. 10-13.

Per iteration, for every beetle at once (the authors' demo code, ``docs/explanation/paper-notes.md``
Sec. 3)::

    xl = x + V d/2,  xr = x - V d/2                 # antennae, d = delta / c (Eq. 13)
    xi = -delta V sign(f(xl) - f(xr))               # toward the better antenna (Eq. 12)
    V  = clip(w V + c1 r1 (pbest - x) + c2 r2 (g - x), -Vmax, Vmax)      (Eq. 11)
    x  = clip(x + lam V + (1 - lam) xi, lower, upper)                    (Eq. 10)

The authors' code uses ``+delta V sign(...)``, which moves toward the WORSE antenna when
minimising; ``literal_sign=True`` restores it. With a linear fitness embedding (Eq. 17)
the antennae cost no product with ``W`` (``W xl = W x + d/2 W V``) and only their
difference is needed, so an iteration costs one product with ``W`` (new positions and
velocities stacked) and one pass over the residuals for 3 evaluations: the antennae of
the new positions are evaluated with them and carried to the next iteration as one
number per beetle (:meth:`~._fitness.L1Residual.evaluate_with_antennae`).

:class:`BeetleStep` is this update with its hyperparameters; :class:`BSO` runs it with a
constant population, :class:`~sedsabso_jax.SEDSABSO` adds annealing and a shrinking one.
"""

from __future__ import annotations

from typing import Any, ClassVar, TypeVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from .. import _deprecation
from ._checks import check_population, check_velocity_update, is_concrete
from ._fitness import Fitness, antenna_difference
from ._population import (
    INITIAL,
    SwarmState,
    absorb_positions,
    extend,
    initial_bests,
    replace,
)
from ._solver import Bounds
from ._swarm import AbstractSwarm

#: A round's evaluation of beetles: raw fitness at ``x``, ``f(x + a v) - f(x - a v)`` and
#: how many of those two were NaN or Inf, per slot.
Evaluation = tuple[Float[Array, " slots"], Float[Array, " slots"], Int[Array, " slots"]]


class BeetleState(SwarmState):
    """:class:`~._population.SwarmState` and each beetle's antennae at its position
    (Eq. 12-13), computed with that position's fitness in the same pass and carried as
    one number per slot: nothing of the fitness's size is carried between iterations."""

    antennae: Float[Array, " slots"]  # f(x + a V) - f(x - a V) (Eq. 12)
    antennae_bad: Int[Array, " slots"]  # how many of those two were NaN or Inf

    per_slot: ClassVar[tuple[str, ...]] = (*SwarmState.per_slot, "antennae", "antennae_bad")


B = TypeVar("B", bound=BeetleState)


def beetle_state(state: SwarmState) -> BeetleState:
    """``state`` with no antennae evaluated yet (zeros)."""
    slots = state.x.shape[0]
    return extend(BeetleState, state, antennae=jnp.zeros(slots, state.x.dtype),
                  antennae_bad=jnp.zeros(slots, jnp.int32))


class BeetleStep(eqx.Module):
    """The beetles' update of Eq. 10-13 and its hyperparameters (defaults: the paper's
    Sec. 5.2), shared by :class:`BSO` and :class:`~sedsabso_jax.SEDSABSO`:
    ``BSO(beetle=BeetleStep(lam=0.5))``."""

    c1: float = 2.0  # c1: cognitive coefficient (Eq. 11)
    c2: float = 2.0  # c2: social coefficient (Eq. 11)
    w: float = 0.8  # w: inertia weight (Eq. 11)
    lam: float = 0.9  # lambda: share of the velocity step vs the antenna step (Eq. 10)
    delta: float = 0.05  # delta: antenna step size, constant (Eq. 12)
    c: float = 2.0  # c: ratio of step size to antenna distance, d = delta / c (Eq. 13)
    vmax_fraction: float = 0.5  # Vmax = vmax_fraction * (upper - lower), the authors' code
    literal_sign: bool = False  # True: the authors' sign, toward the worse antenna

    def __check_init__(self) -> None:
        if not is_concrete(self.c1, self.c2, self.vmax_fraction, self.lam, self.delta,
                           self.c):
            return
        check_velocity_update(self.c1, self.c2, self.vmax_fraction)
        if not 0.0 <= self.lam <= 1.0:
            raise ValueError(f"lam must lie in [0, 1], got {self.lam}")
        if self.delta <= 0 or self.c <= 0:
            raise ValueError(f"delta and c must be > 0, got delta={self.delta}, c={self.c}")

    @property
    def antenna(self) -> float:
        """``a``: the antennae sit at ``x +- a V``, ``a = d / 2`` with ``d = delta / c``
        (Eq. 13)."""
        d = self.delta / self.c
        return 0.5 * d

    def vmax(self, lower: Bounds, upper: Bounds) -> Float[Array, " d"]:
        return self.vmax_fraction * (upper - lower)

    def move(self, s: BeetleState, r1: Float[Array, "slots d"], r2: Float[Array, "slots d"],
             lower: Bounds, upper: Bounds
             ) -> tuple[Float[Array, "slots d"], Float[Array, "slots d"]]:
        """Eq. 10-13 for every slot with ``r1, r2`` the uniforms of Eq. 11: the new
        positions and velocities. The antenna difference ``f(xl) - f(xr)`` at the current
        positions is the state's (computed with their fitness)."""
        direction = jnp.nan_to_num(jnp.sign(s.antennae))  # inf - inf: no preference
        if not self.literal_sign:
            direction = -direction
        xi = self.delta * s.v * direction[:, None]
        vmax = self.vmax(lower, upper)
        v = self.w * s.v + self.c1 * r1 * (s.pbest_x - s.x) + self.c2 * r2 * (s.guide_x - s.x)
        v = jnp.clip(v, -vmax, vmax)
        return jnp.clip(s.x + self.lam * v + (1.0 - self.lam) * xi, lower, upper), v


class AbstractBeetles(AbstractSwarm[B]):
    """Beetles: a swarm moved by :class:`BeetleStep` whose round 0 asks for each
    beetle's position and its two antennae, ``x``, ``x + a V``, ``x - a V`` (``3 N``
    points), evaluated in one pass for Eq. 17
    (:meth:`~._fitness.L1Residual.evaluate_with_antennae`). A concrete one gives
    ``population_size``, ``beetle``, :meth:`evaluations`, :meth:`propose` and
    :meth:`absorb` (with :func:`absorb_beetles`)."""

    beetle: eqx.AbstractVar[BeetleStep]

    def vmax(self, lower: Bounds, upper: Bounds) -> Float[Array, " d"]:
        return self.beetle.vmax(lower, upper)

    def points(self, k: int, s: B) -> Float[Array, "m d"]:
        """Rounds ``-1`` and 0: the beetles and their antennae, ``3 N`` points."""
        if k > 0:
            return super().points(k, s)
        a = self.beetle.antenna
        return jnp.concatenate([s.x, s.x + a * s.v, s.x - a * s.v])

    def evaluate(self, k: int, fitness: Fitness, s: B) -> Any:
        if k > 0:
            return super().evaluate(k, fitness, s)
        return fitness.evaluate_with_antennae(s.x, s.v, self.beetle.antenna)

    def told(self, k: int, s: B, values: Float[Array, " m"]) -> Any:
        if k > 0:
            return values
        n = s.x.shape[0]
        return (values[:n], *antenna_difference(values[n:2 * n],
                                                values[2 * n:]))


def absorb_beetles(k: int, s: B, evaluation: Evaluation
                   ) -> tuple[B, tuple[Float[Array, " d"], Float[Array, ""]]]:
    """Round ``k`` (0 or :data:`~._population.INITIAL`) of the beetles: their fitness
    and antennae taken in, personal and best-ever updated; returns the state and the
    swarm's global best ``(x, f)`` among the active slots."""
    raw, diff, diff_bad = evaluation
    if k == INITIAL:
        s = initial_bests(s, raw)
        best = (s.guide_x, s.guide_f)
    else:
        s, best = absorb_positions(s, raw, 3, jnp.where(s.active, s.antennae_bad, 0))
    return replace(s, antennae=diff, antennae_bad=diff_bad), best


class BSO(AbstractBeetles[BeetleState]):
    """Beetle swarm with a constant population. Defaults: the paper's Sec. 5.2."""

    population_size: int = 50  # N: population size
    beetle: BeetleStep = BeetleStep()  # Eq. 10-13's hyperparameters
    registry_order: ClassVar[int] = 2

    def __check_init__(self) -> None:
        check_population(self.population_size)

    @classmethod
    def paper(cls) -> BSO:
        """The paper's settings (Sec. 5.2): N = 50, c1 = c2 = 2, w = 0.8, lambda = 0.9,
        delta = 0.05, c = 2; Vmax = 0.5 (ub - lb) as in the authors' code."""
        return cls()

    def own_state(self, state: SwarmState) -> BeetleState:
        return beetle_state(state)

    def evaluations(self, n_active: int | Int[np.ndarray, " t"]
                    ) -> int | Int[np.ndarray, " t"]:
        """Three per beetle: its new position and its two antennae (Eq. 12)."""
        return 3 * n_active

    def propose(self, k: int, s: BeetleState, draws: Any, lower: Bounds, upper: Bounds
                ) -> BeetleState:
        """Eq. 10-13 with ``draws = (r1, r2)``."""
        x, v = self.beetle.move(s, draws[0], draws[1], lower, upper)
        return replace(s, x=x, v=v)

    def absorb(self, k: int, s: BeetleState, evaluation: Evaluation) -> BeetleState:
        """The guide is the swarm's best."""
        s, (gx, gf) = absorb_beetles(k, s, evaluation)
        return replace(s, guide_x=gx, guide_f=gf)


#: The population argument of 0.4 and before, kept through 0.5.x.
_deprecation.renamed(BSO, {"n_beetles": "population_size"}, removed_after="0.5")
