"""Excitation trajectories: a finite Fourier series per joint, the paper's Eq. 5-7.

Per joint (``docs/explanation/paper-notes.md`` Sec. 2; Eq. 5's printed signs are garbled, so
``q`` is the integral and ``qdd`` the derivative of Eq. 6)::

    qd(t)  = sum_k  a_k cos(k wf t) - b_k sin(k wf t)                        (Eq. 6)
    q(t)   = q0 + sum_k  a_k / (k wf) sin(k wf t) + b_k / (k wf) cos(k wf t) (Eq. 7)
    qdd(t) = sum_k -a_k k wf sin(k wf t) - b_k k wf cos(k wf t)              (Eq. 5)

``q0`` is the OFFSET of Eq. 7, not the start position: it is the mean position over a
period, so the design can centre the motion inside the position limits, and
``q(0) = q0 + sum_k b_k / (k wf)``. (Eq. 7 prints ``- b_k / (k wf) cos``, which is not an
integral of Eq. 6.) The series is periodic with period ``2 pi / wf``.

:class:`FourierTrajectory` is a JAX pytree (differentiable in its coefficients) with an
``.npz`` file format (:meth:`FourierTrajectory.save`, :meth:`FourierTrajectory.load`).
"""

from __future__ import annotations

import math
import os
import zipfile
import zlib
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _x64
from .._output import PathLike, atomic_write

#: The default fundamental frequency of :func:`~sedsabso_jax.design_excitation` [rad/s]:
#: one period in the 10 s experiment.
DEFAULT_WF = 2 * math.pi * 0.1
_FORMAT = "sedsabso-jax FourierTrajectory 1"
_KEYS = ("format", "a", "b", "q0", "wf")


def _concrete(x) -> bool:
    return not isinstance(x, jax.core.Tracer)


def _float_array(name: str, value, ndim: int) -> Array:
    _x64.require("an excitation trajectory")
    arr: Array | np.ndarray
    if isinstance(value, jax.core.Tracer):
        arr = value.astype(jnp.float64) if jnp.issubdtype(value.dtype, jnp.number) else value
    else:
        arr = np.asarray(value)
        if arr.dtype.kind not in "biuf":
            raise ValueError(f"{name} must be a real numeric array, got dtype {arr.dtype}")
        arr = arr.astype(np.float64)
    if arr.ndim != ndim:
        raise ValueError(f"{name} must be {ndim}-D, got shape {arr.shape}")
    if _concrete(arr) and not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or Inf")
    return jnp.asarray(arr, dtype=jnp.float64)


def check_wf(wf: float) -> float:
    """``wf`` as a float, or a ValueError unless it is a positive finite number (rad/s)."""
    try:
        wf = float(wf)
    except (TypeError, ValueError):
        raise ValueError(f"wf must be a positive number (rad/s), got {wf!r}") from None
    if not (math.isfinite(wf) and wf > 0):
        raise ValueError(f"wf must be a positive finite number (rad/s), got {wf}")
    return wf


def evaluate(a: Float[Array | np.ndarray, "n N"], b: Float[Array | np.ndarray, "n N"],
             q0: Float[Array | np.ndarray, " n"], kw: Float[Array | np.ndarray, " N"],
             c: Float[Array | np.ndarray, "*batch N"], s: Float[Array | np.ndarray, "*batch N"]
             ) -> tuple[Any, Any, Any]:
    """``(q, qd, qdd)`` from coefficients ``(n, N)`` and ``c = cos(k wf t)``,
    ``s = sin(k wf t)`` of shape ``(..., N)``; ``kw = k wf``. Returns ``(..., n)`` each
    (numpy for numpy arguments)."""
    qd = _mm(c, a.T) - _mm(s, b.T)
    q = q0 + _mm(s, (a / kw).T) + _mm(c, (b / kw).T)
    qdd = -_mm(s, (a * kw).T) - _mm(c, (b * kw).T)
    return q, qd, qdd


def _mm(x, y):
    # numpy stays numpy; JAX products at full precision (no TF32 passes for float32 on
    # a GPU)
    if isinstance(x, np.ndarray) and isinstance(y, np.ndarray):
        return x @ y
    return jnp.matmul(x, y, precision=jax.lax.Precision.HIGHEST)


def basis(times: Float[ArrayLike, "*batch"], n_harmonics: int, wf: float
          ) -> tuple[Float[Array, " N"], Float[Array, "*batch N"], Float[Array, "*batch N"]]:
    """``(k wf, cos(k wf t), sin(k wf t))`` for ``k = 1..N``, the last two ``t.shape + (N,)``."""
    kw = wf * jnp.arange(1, n_harmonics + 1, dtype=jnp.float64)
    phase = jnp.asarray(times, jnp.float64)[..., None] * kw
    return kw, jnp.cos(phase), jnp.sin(phase)


class FourierTrajectory(eqx.Module):
    """A finite Fourier series per joint (Eq. 5-7), a pytree; see the module docstring.

    Attributes:
        a: ``(n, N)`` cosine coefficients of the velocity (rad/s or m/s).
        b: ``(n, N)`` sine coefficients of the velocity.
        q0: ``(n,)`` position offset, the mean position over a period (NOT ``q(0)``).
        wf: fundamental angular frequency ``wf`` in rad/s (static).
    """

    a: Float[Array, "n N"]
    b: Float[Array, "n N"]
    q0: Float[Array, " n"]
    wf: float = eqx.field(static=True)

    def __init__(self, a: Float[ArrayLike, "n N"], b: Float[ArrayLike, "n N"],
                 q0: Float[ArrayLike, " n"], wf: float = DEFAULT_WF):
        a = _float_array("a", a, 2)
        b = _float_array("b", b, 2)
        q0 = _float_array("q0", q0, 1)
        if a.shape[0] < 1 or a.shape[1] < 1:
            raise ValueError(f"a must have shape (n_joints, n_harmonics), both >= 1, "
                             f"got {a.shape}")
        if b.shape != a.shape:
            raise ValueError(f"b must have the shape of a, {a.shape}, got {b.shape}")
        if q0.shape != (a.shape[0],):
            raise ValueError(f"q0 must have shape ({a.shape[0]},) (one per joint), "
                             f"got {q0.shape}")
        self.a, self.b, self.q0 = a, b, q0
        self.wf = check_wf(wf)

    @property
    def n_joints(self) -> int:
        return self.a.shape[0]

    @property
    def n_harmonics(self) -> int:
        return self.a.shape[1]

    @property
    def period(self) -> float:
        """``2 pi / wf`` in seconds."""
        return 2 * math.pi / self.wf

    def __call__(self, t: Float[ArrayLike, "*batch"]) -> tuple[Array, Array, Array]:
        """``(q, qd, qdd)`` at times ``t`` (seconds, any shape), each ``t.shape + (n,)``."""
        t = jnp.asarray(t)
        if not (jnp.issubdtype(t.dtype, jnp.floating) or jnp.issubdtype(t.dtype, jnp.integer)):
            raise ValueError(f"t must be real times in seconds, got dtype {t.dtype}")
        return evaluate(self.a, self.b, self.q0, *basis(t, self.n_harmonics, self.wf))

    def sample(self, times: Float[ArrayLike, " T"]
               ) -> tuple[Float[np.ndarray, "T n"], Float[np.ndarray, "T n"],
                          Float[np.ndarray, "T n"]]:
        """``(q, qd, qdd)`` at ``times (T,)`` in numpy, float64 (no JAX dispatch or
        compilation), each ``(T, n)``."""
        kw = self.wf * np.arange(1, self.n_harmonics + 1)
        phase = np.asarray(times, dtype=float)[:, None] * kw
        return evaluate(np.asarray(self.a), np.asarray(self.b), np.asarray(self.q0), kw,
                        np.cos(phase), np.sin(phase))

    def to_vector(self) -> Float[Array, " d"]:
        """Flat ``[a.ravel(), b.ravel(), q0]``, length ``n (2N + 1)`` (joint-major)."""
        return jnp.concatenate([self.a.ravel(), self.b.ravel(), self.q0])

    @classmethod
    def from_vector(cls, x: Float[ArrayLike, " d"], n_joints: int, n_harmonics: int,
                    wf: float = DEFAULT_WF) -> FourierTrajectory:
        """Inverse of :meth:`to_vector`."""
        n, N = int(n_joints), int(n_harmonics)
        if n < 1 or N < 1:
            raise ValueError(f"n_joints and n_harmonics must be >= 1, got {n}, {N}")
        x = jnp.asarray(x)
        if x.shape != (n * (2 * N + 1),):
            raise ValueError(f"x must have shape ({n * (2 * N + 1)},) = n_joints * (2 "
                             f"n_harmonics + 1) for {n} joints and {N} harmonics, "
                             f"got {x.shape}")
        return cls(x[: n * N].reshape(n, N), x[n * N: 2 * n * N].reshape(n, N),
                   x[2 * n * N:], wf)

    def save(self, path: PathLike) -> None:
        """Write ``.npz`` (keys ``format a b q0 wf``) atomically: a temporary file in the
        same directory, then ``os.replace``. The path is used as given."""
        arrays = {"format": np.array(_FORMAT), "a": np.asarray(self.a),
                  "b": np.asarray(self.b), "q0": np.asarray(self.q0),
                  "wf": np.array(self.wf, dtype=np.float64)}
        atomic_write(path, lambda fh: np.savez(fh, **arrays))  # type: ignore[arg-type]

    @classmethod
    def load(cls, path: PathLike) -> FourierTrajectory:
        """Read a file written by :meth:`save` (``np.load(allow_pickle=False)``: object
        arrays are refused, nothing is unpickled)."""
        path = os.fspath(path)
        try:
            data = np.load(path, allow_pickle=False)
        except OSError as err:
            raise ValueError(f"cannot read trajectory file {path!r}: {err}") from None
        except (ValueError, EOFError, zipfile.BadZipFile) as err:  # pickled data, bad zip
            raise ValueError(f"trajectory file {path!r} is not a valid .npz: {err}") from None
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ValueError(f"trajectory file {path!r} is a single .npy array, expected an "
                             f".npz with keys {list(_KEYS)}")
        with data:
            keys = set(data.files)
            missing = [k for k in _KEYS if k not in keys]
            unknown = sorted(keys - set(_KEYS))
            if missing or unknown:
                raise ValueError(f"trajectory file {path!r}: missing keys {missing}, unknown "
                                 f"keys {unknown}; expected exactly {list(_KEYS)}")
            arrays = {}
            for k in _KEYS:
                try:
                    arrays[k] = data[k]
                except ValueError as err:  # object arrays need pickle
                    raise ValueError(f"trajectory file {path!r}: key {k!r} cannot be loaded "
                                     f"without pickle ({err})") from None
                except (OSError, EOFError, zipfile.BadZipFile, zlib.error) as err:
                    raise ValueError(f"trajectory file {path!r}: key {k!r} is corrupt "
                                     f"({type(err).__name__}: {err})") from None
        fmt = arrays["format"]
        if fmt.shape != () or fmt.dtype.kind != "U" or str(fmt) != _FORMAT:
            raise ValueError(f"trajectory file {path!r}: key 'format' must be {_FORMAT!r}, "
                             f"got {fmt!r}")
        for k, ndim in (("a", 2), ("b", 2), ("q0", 1), ("wf", 0)):
            arr = arrays[k]
            if arr.dtype.kind not in "iuf":
                raise ValueError(f"trajectory file {path!r}: key {k!r} must be real numbers, "
                                 f"got dtype {arr.dtype}")
            if arr.ndim != ndim:
                raise ValueError(f"trajectory file {path!r}: key {k!r} must be {ndim}-D, got "
                                 f"shape {arr.shape}")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"trajectory file {path!r}: key {k!r} contains NaN or Inf")
        try:
            return cls(arrays["a"], arrays["b"], arrays["q0"], float(arrays["wf"]))
        except ValueError as err:
            raise ValueError(f"trajectory file {path!r}: {err}") from None

    def __repr__(self) -> str:
        return (f"FourierTrajectory(n_joints={self.n_joints}, n_harmonics={self.n_harmonics}, "
                f"wf={self.wf:.6g} rad/s, period={self.period:.6g} s)")
