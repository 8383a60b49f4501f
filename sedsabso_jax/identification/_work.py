"""How much work a long identification call does, estimated before each step runs, so
that its progress and the time left are right although its fits differ a hundredfold in
cost (a least-squares fit of one validation split against a search of friction at
rest's displacements).

``progress(label, done, total)`` (:data:`~._estimators._estimator.ProgressCallback`)
reports work in these estimates: :func:`fit_seconds` of each fit and
:func:`evaluate_seconds` of the report's evaluation, known before the step runs, in
seconds of the machine they were measured on; a caller's time left is the pace it
measures applied to the work left (``sedsabso-jax identify``'s). A fit's estimate grows
with its rows ``R`` (samples x joints) and columns ``d``: least squares ``R d^2``, a
physically consistent fit's conic solve ``d^3``, a term that reads the fitted values (a
fixed point of fits) ``R d``, a search of ``k`` nonlinear parameters ``R d k`` (none
where they are held); a part's first fit in a call sets it up once (:data:`SETUP`: the
conic solver's import, the search's compilation), and the fit on all the data searches
again at new shapes and measures the searched parameters' uncertainty
(:data:`FINAL_SEARCH`, :data:`FINAL_SETUP`). Another search method or budget than the
default's changes a search's cost, and so the share of the work it is given (not the
pace)."""

from __future__ import annotations

from collections.abc import Collection
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ._estimators._estimator import Estimator
    from ._model._torque_model import TorqueModel

#: Seconds per unit of each part of a fit (module docstring), and each part's seconds
#: per fit however small the fit (what a three-joint robot's fits take): fitted to the
#: KUKA LWR4+ and Staubli TX40 defaults' and a simulated RS010N's fits, timed one by one
#: (2 cores, loaded).
LEAST_SQUARES = 3.0e-10   # x R d^2
CONIC, CONIC_FIT = 1.0e-7, 0.035          # x d^3
FIXED_POINT, FIXED_POINT_FIT = 1.25e-7, 0.02  # x R d
SEARCH, SEARCH_FIT = 6.0e-8, 0.13         # x R d k
#: Seconds of a part's first fit in a call (module docstring).
SETUP = {"conic": 3.0, "search": 8.0}
#: The fit on all the data: its search in searches of its rows, and its compilation.
FINAL_SEARCH, FINAL_SETUP = 5.0, 15.0
#: A fit of an estimator that is costly (a box search per fit) counts this many times.
COSTLY = 50.0
#: The report's evaluation (its predictions), per row and column.
EVALUATE = 5.0e-8


def parts(estimator: Estimator, model: TorqueModel) -> frozenset[str]:
    """The parts of :data:`SETUP` a fit of ``model`` with ``estimator`` has."""
    searched = bool(model.nonlinear()) and (model.search is None or model.search.searches)
    return frozenset(("conic",) * estimator.physical + ("search",) * searched)


def fit_seconds(estimator: Estimator, model: TorqueModel, rows: int, *,
                new: Collection[str] = (), final: bool = False) -> float:
    """The estimated seconds of one fit of ``model`` with ``estimator`` to ``rows`` rows
    (module docstring); ``new``: the parts (:func:`parts`) this fit is the first in its
    call to have, set up by it; ``final``: the fit on all the data."""
    d = model.dim
    seconds = LEAST_SQUARES * rows * d * d
    if estimator.physical:
        seconds += CONIC * d ** 3 + CONIC_FIT
    if estimator.costly:
        seconds *= COSTLY
    if model.waiting or model.iterates:
        seconds += FIXED_POINT * rows * d + FIXED_POINT_FIT
    searched = model.search is None or model.search.searches  # not held where they are
    k = sum(len(found.values) for _, found in model.nonlinear()) if searched else 0
    if k:
        seconds += (SEARCH * rows * d * k + SEARCH_FIT) * (FINAL_SEARCH if final else 1.0)
        seconds += FINAL_SETUP if final else 0.0
    return seconds + sum(SETUP[part] for part in new if part in parts(estimator, model))


def evaluate_seconds(model: TorqueModel, rows: int) -> float:
    """The estimated seconds of the report's evaluation of ``model`` on ``rows`` rows
    (the data and the held-out data)."""
    return EVALUATE * rows * model.dim
