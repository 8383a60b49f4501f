"""The last stage of a search (:func:`polish`): Newton's method on the loss's quadratic
model from finite differences around the best point, until the step's predicted gain is
below the loss's rounding, so that where a search ends does not depend on its path.

A grid's best point can turn on the loss's last bits, which differ between processors
(why, and what it moved: docs/explanation/identification-defaults.md, "The same answer on
every processor"); any path into the minimum's basin ends at the minimum instead:
Newton's method converges there quadratically, and stops where the step's predicted gain
``-g.d / 2`` is below :data:`FTOL` of the loss, the parameters then within about
``sqrt(FTOL N)`` of their standard deviations of the minimum (``N`` rows).

The model: the gradient by central differences, the Hessian's diagonal by second
differences and its other entries by forward differences, all ``1 + 2k + k(k-1)/2``
trials in one compiled call (the population's), step :data:`STEP` (the loss's rounding,
about 1e-14 of it, then moves the gradient by about 1e-11 of it and the Hessian by about
1e-8). Directions whose curvature is below what that rounding can tell from zero are
not stepped along (the data do not determine them), a parameter on a bound whose
gradient points out of the box is held there, and the parameters the caller holds (one
the loss does not feel) stay. A step whose predicted gain is below :data:`FTOL` of the
loss is not taken (it is within the loss's rounding); one the loss does not confirm is
halved, up to :data:`HALVINGS` times.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ._problem import SearchProblem, losses, on_bounds

#: The finite differences' step (log scale).
STEP = 1e-3
#: Newton's method stops when a step's predicted gain is below this fraction of the loss.
FTOL = 1e-13
#: The most times a step the loss does not confirm is halved.
HALVINGS = 8


@dataclasses.dataclass(frozen=True, eq=False)
class Polished:
    """What :func:`polish` returns: the point ``u``, its ``loss``, the trials made, the
    stencils evaluated (``steps``) and whether it stopped because the next step's gain
    was below :data:`FTOL` (``converged``)."""

    u: np.ndarray
    loss: float
    evaluations: int
    steps: int
    converged: bool


def stencil(k: int) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """The trials' offsets in steps (``(1 + 2k + k(k-1)/2, k)``: the point, each
    coordinate up and down, each pair up together) and the pairs."""
    E = np.eye(k)
    pairs = [(i, j) for i in range(k) for j in range(i + 1, k)]
    together = np.array([E[i] + E[j] for i, j in pairs]).reshape(-1, k)
    return np.concatenate([np.zeros((1, k)), E, -E, together]), pairs


def quadratic(f: np.ndarray, k: int, pairs: list[tuple[int, int]], h: float
              ) -> tuple[float, np.ndarray, np.ndarray]:
    """The loss, gradient and Hessian at the stencil's centre from its losses ``f``."""
    f0, up, down, both = f[0], f[1:k + 1], f[k + 1:2 * k + 1], f[2 * k + 1:]
    g = (up - down) / (2 * h)
    H = np.diag((up - 2 * f0 + down) / h ** 2)
    for (i, j), fij in zip(pairs, both):
        H[i, j] = H[j, i] = (fij - up[i] - up[j] + f0) / h ** 2
    return float(f0), g, H


def newton_step(g: np.ndarray, H: np.ndarray, free: np.ndarray, u: np.ndarray,
                lower: np.ndarray, upper: np.ndarray, floor: float) -> np.ndarray:
    """The Newton step on the ``free`` parameters (the others 0) within the box: a
    parameter the step takes out of the box goes to its bound and the others' step is
    solved again with it there. Along the Hessian's eigenvectors: none where the
    eigenvalue's magnitude is below ``floor`` (a curvature the loss's rounding cannot
    tell from 0), by its magnitude elsewhere (a direction of negative curvature is
    descended, not climbed)."""
    d = np.zeros_like(g)
    clipped = np.zeros_like(free)
    for _ in range(g.size):
        F = free & ~clipped
        if not F.any():
            break
        lam, V = np.linalg.eigh(H[np.ix_(F, F)])
        keep = np.abs(lam) > floor
        rhs = V.T @ (g[F] + H[np.ix_(F, clipped)] @ d[clipped])
        d[F] = -V[:, keep] @ (rhs[keep] / np.abs(lam[keep]))
        out = F & ((u + d < lower) | (u + d > upper))
        if not out.any():
            break
        d[out] = np.clip(u + d, lower, upper)[out] - u[out]
        clipped |= out
    return d


def polish(problem: SearchProblem, u: np.ndarray, loss: float, lower: np.ndarray,
           upper: np.ndarray, rtol: float, max_steps: int, batch: int | None = None,
           held: np.ndarray | None = None) -> Polished:
    """Newton's method from ``u`` (whose loss is ``loss``) within ``[lower, upper]``, at
    most ``max_steps`` steps (module docstring); ``rtol``: a step must not raise the loss
    by more than this fraction of it; ``batch``: evaluate the stencil in calls of this
    many trials (a size already compiled), else in one; ``held``: the parameters that
    stay where they are."""
    k = u.size
    offsets, pairs = stencil(k)
    u = on_bounds(u, lower, upper)
    held = np.zeros(k, dtype=bool) if held is None else np.asarray(held, dtype=bool)
    size = len(offsets) if batch is None else batch
    chunks = -(-len(offsets) // size)
    evaluations, steps, converged = 0, 0, False
    scale = abs(loss)
    for steps in range(1, max_steps + 1):
        trials = u + STEP * offsets
        padded = np.concatenate([trials, np.repeat(trials[:1], chunks * size - len(trials), 0)])
        f = np.concatenate([losses(problem, padded[c * size:(c + 1) * size])
                            for c in range(chunks)])[:len(trials)]
        evaluations += chunks * size
        if not np.isfinite(f).all():  # trials the loss cannot evaluate: no model, stay
            break
        f0, g, H = quadratic(f, k, pairs, STEP)
        if steps == 1:  # the size the loss's rounding is relative to: its trials'
            scale = max(scale, float(np.abs(f).max()))
        at_bound = ((u <= lower) & (g > 0)) | ((u >= upper) & (g < 0))
        floor = 4 * FTOL * scale / STEP ** 2
        d = newton_step(g, H, ~(at_bound | held), u, lower, upper, floor)
        if -0.5 * float(g @ d) <= FTOL * scale:  # within the loss's rounding
            converged = True
            break
        for _ in range(HALVINGS + 1):
            f_new = float(losses(problem, (u + d)[None])[0])
            evaluations += 1
            if f_new <= f0 + rtol * scale:
                break
            d = d / 2
        else:  # the model does not describe the loss here (a kink): stay
            break
        u, loss = u + d, f_new
    return Polished(u, loss, evaluations, steps, converged)
