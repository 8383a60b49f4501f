"""Base (minimal) parameters: the identifiable combinations behind the paper's Eq. 3-4.

Numerical method (Gautier 1990, "Numerical calculation of the base inertial parameters of
robots"): stack the regressor at random states, scale its columns to unit norm, take the
rank from a column-pivoted QR, and pick the independent columns in parameter order (a
column is kept when it is not in the span of the columns kept before it, read off a QR
without pivoting). Each dropped parameter is regrouped onto the kept ones with
coefficients from least squares, cleaned of round-off. Keeping earlier parameters gives
the usual regrouped names (Khalil & Dombre 2002, Sec. 10.3): ``ZZ1R = ZZ1 + YY2 + ...``.
"""

from __future__ import annotations

from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg
from jax.typing import DTypeLike
from jaxtyping import Array, ArrayLike, Float

from ._regressor import padded_regressor, take
from ._robot import LINK_PARAMETERS, N_LINK_PARAMETERS, Robot

#: A unit-norm column whose distance to the span of the others is below this is dependent.
RANK_TOLERANCE = 1e-8
#: Regrouping coefficients are rounded to this many significant digits.
COEFFICIENT_DIGITS = 12


class BaseParameters(eqx.Module):
    """A base-parameter set of a robot: ``Y @ p == base.regressor(...) @ base.project(p)``.

    Attributes:
        robot: the robot the set belongs to.
        indices: the full-parameter columns kept, one per base parameter.
        matrix: ``(rank, 12 n)`` map from full to base parameters (``project``).
        names: one name per base parameter, ``R`` appended when others are regrouped on it.
        expressions: readable expressions, e.g. ``"ZZ1 + YY2 + 0.1225*M2"``.
    """

    robot: Robot
    matrix: Float[Array, "rank p"]
    indices: tuple[int, ...] = eqx.field(static=True)
    names: tuple[str, ...] = eqx.field(static=True)
    expressions: tuple[str, ...] = eqx.field(static=True)

    @property
    def rank(self) -> int:
        return len(self.indices)

    @property
    def symbolic(self) -> tuple[Any, ...]:
        """The expressions as sympy objects, exact decimal coefficients."""
        import sympy

        symbols = [sympy.Symbol(n) for n in self.robot.param_names]
        K = np.asarray(self.matrix)
        return tuple(
            sum((sympy.Rational(f"{c:.{COEFFICIENT_DIGITS}g}") * symbols[k]
                 for k, c in enumerate(row) if c != 0.0), sympy.Integer(0))
            for row in K
        )

    def project(self, params: Float[ArrayLike, "*batch p"]) -> Float[Array, "... rank"]:
        """Full parameters ``(..., 12 n)`` -> base parameters ``(..., rank)``."""
        params = jnp.asarray(params, dtype=self.matrix.dtype)
        if params.ndim == 0 or params.shape[-1] != self.robot.n_params:
            raise ValueError(
                f"params must have shape (..., {self.robot.n_params}) for robot "
                f"{self.robot.name!r}, got {params.shape}"
            )
        return jnp.matmul(params, self.matrix.T, precision=jax.lax.Precision.HIGHEST)

    def regressor(self, q: Float[ArrayLike, "*batch n"], qd: Float[ArrayLike, "*batch n"],
                  qdd: Float[ArrayLike, "*batch n"], *, dtype: DTypeLike = jnp.float64,
                  memory_budget: int | None = None) -> Float[Array, "... n rank"]:
        """Base regressor ``(..., n) -> (..., n, rank)``: the kept columns of ``Y``
        (``memory_budget``: see :func:`~sedsabso_jax.regressor`). Compiled once per robot
        structure, dtype and number of samples rounded up
        (:func:`~sedsabso_jax.dynamics._regressor.padded_samples`)."""
        Y, batch = padded_regressor(self.robot, q, qd, qdd, dtype=dtype,
                                    memory_budget=memory_budget)
        return take(Y, batch, tuple(self.indices))

    def joint_columns(self, parameter: str) -> tuple[int | None, ...]:
        """For each joint, the base column that is its link's ``parameter`` (one of
        :data:`~._robot.LINK_PARAMETERS`, e.g. ``"FC"`` for Coulomb friction) kept as a
        base parameter, or None where it is not one (dropped, or regrouped onto another)."""
        if parameter not in LINK_PARAMETERS:
            raise ValueError(f"parameter must be one of {LINK_PARAMETERS}, got {parameter!r}")
        offset = LINK_PARAMETERS.index(parameter)
        return tuple(self.indices.index(k) if k in self.indices else None
                     for k in (N_LINK_PARAMETERS * j + offset
                               for j in range(self.robot.n_joints)))

    @property
    def values(self) -> Float[Array, " rank"]:
        """The robot's own parameters projected on this base."""
        return self.project(self.robot.params)

    def __repr__(self) -> str:
        return f"BaseParameters({self.robot.name!r}, rank={self.rank} of {self.robot.n_params})"


def random_states(robot: Robot, n_samples: int, seed: int = 0
                  ) -> tuple[Float[np.ndarray, "samples n"], Float[np.ndarray, "samples n"],
                             Float[np.ndarray, "samples n"]]:
    """Random (q, qd, qdd), each (n_samples, n): q uniform on [-pi, pi] (revolute) or
    [-1, 1] m (prismatic), qd and qdd standard normal."""
    rng = np.random.default_rng(seed)
    n = robot.n_joints
    span = np.array([np.pi if t == "revolute" else 1.0 for t in robot.joint_types])
    q = rng.uniform(-1.0, 1.0, (n_samples, n)) * span
    return q, rng.standard_normal((n_samples, n)), rng.standard_normal((n_samples, n))


def base_parameters(robot: Robot, *, n_samples: int | None = None, seed: int = 0,
                    tol: float = RANK_TOLERANCE) -> BaseParameters:
    """Compute a base-parameter set of ``robot`` numerically (see the module docstring).

    ``n_samples`` random states (default: enough for four rows per parameter, at least
    50) drawn with ``seed``; ``tol`` is the rank tolerance on unit-norm columns.
    """
    p = robot.n_params
    if n_samples is None:
        n_samples = max(50, -(-4 * p // robot.n_joints))
    # the padded program: the one the base regressor of a model's terms is taken from
    Y, _ = padded_regressor(robot, *random_states(robot, n_samples, seed))
    W = np.asarray(Y)[:n_samples].reshape(-1, p)
    norms = np.linalg.norm(W, axis=0)
    nonzero = norms > tol * max(norms.max(), 1.0)
    Ws = W[:, nonzero] / norms[nonzero]
    R_piv = scipy.linalg.qr(Ws, mode="r", pivoting=True)[0]
    d_piv = np.abs(np.diag(R_piv))
    rank = int(np.sum(d_piv > tol * d_piv[0]))
    d_ord = np.abs(np.diag(scipy.linalg.qr(Ws, mode="r")[0]))
    keep = np.flatnonzero(nonzero)[d_ord > tol * d_piv[0]]
    if len(keep) != rank:
        raise RuntimeError(
            f"base parameters of {robot.name!r}: pivoted QR gives rank {rank} but the "
            f"ordered selection keeps {len(keep)} columns; the regressor is ill-conditioned "
            f"at tolerance {tol:g} (try another seed or n_samples)"
        )
    drop = np.setdiff1d(np.arange(p), keep)
    beta = np.linalg.lstsq(W[:, keep], W[:, drop], rcond=None)[0]
    beta[np.abs(beta) < tol * max(1.0, np.abs(beta).max(initial=0.0))] = 0.0
    beta = np.vectorize(lambda c: float(f"{c:.{COEFFICIENT_DIGITS}g}"), otypes=[float])(beta)
    scale = np.linalg.norm(W[:, drop]) + np.linalg.norm(W[:, keep])
    residual = np.linalg.norm(W[:, keep] @ beta - W[:, drop])
    if residual > 1e-9 * scale:
        raise RuntimeError(
            f"base parameters of {robot.name!r}: regrouping residual {residual:.3g} "
            f"(relative {residual / scale:.3g}) is not round-off"
        )
    K = np.zeros((rank, p))
    K[np.arange(rank), keep] = 1.0
    K[:, drop] = beta
    names = robot.param_names
    return BaseParameters(
        robot=robot,
        matrix=jnp.asarray(K),
        indices=tuple(int(k) for k in keep),
        names=tuple(names[k] + ("R" if np.count_nonzero(K[r]) > 1 else "")
                    for r, k in enumerate(keep)),
        expressions=tuple(_expression(row, names, k) for row, k in zip(K, keep)),
    )


def _expression(row: np.ndarray, names, lead: int) -> str:
    text = names[lead]
    for k in np.flatnonzero(row):
        if k == lead:
            continue
        c = row[k]
        sign = "-" if c < 0 else "+"
        mag = abs(c)
        text += f" {sign} {names[k]}" if mag == 1.0 else f" {sign} {mag:.10g}*{names[k]}"
    return text
