"""The presliding displacements as a search problem for any optimiser: a population's
fitness in one vmapped call, a residual vector for Levenberg-Marquardt.

A model with a :class:`~._terms.Presliding` term is linear in every value but its
displacements ``q_c`` (one per joint), which enter through the state's recursion
(:mod:`._friction_state`). :class:`PreslidingProblem` eliminates the linear values
(variable projection; Golub and Pereyra, *SIAM J. Numer. Anal.* 10(2), 1973,
https://doi.org/10.1137/0710036): for a trial ``u = log q_c`` it integrates the state by a
``lax.scan`` over the samples, forms the normal equations of the columns that do not
depend on ``u`` (``A``, formed once) beside the state's columns ``Z(u)`` (each joint's own
row), solves them and returns the residual. :meth:`~PreslidingProblem.fitness` is a
fitness ``f(u, problem)`` for :func:`~sedsabso_jax.minimise` (SEDSABSO, LDWPSO, evosax
strategies, vmapped over the population) and :meth:`~PreslidingProblem.residual` the residual vector
whose Jacobian (forward mode through the scan and the solve) an optimistix
Levenberg-Marquardt reads. :meth:`~PreslidingProblem.predict` gives the torques of
another recording (``of(..., values=...)``) with the values fitted here.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float, Int

from ..measurements._container import Measurements
from ._friction_state import dahl_state, increments
from ._model import TorqueModel
from ._shapes import Samples
from ._terms import Presliding

#: Tikhonov term of the normal equations, relative to their largest diagonal entry (the
#: columns are scaled to unit norm first): keeps a trial with a vanishing state column
#: (``q_c`` far above every motion) solvable.
RIDGE = 1e-12


class PreslidingProblem(eqx.Module):
    """A :class:`~._terms.Presliding` model's search over ``u = log q_c`` (module
    docstring) at one set of samples. Build it with :meth:`of`."""

    A: Float[Array, "T n d"]  # the columns that do not depend on q_c, scaled
    scale: Float[Array, " d"]  # each column's norm (A's columns are divided by it)
    tau: Float[Array, "T n"]
    dq: Float[Array, "R n"]  # the whole recording's increments
    start: Bool[Array, " R"]
    keep: Int[Array, " T"]  # the samples of the recording fitted
    AtA: Float[Array, "d d"]
    Atb: Float[Array, " d"]
    weights: Float[Array, " n"]  # each joint's rows multiplied by it
    names: tuple[str, ...] = eqx.field(static=True)

    @classmethod
    def of(cls, model: TorqueModel, data: Measurements,
           keep: ArrayLike | None = None,
           weights: Float[ArrayLike, " n"] | None = None) -> PreslidingProblem:
        """The problem of ``model`` (with a :class:`~._terms.Presliding` term; its other
        terms' scales fixed as they are) at the samples ``keep`` (indices or a mask;
        None: all) of the recording ``data``, the state integrated along the whole
        recording, each joint's rows times ``weights`` (e.g. ``1 / limits``; None: 1)."""
        if not any(isinstance(t, Presliding) for t in model.terms):
            raise ValueError(f"PreslidingProblem needs a model with the presliding term, "
                             f"got {model.friction!r}")
        if not isinstance(data, Measurements):
            raise TypeError(f"data must be one recording (sj.Measurements), got "
                            f"{type(data).__name__}")
        rest = dataclasses.replace(model, terms=tuple(
            t for t in model.terms if not isinstance(t, Presliding)))
        n = model.robot.n_joints
        w = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
        if w.shape != (n,) or not np.all(np.isfinite(w) & (w > 0)):
            raise ValueError(f"weights must be {n} finite numbers > 0, got {weights!r}")
        index = np.arange(data.n_samples)
        if keep is not None:
            index = index[np.asarray(keep)]
        samples = Samples(data.q, data.qd, data.qdd, data.tau).subset(index)
        A = np.asarray(samples.rows(rest)) * w[:, None]
        scale = np.linalg.norm(A.reshape(-1, A.shape[-1]), axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        A = A / scale
        tau = np.asarray(samples.tau, dtype=float) * w
        dq, start = increments(data.q)
        M = A.reshape(-1, A.shape[-1])
        return cls(jnp.asarray(A), jnp.asarray(scale), jnp.asarray(tau), jnp.asarray(dq),
                   jnp.asarray(start), jnp.asarray(index), jnp.asarray(M.T @ M),
                   jnp.asarray(M.T @ tau.reshape(-1)), jnp.asarray(w),
                   tuple(rest.names) + tuple(f"FP{j + 1}" for j in range(n)))

    @property
    def n_samples(self) -> int:
        return int(self.tau.size)

    def state(self, u: Float[Array, " n"]) -> Float[Array, "T n"]:
        """The presliding state at ``q_c = exp(u)`` at the samples fitted."""
        return dahl_state(self.dq, self.start, jnp.exp(u))[self.keep]

    def _fit(self, u: Float[Array, " n"]) -> tuple[Float[Array, " p"], Float[Array, "T n"]]:
        """The scaled least-squares values and the weighted state at ``q_c = exp(u)``."""
        zw = self.state(u) * self.weights  # the state's columns, each joint's own row
        AtZ = jnp.einsum("tjd,tj->dj", self.A, zw)
        G = jnp.block([[self.AtA, AtZ], [AtZ.T, jnp.diag(jnp.sum(zw ** 2, 0))]])
        h = jnp.concatenate([self.Atb, jnp.sum(zw * self.tau, 0)])
        ridge = RIDGE * jnp.max(jnp.diag(G))
        return jnp.linalg.solve(G + ridge * jnp.eye(G.shape[0]), h), zw

    def solve(self, u: Float[Array, " n"]) -> Float[Array, " p"]:
        """The least-squares values at ``q_c = exp(u)``, in :attr:`names`' order (the
        model's values, the ``FP`` last)."""
        x, _ = self._fit(u)
        d = self.A.shape[-1]
        return jnp.concatenate([x[:d] / self.scale, x[d:]])

    def predict(self, u: Float[Array, " n"], values: Float[Array, " p"]
                ) -> Float[Array, "T n"]:
        """The torques (unweighted) of ``values`` (:meth:`solve`'s, perhaps of another
        recording's problem) at ``q_c = exp(u)``."""
        d = self.A.shape[-1]
        return (self.A @ (values[:d] * self.scale)) / self.weights + self.state(u) * values[d:]

    def residual(self, u: Float[Array, " n"], args: object = None) -> Float[Array, " N"]:
        """The weighted residual of the least-squares values at ``q_c = exp(u)``,
        flattened (``(T n,)``; ``args`` unused)."""
        x, zw = self._fit(u)
        d = self.A.shape[-1]
        return (self.A @ x[:d] + zw * x[d:] - self.tau).reshape(-1)

    def loss(self, u: Float[Array, " n"], args: object = None) -> Float[Array, ""]:
        """The weighted residual's mean square at ``q_c = exp(u)`` (``args`` unused)."""
        return jnp.mean(self.residual(u) ** 2)

    @staticmethod
    def fitness(u: Float[Array, " n"], problem: PreslidingProblem) -> Float[Array, ""]:
        """:meth:`loss` as a fitness ``f(u, args)`` whose ``args`` is the problem, for
        :func:`~sedsabso_jax.minimise` (``args=problem``): the problem's arrays are then
        the compiled run's arguments, not constants baked into it."""
        return problem.loss(u)
