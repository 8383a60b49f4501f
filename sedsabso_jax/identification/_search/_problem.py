"""What a search of a few parameters reads of its problem (:class:`SearchProblem`), the
population's losses in one compiled call (:func:`losses`), and what a search returns
(:class:`Searched`)."""

from __future__ import annotations

import dataclasses
import threading
from typing import Protocol

import equinox as eqx
import jax
import numpy as np
from jaxtyping import Array, Float


class SearchProblem(Protocol):
    """A problem in ``k`` parameters ``u``, an ``equinox.Module`` (its arrays are the
    compiled calls' arguments, so one compilation serves every problem of one shape)."""

    def loss(self, u: Float[Array, " k"]) -> Float[Array, ""]:
        """The loss at ``u`` (traceable)."""
        ...

    def residual(self, u: Float[Array, " k"]) -> Float[Array, " N"]:
        """The residual vector whose mean square is :meth:`loss` (traceable)."""
        ...


def fitness(u, problem: SearchProblem):
    """The problem's loss at ``u`` as a fitness ``f(u, args)`` whose ``args`` is the
    problem: the one wrapper every search evaluates (:func:`losses`,
    :func:`~sedsabso_jax.minimise` with ``args=problem``: the problem's arrays are the
    compiled run's arguments, not constants baked into it)."""
    return problem.loss(u)


_population = eqx.filter_jit(jax.vmap(fitness, (0, None)))

#: One search's compiled call at a time in the process (:func:`losses`, and the
#: population and least-squares searches), until its results are read. On the CPU,
#: jaxlib's LAPACK kernels (the Cholesky factorisation of a population's normal
#: equations, one per trial) split a large batch over XLA's intra-op threads and wait
#: for the parts on the thread they run on: as many such calls at once as that pool has
#: threads wait on each other for ever. A validation's splits, fitted on as many threads
#: as there are cores, did (two threads, 98 trials of 21 moved columns, 2 cores:
#: tests/test_validations.py); they take turns here.
COMPILED = threading.RLock()


#: The fewest members a population is evaluated with: a single trial (a search's start,
#: a step) is evaluated beside a copy of itself, so that it and a pair of trials share
#: one compilation (seconds each; a pair costs what one does).
SMALLEST = 2


def losses(problem: SearchProblem, U: Float[np.ndarray, "p k"]) -> Float[np.ndarray, " p"]:
    """The losses of the population ``U`` (one row per member), in one vmapped call
    (:data:`COMPILED`; at least :data:`SMALLEST` members)."""
    U = np.asarray(U, dtype=float)
    padded = np.concatenate([U, np.repeat(U[:1], SMALLEST - len(U), 0)]) if len(
        U) < SMALLEST else U
    with COMPILED:
        return np.asarray(_population(padded, problem))[:len(U)]


def on_bounds(u: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """``u`` in the box, a value within 1e-9 of the box's width of a bound on it (a grid
    point meant to be on a bound can land an ulp inside, and its trial then differs from
    the bound's in the loss's last bits only)."""
    near = 1e-9 * (upper - lower)
    return np.where(u <= lower + near, lower, np.where(u >= upper - near, upper, u))


@dataclasses.dataclass(frozen=True, eq=False)
class Searched:
    """What a search returns: the best ``u`` found, its ``loss``, the ``evaluations``
    made (a Jacobian counted as ``k + 1``) and the seconds it took; a search that ends
    with Newton's method (:func:`~._newton.polish`) also says its ``newton_steps``,
    whether it ``converged``, and which parameters it ``held`` because the loss does not
    feel them (None: not said)."""

    u: np.ndarray
    loss: float
    evaluations: int
    seconds: float
    newton_steps: int | None = None
    converged: bool | None = None
    held: np.ndarray | None = None
