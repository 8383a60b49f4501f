"""The search of a torque model's nonlinear parameters as one compiled problem: variable
projection (Golub and Pereyra, *SIAM J. Numer. Anal.* 10(2), 1973,
https://doi.org/10.1137/0710036), the linear values solved in closed form for each
trial of the nonlinear ones.

A model is linear in every value but the few parameters ``u`` (log scale) its terms
search (:meth:`~sedsabso_jax.TorqueModel.nonlinear`). Its columns split in two: those no
trial moves (``A``, the ones the model fits, their normal equations formed once,
:func:`fixed`) and those a trial moves (``C(u)``,
those whose derivative in ``u`` is nonzero, by forward mode through the terms' own code:
a term's own columns, the Coulomb columns a Coulomb shape reshapes, and the columns that
read that shape). A moved column is nonzero on few joints'
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
import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._model._leaves import tree_key
from .._model._term import Signals, diagonal
from .._model._torque_model import TorqueModel
from .._recordings import Data
from .._search._problem import fitness
from ._samples import Samples

#: Tikhonov term of the normal equations, relative to their largest diagonal entry (the
#: columns are scaled to unit norm first): keeps a trial with a vanishing column (a
#: presliding displacement far above every motion) solvable.
RIDGE = 1e-12


@dataclasses.dataclass(frozen=True, eq=False)
class Recipe:
    """The static part of a :class:`Projection`: the model, the column blocks a trial
    computes (the Coulomb columns where a term reshapes them, then the terms
    ``terms``), the moved columns' (block column, joint) pairs, and for each joint whose
    row a moved column reaches, the unmoved columns nonzero on that row (``rows``:
    ``(joint, columns)``, every joint; a joint's own friction meets few of the robot's
    columns).
    Equal (and hashed) by what the compiled code reads, so that problems of one model
    structure share a compilation. ``read``: the (term, field) pairs of the terms it
    computes that hold values read of a fit
    (:attr:`~.._model._term.AbstractTerm.read_fields`), None in ``model``: the problem
    carries them as arrays (they differ between a validation's splits)."""

    model: TorqueModel
    coulomb: bool
    terms: tuple[int, ...]
    pair_column: tuple[int, ...]
    pair_joint: tuple[int, ...]
    moved_columns: int
    rows: tuple[tuple[int, tuple[int, ...]], ...]
    read: tuple[tuple[int, str], ...] = ()

    @functools.cached_property
    def key(self) -> tuple:
        """What the compiled code reads of the model, by structure and values
        (:func:`~.._model._torque_model.tree_key`): its base, recordings and
        transmission, the terms it computes and those that shape the Coulomb columns
        (without what they read of a fit, :attr:`read`)."""
        m = self.model
        return (tree_key((m.base, m.recordings, m.transmission,
                          tuple(m.terms[i] for i in self.terms), m.shaping)),
                self.coulomb, self.pair_column, self.pair_joint, self.moved_columns,
                self.rows, self.read)

    def __hash__(self) -> int:
        return hash(self.key)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Recipe) and self.key == other.key

    def with_read(self, values: tuple) -> TorqueModel:
        """The model with the fields :attr:`read` at ``values`` (floats, or a trial's
        traced values)."""
        terms = list(self.model.terms)
        for (i, field), value in zip(self.read, values):
            terms[i] = eqx.tree_at(lambda t: getattr(t, field), terms[i], value,
                                   is_leaf=lambda x: x is None)
        return eqx.tree_at(lambda m: m.terms, self.model, tuple(terms))

    @property
    def column_of_pair(self) -> np.ndarray:
        """Each pair's column among the moved columns (0..moved_columns-1)."""
        return np.unique(np.asarray(self.pair_column), return_inverse=True)[1]


class Projection(eqx.Module):
    """A model's nonlinear search at some samples (module docstring); build it with
    :meth:`of`."""

    q: Float[Array, "T n"]
    qd: Float[Array, "T n"]
    qdd: Float[Array, "T n"]
    recording: Array | None
    rigid: Array | None
    weights: Float[Array, " n"]
    mask: Float[Array, " T"]
    A_rows: tuple                   # per joint (recipe.rows): the columns no trial moves
                                    # that reach its row, weighted, scaled, masked
    b: Float[Array, "T n"]          # the torques, weighted, masked
    P: Float[Array, "p p"]          # (A^T A + ridge)^-1 of the unmoved columns
    PAtb: Float[Array, " p"]        # their least-squares values without the moved ones
    floor: Float[Array, ""]         # b^T b - b^T A P A^T b: their residual
    rows: Float[Array, ""]          # the weighted rows fitted (samples x joints)
    read: tuple                     # the values recipe.read names, as arrays
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
        root = samples.root
        T = root.q.shape[0]
        # the samples fitted, a mask over the whole recordings' rows
        mask = np.ones(T, dtype=bool) if samples.mask is None else samples.mask.copy()
        if keep is not None:
            inner = np.zeros(int(mask.sum()), dtype=bool)
            inner[np.asarray(keep)] = True
            mask[mask] = inner
        return cls._of(model, root, mask.astype(float), weights)

    @classmethod
    def _of(cls, model: TorqueModel, root: Samples, mask: np.ndarray, weights: np.ndarray
            ) -> Projection:
        found = model.nonlinear()
        if not found:
            raise ValueError(f"the torque model {model.friction!r} has no parameters to "
                             f"search")
        # kept for the other splits where the whole's rows of this model are (a model
        # the validation fits unchanged on every split)
        Y0 = root.rows(model, every_column=True, cache=root.has_rows(model))
        # which columns move, and the recording's signals, once per structure of model
        shared = root.kept("signals", model.structure, lambda: _signals(model, root))
        moved, recipe = root.kept("moved", model.structure, lambda: _moved(model, Y0, shared))
        w = np.asarray(weights, dtype=float)
        A = Y0[..., fixed(model, moved)] * (w[:, None] * mask[:, None, None])
        M = A.reshape(-1, A.shape[-1])
        scale = np.linalg.norm(M, axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        A, M = A / scale, M / scale
        b = root.tau * w * mask[:, None]
        AtA, Atb = M.T @ M, M.T @ b.reshape(-1)
        P = np.linalg.inv(AtA + RIDGE * np.max(np.diag(AtA)) * np.eye(len(AtA)))
        PAtb = P @ Atb
        q, qd, qdd, recording, rigid = shared
        return cls(q=q, qd=qd, qdd=qdd, recording=recording, rigid=rigid,
                   weights=jnp.asarray(w), mask=jnp.asarray(mask),
                   A_rows=tuple(jnp.asarray(A[:, j][:, list(cols)])
                                for j, cols in recipe.rows),
                   b=jnp.asarray(b), P=jnp.asarray(P), PAtb=jnp.asarray(PAtb),
                   floor=jnp.asarray(float(b.reshape(-1) @ b.reshape(-1) - Atb @ PAtb)),
                   rows=jnp.asarray(float(mask.sum() * model.robot.n_joints)),
                   read=tuple(jnp.asarray(np.asarray(getattr(model.terms[i], field),
                                                     dtype=float))
                              for i, field in recipe.read), recipe=recipe)

    def moving(self, u: Float[Array, " k"]) -> Float[Array, "T K"]:
        """The moved columns at ``u``, on their pairs' rows, weighted and masked."""
        r = self.recipe
        model = r.with_read(self.read).with_nonlinear(jnp.exp(u))
        n = model.robot.n_joints
        coulomb, _ = model.coulomb(self.qd)
        s = Signals(self.q, self.qd, self.qdd, self.recording, coulomb, self.rigid)
        blocks = [diagonal(coulomb, n)] if r.coulomb else []
        blocks += [jnp.asarray(model.terms[i].columns(model, s)) for i in r.terms]
        C = jnp.concatenate(blocks, -1)
        joints = np.asarray(r.pair_joint)
        V = C[:, joints, np.asarray(r.pair_column)]
        return V * self.weights[joints] * self.mask[:, None]

    def _cross(self, u):
        """The moved columns' cross products at ``u``, scaled to unit norm: with the
        unmoved columns ``A^T C``, with themselves ``C^T C``, with the torques ``C^T b``;
        the scale, and the moved columns' values (each joint's row with its few
        columns)."""
        r = self.recipe
        V = self.moving(u)
        joints = np.asarray(r.pair_joint)
        blocks, rows, cols, gram, gi, gj = [], [], [], [], [], []
        for (j, columns), Aj in zip(r.rows, self.A_rows):
            pairs = np.flatnonzero(joints == j)
            if not pairs.size:  # no moved column reaches this row
                continue
            Vj = V[:, pairs]
            blocks.append((Aj.T @ Vj).reshape(-1))
            rows.append(np.repeat(columns, len(pairs)))
            cols.append(np.tile(pairs, len(columns)))
            gram.append((Vj.T @ Vj).reshape(-1))
            gi.append(np.repeat(pairs, len(pairs)))
            gj.append(np.tile(pairs, len(pairs)))
        K, p = len(joints), self.P.shape[0]
        AtV = jnp.zeros((p, K)).at[np.concatenate(rows), np.concatenate(cols)].set(
            jnp.concatenate(blocks))
        VtV = jnp.zeros((K, K)).at[np.concatenate(gi), np.concatenate(gj)].set(
            jnp.concatenate(gram))
        S = np.zeros((K, r.moved_columns))
        S[np.arange(K), r.column_of_pair] = 1.0
        AtC, CtC = AtV @ S, S.T @ VtV @ S
        Ctb = S.T @ jnp.sum(V * self.b[:, joints], axis=0)
        norms = jnp.sqrt(jnp.diag(CtC))
        c = 1.0 / jnp.where(norms > 0, norms, 1.0)
        return AtC * c, CtC * jnp.outer(c, c), Ctb * c, c, V

    def _reduced(self, u):
        """The normal equations reduced to the moved columns (the unmoved ones eliminated
        through :attr:`P`, their inverse Gram matrix, formed once): ``S y = g`` with
        ``S = C^T C - C^T A P A^T C`` (plus :data:`RIDGE`), ``g = C^T b - C^T A P A^T
        b``, and ``Z = P A^T C``."""
        AtC, CtC, Ctb, c, V = self._cross(u)
        Z = self.P @ AtC
        S = CtC - AtC.T @ Z
        S = S + RIDGE * jnp.max(jnp.diag(CtC)) * jnp.eye(S.shape[0])
        g = Ctb - AtC.T @ self.PAtb
        y = jax.scipy.linalg.cho_solve(jax.scipy.linalg.cho_factor(S), g)
        return y, g, Z, c, V

    def loss(self, u: Float[Array, " k"]) -> Float[Array, ""]:
        """The weighted residual's mean square over the samples fitted, the linear
        values solved (module docstring)."""
        y, g, _, _, _ = self._reduced(u)
        return (self.floor - y @ g) / self.rows

    #: :meth:`loss` as a fitness ``f(u, args)`` for :func:`~sedsabso_jax.minimise`
    #: (``args=problem``): the searches' one wrapper, :func:`~.._search._problem.fitness`.
    fitness = staticmethod(fitness)

    def residual(self, u: Float[Array, " k"]) -> Float[Array, " N"]:
        """The weighted residual ``(T n,)`` at ``u``, the linear values solved (zero on
        the samples not fitted); its mean square over those is :meth:`loss`."""
        y, _, Z, c, V = self._reduced(u)
        xa = self.PAtb - Z @ y  # the unmoved columns' values
        r = self.recipe
        xc = (y * c)[r.column_of_pair]
        fitted = jnp.stack([Aj @ xa[np.asarray(columns, dtype=int)]
                            for (_, columns), Aj in zip(r.rows, self.A_rows)], -1)
        fitted = fitted.at[:, np.asarray(r.pair_joint)].add(V * xc)
        return (fitted - self.b).reshape(-1) * jnp.sqrt(self.b.size / self.rows)


def _moved(model: TorqueModel, Y0: np.ndarray, shared: tuple) -> tuple[np.ndarray, Recipe]:
    """Which of ``model``'s every columns (``Y0``, at the start values) its searched
    parameters move, and the recipe: a column moves where its derivative with respect to
    them is nonzero (forward mode through the Coulomb shape and the terms' own columns at
    the start values, the recordings' signals ``shared``, along a fixed direction of
    random positive weights: two parameters' effects on a column cancel only at an exact
    tie); a column reaches a joint's row where its value or its derivative is nonzero
    there."""
    u0 = np.log(np.concatenate([f.values for _, f in model.nonlinear()]))
    q, qd, qdd, recording, rigid = shared

    def columns(u):
        m = model.with_nonlinear(jnp.exp(u))
        coulomb, _ = m.coulomb(qd)
        s = Signals(q, qd, qdd, recording, coulomb, rigid)
        return coulomb, [jnp.asarray(t.columns(m, s)) for t in m.terms]

    direction = np.random.default_rng(0).uniform(0.5, 1.5, u0.shape)
    _, (d_coulomb, d_terms) = jax.jvp(columns, (jnp.asarray(u0),), (jnp.asarray(direction),))
    derivative = np.zeros(Y0.shape, dtype=bool)
    d_coulomb = np.asarray(d_coulomb) != 0
    for j, c in enumerate(model.base.joint_columns("FC")):
        if c is not None:
            derivative[:, j, c] = d_coulomb[:, j]
    d_terms = [np.asarray(d).reshape(Y0.shape[:2] + (-1,)) != 0 for d in d_terms]
    derivative[..., model.base.rank:] = np.concatenate(d_terms, -1)
    moved = np.any(derivative, axis=(0, 1))
    return moved, _recipe(model, moved, (Y0 != 0) | derivative)


def fixed(model: TorqueModel, moved: np.ndarray) -> np.ndarray:
    """The columns no trial moves that the model fits (``A``): not ``moved``, and not
    spanned by the base regressor (:attr:`~sedsabso_jax.TorqueModel.kept`). A spanned
    column would add nothing to ``A``'s range but an exact dependency: its inverse Gram
    matrix would then grow to ``1 / RIDGE`` along it and carry the rounding of ``A^T C``
    into the loss, in jumps that keep Newton's method from converging."""
    return ~moved & model.kept


def _signals(model: TorqueModel, root: Samples) -> tuple:
    """The whole recordings' signals a trial's columns read, as JAX arrays: positions,
    velocities, accelerations, recordings, rigid-body rows."""
    rigid = model.signals(root.q, root.qd, root.qdd, root.recording,
                          root.base_rows(model)).rigid
    return (jnp.asarray(root.q), jnp.asarray(root.qd), jnp.asarray(root.qdd),
            None if root.recording is None else jnp.asarray(root.recording),
            None if rigid is None else jnp.asarray(rigid))


def _recipe(model: TorqueModel, moved: np.ndarray, nonzero: np.ndarray) -> Recipe:
    """The blocks, pairs and rows of ``model``'s moved columns (``moved``: per column of
    every column, ``nonzero (T, n, D)``: where a column's value or derivative is nonzero)."""
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
    on_row = np.any(nonzero[:, :, fixed(model, moved)], axis=0)  # (n, unmoved columns)
    rows = tuple((j, tuple(int(c) for c in np.flatnonzero(on_row[j])))
                 for j in range(model.robot.n_joints))
    read = tuple((i, field) for i in terms for field in model.terms[i].read_fields
                 if getattr(model.terms[i], field) is not None)
    recipe = Recipe(model, coulomb, tuple(terms), tuple(pair_column), tuple(pair_joint),
                    int(moved.sum()), rows, read)
    return dataclasses.replace(recipe, model=recipe.with_read((None,) * len(read)))
