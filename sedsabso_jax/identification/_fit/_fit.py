"""Fitting a torque model with any estimator (:func:`fit`): one linear fit, wrapped in
what the model's terms ask for, in three stages that read the terms' answers and branch
on none of their kinds:

1. **Values a term reads** (:attr:`~sedsabso_jax.identification.AbstractTerm.waiting`):
   where a term's columns read the model's own fitted values (friction that grows with
   the transmitted torque reads the rigid-body torque), the model without those terms
   is fitted first (ordinary least squares) and the terms read its values.
2. **Nonlinear parameters** (:meth:`~sedsabso_jax.TorqueModel.nonlinear`: velocity
   scales, presliding displacements): searched by the model's search method
   (:attr:`~sedsabso_jax.TorqueModel.search`) on the compiled variable-projection
   problem (:mod:`._projection`), the linear values solved by least squares for each
   trial with the estimator's row weights (the torque limits' where it weighs by them,
   else equal).
3. **The estimator's fit** of the model so completed (OLS, WLS, physically consistent,
   L1, a box search: any), through the normal equations where the samples are a
   validation's split and the estimator reads only them; again, with the values each
   fit gives, while a term reads every fit's values (a fixed point,
   :attr:`~sedsabso_jax.identification.AbstractTerm.iterates`), until its columns
   change by less than :data:`SETTLE_RTOL`.

:func:`fit` returns the model as fitted (its parameters found, the values its terms
read) with the estimator's fit and a report of the stages.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from ..._deprecation import caller_stacklevel
from .._estimators._estimator import Estimator, EstimatorFit, FitProblem
from .._estimators._least_squares import OLS
from .._model._leaves import tree_key
from .._model._torque_model import TorqueModel
from .._search._methods import HELD
from ._projection import Projection
from ._samples import Samples

#: A term that reads every fit's values has settled when its columns change by less than
#: this fraction of their largest value (the conic solver's own precision: a physically
#: consistent fit jitters at about 1e-6), or after :data:`SETTLE_ITERATIONS` fits.
SETTLE_RTOL = 1e-5
#: The most fits of a fixed point.
SETTLE_ITERATIONS = 30


@dataclasses.dataclass(frozen=True, eq=False)
class Fitted:
    """What :func:`fit` returns: the ``model`` as fitted (its searched parameters and the
    values its terms read set), the estimator's ``fit`` of it, and a JSON-ready
    ``report``: per term that read fitted values (by its name), the fits it took
    (``iterations``; a fixed point's last ``change`` and whether it ``settled``), and
    ``searched``: the search's method, trials and seconds."""

    model: TorqueModel
    fit: EstimatorFit
    report: dict


def linear(estimator: Estimator, model: TorqueModel, samples: Samples,
           limits: np.ndarray | None, warn: bool = True) -> EstimatorFit:
    """One fit of ``model`` as it is, through the normal equations where the samples are
    compressed and the estimator reads only them."""
    if samples.compressed and estimator.normal_equations:
        return estimator.fit(samples.problem(model, limits))
    return estimator.fit(FitProblem.of(model, samples.rows(model), samples.tau, limits, warn))


def search_weights(estimator: Estimator, model: TorqueModel, limits: np.ndarray | None
                   ) -> np.ndarray:
    """Each joint's row weight in the search: ``1 / limits`` where the estimator weighs by
    the limits, else 1."""
    if estimator.weights == "limits" and limits is not None:
        return 1.0 / np.asarray(limits, dtype=float)
    return np.ones(model.robot.n_joints)


def search(estimator: Estimator, model: TorqueModel, samples: Samples,
           limits: np.ndarray | None) -> tuple[TorqueModel, dict]:
    """The model with its nonlinear parameters at the best its search method finds
    (module docstring, stage 2), and what the search did; kept on the samples for the
    next estimator with the same row weights (a validation's candidates)."""
    weights = search_weights(estimator, model, limits)
    # the model's structure and its search (the model's own tree also holds what it has
    # worked out about itself, functools.cached_property: not a key)
    return samples.kept(("searched", weights.tobytes()),
                        (model.structure, tree_key(model.search)),
                        lambda: _searched(model, samples, weights))


def _searched(model: TorqueModel, samples: Samples, weights: np.ndarray
              ) -> tuple[TorqueModel, dict]:
    found = [f for _, f in model.nonlinear()]
    lower = np.log(np.concatenate([f.lower for f in found]))
    upper = np.log(np.concatenate([f.upper for f in found]))
    start = np.log(np.concatenate([f.values for f in found]))
    problem = Projection.of(model, samples, weights)
    method = model.searched_by
    searched = method.search(problem, start, lower, upper)
    names = [n for f in found for n in f.names]
    polished: dict = {} if searched.held is None else {
        "held": [n for n, h in zip(names, searched.held) if h]}
    if searched.newton_steps is not None:
        polished.update(newton_steps=searched.newton_steps, converged=searched.converged)
    return model.with_nonlinear(np.exp(searched.u)), {
        **method.settings(), "evaluations": searched.evaluations, "loss": searched.loss,
        "seconds": searched.seconds, **polished}


def fit(estimator: Estimator, model: TorqueModel, samples: Samples,
        limits: np.ndarray | None, warn: bool = True) -> Fitted:
    """Fit ``model`` to ``samples`` with ``estimator`` (module docstring)."""
    report: dict = {}
    readers = [t.name for t in model.terms if t.waiting or t.iterates]
    if model.waiting:
        without = model.without_waiting()
        first = dict(zip(without.names, linear(OLS(), without, samples, None, False).x))
        # the first fit's values by name: a body term after the waiting ones (a payload)
        # sits elsewhere in the model with them
        model = model.reading(np.array([first.get(n, 0.0) for n in model.names]),
                              only=lambda term: term.waiting)
    if model.nonlinear() and model.searched_by.searches:
        model, report["searched"] = search(estimator, model, samples, limits)
        # the model carries what it found: fitting it again fits the same model
        model = dataclasses.replace(model, search=HELD)
    elif model.nonlinear():
        report["searched"] = {**model.searched_by.settings(), "evaluations": 0}
    out = linear(estimator, model, samples, limits, warn)
    iterations, change = 1, 0.0
    while model.iterates:
        new = model.reading(out.x, only=lambda term: term.iterates)
        change = _change(model, new, samples)
        model = new
        if change < SETTLE_RTOL or iterations >= SETTLE_ITERATIONS:
            break
        out = linear(estimator, model, samples, limits, False)
        iterations += 1
    step: dict = {"iterations": iterations}
    if model.iterates:
        step.update(change=change, settled=change < SETTLE_RTOL)
        if change >= SETTLE_RTOL and warn:
            warnings.warn(f"identify: the fixed point of {', '.join(readers)} did not settle "
                          f"in {SETTLE_ITERATIONS} fits (its columns still changed by "
                          f"{change:.2g} of their peak): its coefficients may be too large "
                          f"to identify from these data", stacklevel=caller_stacklevel())
    report.update({name: step for name in readers})
    return Fitted(model, out, report)


def _change(old: TorqueModel, new: TorqueModel, samples: Samples) -> float:
    """How much the columns of ``new`` moved from ``old``'s, relative to their peak."""
    a, b = samples.rows(old, cache=False), samples.rows(new, cache=False)
    return float(np.max(np.abs(b - a)) / max(np.max(np.abs(b)), 1e-300))
