"""A call's progress in estimated seconds (:mod:`.._work`), not in fits: the seconds of
each split's fit known before it runs (:func:`split_seconds`), of a grid of candidates
(:func:`grid_seconds`) and of the kept terms (:func:`kept_seconds`), added up as the
work ends by the one counter of a call (:class:`Fits`)."""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence

import numpy as np

from .._estimators._estimator import Estimator, ProgressCallback
from .._fit._samples import Samples
from .._model._torque_model import TorqueModel
from .._work import fit_seconds, parts
from ._kept_terms import KeptTerms
from ._splits import Splits


class Fits:
    """The one counter of a call's progress: adds up the estimated seconds of the work
    done for ``progress(label, done, total)`` (None: nothing), ``total`` the work done,
    the work known ahead (:meth:`ahead`, revised as choices are made) and ``later``
    seconds after it (the stages of :func:`~sedsabso_jax.select_and_identify` after a
    validation's)."""

    def __init__(self, progress: ProgressCallback | None, later: float = 0.0):
        self.progress, self.later, self.done, self.total = progress, later, 0.0, later

    @classmethod
    def of(cls, progress: ProgressCallback | Fits | None) -> Fits:
        """``progress`` as a counter: a :class:`Fits` as it is (a stage of a call)."""
        return progress if isinstance(progress, Fits) else cls(progress)

    def ahead(self, seconds: float) -> None:
        """The work known ahead is ``seconds`` (then ``later``)."""
        self.total = self.done + seconds + self.later

    def step(self, label: str, seconds: float, later: float) -> None:
        """A step of ``seconds`` done, with ``later`` seconds after it."""
        self.done += seconds
        self.later, self.total = later, self.done + later
        if self.progress is not None:
            self.progress(label, self.done, self.total)

    def after(self, label: str, seconds: Sequence[float]) -> Callable[[], None] | None:
        """The ``on_fit`` of :func:`~._cross_validation.cross_validation_of` for fits
        labelled so, of ``seconds`` each in turn (a validation's: its splits')."""
        if self.progress is None:
            return None
        report, each = self.progress, iter(seconds)

        def fitted() -> None:
            self.done += next(each, 0.0)
            report(label, self.done, self.total)

        return fitted


def train_rows(samples: Samples, splits: Splits) -> list[int]:
    """The rows (samples x joints) each split fits."""
    return [samples.q.shape[1] * int(np.count_nonzero(t)) for t in splits.train]


def split_seconds(rows: Sequence[int], estimator: Estimator, model: TorqueModel,
                  new: Collection[str] = ()) -> list[float]:
    """The estimated seconds of each split's fit (:func:`~.._work.fit_seconds`; ``rows``:
    :func:`train_rows`), the first setting up the parts ``new``."""
    return [fit_seconds(estimator, model, r, new=new if i == 0 else ())
            for i, r in enumerate(rows)]


def grid_seconds(rows: Sequence[int], grid: Sequence[tuple[Estimator, TorqueModel]],
                 seen: Collection[str] = ()) -> list[list[float]]:
    """Each candidate's :func:`split_seconds`, in order: the first with a part
    (:func:`~.._work.parts`) not in ``seen`` (the parts of the fits before) sets it up."""
    out, done = [], set(seen)
    for estimator, model in grid:
        out.append(split_seconds(rows, estimator, model, parts(estimator, model) - done))
        done |= parts(estimator, model)
    return out


def kept_seconds(rows: Sequence[int], kept: KeptTerms, estimator: Estimator,
                 model: TorqueModel, seen: Collection[str]) -> list[list[float]]:
    """The :func:`split_seconds` of validating each of ``kept``'s terms added to
    ``model`` with ``estimator``, after fits with the parts ``seen``."""
    return grid_seconds(rows, [(estimator, m) for m in kept.models(model)], seen)
