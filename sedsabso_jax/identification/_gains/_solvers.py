"""The ways to solve the equations of :mod:`._equations`.

Each joint's rows are divided by its sigma, Gautier's two-step estimate (the RMS of the
joint's residual after an unweighted fit, then once more after the fit so weighted;
compressed once, :mod:`._compressed`). On the weighted rows ``W theta ~ b``:

- :class:`OrdinaryGains` (``ordinary``): least squares (minimum norm, columns scaled to
  unit norm). The currents are in the gains' columns: an errors-in-variables fit, whose
  gains the currents' noise biases toward zero (:mod:`._likelihood`).
- :class:`TotalGains` (``total``): total least squares of the homogeneous system
  ``[W, -b] [theta; 1] = 0`` (Gautier & Briot 2014; FIGAROH's drive-gain step): the right
  singular vector of the smallest singular value of the column-scaled ``[W, -b]``,
  normalised so that the known payload's coefficient is 1. It treats every column as
  noisy, the regressor's as much as the currents'.
- :class:`LikelihoodGains` (``likelihood``, the default): the maximum likelihood for noise
  in the currents (:mod:`._likelihood`), from the total least squares' estimate.
- :class:`PhysicalGains` (``physical``): the maximum likelihood's gains, then the model's
  values at those gains over the payloads a real body can be (its pseudo-inertia positive
  semidefinite, Wensing, Kim & Slotine, IEEE RA-L 2018) with its mass (and centre of mass)
  as known, and the model's terms' coefficients ``>= 0`` where a physical body has them
  so (the conic programme of :func:`~.._estimators._conic.statement`, Clarabel through
  cvxpy).

The standard deviations are those of the least squares (or of the likelihood's
linearisation) at the returned estimate (:func:`~._compressed.std`).
"""

from __future__ import annotations

import abc
import dataclasses
from typing import ClassVar

import equinox as eqx
import numpy as np

from .._estimators._conic import NOT_SOLVED, Placed, satisfied
from .._fit._uncertainty import RANK_TOLERANCE
from .._payload._least_squares import LinearFit
from ._compressed import compress
from ._equations import GainEquations, payload_columns
from ._likelihood import gain_map, maximum_likelihood


@dataclasses.dataclass(frozen=True, eq=False)
class Solution:
    """The unknowns ``theta`` (the free model values, then the gains), and for their
    standard deviations the weighted rows' Jacobian ``W`` and ``residual``, compressed
    (:mod:`._compressed`), the ``rows`` they stand for, and ``G``, the derivatives of
    ``theta`` by ``W``'s unknowns; the solver's ``report``."""

    theta: np.ndarray
    W: np.ndarray
    residual: np.ndarray
    rows: int
    G: np.ndarray
    report: dict


def compressed_rows(eq: GainEquations) -> tuple[np.ndarray, int, np.ndarray]:
    """``(R, T, acting)``: each joint's rows ``[X, b]`` (:attr:`GainEquations.rows`)
    compressed, the samples, and the unknowns acting on each joint."""
    X, b = eq.rows
    acting = np.count_nonzero(np.any(X != 0, axis=0), axis=-1)
    return compress(np.concatenate([X, b[..., None]], -1)), X.shape[0], acting


def weighted(R: np.ndarray, sigma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The compressed rows ``R`` divided by each joint's ``sigma``: ``(W, b)``."""
    u = R.shape[-1] - 1
    return ((R[..., :u] / sigma[:, None, None]).reshape(-1, u),
            (R[..., u] / sigma[:, None]).reshape(-1))


def gautier(R: np.ndarray, T: int, acting: np.ndarray) -> np.ndarray:
    """Each joint's sigma, Gautier's two-step estimate (module docstring)."""
    u = R.shape[-1] - 1
    sigma = np.ones(R.shape[0])
    for _ in range(2):
        x = LinearFit.of(*weighted(R, sigma)).x
        r2 = np.sum((R[..., :u] @ x - R[..., u]) ** 2, axis=-1)
        sigma = np.sqrt(r2 / np.maximum(T - acting, 1))
        sigma = np.where(sigma > 0, sigma, max(float(sigma.max()), 1e-300))
    return sigma


def total(W: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Total least squares of ``W theta ~ b`` (module docstring), on the columns scaled to
    unit norm and, where ``W`` is rank deficient, on the combinations of them it
    determines (the others are left at 0, as the minimum-norm least squares leaves them)."""
    norms = np.linalg.norm(W, axis=0)
    scale = np.where(norms > RANK_TOLERANCE * norms.max(initial=0.0), norms, np.inf)
    _, sv, Vt = np.linalg.svd(W / scale, full_matrices=False)
    rank = int(np.sum(sv > RANK_TOLERANCE * sv[0])) if sv.size and sv[0] > 0 else 0
    basis = Vt[:rank].T  # the determined combinations of the scaled columns
    # in an orthonormal basis of what they determine the scaled columns' perturbations
    # keep their norm; b scaled to unit norm
    z_norms = np.r_[np.ones(rank), max(float(np.linalg.norm(b)), 1e-300)]
    Zs = np.column_stack([(W / scale) @ basis, -b]) / z_norms
    unit = np.linalg.svd(Zs, full_matrices=False)[2][-1]
    if not abs(unit[-1]) > 1e-8:
        raise ValueError("total least squares: the smallest singular vector leaves out the "
                         "known payload: the payload's mass does not fix the scale")
    v = unit / z_norms
    return (basis @ (v[:-1] / v[-1])) / scale


def physical(eq: GainEquations, fit: LinearFit) -> tuple[np.ndarray, dict]:
    """The least squares of ``fit``'s rows over consistent payloads of the known mass and
    nonnegative term coefficients (module docstring): ``(theta, solver report)``."""
    position = {int(c): i for i, c in enumerate(eq.free)}
    index, known = np.full(10, -1), np.zeros(10)
    for row, column in enumerate(payload_columns(eq.model)):
        if int(column) in position:
            index[row] = position[int(column)]
        else:
            known[row] = eq.known[list(eq.fixed).index(column)]
    nonneg = tuple(position[int(c)] for c in np.flatnonzero(eq.model.nonnegative)
                   if int(c) in position)
    payload = Placed(index, np.where(index >= 0, fit.scale[np.maximum(index, 0)], 1.0), known)
    if satisfied(fit.x * fit.scale, nonneg, (payload,)):
        return fit.x, {"solver": NOT_SOLVED, "status": "optimal"}
    return fit.constrained(nonneg, (payload,), "drive gains",
                           "no consistent payload of the given mass was found")


class AbstractGainMethod(eqx.Module):
    """A way to solve the drive gains' equations (module docstring): :meth:`solve`."""

    name: eqx.AbstractClassVar[str]   # the command's ``--method`` word, the report's
    label: eqx.AbstractClassVar[str]  # what the text calls it

    @abc.abstractmethod
    def solve(self, eq: GainEquations) -> Solution:
        """The equations ``eq`` solved, on Gautier's weighted rows."""

    def first_stage(self) -> AbstractGainMethod:
        """The method of the first of two stages (a term waiting for fitted values)."""
        return self


class OrdinaryGains(AbstractGainMethod):
    """Least squares of the weighted rows (module docstring): the currents' noise biases
    the gains toward zero."""

    name: ClassVar[str] = "ordinary"
    label: ClassVar[str] = "ordinary least squares"

    def solve(self, eq: GainEquations) -> Solution:
        W, b, rows, report = weighted_rows(eq)
        theta = LinearFit.of(W, b).x
        return Solution(theta, W, W @ theta - b, rows, np.eye(W.shape[1]), report)


class TotalGains(AbstractGainMethod):
    """Total least squares (Gautier & Briot 2014; module docstring)."""

    name: ClassVar[str] = "total"
    label: ClassVar[str] = "total least squares"

    def solve(self, eq: GainEquations) -> Solution:
        W, b, rows, report = weighted_rows(eq)
        theta = total(W, b)
        return Solution(theta, W, W @ theta - b, rows, np.eye(W.shape[1]), report)


class LikelihoodGains(AbstractGainMethod):
    """The maximum likelihood for noise in the currents, from the total least squares'
    estimate (:mod:`._likelihood`): the default."""

    name: ClassVar[str] = "likelihood"
    label: ClassVar[str] = "maximum likelihood (noise in the currents)"

    def solve(self, eq: GainEquations) -> Solution:
        return _likelihood(eq, physical_payload=False)


class PhysicalGains(AbstractGainMethod):
    """The maximum likelihood's gains, the model's values refitted over physically
    consistent payloads of the given mass (module docstring)."""

    name: ClassVar[str] = "physical"
    label: ClassVar[str] = "maximum likelihood, the payload physically consistent"

    def solve(self, eq: GainEquations) -> Solution:
        return _likelihood(eq, physical_payload=True)

    def first_stage(self) -> AbstractGainMethod:
        return LikelihoodGains()


#: The command's words for the methods (module docstring).
GAIN_METHODS: dict[str, type[AbstractGainMethod]] = {
    m.name: m for m in (OrdinaryGains, TotalGains, LikelihoodGains, PhysicalGains)}


def weighted_rows(eq: GainEquations) -> tuple[np.ndarray, np.ndarray, int, dict]:
    """``eq``'s rows compressed and divided by Gautier's sigma: ``(W, b, rows, report)``
    (``rows``: the rows they stand for)."""
    R, T, acting = compressed_rows(eq)
    sigma = gautier(R, T, acting)
    W, b = weighted(R, sigma)
    return W, b, T * R.shape[0], {"sigma": sigma.tolist()}


def _likelihood(eq: GainEquations, physical_payload: bool) -> Solution:
    W, b, _, report = weighted_rows(eq)
    problem, x, h, s, found = maximum_likelihood(eq, total(W, b))
    report = {**report, **found}
    if physical_payload:
        x, solved = physical(eq, LinearFit.of(*problem.rows(h, s)))
        report["solver"] = solved
    return Solution(np.r_[x, 1.0 / h], problem.jacobian(x, h, s), problem.residual(x, h, s),
                    problem.samples * h.size, gain_map(x.size, h), report)
