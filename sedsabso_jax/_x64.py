"""Float64 without touching the user's JAX: the package never turns on JAX's 64-bit mode
itself (importing it changes no configuration). Code that needs float64 (robots, the
regressor, base parameters, identification, excitation design) checks the mode where it
starts and stops with one line saying how to enable it; the optimisers run in whatever
mode the user chose (float32 when it is off). The ``sedsabso-jax`` command, an
application, turns the mode on for itself."""

from __future__ import annotations

import jax
import numpy as np
from jax.typing import DTypeLike

#: What to do, in one line.
HOW = ("call jax.config.update('jax_enable_x64', True) at the start of the program, before "
       "other JAX work (or set the environment variable JAX_ENABLE_X64=1)")


class Float64Required(RuntimeError):
    """Raised where float64 work is asked for while JAX's 64-bit mode is off."""


def enabled() -> bool:
    """Whether JAX's 64-bit mode is on."""
    return bool(jax.config.jax_enable_x64)  # type: ignore[attr-defined]


def require(what: str) -> None:
    """Raise :class:`Float64Required` naming ``what`` unless JAX's 64-bit mode is on."""
    if not enabled():
        raise Float64Required(f"{what} needs float64, and JAX's 64-bit mode is off: {HOW}")


def float_dtype(dtype: DTypeLike | None = None) -> np.dtype:
    """``dtype`` as float32 or float64 (None: float64 in JAX's 64-bit mode, else
    float32); float64 while the mode is off is an error saying how to turn it on."""
    import jax.numpy as jnp

    dtype = jnp.dtype((jnp.float64 if enabled() else jnp.float32) if dtype is None else dtype)
    if dtype not in (jnp.dtype(jnp.float32), jnp.dtype(jnp.float64)):
        raise ValueError(f"dtype must be float32 or float64, got {dtype}")
    if dtype == jnp.float64:
        require("dtype float64")
    return dtype
