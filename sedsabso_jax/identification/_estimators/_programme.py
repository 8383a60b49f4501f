"""The semidefinite programme of the links' physically consistent fit
(:func:`~._physical.fit_physical`) as Clarabel takes it: built for one model shape, entry
for entry as cvxpy canonicalises its statement, and set up once (:func:`programme`)."""

from __future__ import annotations

import dataclasses
import functools
import threading

import numpy as np
import scipy.sparse as sp

from ...dynamics._robot import N_LINK_PARAMETERS

#: Smallest eigenvalue of each link's pseudo-inertia in a physical fit (kg m^2, kg).
PSD_MARGIN = 1e-6


def inertial_params(J):
    """A link's 10 parameters ``[Ixx Iyy Izz Ixy Ixz Iyz m mx my mz]`` from its
    pseudo-inertia ``J`` (a NumPy or JAX array, or a cvxpy variable: affine expressions),
    the inverse of ``pseudo_inertia``: ``I = tr(S) 1 - S`` with ``S`` the upper-left 3x3
    block."""
    return [J[1, 1] + J[2, 2], J[0, 0] + J[2, 2], J[0, 0] + J[1, 1],
            -J[0, 1], -J[0, 2], -J[1, 2], J[3, 3], J[0, 3], J[1, 3], J[2, 3]]


#: A pseudo-inertia's upper triangle, row by row: the order of cvxpy's variables of a
#: symmetric matrix, and of each link's variables in :class:`Programme`.
TRIANGLE = tuple((i, j) for i in range(4) for j in range(i, 4))
#: Clarabel's order of a positive semidefinite cone's vector: the upper triangle, column
#: by column, the off-diagonal entries times sqrt(2).
SVEC = tuple((i, j) for j in range(4) for i in range(j + 1))


def _link_map() -> np.ndarray:
    """(10, 10): a link's 10 parameters (rows) from its pseudo-inertia's triangle (columns,
    :data:`TRIANGLE`), :func:`inertial_params` of unit matrices."""
    link = np.zeros((10, 10))
    for t, (i, j) in enumerate(TRIANGLE):
        unit = np.zeros((4, 4))
        unit[i, j] = unit[j, i] = 1.0
        link[:, t] = inertial_params(unit)
    return link


@dataclasses.dataclass(frozen=True)
class Programme:
    """The semidefinite programme of :func:`~._physical.fit_physical` for one shape of
    model, as cvxpy
    gives it to Clarabel. cvxpy canonicalises the statement (over the links' pseudo-inertias
    ``J``, the friction, the extras and each body term's pseudo-inertia ``B``)::

        minimise ||[M pe - c; sqrt(lambda) p - pulled]||,   pe = [p, extras],
        J_i - PSD_MARGIN 1 >= 0, friction >= 0, extras[nonneg] >= 0,
        B_k - PSD_MARGIN 1 >= 0, extras[bodies_k : bodies_k + 10] = inertial_params(B_k)

    (``p`` the links' :func:`inertial_params` of each ``J`` and ``Fc, Fv``) to Clarabel's
    variables ``[t, J_1, friction, J_2 .. J_n, extras, B_1 ..]`` (each matrix by
    :data:`TRIANGLE`) and rows: the equalities, the nonnegative, the second-order cone
    ``(t, M pe - c, sqrt(lambda) p - pulled)``, each ``J``'s and ``B``'s cone
    (:data:`SVEC`). Built here entry for entry in the same order by the same
    floating-point operations, so Clarabel gets the same bytes without cvxpy's
    canonicalisation per shape and its time per solve (``python -m
    benchmarks.physical_fit``); the tests check them equal to cvxpy's. The solver is set
    up on the trivial instance (``M = 0, c = 0, lambda = 1``), as cvxpy's first solve
    does, and keeps that equilibration for every fit: the same data give the same
    numbers after any other fits."""

    n_joints: int
    dim: int
    n_extra: int
    nonneg: tuple[int, ...]
    bodies: tuple[int, ...]

    @property
    def n_variables(self) -> int:
        return 1 + N_LINK_PARAMETERS * self.n_joints + self.n_extra + 10 * len(self.bodies)

    @functools.cached_property
    def _layout(self):
        """Each of ``pe``'s parameters as up to two variables with a sign (``first,
        first_sign, second, second_sign``; ``second = -1`` for none), where each ``J``
        and ``B`` starts, and the link map."""
        n, link = self.n_joints, _link_map()
        J = np.array([1] + [11 + 2 * n + 10 * (i - 1) for i in range(1, n)], dtype=int)
        B = 1 + N_LINK_PARAMETERS * n + self.n_extra + 10 * np.arange(len(self.bodies))
        first, second = [], []
        for i in range(n):
            for k in range(10):
                t, *more = np.flatnonzero(link[k])
                first.append((J[i] + t, link[k, t]))
                second.append((J[i] + more[0], link[k, more[0]]) if more else (-1, 0.0))
            first += [(11 + 2 * i, 1.0), (12 + 2 * i, 1.0)]
            second += [(-1, 0.0), (-1, 0.0)]
        first += [(1 + N_LINK_PARAMETERS * n + k, 1.0) for k in range(self.n_extra)]
        second += [(-1, 0.0)] * self.n_extra
        v1, s1 = (np.array(column) for column in zip(*first))
        v2, s2 = (np.array(column) for column in zip(*second))
        return v1.astype(int), s1, v2.astype(int), s2, J, B.astype(int), link

    @functools.cached_property
    def _terms(self) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], ...]:
        """``pe``'s parameters by the variables they read: the first term of each
        variable (``variables, signs, parameters``), then the second term of those with
        two (a diagonal of ``J`` is in two moments of inertia)."""
        v1, s1, v2, s2, *_ = self._layout
        var = np.r_[v1, v2[v2 >= 0]]
        sign = np.r_[s1, s2[v2 >= 0]]
        column = np.r_[np.arange(len(v1)), np.flatnonzero(v2 >= 0)]
        order = np.lexsort((column, var))
        var, sign, column = var[order], sign[order], column[order]
        first = np.r_[True, var[1:] != var[:-1]]
        return tuple((var[k], sign[k], column[k]) for k in (first, ~first))

    @functools.cached_property
    def _pattern(self):
        """``A``'s entries as (row, column) in the order :meth:`data` computes their
        values, the permutation to Clarabel's compressed columns, its ``indices, indptr``
        and the number of rows."""
        n, nv, nb = self.n_joints, self.n_variables, len(self.bodies)
        v1, _, v2, _, J, B, link = self._layout
        d_full, n_pe = N_LINK_PARAMETERS * n, N_LINK_PARAMETERS * n + self.n_extra
        eq_link, eq_t = np.nonzero(link)  # a body's parameters from its triangle
        eq_rows = (np.r_[(10 * np.arange(nb)[:, None] + np.arange(10)).ravel(),
                         (10 * np.arange(nb)[:, None] + eq_link).ravel()] if nb
                   else np.zeros(0, dtype=int))
        eq_cols = (np.r_[(1 + d_full + np.asarray(self.bodies)[:, None] + np.arange(10)).ravel(),
                         (B[:, None] + eq_t).ravel()] if nb else np.zeros(0, dtype=int))
        nonneg = np.r_[11 + np.arange(2 * n), 1 + d_full + np.asarray(self.nonneg, dtype=int)]
        soc = 10 * nb + len(nonneg)  # the cone's first row, t
        two = v2[:d_full] >= 0
        prior = soc + 1 + self.dim + np.arange(d_full)
        psd = soc + 1 + self.dim + d_full
        svec = np.array([TRIANGLE.index(e) for e in SVEC])
        rows = np.concatenate([
            eq_rows, 10 * nb + np.arange(len(nonneg)), [soc],
            np.repeat(soc + 1 + np.arange(self.dim), n_pe), prior, prior[two],
            psd + np.arange(10 * (n + nb))]).astype(int)
        cols = np.concatenate([
            eq_cols, nonneg, [0], np.tile(np.arange(1, 1 + n_pe), self.dim), v1[:d_full],
            v2[:d_full][two], (np.r_[J, B][:, None] + svec).ravel()]).astype(int)
        order = np.lexsort((rows, cols))
        return order, rows[order], np.searchsorted(cols[order], np.arange(nv + 1)), \
            psd + 10 * (n + nb)

    def data(self, M: np.ndarray, c: np.ndarray, root: float, pulled: np.ndarray) -> dict:
        """Clarabel's ``P, q, A, b`` for ``M``, ``c``, ``root = sqrt(lambda)`` and
        ``pulled = sqrt(lambda) p_prior`` (all in units of ``||c||``)."""
        n, nv, nb = self.n_joints, self.n_variables, len(self.bodies)
        v1, s1, v2, s2, _, _, link = self._layout
        d_full, n_pe = N_LINK_PARAMETERS * n, N_LINK_PARAMETERS * n + self.n_extra
        block = np.zeros((self.dim, 1 + n_pe))  # -M pe in the variables, as cvxpy sums it
        for var, sign, column in self._terms:  # each variable's terms, at most two
            block[:, var] -= sign * M[:, column]
        block[block == 0] = -0.0  # cvxpy's zeros are negative (the same bytes to Clarabel)
        two = v2 >= 0
        n_first = 10 * nb + 2 * n + len(self.nonneg)
        psd = np.tile([-1.0 if i == j else -np.sqrt(2) for i, j in SVEC], n + nb)
        values = np.concatenate([
            np.ones(10 * nb), np.tile(-link[np.nonzero(link)], nb),  # the equalities
            np.full(n_first - 10 * nb + 1, -1.0),  # the nonnegative, the cone's t
            block[:, 1:].ravel(), -root * s1[:d_full], -root * s2[:d_full][two[:d_full]], psd])
        order, indices, indptr, n_rows = self._pattern
        margin = np.tile([-PSD_MARGIN if i == j else 0.0 for i, j in SVEC], n + nb)
        return {"P": sp.triu(sp.csc_array((nv, nv))).tocsc(), "q": np.r_[1.0, np.zeros(nv - 1)],
                "A": sp.csc_array((values[order], indices, indptr), shape=(n_rows, nv)),
                "b": np.concatenate([np.zeros(n_first + 1), -c, -pulled, margin])}

    @functools.cached_property
    def solver(self):
        """Clarabel set up on the trivial instance and solved once (cvxpy's first solve)."""
        import clarabel

        n, nb = self.n_joints, len(self.bodies)
        d_full = N_LINK_PARAMETERS * n
        data = self.data(np.zeros((self.dim, d_full + self.n_extra)), np.zeros(self.dim), 1.0,
                         np.zeros(d_full))
        cones = [*([clarabel.ZeroConeT(10 * nb)] if nb else []),
                 clarabel.NonnegativeConeT(2 * n + len(self.nonneg)),
                 clarabel.SecondOrderConeT(1 + self.dim + d_full),
                 *[clarabel.PSDTriangleConeT(4) for _ in range(n + nb)]]
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        solver = clarabel.DefaultSolver(data["P"], data["q"], data["A"], data["b"], cones,
                                        settings)
        solver.solve()
        return solver

    def parameters(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The full parameters ``p`` and the extras in Clarabel's solution ``x`` (each a
        variable with its sign or the sum of two, as cvxpy evaluates them)."""
        v1, s1, v2, s2, *_ = self._layout
        one = s1 * x[v1]
        pe = np.where(v2 >= 0, one + s2 * x[np.maximum(v2, 0)], one)
        d_full = N_LINK_PARAMETERS * self.n_joints
        return pe[:d_full], pe[d_full:]


def programme(n_joints: int, dim: int, n_extra: int, nonneg: tuple[int, ...],
              bodies: tuple[int, ...] = ()) -> Programme:
    """The :class:`Programme` of one model shape, built and set up once per thread (a
    solver takes one fit at a time; every thread's is set up alike, so gives the same
    numbers)."""
    return _programme(threading.get_ident(), n_joints, dim, n_extra, nonneg, bodies)


@functools.lru_cache(maxsize=256)  # a few shapes on each of the split threads
def _programme(thread: int, n_joints: int, dim: int, n_extra: int, nonneg: tuple[int, ...],
               bodies: tuple[int, ...]) -> Programme:
    return Programme(n_joints, dim, n_extra, nonneg, bodies)
