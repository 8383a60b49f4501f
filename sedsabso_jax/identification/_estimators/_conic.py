"""The one conic programme of the physically consistent fits (the links' and the terms'
:mod:`._physical`, the payload's :func:`~.._payload._least_squares.consistent`, the drive
gains' :func:`~.._gains._solvers.physical`), stated once (:func:`statement`), and its
solve: Clarabel, its status checked and its report made alike. A statement is solved
through cvxpy (:meth:`Statement.solve`); the links' fit, hundreds of solves in one default
identification, gives Clarabel the statement's data directly (:func:`solve_data`, the
data built entry for entry by :class:`~._programme.Programme`)."""

from __future__ import annotations

import dataclasses
import functools
import threading
import time
import warnings
from typing import Any

import numpy as np

from ..._deprecation import caller_stacklevel
from ...dynamics._inertia import pseudo_inertia
from ._programme import PSD_MARGIN, inertial_params

#: The report of a fit whose least-squares solution already meets the constraints.
NOT_SOLVED = "none (the least-squares solution is consistent)"
#: Clarabel's statuses in cvxpy's words (its ``CLARABEL.STATUS_MAP``; any other one is
#: ``"solver_error"``), so that both ways of solving report alike without importing cvxpy.
STATUS = {"Solved": "optimal", "AlmostSolved": "optimal_inaccurate",
          "PrimalInfeasible": "infeasible", "DualInfeasible": "unbounded",
          "AlmostPrimalInfeasible": "infeasible_inaccurate",
          "AlmostDualInfeasible": "unbounded_inaccurate", "MaxIterations": "user_limit",
          "MaxTime": "user_limit"}


@dataclasses.dataclass(frozen=True, eq=False)
class Placed:
    """A body whose parameters stand among the unknowns ``z`` of :func:`statement`, each
    in its own unit: ``z[index[r]] = weight[r] * inertial_params(B)[r]`` where ``index[r]
    >= 0``, and ``inertial_params(B)[r] = known[r]`` where it is -1 (the gains' known
    mass). Stated by substitution (no equality between ``z`` and ``B``), it keeps
    Clarabel's accuracy whatever the columns' scales."""

    index: np.ndarray
    weight: np.ndarray
    known: np.ndarray

    def values(self, z: np.ndarray) -> np.ndarray:
        """The body's 10 parameters in ``z``."""
        placed = self.index >= 0
        out = np.array(self.known, dtype=float)
        out[placed] = z[self.index[placed]] / self.weight[placed]
        return out


#: A body among the unknowns ``z``: the start of its 10 parameters in a row (stated by an
#: equality, as :class:`~._programme.Programme` builds it), or :class:`Placed`.
Body = int | Placed


def satisfied(z: np.ndarray, nonneg: tuple[int, ...] = (), bodies: tuple[Body, ...] = ()
              ) -> bool:
    """Whether ``z`` meets :func:`statement`'s constraints (the links aside): then the
    least squares' own solution is the constrained optimum too, and no solve is needed."""
    own = (z[b:b + 10] if isinstance(b, int) else b.values(z) for b in bodies)
    return bool(np.all(z[list(nonneg)] >= 0)) and all(
        np.linalg.eigvalsh(pseudo_inertia(p)).min() >= PSD_MARGIN for p in own)


@dataclasses.dataclass(frozen=True, eq=False)
class Statement:
    """:func:`statement`'s cvxpy problem: its data as parameters (``M, c, root, pulled``)
    and its unknowns (``p``, the links' full parameters, an expression, or None; ``z``)."""

    problem: Any
    M: Any
    c: Any
    root: Any
    pulled: Any
    p: Any
    z: Any

    def set_up(self) -> Statement:
        """The statement solved once on the trivial instance (``M = 0, c = 0, root =
        1``), as :class:`~._programme.Programme`'s solver is: its equilibration is then
        every later solve's, so the same data give the same numbers after any other fits
        (for a statement many fits share; a statement solved once is better equilibrated
        on its own data)."""
        import cvxpy as cp

        for v in (self.M, self.c, self.pulled):
            v.value = np.zeros(v.shape)
        self.root.value = 1.0
        self.problem.solve(solver=cp.CLARABEL)
        return self

    def solve(self, M: np.ndarray, c: np.ndarray, root: float, pulled: np.ndarray,
              what: str, none_found: str, *, started: float | None = None
              ) -> tuple[np.ndarray, dict]:
        """``z`` at the optimum for these data and the report
        ``{"solver", "status", "iterations", "seconds"}``.

        Arguments:
            M, c, root, pulled: the data (:func:`statement`'s).
            what: the fit, as errors and warnings name it (``"payload"``).
            none_found: what a solve that ends neither optimal nor inaccurate did not find.
            started: ``time.perf_counter()`` when the fit began (None: now).

        Raises RuntimeError when the solver fails or ends not optimal; warns when it
        stops at its iteration limit or stalls (status ``optimal_inaccurate``: feasible,
        maybe off the optimum)."""
        import cvxpy as cp

        t0 = time.perf_counter() if started is None else started
        self.M.value, self.c.value, self.root.value, self.pulled.value = M, c, root, pulled
        try:
            self.problem.solve(solver=cp.CLARABEL)
        except cp.error.SolverError as err:
            raise RuntimeError(f"{what}: the conic solver failed: {err}") from None
        report = _checked(str(self.problem.status),
                          int(self.problem.solver_stats.num_iters or 0), "Clarabel (cvxpy)",
                          what, none_found, t0)
        return np.asarray(self.z.value, dtype=float), report


def statement(dim: int, n_z: int, nonneg: tuple[int, ...] = (), bodies: tuple[Body, ...] = (),
              links: int = 0) -> Statement:
    """The physically consistent least squares, stated in cvxpy (Wensing, Kim & Slotine,
    IEEE RA-L 2018: a body's parameters are physical exactly when its pseudo-inertia is
    positive semidefinite)::

        minimise ||[M pe - c; root r - pulled]||,   pe = [p, z],  r = p if links else z,
        J_i - PSD_MARGIN 1 >= 0,  friction >= 0,  z[nonneg] >= 0,
        B_k - PSD_MARGIN 1 >= 0,  (the body k's parameters in z) = inertial_params(B_k)

    over the ``links`` links' pseudo-inertias ``J_i`` and friction (``p``: each link's
    :func:`~._programme.inertial_params` of ``J_i``, then ``Fc, Fv``), the other unknowns
    ``z`` (``n_z``) and each body's pseudo-inertia ``B_k`` (:data:`Body`); ``M`` has ``dim``
    rows. The data are parameters (cvxpy canonicalises the statement once); Clarabel
    equilibrates the data of the first solve and keeps that for every later one
    (:meth:`Statement.set_up`)."""
    import cvxpy as cp

    d_full = 12 * links
    M = cp.Parameter((dim, d_full + n_z), name="M")
    c, root = cp.Parameter(dim, name="c"), cp.Parameter(nonneg=True, name="root")
    pulled = cp.Parameter(d_full if links else n_z, name="pulled")
    J = [cp.Variable((4, 4), symmetric=True, name=f"J{i + 1}") for i in range(links)]
    friction: Any = cp.Variable(2 * links, name="friction") if links else None
    placed = [b for b in bodies if isinstance(b, Placed)]
    B = [cp.Variable((4, 4), symmetric=True, name=f"body{k + 1}") for k in range(len(bodies))]
    z = _unknowns(n_z, placed, [Bk for Bk, b in zip(B, bodies) if isinstance(b, Placed)])
    p = cp.hstack([e for i in range(links) for e in
                   (*inertial_params(J[i]), friction[2 * i], friction[2 * i + 1])]) \
        if links else None
    pe = z if p is None else p if z is None else cp.hstack([p, z])
    constraints = [Ji - PSD_MARGIN * np.eye(4) >> 0 for Ji in J] + (
        [friction >= 0] if links else [])
    if nonneg:
        constraints.append(z[list(nonneg)] >= 0)
    for Bk, body in zip(B, bodies):
        constraints.append(Bk - PSD_MARGIN * np.eye(4) >> 0)
        own = cp.hstack(inertial_params(Bk))
        if isinstance(body, int):
            constraints.append(z[body:body + 10] == own)
        elif np.any(body.index < 0):
            constraints.append(own[list(np.flatnonzero(body.index < 0))]
                               == body.known[body.index < 0])
    r = p if links else z
    problem = cp.Problem(cp.Minimize(cp.norm(cp.hstack([M @ pe - c, root * r - pulled]))),
                         constraints)
    return Statement(problem, M, c, root, pulled, p, z)


def _unknowns(n_z: int, placed: list[Placed], B: list) -> Any:
    """``z`` as cvxpy sees it: a variable, or where bodies are :class:`Placed` in it, the
    variable of its other entries and each body's parameters put in their places."""
    import cvxpy as cp

    if not n_z:
        return None
    if not placed:
        return cp.Variable(n_z, name="z")
    taken = np.concatenate([b.index[b.index >= 0] for b in placed])
    free = np.setdiff1d(np.arange(n_z), taken)
    z = np.eye(n_z)[:, free] @ cp.Variable(free.size, name="z") if free.size else 0
    for b, Bk in zip(placed, B):
        put = np.zeros((n_z, 10))
        put[b.index[b.index >= 0], np.flatnonzero(b.index >= 0)] = b.weight[b.index >= 0]
        z = z + put @ cp.hstack(inertial_params(Bk))
    return z


def shared_statement(dim: int, n_z: int, nonneg: tuple[int, ...] = (),
                     bodies: tuple[int, ...] = ()) -> Statement:
    """:func:`statement` of a shape that many fits share (bodies as starts), stated once
    per thread (a cvxpy problem takes one solve at a time)."""
    return _shared(threading.get_ident(), dim, n_z, nonneg, bodies)


@functools.lru_cache(maxsize=64)
def _shared(thread: int, dim: int, n_z: int, nonneg: tuple[int, ...],
            bodies: tuple[int, ...]) -> Statement:
    return statement(dim, n_z, nonneg, bodies).set_up()


def solve_data(solver: Any, data: dict, what: str, none_found: str, *,
               started: float | None = None) -> tuple[np.ndarray, dict]:
    """Solve a programme given to Clarabel as data, as cvxpy solves a problem it has solved
    before (its warm start): ``solver`` (a ``clarabel.DefaultSolver`` set up once on the
    programme's shape) takes the new data by ``update`` and keeps the equilibration of
    the data it was set up with.

    Arguments:
        solver: the ``clarabel.DefaultSolver``.
        data: ``{"P", "q", "A", "b"}``, of the shapes it was set up with.
        what, none_found, started: as :meth:`Statement.solve`'s.

    Returns ``(x, report)``: Clarabel's primal solution and the report of
    :meth:`Statement.solve`."""
    t0 = time.perf_counter() if started is None else started
    settings = solver.get_settings()
    settings.verbose = False
    try:
        solver.update(**data, settings=settings)
        solution = solver.solve()
    except Exception as err:  # Clarabel's errors (bad data, a panic) have no common class
        raise RuntimeError(f"{what}: the conic solver failed: {err}") from None
    status = STATUS.get(str(solution.status), "solver_error")
    return (np.array(solution.x, dtype=float),
            _checked(status, int(solution.iterations), "Clarabel", what, none_found, t0))


def _checked(status: str, iterations: int, solver: str, what: str, none_found: str,
             started: float) -> dict:
    """The report of a solve that ended with ``status`` (cvxpy's words); raises where it
    is neither optimal nor inaccurate, warns where it is inaccurate."""
    if status not in ("optimal", "optimal_inaccurate"):
        raise RuntimeError(f"{what}: Clarabel ended with status {status!r}; {none_found}")
    if status == "optimal_inaccurate":
        warnings.warn(f"{what}: Clarabel reached its iteration limit or stalled (status "
                      f"'optimal_inaccurate'); the parameters are feasible but may be off "
                      f"the optimum", stacklevel=caller_stacklevel())
    return {"solver": solver, "status": status, "iterations": iterations,
            "seconds": time.perf_counter() - started}
