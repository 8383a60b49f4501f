"""The links' physically consistent fit gives Clarabel what cvxpy would: its programme,
built entry for entry (``_estimators/_programme.py``), against the package's one statement
of the physically consistent least squares (``_estimators/_conic.py``, with links)
canonicalised by cvxpy; and that statement against the benchmark's own of the links' fit
(``benchmarks.physical_fit.cvxpy_programme``, how the package solved it before 0.21)."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.physical_fit import cvxpy_programme
from sedsabso_jax.identification._estimators._conic import solve_data, statement
from sedsabso_jax.identification._estimators._programme import Programme

#: (joints, rows of the factor, extras, extras >= 0, bodies among the extras)
SHAPES = [(2, 15, 0, (), ()), (2, 18, 3, (), ()), (2, 20, 13, (0, 1), (3,)),
          (3, 30, 25, (2,), (0, 14))]


def _instance(rng, n, dim, n_extra):
    """Data in units of ``||c||``; a third of ``M``'s entries zeros of either sign (the
    factor's zeros, and cvxpy's -0.0)."""
    M = rng.normal(size=(dim, 12 * n + n_extra))
    M[rng.random(M.shape) < 0.3] = 0.0
    M[rng.random(M.shape) < 0.1] = -0.0
    c = rng.normal(size=dim)
    return M, c / np.linalg.norm(c), float(rng.uniform(1e-3, 1.0)), rng.normal(size=12 * n)


@pytest.mark.parametrize("shape", SHAPES, ids=str)
def test_the_programme_is_cvxpys_to_the_byte(shape):
    """Clarabel's data (``A, b, q`` and the cones) and its solution's parameters are
    cvxpy's of the package's statement to the last bit (which states the benchmark's
    programme), for several instances solved one after another in either
    order (the set-up solver keeps one equilibration, as cvxpy's does)."""
    import cvxpy as cp

    n, dim, n_extra, nonneg, bodies = shape
    s = statement(dim, n_extra, nonneg, bodies, links=n).set_up()
    problem, (M, c, root, pulled), p, extras = s.problem, (s.M, s.c, s.root, s.pulled), s.p, s.z
    benchmark, values = cvxpy_programme(*shape)[:2]
    ours = Programme(*shape)
    rng = np.random.default_rng(sum(map(len, (nonneg, bodies))) + dim)
    instances = [_instance(rng, n, dim, n_extra) for _ in range(3)]
    theirs = []
    for instance in instances:
        M.value, c.value, root.value, pulled.value = instance
        data, _, _ = problem.get_problem_data(cp.CLARABEL)
        for v, given in zip(values, instance):
            v.value = given
        reference = benchmark.get_problem_data(cp.CLARABEL)[0]
        assert (reference["A"] != data["A"]).nnz == 0
        assert np.array_equal(reference["b"], data["b"])
        assert np.array_equal(reference["c"], data["c"])
        mine = ours.data(*instance)
        for key, cvx in (("A", data["A"]), ("b", data["b"]), ("q", data["c"])):
            got = mine[key]
            if key == "A":
                assert got.shape == cvx.shape
                assert np.array_equal(got.indptr, cvx.indptr)
                assert np.array_equal(got.indices, cvx.indices)
                got, cvx = got.data, cvx.data
            assert got.tobytes() == np.asarray(cvx, dtype=float).tobytes(), key
        dims = data["dims"]
        assert (dims.zero, dims.nonneg, dims.soc, dims.psd) == (
            10 * len(bodies), 2 * n + len(nonneg), [1 + dim + 12 * n], [4] * (n + len(bodies)))
        problem.solve(solver=cp.CLARABEL)
        theirs.append(np.concatenate([p.value, extras.value if extras is not None else []]))
    for k in (2, 0, 1):
        x, report = solve_data(ours.solver, ours.data(*instances[k]), "test", "none")
        assert report["status"] == "optimal"
        assert np.concatenate(ours.parameters(x)).tobytes() == theirs[k].tobytes()


def test_a_shared_statement_is_one_per_thread():
    """The terms-only fit's statement, shared by the fits of one shape, is one per thread
    (the threads that fit a validation's splits at once would otherwise set one problem's
    data under each other's solve), and the same one again on the same thread."""
    import threading

    from sedsabso_jax.identification._estimators._conic import shared_statement

    shape = (12, 12, (11,), (0,))
    here = shared_statement(*shape)
    there = []
    thread = threading.Thread(target=lambda: there.append(shared_statement(*shape)))
    thread.start()
    thread.join()
    assert shared_statement(*shape) is here and there[0] is not here
