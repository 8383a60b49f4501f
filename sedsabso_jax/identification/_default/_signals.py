"""The signal chain chosen by validation (:class:`ChainSelection`, :func:`choose_chain`).

Each candidate :class:`~sedsabso_jax.measurements.SignalChain` (which velocities and
accelerations, recorded or derived, and the low-pass cutoff that derives them) makes the
recordings again from their recorded signals; the torque model and estimator the
validation chose (the kept terms included; their nonlinear parameters held at the values
a fit to all the loaded data finds) are validated on each, all on the same samples
(the ends trimmed by the longest ringing of any candidate) and by the same splits (those
the model was chosen by, on these samples). The chain the data were loaded with is kept
unless it validates worse than the lowest by the default's rule
(:meth:`~._policy.Default.not_worse`); else the lowest is chosen. The torques are the
recorded ones throughout, so every candidate is scored against the same measurements.
Why: docs/explanation/identification-defaults.md."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import ClassVar

import equinox as eqx
import numpy as np

from ..._output import columns_note, markdown_table
from ...dynamics._robot import Robot
from ...measurements._chain import SignalChain
from ...measurements._container import Measurements
from ...measurements._signal import edge_seconds
from .._estimators._estimator import Estimator
from .._fit._fit import fit as fit_model
from .._fit._samples import recorded
from .._model._torque_model import TorqueModel
from .._validation._cross_validation import CrossValidation, cross_validation_of
from .._validation._progress import Fits, split_seconds, train_rows
from .._validation._splits import Splits, Validation
from ._policy import DEFAULT


@dataclasses.dataclass(frozen=True, eq=False)
class ChainSelection:
    """Every candidate chain's validation (``chains``, ``validations``, ``labels`` in
    the order tried, the loaded chain first), the index ``chosen``, the seconds
    ``trim_s`` dropped at each end while they were compared, and the model and
    estimator they were compared with."""

    chains: tuple[SignalChain, ...]
    validations: tuple[CrossValidation, ...]
    labels: tuple[str, ...]
    chosen: int
    trim_s: float
    judged_with: str

    @property
    def chain(self) -> SignalChain:
        """The chosen chain."""
        return self.chains[self.chosen]

    @property
    def lowest(self) -> int:
        return int(np.argmin([cv.score for cv in self.validations]))

    def table(self) -> list[list[str]]:
        """Rows ``[signals, error +- SE, chosen/lowest/loaded]``."""
        return [[label, f"{cv.score:.4f} +- {cv.standard_error:.4f}",
                 ", ".join(m for m, on in (("chosen", i == self.chosen),
                                           ("lowest", i == self.lowest and i != self.chosen),
                                           ("as loaded", i == 0)) if on)]
                for i, (label, cv) in enumerate(zip(self.labels, self.validations))]

    def lines(self) -> list[str]:
        """The report's table of the candidates, with what it means."""
        return [f"signals chosen by validation ({self.judged_with}; the chain as loaded "
                f"unless the lowest beats it by more than one standard error; "
                f"{self.trim_s:g} s dropped at each end while compared):", "",
                markdown_table(["signals", "error [%]", "choice"], self.table()), "",
                columns_note(("signals", "velocities and accelerations `recorded` or "
                              "`derived` from the positions by a zero-phase low-pass at the "
                              "cutoff (`recorded qd`: velocities recorded, accelerations "
                              "derived)"),
                             ("error [%]", "the validated error +- its standard error"),
                             ("choice", "`chosen`, `lowest`, `as loaded`")), ""]

    def as_dict(self) -> dict:
        return {"rule": "the chain as loaded unless its split-by-split excess over the "
                        "lowest validated error is above one standard error (or 1 % of "
                        "the lowest); then the lowest",
                "judged_with": self.judged_with, "trimmed_s": self.trim_s,
                "chosen": self.labels[self.chosen],
                "candidates": [{"signals": label, "cutoff_hz": c.cutoff_hz,
                                "derive": c.derive, "score": cv.score,
                                "standard_error": cv.standard_error,
                                "fold_scores": cv.fold_scores.tolist()}
                               for label, c, cv in zip(self.labels, self.chains,
                                                       self.validations)]}


def common_trim(recordings: Sequence[Measurements], chains: Sequence[SignalChain]) -> float:
    """The seconds every candidate drops at each end: the longest ringing of a chain that
    filters a recording that trims its edges."""
    return max([edge_seconds(c.cutoff_hz) for c in chains for r in recordings
                if r.recorded is not None and r.recorded.trim_edges
                and c.filters(r.recorded)], default=0.0)


def restricted(splits: Splits, keep: np.ndarray) -> Splits:
    """``splits`` on the samples ``keep`` marks (a mask over the samples they cut)."""
    return dataclasses.replace(
        splits, train=tuple(t[keep] for t in splits.train),
        test=tuple(t[keep] for t in splits.test),
        labels=None if splits.labels is None else splits.labels[keep])


class OnSamples(Validation):
    """``validation``'s ``given`` splits, made of the loaded recordings and kept on the
    samples every signal chain keeps: what the stages after the chain's choice split
    the chosen chain's recordings by (the splits the chains were compared by)."""

    validation: Validation
    given: Splits = eqx.field(static=True)
    kind: ClassVar[str] = "on the signal chains' samples"

    def splits(self, recordings: Sequence[Measurements]) -> Splits:
        count = sum(r.n_samples for r in recordings)
        if count != len(self.given.train[0]):
            raise ValueError(f"these splits cut {len(self.given.train[0])} samples, the "
                             f"recordings have {count}")
        return self.given

    def describe(self) -> str:
        return self.validation.describe()

    def settings(self) -> dict:
        return self.validation.settings()


def choose_chain(robot: Robot, recordings: list[Measurements],
                 chains: Sequence[SignalChain], estimator: Estimator, model: TorqueModel,
                 validation: Validation, limits: np.ndarray | None, fits: Fits
                 ) -> tuple[ChainSelection, list[Measurements], Validation]:
    """Validate ``estimator`` and ``model`` on ``recordings`` made again by each of
    ``chains`` (the first: as loaded) and choose (module docstring). Returns the
    selection, and the recordings and the validation to go on with: as given where the
    loaded chain is kept, else the chosen chain's recordings on the samples compared and
    the splits they were compared by (:class:`OnSamples`)."""
    # the chosen model's nonlinear parameters held where the loaded signals put them
    model = fit_model(estimator, model, recorded(robot, recordings)[1], limits,
                      warn=False).model
    trim = common_trim(recordings, chains)
    made = [[r.with_chain(c, trim_s=trim, given=False) for r in recordings] for c in chains]
    # the splits the model was chosen by, on the samples every chain keeps
    keep = np.concatenate([np.isin(r.times, m.times) for r, m in zip(recordings, made[0])])
    splits = restricted(validation.splits(recordings), keep)
    settings = {**validation.settings(), "description": validation.describe()}
    labels = tuple(c.label(recordings[0].recorded) for c in chains)
    tried: list[CrossValidation] = []
    for label, recs in zip(labels, made):
        _, samples = recorded(robot, recs)
        each = split_seconds(train_rows(samples, splits), estimator, model)
        if not tried:
            fits.ahead(len(chains) * sum(each))
        tried.append(cross_validation_of(estimator, model, samples, splits, limits, settings,
                                         on_fit=fits.after(f"signals: {label}", each)))
    best = min(tried, key=lambda cv: cv.score)
    chosen = 0 if DEFAULT.not_worse(tried[0], best) else tried.index(best)
    selection = ChainSelection(tuple(chains), tuple(tried), labels, chosen, trim,
                               f"{estimator.name}, {model.friction}")
    if chosen == 0:
        return selection, recordings, validation
    return selection, made[chosen], OnSamples(validation, splits)
