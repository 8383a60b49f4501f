"""COCO's bbob suite in JAX (``sedsabso_jax.compare._coco``) against ``cocoex``, COCO's
own C code (coco-experiment), value by value: every function f1-f24 in dimensions 2, 3,
5, 10, 20 and 40, instances 1-15, at 5 random points of [-5, 5]^d, 2 points of [-7, 7]^d
(mostly outside the box: the penalties), 3 points near x_opt (1e-3 away) and x_opt
itself; in d = 2 also the instances of recent workshops (71-80, 101-110) and the largest
number. x_opt and f_opt equal COCO's ``best_parameter`` and ``best_value`` exactly.

Precision: ``|f - f_coco| <= 1e-10 max(|f_coco|, |f_coco - f_opt|)``. The scale is the
larger of the two terms COCO adds last (``f - f_opt`` and ``f_opt``): where they nearly
cancel, ``f_coco`` carries the rounding of the larger one, and a bare relative difference
means nothing (f19 near ``f = 0`` differs by 1e-10 of ``|f|`` for that reason alone).

Also: the compiled function under ``vmap`` and ``jit``, float64, one compilation for all
functions and instances of a dimension, and the one-line errors for bad arguments.
About 20-30 s on 2 cores (most of it one compilation per dimension and d = 40's
rotations).
"""

from __future__ import annotations

import jax
import numpy as np
import pytest

from sedsabso_jax.compare import coco_function
from sedsabso_jax.compare._coco import coco_args, coco_optimum, coco_value, coco_values
from sedsabso_jax.optim._fitness import BlackBox

cocoex = pytest.importorskip("cocoex")
if not hasattr(cocoex, "BareProblem"):
    pytest.skip("cocoex without BareProblem (coco-experiment >= 2.7)", allow_module_level=True)

DIMENSIONS = (2, 3, 5, 10, 20, 40)
INSTANCES = range(1, 16)
TOLERANCE = 1e-10


def points(rng, x_opt):
    """The 11 points of an instance (see the module's docstring)."""
    d = x_opt.shape[0]
    return np.concatenate([rng.uniform(-5, 5, (5, d)), rng.uniform(-7, 7, (2, d)),
                           x_opt + 1e-3 * rng.standard_normal((3, d)), x_opt[None]])


@pytest.mark.parametrize("dim", DIMENSIONS)
def test_every_function_and_instance_matches_cocoex(dim):
    rng = np.random.default_rng(dim)
    worst: dict[int, tuple[float, int]] = {}
    wrong_optimum = []
    for function in range(1, 25):
        for instance in INSTANCES:
            coco = cocoex.BareProblem("bbob", function, dim, instance)
            f_opt, x_opt = coco_optimum(function, instance, dim)
            if f_opt != coco.best_value() or not np.array_equal(x_opt, coco.best_parameter()):
                wrong_optimum.append((function, instance))
            X = points(rng, x_opt)
            want = coco(X)
            got = np.asarray(coco_values(X, coco_args(function, instance, dim)))
            scale = np.maximum(np.abs(want), np.abs(want - f_opt))
            rel = float(np.max(np.abs(got - want) / scale))
            if rel > worst.get(function, (-1.0, 0))[0]:
                worst[function] = (rel, instance)
    assert not wrong_optimum, f"d = {dim}: x_opt or f_opt differ from COCO's: {wrong_optimum}"
    bad = {f: w for f, w in worst.items() if not w[0] <= TOLERANCE}
    assert not bad, (f"d = {dim}: (largest relative difference, instance) per function "
                     f"above {TOLERANCE}: {bad}")


def test_recent_and_extreme_instance_numbers():
    """The instances of recent BBOB workshops (2018: 71-80, 2023: 101-110) and the largest
    number, in d = 2 (compiled above)."""
    rng = np.random.default_rng(7)
    for function in range(1, 25):
        for instance in (*range(71, 81), *range(101, 111), 2**31 - 1):
            coco = cocoex.BareProblem("bbob", function, 2, instance)
            f_opt, x_opt = coco_optimum(function, instance, 2)
            assert f_opt == coco.best_value() and np.array_equal(x_opt, coco.best_parameter())
            X = points(rng, x_opt)
            want = coco(X)
            got = np.asarray(coco_values(X, coco_args(function, instance, 2)))
            scale = np.maximum(np.abs(want), np.abs(want - f_opt))
            assert np.max(np.abs(got - want) / scale) <= TOLERANCE, (function, instance)


def test_function_is_compiled_vmappable_float64():
    f, f_opt, x_opt = coco_function(21, 3, 2)
    assert isinstance(f_opt, float) and isinstance(x_opt, np.ndarray) and x_opt.shape == (2,)
    X = np.random.default_rng(0).uniform(-5, 5, (3, 11, 2))
    X[2, 0], X[2, 1] = x_opt, np.nan
    batched = jax.jit(jax.vmap(f))(X)  # vmapped over a leading batch, inside a jit
    assert batched.shape == (3, 11) and batched.dtype == np.float64
    for k in range(3):
        np.testing.assert_array_equal(batched[k], f(X[k]))
    coco = cocoex.BareProblem("bbob", 21, 2, 3)
    np.testing.assert_allclose(batched[:2], coco(X[:2].reshape(-1, 2)).reshape(2, 11),
                               rtol=1e-12)
    assert float(batched[2, 0]) == pytest.approx(f_opt, abs=1e-12)
    assert np.isnan(batched[2, 1])  # NaN in, NaN out, as in COCO
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 2\)"):
        f(np.zeros((3, 4)))


def test_one_compilation_per_dimension():
    """Other functions and instances reuse the compiled code: they are arguments."""
    X = np.random.default_rng(1).uniform(-5, 5, (11, 2))
    coco_function(1, 1, 2)[0](X)
    compiled = coco_values._cache_size()
    for function in (2, 7, 16, 21, 22, 24):
        for instance in (1, 9, 71):
            coco_function(function, instance, 2)[0](X)
    assert coco_values._cache_size() == compiled

    evaluate = jax.jit(lambda fitness, X: fitness.evaluate(X))  # as the swarms see it
    for function in (1, 20, 23):
        fitness = BlackBox(coco_value, coco_args(function, 2, 2))
        np.testing.assert_array_equal(evaluate(fitness, X), coco_function(function, 2, 2)[0](X))
    assert evaluate._cache_size() == 1


@pytest.mark.parametrize("function, instance, dimension, match", [
    (0, 1, 5, r"function 0 .*from 1 to 24"),
    (25, 1, 5, r"function 25 .*from 1 to 24"),
    (2.0, 1, 5, r"function 2\.0 .*integer"),
    (True, 1, 5, r"function True .*integer"),
    (1, 0, 5, r"instance 0 .*from 1"),
    (1, -3, 5, r"instance -3 .*from 1"),
    (1, 1.5, 5, r"instance 1\.5 .*integer"),
    (1, 1, 1, r"dimension 1 .*from 2 to 44"),
    (1, 1, 45, r"dimension 45 .*from 2 to 44"),
    (1, 1, "5", r"dimension '5' .*integer"),
])
def test_bad_arguments(function, instance, dimension, match):
    with pytest.raises(ValueError, match=match) as info:
        coco_function(function, instance, dimension)
    assert "\n" not in str(info.value)
