"""The search of a torque model's nonlinear parameters as one compiled problem: variable
projection (Golub and Pereyra, *SIAM J. Numer. Anal.* 10(2), 1973,
https://doi.org/10.1137/0710036), the linear values solved in closed form for each
trial of the nonlinear ones.

A model is linear in every value but the few parameters ``u`` (log scale) its terms
search (:meth:`~sedsabso_jax.TorqueModel.nonlinear`). Its columns split in two: those no
trial moves (``A``, their normal equations formed once) and those a trial moves (``C(u)``,
found by moving ``u``: a term's own columns, the Coulomb columns a Coulomb shape
reshapes, and the columns that read that shape). A moved column is nonzero on few joints'
rows (one, for a joint's own friction), so each is held as its values on those rows
only: ``V (T, K)``, one column per (column, joint) pair. For a trial the problem computes
``V(u)`` with the terms' own code (``jax.numpy``), the cross products ``A^T C``, ``C^T C``,
``C^T b`` from it, solves the normal equations (columns scaled to unit norm, a
:data:`RIDGE` for columns that vanish) and returns the residual's mean square::

    loss(u) = min_x |W (A x_A + C(u) x_C - b)|^2 / N

``W`` weighs each joint's rows, and a mask keeps a validation split's training samples:
the arrays are always the whole recordings' (a term's state is integrated along them),
so every split of a recording, and the fit on all of it, is one compiled call of one
shape. :class:`Projection` is an ``equinox.Module`` (its arrays the compiled calls'
arguments, the model a static part), a :class:`~.._search._problem.SearchProblem` for
any search method.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._model._term import Signals, diagonal
from .._model._torque_model import TorqueModel
from .._recordings import Data
from ._samples import Samples

#: Tikhonov term of the normal equations, relative to their largest diagonal entry (the
#: columns are scaled to unit norm first): keeps a trial with a vanishing column (a
#: presliding displacement far above every motion) solvable.
RIDGE = 1e-12
#: How far (in ``u``, log scale) the parameters are moved to find the columns they move.
PROBE_STEP = 0.5


@dataclasses.dataclass(frozen=True, eq=False)
class Recipe:
    """The static part of a :class:`Projection`: the model, the column blocks a trial
    computes (the Coulomb columns where a term reshapes them, then the terms'
    ``terms``), and the moved columns' (block column, joint) pairs. Equal (and hashed)
    by what the compiled code reads, so that problems of one model structure share a
    compilation."""

    model: TorqueModel
    coulomb: bool
    terms: tuple[int, ...]
    pair_column: tuple[int, ...]
    pair_joint: tuple[int, ...]
    moved_columns: int

    @property
    def key(self) -> tuple:
        """What the compiled code reads of the model: its base, recordings and
        transmission, the terms it computes and those that shape the Coulomb columns."""
        m = self.model
        shaping = tuple(t for t in m.terms if t.coulomb(np.zeros((1, m.robot.n_joints)))
                        is not None)
        return (id(m.base), m.recordings, None if m.transmission is None
                else m.transmission.tobytes(), tuple(m.terms[i] for i in self.terms),
                shaping, self.coulomb, self.pair_column, self.pair_joint, self.moved_columns)

    def __hash__(self) -> int:
        return hash(self.key)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Recipe) and self.key == other.key


class Projection(eqx.Module):
    """A model's nonlinear search at some samples (module docstring); build it with
    :meth:`of`."""

    q: Float[Array, "T n"]
    qd: Float[Array, "T n"]
    qdd: Float[Array, "T n"]
    recording: Array | None
    steps: tuple
    rigid: Array | None
    weights: Float[Array, " n"]
    mask: Float[Array, " T"]
    A: Float[Array, "T n p"]        # the columns no trial moves, weighted, scaled, masked
    pair_A: Float[Array, "T K p"]   # A at each pair's joint row
    pair_b: Float[Array, "T K"]     # b at each pair's joint row
    b: Float[Array, "T n"]          # the torques, weighted, masked
    AtA: Float[Array, "p p"]
    Atb: Float[Array, " p"]
    btb: Float[Array, ""]
    rows: Float[Array, ""]          # the weighted rows fitted (samples x joints)
    recipe: Recipe = eqx.field(static=True)

    @classmethod
    def of(cls, model: TorqueModel, data: Samples | Data,
           weights: Float[ArrayLike, " n"] | None = None,
           keep: ArrayLike | None = None) -> Projection:
        """The problem of ``model``'s nonlinear parameters (from their values in the
        model) at ``data`` (recordings as :func:`~sedsabso_jax.identify` takes them, or a
        fit's samples), at the samples ``keep`` selects (a mask or indices; None: all),
        each joint's rows times ``weights`` (e.g. ``1 / limits``; None: 1)."""
        n = model.robot.n_joints
        weights = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
        if weights.shape != (n,) or not np.all(np.isfinite(weights) & (weights > 0)):
            raise ValueError(f"weights must be {n} finite numbers > 0, got {weights!r}")
        samples = data if isinstance(data, Samples) else Samples.of(model.robot, data)
        if keep is not None:
            samples = samples.subset(np.asarray(keep))
        return cls._of(model, samples, weights)

    @classmethod
    def _of(cls, model: TorqueModel, samples: Samples, weights: np.ndarray) -> Projection:
        found = model.nonlinear()
        if not found:
            raise ValueError(f"the torque model {model.friction!r} has no parameters to "
                             f"search")
        root = samples.root
        u0 = np.log(np.concatenate([f.values for _, f in found]))
        Y0 = root.rows(model, every_column=True)
        Y1 = root.rows(model.with_nonlinear(np.exp(u0 + PROBE_STEP)), every_column=True)
        moved = np.any(Y0 != Y1, axis=(0, 1))
        recipe = _recipe(model, moved, (Y0 != 0) | (Y1 != 0))
        mask = np.zeros(root.q.shape[0])
        mask[np.arange(root.q.shape[0]) if samples.keep is None else samples.keep] = 1.0
        w = np.asarray(weights, dtype=float)
        A = Y0[..., ~moved] * (w[:, None] * mask[:, None, None])
        scale = np.linalg.norm(A.reshape(-1, A.shape[-1]), axis=0)
        A = A / np.where(scale > 0, scale, 1.0)
        b = root.tau * w * mask[:, None]
        M = A.reshape(-1, A.shape[-1])
        joints = np.asarray(recipe.pair_joint, dtype=int)
        return cls(root.q, root.qd, root.qdd, root.recording,
                   Signals(root.q, root.qd, root.qdd, root.recording, None).increments(),
                   model.signals(root.q, root.qd, root.qdd, root.recording,
                                 root.base_rows(model)).rigid, jnp.asarray(w),
                   jnp.asarray(mask), jnp.asarray(A), jnp.asarray(A[:, joints, :]),
                   jnp.asarray(b[:, joints]), jnp.asarray(b), jnp.asarray(M.T @ M),
                   jnp.asarray(M.T @ b.reshape(-1)), jnp.asarray(float(b.reshape(-1)
                                                                       @ b.reshape(-1))),
                   jnp.asarray(float(mask.sum() * model.robot.n_joints)), recipe)

    def moving(self, u: Float[Array, " k"]) -> Float[Array, "T K"]:
        """The moved columns at ``u``, on their pairs' rows, weighted and masked."""
        r = self.recipe
        model = r.model.with_nonlinear(jnp.exp(u))
        n = model.robot.n_joints
        coulomb, _ = model.coulomb(self.qd, jnp)
        s = Signals(self.q, self.qd, self.qdd, self.recording, coulomb, jnp, self.rigid,
                    steps=self.steps)
        blocks = [diagonal(coulomb, n, jnp)] if r.coulomb else []
        blocks += [jnp.asarray(model.terms[i].columns(model, s)) for i in r.terms]
        C = jnp.concatenate(blocks, -1)
        joints = np.asarray(r.pair_joint)
        V = C[:, joints, np.asarray(r.pair_column)]
        return V * self.weights[joints] * self.mask[:, None]

    def _normal(self, u):
        """The scaled normal equations ``G x = h`` at ``u`` and the moved columns'
        scale."""
        r = self.recipe
        V = self.moving(u)
        S = np.zeros((len(r.pair_column), r.moved_columns))
        S[np.arange(len(r.pair_column)), _column_of_pair(r)] = 1.0
        same = np.equal.outer(np.asarray(r.pair_joint), np.asarray(r.pair_joint))
        AtC = jnp.einsum("tkp,tk->pk", self.pair_A, V) @ S
        CtC = S.T @ ((V.T @ V) * same) @ S
        Ctb = S.T @ jnp.einsum("tk,tk->k", V, self.pair_b)
        norms = jnp.sqrt(jnp.diag(CtC))
        c = 1.0 / jnp.where(norms > 0, norms, 1.0)
        G = jnp.block([[self.AtA, AtC * c], [(AtC * c).T, CtC * jnp.outer(c, c)]])
        h = jnp.concatenate([self.Atb, Ctb * c])
        return G, h, c, V

    def _solve(self, G, h):
        ridge = RIDGE * jnp.max(jnp.diag(G))
        return jnp.linalg.solve(G + ridge * jnp.eye(G.shape[0]), h)

    def loss(self, u: Float[Array, " k"]) -> Float[Array, ""]:
        """The weighted residual's mean square over the samples fitted, the linear
        values solved (module docstring)."""
        G, h, _, _ = self._normal(u)
        x = self._solve(G, h)
        return (self.btb - 2 * x @ h + x @ G @ x) / self.rows

    def residual(self, u: Float[Array, " k"]) -> Float[Array, " N"]:
        """The weighted residual ``(T n,)`` at ``u``, the linear values solved (zero on
        the samples not fitted); its mean square over those is :meth:`loss`."""
        G, h, c, V = self._normal(u)
        x = self._solve(G, h)
        p = self.A.shape[-1]
        r = self.recipe
        xc = (x[p:] * c)[_column_of_pair(r)]
        fitted = (self.A @ x[:p]).at[:, np.asarray(r.pair_joint)].add(V * xc)
        return (fitted - self.b).reshape(-1) * jnp.sqrt(self.b.size / self.rows)


def _column_of_pair(recipe: Recipe) -> np.ndarray:
    """Each pair's column among the moved columns (0..moved_columns-1)."""
    return np.unique(np.asarray(recipe.pair_column), return_inverse=True)[1]


def _recipe(model: TorqueModel, moved: np.ndarray, nonzero: np.ndarray) -> Recipe:
    """The blocks and pairs of ``model``'s moved columns (``moved``: per column of
    every column, ``nonzero (T, n, D)``: where either probe's rows were nonzero)."""
    rank = model.base.rank
    sizes = [len(t.names(model)) for t in model.terms]
    starts = np.cumsum([rank, *sizes])[:-1]
    fc = np.array(model.base.joint_columns("FC"), dtype=object)
    coulomb = bool(np.any(moved[:rank]))
    if coulomb and not set(np.flatnonzero(moved[:rank])) <= set(fc[fc != None]):  # noqa: E711
        raise ValueError("a term moved base columns other than the Coulomb columns")
    index = [int(c) for c in fc] if coulomb else []  # block column -> every column
    terms = []
    for i, (start, size) in enumerate(zip(starts, sizes)):
        if size and np.any(moved[start:start + size]):
            terms.append(i)
            index += list(range(start, start + size))
    pair_column, pair_joint = [], []
    for m, e in enumerate(index):
        if moved[e]:
            for j in np.flatnonzero(np.any(nonzero[:, :, e], axis=0)):
                pair_column.append(m)
                pair_joint.append(int(j))
    return Recipe(model, coulomb, tuple(terms), tuple(pair_column), tuple(pair_joint),
                  int(moved.sum()))
