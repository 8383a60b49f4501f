"""COCO's bbob suite, the 24 noiseless functions f1-f24 with COCO's numbered instances, in
JAX: the values ``cocoex`` returns (coco-experiment 2.8.2) to rounding, any dimension from
2 to 44. In float64, ``|f - f_coco| <= 1e-10 max(|f_coco|, |f_coco - f_opt|)`` (checked on
every function, dimensions 2-40, instances 1-15: tests/test_coco.py); COCO's x_opt and
f_opt exactly.

Hansen et al., "Real-parameter black-box optimization benchmarking 2009: noiseless
functions definitions", INRIA RR-6829 (2009). Reproduced from COCO's C sources
(github numbbo/coco, ``code-experiments/src/``): ``suite_bbob.c`` (seeds),
``suite_bbob_legacy_code.c`` (the random generator, x_opt, f_opt, rotations: in
:mod:`._coco_random`), the ``f_*.c`` allocators (each function's instance: in
:mod:`._coco_instances`) and their ``transform_vars_*.c`` / ``transform_obj_*.c``
(the evaluation: in :mod:`._coco_functions`).

Two forms:

- :func:`coco_function` ``(function, instance, dimension) -> (f, f_opt, x_opt)``: ``f``
  maps points ``(..., dimension)`` to values ``(...)`` (a population ``(n, dimension)``
  to ``n`` values), jit-compiled and vmappable; ``f_opt`` COCO's optimal value (float),
  ``x_opt`` its optimum (NumPy).
- For optimisers that must compile once for the whole suite: :func:`coco_value`
  ``(x, args)`` on ONE point, with the function and its instance in ``args``
  (:func:`coco_args`, a :class:`CocoArgs` of arrays whose shapes depend only on the
  dimension). ``lax.switch`` on ``args.fid`` picks the function at run time, so one
  compiled fitness serves all 24 functions and every instance of a dimension::

      fitness = BlackBox(coco_value, coco_args(function, instance, dimension))

  Batch points, not functions: vmapped over ``args`` with a batched ``fid``, the switch
  becomes a select that evaluates all 24 functions. :func:`coco_values` is the compiled
  population form, ``(X, args) -> values``.

Instance data (x_opt, f_opt, R, Q, Gallagher's peaks) are drawn once per (function,
instance, dimension) in NumPy float64 with COCO's own generator, bit for bit; an
evaluation is arithmetic on them. The package never turns on JAX's 64-bit mode: in
float32 the arrays and values are float32.
"""

from __future__ import annotations

import numbers
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import DTypeLike
from jaxtyping import Array, ArrayLike, Float, Int

from .. import _x64
from ._coco_functions import FUNCTIONS
from ._coco_instances import instance_data
from ._coco_random import MAX_DIMENSION

#: COCO's bbob suite: f1-f24.
COCO_FUNCTIONS = 24
#: The largest instance number: COCO's generator casts ``seed / 127773`` to ``int``.
MAX_INSTANCE = 2**31 - 1

# f17/f18 and f21/f22 share their code: one branch each
_UNIQUE = tuple(dict.fromkeys(FUNCTIONS))
_BRANCH_OF = np.array([_UNIQUE.index(fn) for fn in FUNCTIONS], dtype=np.int32)


class CocoArgs(NamedTuple):
    """What :func:`coco_value` reads: the function (``fid``, 0-based: f1 is 0) and its
    instance's data, the same fields and shapes for every function of a dimension ``d``
    (unused fields are zeros; see :mod:`._coco_instances` for each field's meaning per
    function)."""

    fid: Int[Array, ""]
    xopt: Float[Array, " d"]
    fopt: Float[Array, ""]
    R: Float[Array, "d d"]
    Q: Float[Array, "d d"]
    peaks: Float[Array, "101 d"]
    peak_scales: Float[Array, "101 d"]
    peak_weights: Float[Array, " 101"]


def _integer(value: Any, name: str, low: int, high: int, expected: str) -> int:
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    if not ok or not low <= int(value) <= high:
        raise ValueError(f"COCO bbob {name} {value!r} is not valid; expected {expected}")
    return int(value)


def check_instance(function: Any, instance: Any, dimension: Any) -> tuple[int, int, int]:
    """``(function, instance, dimension)`` as ints, or a one-line ValueError naming the
    bad one and what it must be."""
    return (_integer(function, "function", 1, COCO_FUNCTIONS,
                     f"an integer from 1 to {COCO_FUNCTIONS}"),
            _integer(instance, "instance", 1, MAX_INSTANCE,
                     f"an integer from 1 to {MAX_INSTANCE} (COCO's instance number)"),
            _integer(dimension, "dimension", 2, MAX_DIMENSION,
                     f"an integer from 2 to {MAX_DIMENSION} (COCO's rotations hold at "
                     f"most {MAX_DIMENSION} x {MAX_DIMENSION})"))


def coco_args(function: int, instance: int, dimension: int,
              dtype: DTypeLike | None = None) -> CocoArgs:
    """The runtime arguments of :func:`coco_value` for COCO's bbob ``function`` (1-24),
    ``instance`` (COCO's number: 1, 2, ...) in ``dimension`` dimensions, as JAX arrays of
    ``dtype`` (None: float64 in JAX's 64-bit mode, else float32). The data are drawn once
    per (function, instance, dimension) and kept."""
    function, instance, dimension = check_instance(function, instance, dimension)
    dtype = _x64.float_dtype(dtype)
    data = instance_data(function, instance, dimension)
    floats = (jnp.asarray(a, dtype=dtype) for a in (
        data.xopt, data.fopt, data.R, data.Q, data.peaks, data.peak_scales, data.peak_weights))
    return CocoArgs(jnp.asarray(function - 1, dtype=jnp.int32), *floats)


def coco_optimum(function: int, instance: int, dimension: int) -> tuple[float, np.ndarray]:
    """``(f_opt, x_opt)``: COCO's optimal value (``best_value``) and optimum
    (``best_parameter``) of the instance, float64."""
    function, instance, dimension = check_instance(function, instance, dimension)
    data = instance_data(function, instance, dimension)
    return data.f_opt, np.array(data.x_opt)


def coco_value(x: Float[Array, " d"], args: CocoArgs) -> Float[Array, ""]:
    """The value at one point ``x`` of the bbob function and instance in ``args``
    (:func:`coco_args`), f_opt included: a fitness ``fn(x, args)`` for
    :class:`~sedsabso_jax.optim._fitness.BlackBox`. The function is chosen at run time,
    so the same compiled code serves every function and instance of a dimension. NaN in
    ``x`` gives NaN, as in COCO."""
    value = jax.lax.switch(jnp.asarray(_BRANCH_OF)[args.fid], _UNIQUE, x, args)
    return jnp.where(jnp.any(jnp.isnan(x)), jnp.nan, value)


def _values(X, args):
    flat = X.reshape((-1, X.shape[-1]))
    return jax.vmap(coco_value, in_axes=(0, None))(flat, args).reshape(X.shape[:-1])


#: ``(X, args) -> values``: compiled once per dimension, batch shape and dtype, for all
#: functions and instances (``args`` are arguments, not constants).
coco_values = jax.jit(_values)


def coco_function(function: int, instance: int, dimension: int
                  ) -> tuple[Callable[[Float[ArrayLike, "*batch d"]], Float[Array, "*batch"]],
                             float, np.ndarray]:
    """COCO's bbob ``function`` (1-24), ``instance`` (COCO's instance number: 1, 2, ...)
    in ``dimension`` dimensions (2-44): ``(f, f_opt, x_opt)``.

    ``f(X)`` evaluates the points ``X`` of shape ``(..., dimension)`` (a population
    ``(n, dimension)`` gives ``n`` values), f_opt included, as ``cocoex`` does to
    rounding; it runs compiled code (one compilation per dimension and batch shape,
    shared by all functions and instances) and can be vmapped and jitted. ``f_opt`` is
    COCO's optimal value, ``x_opt`` (NumPy, float64) its optimum (``f(x_opt)`` is
    ``f_opt`` to rounding).
    Bad arguments raise a one-line ValueError.

    Hansen et al., "Real-parameter black-box optimization benchmarking 2009: noiseless
    functions definitions", INRIA RR-6829 (2009); COCO's ``suite_bbob.c``."""
    args = coco_args(function, instance, dimension)
    f_opt, x_opt = coco_optimum(function, instance, dimension)

    def f(X: Float[ArrayLike, "*batch d"]) -> Float[Array, "*batch"]:
        X = jnp.asarray(X)
        if X.ndim == 0 or X.shape[-1] != dimension:
            raise ValueError(f"points must have shape (..., {dimension}), got {X.shape}")
        return coco_values(X, args)

    f.__doc__ = f"COCO bbob f{function}, instance {instance}, d = {dimension}."
    return f, f_opt, x_opt
