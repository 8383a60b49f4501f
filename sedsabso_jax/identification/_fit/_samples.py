"""The samples a fit reads (:class:`Samples`): one or several recordings stacked, or a
split of them (a validation's, a mask over the whole recordings' rows), with what is
computed on them kept for the next fit: the base regressor's rows, a model's rows and
their normal equations."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ...dynamics._robot import Robot
from ...measurements._container import Measurements
from .._estimators._estimator import FitProblem
from .._estimators._normal_equations import NormalEquations
from .._model._leaves import tree_key
from .._model._torque_model import TorqueModel
from .._recordings import Data, is_several, recordings_of, stacked


@dataclasses.dataclass(frozen=True, eq=False)
class Samples:
    """The samples a fit reads, each ``(T, n)`` (``recording``: each sample's recording,
    ``(T,)``, or None), in time order within each recording.

    A :meth:`split` is the whole samples (``whole``) and a ``mask`` over their rows: a
    term that carries a state along the samples integrates it on the whole and takes the
    split's rows. A split is ``compressed``: a least-squares estimator fits it through its
    normal equations (a validation's training samples, whose fits are judged by their
    predictions only), formed from the whole's where the split is most of it and the
    whole's rows of that model are at hand."""

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    recording: np.ndarray | None = None
    compressed: bool = False
    whole: Samples | None = None
    mask: np.ndarray | None = None
    _kept: dict = dataclasses.field(default_factory=dict, repr=False)

    @classmethod
    def of(cls, robot: Robot, data: Data) -> Samples:
        """The samples of ``data`` (:func:`recorded`)."""
        return recorded(robot, data)[1]

    def kept(self, kind: Any, key: tuple, make) -> Any:
        """``make()``, kept on these samples per (``kind``, ``key``): a model's
        :attr:`~sedsabso_jax.TorqueModel.structure`, a base's :func:`tree_key`, a split's
        mask (what sets the value, never an object's identity)."""
        if (kind, key) not in self._kept:
            self._kept[kind, key] = make()
        return self._kept[kind, key]

    @property
    def root(self) -> Samples:
        """The whole samples (itself unless a split)."""
        return self if self.whole is None else self.whole

    def base_rows(self, model: TorqueModel) -> np.ndarray:
        """The base regressor's rows ``(T, n, b)`` (computed once, on the whole)."""
        if self.whole is not None:
            return self.whole.base_rows(model)[self.mask]
        return self.kept("base", tree_key(model.base), lambda: np.asarray(
            model.base.regressor(self.q, self.qd, self.qdd)))

    def _rows(self, model: TorqueModel, every_column: bool) -> np.ndarray:
        # on the whole recordings, a split's rows taken: a state integrates along the
        # whole, and every split's columns are computed at one shape (one compilation
        # of each jax.numpy operation, not one per split)
        root, mask = self.root, self.mask
        return model.regressor(root.q, root.qd, root.qdd, root.recording,
                               base_rows=root.base_rows(model), every_column=every_column,
                               rows=mask)

    def rows(self, model: TorqueModel, every_column: bool = False, cache: bool = True
             ) -> np.ndarray:
        """``model``'s regressor at these samples, ``(T, n, d)`` (``every_column``: as
        :meth:`~sedsabso_jax.TorqueModel.regressor`'s): the whole's rows of the model,
        taken, where they were computed; on the whole, kept (``cache``)."""
        if every_column:
            if self.whole is None and cache:
                return self.kept("every", model.structure, lambda: self._rows(model, True))
            return self._rows(model, True)
        found = self.root._kept.get(("rows", model.structure))
        if found is not None:
            return found if self.whole is None else found[self.mask]
        if self.whole is None and cache:
            return self.kept("rows", model.structure, lambda: self._rows(model, False))
        if not (cache and self.small):
            return self._rows(model, False)
        # a split of at most half of the whole (a validation's test rows) keeps the rows
        # of the last model it read: each estimator's fit of a model whose terms read one
        # first fit (the same on every estimator) predicts it in turn
        last = self._kept.get("last rows")
        if last is None or last[0] != model.structure:
            last = self._kept["last rows"] = (model.structure, self._rows(model, False))
        return last[1]

    @property
    def small(self) -> bool:
        """Whether these samples are a split of at most half of the whole."""
        return self.mask is not None and 2 * int(self.mask.sum()) <= self.root.q.shape[0]

    def has_rows(self, model: TorqueModel) -> bool:
        """Whether the whole's rows of ``model`` are kept."""
        return ("rows", model.structure) in self.root._kept

    def split(self, mask: np.ndarray) -> Samples:
        """The samples ``mask`` (booleans, one per sample here) keeps: a validation's
        split, ``compressed``, a mask over the whole's rows; one object per split (kept by
        its mask)."""
        mask = np.asarray(mask)
        if mask.dtype != bool or mask.shape != self.q.shape[:1]:
            raise ValueError(f"a split is a mask of {self.q.shape[0]} booleans, got "
                             f"{mask.dtype} {mask.shape}")
        if self.mask is not None:  # a split of a split: the same rows of the whole
            inner, mask = mask, np.zeros_like(self.mask)
            mask[np.flatnonzero(self.mask)[inner]] = True
        root = self.root
        key = ("split", mask.tobytes())
        if key not in root._kept:
            root._kept[key] = Samples(
                root.q[mask], root.qd[mask], root.qdd[mask], root.tau[mask],
                None if root.recording is None else root.recording[mask], True,
                whole=root, mask=mask)
        return root._kept[key]

    def normal_equations(self, model: TorqueModel) -> NormalEquations:
        """The normal equations of ``model``'s rows at these samples: a split that is
        most of the whole, whose rows of ``model`` the whole has, takes the whole's less
        those of the samples it leaves out."""
        whole = self.whole
        rows = None if whole is None else whole._kept.get(("rows", model.structure))
        if whole is None or rows is None or self.mask is None or self.small:
            return self.kept("normal", model.structure,
                             lambda: NormalEquations.of(self.rows(model), self.tau))
        out = ~self.mask
        everything = whole.normal_equations(model)
        return everything - NormalEquations.of(rows[out], whole.tau[out])

    def problem(self, model: TorqueModel, limits: np.ndarray | None, warn: bool = True
                ) -> FitProblem:
        """What an estimator fits: the compressed rows of a split (kept per model and
        limits), or the rows themselves."""
        if self.compressed:
            key = None if limits is None else np.asarray(limits).tobytes()
            found = self.kept("problems", model.structure, dict)
            if key not in found:
                found[key] = self.normal_equations(model).problem(model, limits)
            return found[key]
        return FitProblem.of(model, self.rows(model), self.tau, limits, warn)

    def predict(self, model: TorqueModel, values: np.ndarray) -> np.ndarray:
        """``model``'s torques with ``values`` at these samples (as
        :meth:`~sedsabso_jax.TorqueModel.predict`, from the rows computed so far)."""
        values = np.asarray(values, dtype=float)
        if values.shape != (model.dim,):
            raise ValueError(f"values must have shape ({model.dim},), got {values.shape}")
        return self.rows(model.reading(values, only=lambda term: term.waiting)) @ values


def recorded(robot: Robot, data: Data) -> tuple[list[Measurements], Samples]:
    """The one normalisation of the data every fit reads: ``data``
    (:data:`~.._recordings.Data`) as checked recordings of ``robot``
    (:func:`~.._recordings.recordings_of`) and their samples stacked, each sample's
    recording kept where ``data`` is several recordings
    (:func:`~.._recordings.is_several`; else None). Returns ``(recordings, samples)``."""
    recordings = recordings_of(robot, data)
    q, qd, qdd, tau, index = stacked(recordings)
    return recordings, Samples(q, qd, qdd, tau, index if is_several(data) else None)

