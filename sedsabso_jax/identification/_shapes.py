"""Fitting a torque model that takes more than one linear fit
(:attr:`~._model.TorqueModel.nonlinear`), with any estimator:

- **velocity scales** of terms with ``fitted=True`` (:class:`~._terms.SmoothCoulomb`,
  :class:`~._terms.Stribeck`): a few numbers, nearly separable by joint, searched in log
  scale within their bounds by Powell's method (scipy; a coordinate-wise search, which
  matched CMA-ES on such scales), each trial a least-squares fit of the rest (variable
  projection), then the estimator's fit with the scales found; their standard
  deviations from the residual's Jacobian (``s^2 (J^T J)^-1``, the scales and the linear
  values together) and whether they ended on a bound;
- **friction that grows with the transmitted torque** (:class:`~._terms.LoadFriction`):
  its columns read the rigid-body torque of the model's own parameters, a bilinear
  problem. Two stages: the load is the rigid-body torque of an ordinary least-squares
  fit of the model without the load terms (or the model's load point where one is set),
  then the estimator fits the model with that load. Each stage is a linear fit, so it
  works for every estimator (least squares, physically consistent, L1, a box search),
  where a joint solve of the bilinear problem would need each one's nonlinear form.
  ``LoadFriction(fixed_point=True)`` goes on to a fixed point: fit with the load of the
  last fit's parameters until the load changes by less than :data:`LOAD_RTOL`. The
  fitted model keeps the load its fit used (its load point), and predicts with it.
  Measured on the KUKA LWR4+ and the Staubli TX40 (offset, smooth Coulomb and load
  friction, + coupling on the TX40; the default's validation; OLS unconstrained and
  physically consistent): the fixed point took 6-30 fits (unconstrained on the KUKA it
  did not settle in 30), validated 0.389 % and 0.230 % on the KUKA against the two
  stages' 0.320 % and 0.219 %, and on the TX40 within 0.2 % of them (1.865 % and
  1.830 % against 1.867 % and 1.834 %), 1.2-3.6 times slower.

:func:`fit` does both (the load's first stage, then the scales' search with that load,
then the estimator's fit) and returns the model as fitted (scales and load point set)
with the linear fit.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
from scipy.optimize import minimize

from .._deprecation import caller_stacklevel
from ._compressed import NormalEquations
from ._estimators import OLS
from ._fitting import Estimator, EstimatorFit, FitProblem
from ._model import TorqueModel

#: The fixed point of load-dependent friction stops when the rigid-body torque changes by
#: less than this fraction of its largest value (the conic solver's own precision: a
#: physically consistent fit jitters at about 1e-6), or after :data:`LOAD_ITERATIONS`.
LOAD_RTOL = 1e-5
#: The most fits of the load's fixed point.
LOAD_ITERATIONS = 30
#: A fitted velocity scale within this factor of a bound counts as on it.
AT_BOUND = 1.02


@dataclasses.dataclass(frozen=True, eq=False)
class Samples:
    """The samples a fit reads, each ``(T, n)`` (``recording``: each sample's recording,
    ``(T,)``, or None), in time order within each recording. A :meth:`subset` remembers
    the samples it was taken from (``whole``, and the indices ``keep`` into them): a
    model whose columns integrate a state along the recording
    (:attr:`~._model.TorqueModel.stateful`) has a subset's rows computed on the whole
    samples, then taken, so the state never jumps over the samples left out.
    ``compressed``: a least-squares estimator may fit them through their normal
    equations (:mod:`._compressed`: a validation's training subsets, whose fits are only
    judged by their predictions)."""

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    recording: np.ndarray | None = None
    compressed: bool = False
    _base_rows: dict = dataclasses.field(default_factory=dict, repr=False)
    whole: Samples | None = None
    keep: np.ndarray | None = None

    def _recording(self, model: TorqueModel) -> np.ndarray | None:
        return self.recording if model.recordings > 1 or model.stateful else None

    def rows(self, model: TorqueModel, every_column: bool = False) -> np.ndarray:
        """``model``'s regressor at these samples, ``(T, n, d)`` (the base regressor
        computed once per set of base parameters; ``every_column``: as
        :meth:`~._model.TorqueModel.regressor`'s)."""
        if model.stateful and self.whole is not None:
            return self.whole.rows(model, every_column)[self.keep]
        key = id(model.base)
        if key not in self._base_rows:
            self._base_rows[key] = (model.base, np.asarray(
                model.base.regressor(self.q, self.qd, self.qdd)))
        return model.regressor(self.q, self.qd, self.qdd, self._recording(model),
                               base_rows=self._base_rows[key][1], every_column=every_column)

    def subset(self, keep: np.ndarray) -> Samples:
        """The samples ``keep`` selects (a validation's split: ``compressed``), with the
        base regressor's rows computed so far."""
        index = np.arange(self.q.shape[0])[keep]
        whole, index = (self, index) if self.whole is None else (
            self.whole, np.asarray(self.keep)[index])
        return Samples(self.q[keep], self.qd[keep], self.qdd[keep], self.tau[keep],
                       None if self.recording is None else self.recording[keep], True,
                       {k: (base, Y[keep]) for k, (base, Y) in self._base_rows.items()},
                       whole=whole, keep=index)

    def predict(self, model: TorqueModel, values: np.ndarray) -> np.ndarray:
        """``model``'s torques with ``values`` at these samples (as
        :meth:`~._model.TorqueModel.predict`, from the rows computed so far)."""
        values = np.asarray(values, dtype=float)
        if values.shape != (model.dim,):
            raise ValueError(f"values must have shape ({model.dim},), got {values.shape}")
        return self.rows(model.at_load_of(values)) @ values


@dataclasses.dataclass(frozen=True, eq=False)
class Fitted:
    """What :func:`fit` returns: the ``model`` as fitted (its searched scales and load
    point set), the linear ``fit`` of it, its rows ``Y`` and a JSON-ready ``report``
    (``shapes``: each scale's value, standard deviation and whether it is on a bound;
    ``load``: the fixed point's iterations, last change and whether it settled)."""

    model: TorqueModel
    fit: EstimatorFit
    Y: np.ndarray
    report: dict


def linear(estimator: Estimator, model: TorqueModel, samples: Samples,
           limits: np.ndarray | None, warn: bool = True) -> tuple[EstimatorFit, np.ndarray]:
    """One linear fit of ``model`` (its scales and load point as they are), through
    the normal equations where the samples are ``compressed`` and the estimator reads
    them."""
    Y = samples.rows(model)
    if samples.compressed and estimator.normal_equations:
        problem = NormalEquations.of(Y, samples.tau).problem(model, limits)
        return estimator.fit(problem), Y
    return estimator.fit(FitProblem(model, Y, samples.tau, limits, warn)), Y


def fit(estimator: Estimator, model: TorqueModel, samples: Samples,
        limits: np.ndarray | None, warn: bool = True) -> Fitted:
    """Fit ``model`` to ``samples`` with ``estimator`` (module docstring); a linear model
    takes one fit."""
    report: dict = {}
    if model.needs_load and model.load_point is None:
        model = _first_stage(model, samples)
    if model.shapes():
        model = _search_shapes(estimator, model, samples, limits)
    if model.needs_load:
        model, out, Y, report["load"] = _settle_load(estimator, model, samples, limits, warn)
    else:
        out, Y = linear(estimator, model, samples, limits, warn)
    if model.shapes():
        report["shapes"] = _shape_report(model, out, samples)
    return Fitted(model, out, Y, report)


def _search_shapes(estimator: Estimator, model: TorqueModel, samples: Samples,
                   limits: np.ndarray | None) -> TorqueModel:
    """The scales minimising the least-squares residual (per-joint weights: the torque
    limits' for an estimator weighting by them, else equal), the other values solved in
    closed form for each (variable projection): the columns the scales do not touch
    enter once, through their normal equations, so a trial costs the touched columns
    only. The estimator itself then fits with the scales found."""
    found = [s for _, s in model.shapes()]
    z0 = np.log(np.concatenate([s.values for s in found]))
    lo = np.log(np.concatenate([s.lower for s in found]))
    hi = np.log(np.concatenate([s.upper for s in found]))
    w = 1.0 / limits if estimator.weights == "limits" and limits is not None else None

    def rows(z: np.ndarray) -> np.ndarray:  # every column: which regroup may change
        Y = samples.rows(model.with_shapes(np.exp(z)), every_column=True)
        return Y if w is None else Y * w[:, None]

    tau = samples.tau if w is None else samples.tau * w
    Y0 = rows(z0)
    moved = np.any(rows(z0 + 0.5) != Y0, axis=(0, 1))  # the columns the scales touch
    A, b = Y0[..., ~moved].reshape(-1, int((~moved).sum())), tau.reshape(-1)
    AtA, Atb, btb = A.T @ A, A.T @ b, float(b @ b)

    def loss(z: np.ndarray) -> float:
        C = rows(z)[..., moved].reshape(b.size, -1)
        AtC = A.T @ C
        G = np.block([[AtA, AtC], [AtC.T, C.T @ C]])
        h = np.concatenate([Atb, C.T @ b])
        x = np.linalg.lstsq(G, h, rcond=None)[0]
        return btb - 2 * float(x @ h) + float(x @ G @ x)

    best = minimize(loss, z0, method="Powell", bounds=list(zip(lo, hi)),
                    options={"xtol": 1e-3, "ftol": 1e-10, "maxfev": 60 * z0.size})
    return model.with_shapes(np.exp(best.x))


def _shape_report(model: TorqueModel, out: EstimatorFit, samples: Samples) -> dict:
    """Each searched scale's value, standard deviation (``s^2 (J^T J)^-1`` of the
    weighted residual over the log scales and the linear values, by central
    differences) and whether it ended on a bound."""
    found = [s for _, s in model.shapes()]
    names = [n for s in found for n in s.names]
    theta = np.concatenate([s.values for s in found])
    lower = np.concatenate([s.lower for s in found])
    upper = np.concatenate([s.upper for s in found])
    sigma = np.asarray(out.sigma, dtype=float)

    def residual(z: np.ndarray) -> np.ndarray:
        Y = samples.rows(model.with_shapes(np.exp(z)))
        return ((Y @ out.x - samples.tau) / sigma).reshape(-1)

    z, h = np.log(theta), 1e-4
    r = residual(z)
    Jz = np.stack([(residual(z + h * e) - residual(z - h * e)) / (2 * h)
                   for e in np.eye(z.size)], -1)
    W = (samples.rows(model) / sigma[:, None]).reshape(r.size, -1)
    J = np.concatenate([Jz, W], -1)
    dof = max(r.size - J.shape[1], 1)
    std = theta * _std(J, r @ r / dof)[:z.size]  # d theta = theta d z
    return {name: {"value": float(t), "std": float(s),
                   "at_bound": bool(t <= lower[i] * AT_BOUND or t >= upper[i] / AT_BOUND)}
            for i, (name, t, s) in enumerate(zip(names, theta, std))}


def _std(J: np.ndarray, s2: float, rtol: float = 1e-10) -> np.ndarray:
    """Each parameter's standard deviation ``sqrt(s2 diag((J^T J)^-1))`` from the SVD of
    ``J`` with unit-norm columns: ``inf`` for a parameter with a part in a direction the
    rows do not determine (a singular value below ``rtol`` of the largest)."""
    norms = np.linalg.norm(J, axis=0)
    scale = np.where(norms > 0, norms, 1.0)
    _, sv, Vt = np.linalg.svd(J / scale, full_matrices=False)
    ok = sv > rtol * sv.max()
    var = (Vt[ok] ** 2 / sv[ok, None] ** 2).sum(0) * s2 / scale ** 2
    free = np.abs(Vt[~ok]).max(0) > 1e-6 if (~ok).any() else np.zeros(J.shape[1], bool)
    return np.where(free | (norms == 0), np.inf, np.sqrt(var))


def _first_stage(model: TorqueModel, samples: Samples) -> TorqueModel:
    """``model`` with its load point at an ordinary least-squares fit of the model
    without its load terms (the first of the load's two stages)."""
    plain = dataclasses.replace(model, terms=tuple(t for t in model.terms if not t.needs_load))
    first, _ = linear(OLS(), plain, samples, None, False)
    return model.linearized_at(first.x)  # its base part: the same base columns


def _settle_load(estimator: Estimator, model: TorqueModel, samples: Samples,
                 limits: np.ndarray | None, warn: bool
                 ) -> tuple[TorqueModel, EstimatorFit, np.ndarray, dict]:
    """The load-dependent friction's fit (module docstring): the load of a first fit,
    then the estimator's fit with it; a fixed point where a term asks for one."""
    settle = model.load_fixed_point
    rigid = model.rigid_columns
    load = None
    change = np.inf
    for iteration in range(1, (LOAD_ITERATIONS if settle else 1) + 1):
        out, Y = linear(estimator, model, samples, limits, warn and iteration == 1)
        if not settle:  # two stages: the model keeps the load its fit used
            return model, out, Y, {"iterations": 1}
        new = Y[..., rigid] @ out.x[rigid]
        if load is not None:
            change = float(np.max(np.abs(new - load)) / max(np.max(np.abs(new)), 1e-300))
        load, model = new, model.linearized_at(out.x)
        if change < LOAD_RTOL:
            break
    report = {"iterations": iteration}
    settled = change < LOAD_RTOL
    if not settled and warn:
        warnings.warn(f"identify: the load-dependent friction's fixed point did not settle "
                      f"in {LOAD_ITERATIONS} fits (the rigid-body torque still changed by "
                      f"{change:.2g} of its peak): its coefficients may be too large to "
                      f"identify from these data", stacklevel=caller_stacklevel())
    return model, out, Y, {**report, "change": change, "settled": settled}
