"""Maximum likelihood of the drive gains when the recorded currents carry the noise.

The equations of :mod:`._equations` hold the currents in the gains' columns: least
squares on them is an errors-in-variables fit, and its gains are biased toward zero by
the noise that the other columns cannot explain. The other columns explain nearly all of
a current (the robot's torque over its gain), so the payload's share is what is left
(the bias measured: docs/how-to/current-controlled.md). The model of the data is
instead::

    c_m(t) = h_m (K^-T (Y x + Y_p p))_m(t) + e_m(t),     h_m = 1 / g_m

each motor's current the torque over its gain, ``e_m`` Gaussian of standard deviation
``s_m``. The maximum-likelihood estimate minimises ``sum_m |r_m|^2 / s_m^2`` with ``r_m =
h_m (K^-T (Y x + k))_m - c_m`` (``k`` the known payload's torque), bilinear in ``(x, h)``:
Gauss-Newton on both from the total least squares' estimate, each step a least squares
of the Jacobian (``dr/dx = h_m (K^-T Y)_m``, ``dr/dh_m = (K^-T (Y x + k))_m``) on the
motors' compressed rows (:mod:`._compressed`), halved while it does not lower the
loss; ``s_m`` is the RMS of each motor's residual, estimated at the start and once more
at the first optimum (as Gautier's two-step weights). It is
the structured total least squares of the equations (Markovsky & Van Huffel, Signal
Processing 87(10), 2007): a current's error perturbs its own gain's column only.
"""

from __future__ import annotations

import numpy as np

from .._payload._least_squares import LinearFit
from ._compressed import compress
from ._equations import GainEquations

#: Gauss-Newton stops when no gain moves by more than this fraction of itself.
TOLERANCE = 1e-10
#: The most Gauss-Newton steps per pass.
STEPS = 50


class Likelihood:
    """The residual and Jacobian of the maximum-likelihood problem of ``eq`` (module
    docstring), in current units over each motor's ``s``, on each motor's rows ``[K^-T Y,
    K^-T k, c]`` compressed once (:mod:`._compressed`): for ``v_m = [h_m x; h_m; -1]``
    the motor's residual is ``R_m v_m / s_m``."""

    def __init__(self, eq: GainEquations):
        inverse = np.linalg.inv(eq.motors.T)  # g * c = K^-T tau
        Y = np.einsum("mj,tjd->tmd", inverse, eq.A[..., eq.free])
        k = eq.known_torque @ inverse.T
        self.p, self.samples = eq.free.size, Y.shape[0]
        self.acting = np.count_nonzero(np.any(Y != 0, axis=0), axis=-1) + 1
        self.R = compress(np.concatenate([Y, k[..., None], eq.current[..., None]], -1))

    def _coefficients(self, x: np.ndarray, h: np.ndarray) -> np.ndarray:
        return np.concatenate([h[:, None] * x, h[:, None], -np.ones((h.size, 1))], -1)

    def residual(self, x: np.ndarray, h: np.ndarray, s: np.ndarray) -> np.ndarray:
        v = self._coefficients(x, h)
        return (np.einsum("mij,mj->mi", self.R, v) / s[:, None]).reshape(-1)

    def jacobian(self, x: np.ndarray, h: np.ndarray, s: np.ndarray) -> np.ndarray:
        """The residual's derivatives by ``x`` and ``h``, ``(m (p + 2), p + m)``."""
        m, p = h.size, self.p
        D = np.zeros((m, p + 2, p + m))  # dv_m / d(x, h)
        D[:, np.arange(p), np.arange(p)] = h[:, None]
        D[np.arange(m), :p, p + np.arange(m)] = x
        D[np.arange(m), p, p + np.arange(m)] = 1.0
        return (np.einsum("mij,mjk->mik", self.R, D) / s[:, None, None]).reshape(-1, p + m)

    def rows(self, h: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The least squares in ``x`` at the gains ``1 / h``: ``(W, b)``."""
        p = self.p
        W = self.R[..., :p] * (h / s)[:, None, None]
        b = (self.R[..., p + 1] - h[:, None] * self.R[..., p]) / s[:, None]
        return W.reshape(-1, p), b.reshape(-1)

    def spread(self, x: np.ndarray, h: np.ndarray) -> np.ndarray:
        """Each motor's residual RMS over its samples less the unknowns acting on it."""
        r2 = np.sum(np.einsum("mij,mj->mi", self.R, self._coefficients(x, h)) ** 2, -1)
        s = np.sqrt(r2 / np.maximum(self.samples - self.acting, 1))
        return np.where(s > 0, s, max(float(s.max()), 1e-300))

    def optimum(self, x: np.ndarray, h: np.ndarray, s: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, int]:
        """Gauss-Newton from ``(x, h)`` with the weights ``s``: ``(x, h, steps)``."""
        loss = float(np.sum(self.residual(x, h, s) ** 2))
        for step in range(1, STEPS + 1):
            r = self.residual(x, h, s)
            delta = LinearFit.of(self.jacobian(x, h, s), -r).x
            t = 1.0
            while t > 1e-6:
                nx, nh = x + t * delta[:self.p], h + t * delta[self.p:]
                new = float(np.sum(self.residual(nx, nh, s) ** 2))
                if new <= loss:
                    break
                t /= 2
            else:
                return x, h, step
            x, h, loss = nx, nh, new
            if np.all(np.abs(t * delta[self.p:]) <= TOLERANCE * np.abs(h)):
                return x, h, step
        return x, h, STEPS


def maximum_likelihood(eq: GainEquations, start: np.ndarray
                       ) -> tuple[Likelihood, np.ndarray, np.ndarray, np.ndarray, dict]:
    """The maximum-likelihood estimate from ``start`` (the unknowns: free values, then
    gains): ``(problem, x, h, s, report)``."""
    problem = Likelihood(eq)
    x, g = start[:problem.p], start[problem.p:]
    if not np.all(np.isfinite(g)) or np.any(g == 0):
        joints = [int(j) + 1 for j in np.flatnonzero(~np.isfinite(g) | (g == 0))]
        raise ValueError(f"drive gains: the data do not determine the gains of joints (or "
                         f"motors) {joints}: a first total least-squares fit gives them 0 or "
                         f"none; record motions of every joint with the payload and without "
                         f"it, or give those gains")
    h = 1.0 / g
    steps = []
    for _ in range(2):  # the weights at the start, then at the first optimum
        s = problem.spread(x, h)
        x, h, k = problem.optimum(x, h, s)
        steps.append(k)
    return problem, x, h, s, {"gauss_newton_steps": steps, "current_sigma": s.tolist()}


def gain_map(p: int, h: np.ndarray) -> np.ndarray:
    """The derivatives of the unknowns ``(x, g)`` by the Jacobian's ``(x, h)``, ``g = 1 /
    h``: what carries the standard deviations over."""
    G = np.zeros((p + h.size, p + h.size))
    G[:p, :p] = np.eye(p)
    G[p:, p:] = np.diag(-1.0 / h ** 2)
    return G
