"""Linearly decreasing inertia weight PSO (LDWPSO): Y. Shi, R. Eberhart, "A modified
particle swarm optimizer", IEEE ICEC 1998; "Empirical study of particle swarm
optimization", CEC 1999; ``docs/explanation/paper-notes.md`` Sec. 5::

    w(t) = w_start - (w_start - w_end) t / (K - 1)
    V = clip(w(t) V + c1 r1 (pbest - x) + c2 r2 (g - x), -Vmax, Vmax)
    x = clip(x + V, lower, upper)
"""

from __future__ import annotations

from typing import Any, ClassVar

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from .. import _deprecation
from ._checks import check_population, check_velocity_update, is_concrete
from ._population import INITIAL, SwarmState, absorb_positions, initial_bests, replace
from ._solver import Bounds
from ._swarm import AbstractSwarm


class LDWPSO(AbstractSwarm[SwarmState]):
    """PSO with inertia falling linearly from 0.9 to 0.4. Defaults: the paper's Sec. 5.2."""

    population_size: int = 50  # N: population size
    c1: float = 2.0  # c1: cognitive coefficient
    c2: float = 2.0  # c2: social coefficient
    w_start: float = 0.9  # w(0): inertia at the first iteration
    w_end: float = 0.4  # w(K - 1): inertia at the last iteration
    vmax_fraction: float = 0.5  # Vmax = vmax_fraction * (upper - lower)
    registry_order: ClassVar[int] = 3

    def __check_init__(self) -> None:
        check_population(self.population_size)
        if is_concrete(self.c1, self.c2, self.vmax_fraction):
            check_velocity_update(self.c1, self.c2, self.vmax_fraction)

    @classmethod
    def paper(cls) -> LDWPSO:
        """N = 50, c1 = c2 = 2, w from 0.9 to 0.4, Vmax = 0.5 (ub - lb)."""
        return cls()

    def vmax(self, lower: Bounds, upper: Bounds) -> Float[Array, " d"]:
        return self.vmax_fraction * (upper - lower)

    def evaluations(self, n_active: int | Int[np.ndarray, " t"]
                    ) -> int | Int[np.ndarray, " t"]:
        """One per particle."""
        return n_active

    def propose(self, k: int, s: SwarmState, draws: Any, lower: Bounds, upper: Bounds
                ) -> SwarmState:
        """The velocity and position updates with ``draws = (r1, r2)``."""
        w = self.w_start - (self.w_start - self.w_end) * s.t / max(s.iterations - 1, 1)
        r1, r2 = draws
        vmax = self.vmax(lower, upper)
        v = w * s.v + self.c1 * r1 * (s.pbest_x - s.x) + self.c2 * r2 * (s.guide_x - s.x)
        v = jnp.clip(v, -vmax, vmax)
        return replace(s, x=jnp.clip(s.x + v, lower, upper), v=v)

    def absorb(self, k: int, s: SwarmState, raw: Float[Array, " slots"]) -> SwarmState:
        """The guide is the swarm's best."""
        if k == INITIAL:
            return initial_bests(s, raw)
        s, (gx, gf) = absorb_positions(s, raw, 1)
        return replace(s, guide_x=gx, guide_f=gf)


#: The population argument of 0.4 and before, kept through 0.5.x.
_deprecation.renamed(LDWPSO, {"n_particles": "population_size"}, removed_after="0.5")
