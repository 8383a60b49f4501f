"""Dahl's presliding friction state along a recording (:class:`~._presliding.Presliding`).

Dahl (1968; P. R. Dahl, *A solid friction model*, Aerospace Corp. TOR-0158(3107-18)-1;
reviewed in Armstrong-Helouvry, Dupont and Canudas de Wit, *Automatica* 30(7), 1994,
https://doi.org/10.1016/0005-1098(94)90209-7, Eq. 10) writes the friction ``F`` of a
contact as a function of the distance travelled, not of the speed: with exponent 1,
``dF/dx = sigma (1 - F/F_c sign(v))``. Written for the normalised state ``z = F / F_c``
of each joint ``j`` and its characteristic displacement ``q_c = F_c / sigma`` (rad or m;
the displacement over which the friction builds up, ~63 %, after a reversal)::

    dz_j / dq_j = (1 - z_j sign(qd_j)) / q_c_j,     |z_j| <= 1,

so ``z`` relaxes to ``sign(qd)`` exponentially in the distance moved and keeps its value
while the joint stands still: it holds a torque at rest (presliding, the elastic
deformation of the contacts before they slide), which no function of the speed predicts.
Within one sampling interval the direction ``s = sign(dq)`` of the position increment
``dq`` is constant, and the equation integrates exactly::

    z_{k+1} = s_k + (z_k - s_k) a_k,    a_k = exp(-|dq_k| / q_c)        (exact, any |dq|)

(no step-size limit: a stiff ``q_c`` far below the increments gives ``z = sign(dq)``,
Coulomb's friction; ``dq = 0`` leaves ``z`` as it was). The increments are those of the
recorded positions, so the state is rate-independent, as Dahl's is. Each recording starts
from ``z = 0`` (the state before it is unknown).

The update is affine in ``z``, ``z_{k+1} = a_k z_k + b_k`` with ``b_k = s_k (1 - a_k)``
(a restart: ``a = b = 0``), and affine maps compose associatively, ``(a2, b2) o (a1, b1)
= (a2 a1, a2 b1 + b2)``: the whole recording is a prefix composition, which
``jax.lax.associative_scan`` computes in ``log2(T)`` parallel steps instead of ``T``
sequential ones (:data:`SEQUENTIAL` chooses per backend, :func:`dahl_state`). Why
Dahl's and not LuGre's: docs/explanation/identification-defaults.md.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, ArrayLike, Bool, Float

#: The backends on which :func:`dahl_state` runs the sequential ``lax.scan`` (the
#: others: the associative scan, which removes the ``T`` sequential steps; the timings:
#: docs/how-to/friction-at-rest.md).
SEQUENTIAL = ("cpu",)


def increments(q: Float[ArrayLike, "T n"], recording: ArrayLike | None = None
               ) -> tuple[Float[Array, "T n"], Bool[Array, " T"]]:
    """The position increments ``dq_k = q_k - q_{k-1}`` (``(T, n)``, 0 at a recording's
    first sample) and where each recording starts (``(T,)``): at sample 0 and wherever
    ``recording`` (each sample's recording, ``(T,)``; None: one recording) changes.
    Computed with ``jax.numpy`` (traced positions too: a compiled search's)."""
    q = jnp.asarray(q)
    if q.ndim != 2:
        raise ValueError(f"the presliding state needs positions (samples, joints) in time "
                         f"order, got shape {q.shape}")
    start = jnp.arange(q.shape[0]) == 0
    if recording is not None:
        index = jnp.asarray(recording)
        if index.shape != q.shape[:1]:
            raise ValueError(f"recording must hold one value per sample {q.shape[:1]}, got "
                             f"shape {index.shape}")
        start = start.at[1:].set(index[1:] != index[:-1])
    dq = q - jnp.concatenate([q[:1], q[:-1]])  # 0 at the first sample
    return jnp.where(start[:, None], 0.0, dq), start


def _steps(dq, start, q_c):
    """The affine maps ``z -> a z + b`` of each sample (module docstring)."""
    a = jnp.where(start[:, None], 0.0, jnp.exp(-jnp.abs(dq) / q_c))
    s = jnp.sign(dq)
    return a, jnp.where(start[:, None], 0.0, s - s * a)


def _compose(first, second):
    a1, b1 = first
    a2, b2 = second
    return a2 * a1, a2 * b1 + b2


@functools.partial(jax.jit, static_argnames="sequential")
def dahl_state(dq: Float[ArrayLike, "T n"], start: Bool[ArrayLike, " T"],
               q_c: Float[ArrayLike, " n"], *, sequential: bool | None = None
               ) -> Float[Array, "T n"]:
    """The state ``z`` (``(T, n)``, in ``[-1, 1]``) after each sample's increment ``dq``
    (:func:`increments`), from ``z = 0`` at each ``start``, for the characteristic
    displacements ``q_c`` (``(n,)``, > 0): the exact update of the module docstring, by
    a sequential ``lax.scan`` or an associative scan (``sequential`` None: per backend,
    :data:`SEQUENTIAL`); compiled once per shape, differentiable in ``q_c``, vmappable
    over populations of ``q_c``."""
    q_c = jnp.asarray(q_c)
    dq = jnp.asarray(dq, dtype=q_c.dtype)
    start = jnp.asarray(start)
    if sequential is None:
        sequential = jax.default_backend() in SEQUENTIAL
    if not sequential:
        return lax.associative_scan(_compose, _steps(dq, start, q_c))[1]

    def step(z, inputs):
        d, first = inputs
        z = jnp.where(first, jnp.zeros_like(z), z)
        s = jnp.sign(d)
        z = s + (z - s) * jnp.exp(-jnp.abs(d) / q_c)
        return z, z

    _, z = lax.scan(step, jnp.zeros(dq.shape[-1], q_c.dtype), (dq, start))
    return z

