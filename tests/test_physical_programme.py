"""The links' physically consistent fit gives Clarabel what cvxpy would: its programme,
built entry for entry (``_estimators/_programme.py``), against the same programme stated in
cvxpy (``benchmarks.physical_fit.cvxpy_programme``) and canonicalised by cvxpy."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.physical_fit import cvxpy_programme
from sedsabso_jax.identification._estimators._conic import solve_data
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
    cvxpy's to the last bit, for several instances solved one after another in either
    order (the set-up solver keeps one equilibration, as cvxpy's does)."""
    import cvxpy as cp

    n, dim, n_extra, nonneg, bodies = shape
    problem, (M, c, root, pulled), p, extras = cvxpy_programme(*shape)
    ours = Programme(*shape)
    rng = np.random.default_rng(sum(map(len, (nonneg, bodies))) + dim)
    instances = [_instance(rng, n, dim, n_extra) for _ in range(3)]
    theirs = []
    for values in instances:
        M.value, c.value, root.value, pulled.value = values
        data, _, _ = problem.get_problem_data(cp.CLARABEL)
        mine = ours.data(*values)
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
