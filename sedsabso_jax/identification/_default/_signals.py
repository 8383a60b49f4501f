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

Where asked (``largest_delay_s``), the torques' delay behind the motion comes first: it
is searched with the same model (:func:`~.._fit._delay.estimate_delay`: variable
projection over whole-sample shifts, sub-sample by the parabola's vertex) on the loaded
chain's recordings, and that chain with the delay is validated by the same splits, each
split's delay searched on its training samples only (a delay at the search's bound on
all the data is not tried). Where it validates better by the same rule, it is the chain
to beat, and every other chain is validated with its own delay searched likewise (a
delay is the logger's, shared by every chain; searched first, it does not confound the
choice of the cutoff). Where the loaded chain's delay lies at the search's bound (its
signals disagree in time among themselves: a logger's late velocities), the first chain
derived from the positions alone takes its place: its delay is searched and validated
likewise, and where it validates better every other chain gets its own. Where no delay
was kept so and another chain is chosen, the delay is searched on the chosen chain's
recordings and validated likewise. The delay applied is all the data's on the chosen
chain. Why:
docs/explanation/identification-defaults.md."""

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
from .._fit._delay import DelayEstimate, delay_of, shifts_within
from .._fit._fit import fit as fit_model
from .._fit._samples import Samples, recorded
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
    estimator they were compared with; ``searches`` each delay search on all of a chain's
    data, ``(label of the chain searched on, DelayEstimate, kept, index of the chain
    with it validated or -1)`` (the loaded chain's first; where it lay at the bound, the
    first derived chain's; kept, every later chain was validated with its own delay;
    then, where none was kept and another chain was chosen, that chain's), and
    ``split_delays`` each chain's delay [s] searched on each split's training samples
    (empty: validated without a delay)."""

    chains: tuple[SignalChain, ...]
    validations: tuple[CrossValidation, ...]
    labels: tuple[str, ...]
    chosen: int
    trim_s: float
    judged_with: str
    searches: tuple[tuple[str, DelayEstimate, bool, int], ...] = ()
    split_delays: tuple[tuple[float, ...], ...] = ()

    @property
    def delay(self) -> DelayEstimate | None:
        """The loaded chain's delay search (None: not searched)."""
        return self.searches[0][1] if self.searches else None

    @property
    def delayed(self) -> bool:
        """Whether a delay was kept before the other chains were validated (the loaded
        chain's, or the first derived chain's where the loaded one's lay at the bound):
        every later chain validated with its own."""
        return any(self._leads(i) for i in range(len(self.searches)))

    def _leads(self, i: int) -> bool:
        """Whether search ``i`` was kept and chains were validated after it."""
        _, _, kept, index = self.searches[i]
        return kept and 0 <= index < len(self.chains) - 1

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
                             ("choice", "`chosen`, `lowest`, `as loaded`")), "",
                *[x for line in self.delay_lines() for x in (line, "")]]

    def delay_lines(self) -> list[str]:
        """Each delay search's finding, in words."""
        out = []
        for i, (label, d, kept, index) in enumerate(self.searches):
            found = (f"the torques {1e3 * d.seconds:+.3g} ms ({d.samples:+.2f} samples) behind "
                     f"the motion, +- {1e3 * d.standard_error_s:.2g} ms (white residuals)")
            where = f"delay, searched with the chosen model on the {label} signals"
            if index < 0:
                out.append(f"{where} up to {1e3 * abs(d.shifts[0]) / d.rate:.3g} ms: the "
                           f"best lies at that bound ({found}), so none was tried")
                continue
            splits = self.split_delays[index]
            found += (f", {1e3 * min(splits):+.3g} to {1e3 * max(splits):+.3g} ms on the "
                      f"splits' training samples" if splits else "")
            out.append(f"{where}: {found}; " + (
                "not kept: it does not validate better than none" if not kept else
                "it validates better: every later chain was validated with its own delay"
                if self._leads(i) else "it validates better and is applied"))
        return out

    def as_dict(self) -> dict:
        return {"rule": "the chain as loaded unless its split-by-split excess over the "
                        "lowest validated error is above one standard error (or 1 % of "
                        "the lowest); then the lowest",
                "judged_with": self.judged_with, "trimmed_s": self.trim_s,
                "chosen": self.labels[self.chosen],
                "delay_searches": [
                    {"on": label, "seconds": d.seconds, "samples": d.samples,
                     "standard_error_s": d.standard_error_s, "at_bound": d.at_bound,
                     "kept": kept, "line": line}
                    for (label, d, kept, _), line in zip(self.searches, self.delay_lines())],
                "candidates": [{"signals": label, "cutoff_hz": c.cutoff_hz,
                                "derive": c.derive, "delay_s": c.delay_s,
                                "split_delays_s": list(ds), "score": cv.score,
                                "standard_error": cv.standard_error,
                                "fold_scores": cv.fold_scores.tolist()}
                               for label, c, cv, ds in zip(
                                   self.labels, self.chains, self.validations,
                                   self.split_delays or ((),) * len(self.chains))]}


def common_trim(recordings: Sequence[Measurements], chains: Sequence[SignalChain],
                delay_s: float = 0.0) -> float:
    """The seconds every candidate drops at each end: the longest ringing of a chain that
    filters a recording that trims its edges, at least any chain's delay and ``delay_s``
    (the largest delay searched)."""
    return max([edge_seconds(c.cutoff_hz) for c in chains for r in recordings
                if r.recorded is not None and r.recorded.trim_edges
                and c.filters(r.recorded)] + [abs(c.delay_s) for c in chains]
               + [abs(delay_s)])


def restricted(splits: Splits, keep: np.ndarray) -> Splits:
    """``splits`` on the samples ``keep`` marks (a mask over the samples they cut), less
    those left with no sample to fit or to predict (a short recording's fastest samples
    in its trimmed ends)."""
    kept = [i for i, (a, b) in enumerate(zip(splits.train, splits.test))
            if a[keep].any() and b[keep].any()]
    return dataclasses.replace(
        splits, train=tuple(splits.train[i][keep] for i in kept),
        test=tuple(splits.test[i][keep] for i in kept),
        names=tuple(splits.names[i] for i in kept),
        parts=tuple(splits.parts[i] for i in kept) if splits.parts else (),
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
                 validation: Validation, limits: np.ndarray | None, fits: Fits,
                 largest_delay_s: float | None = None, samples: Samples | None = None
                 ) -> tuple[ChainSelection | None, list[Measurements], Validation]:
    """Validate ``estimator`` and ``model`` on ``recordings`` made again by each of
    ``chains`` (the first: as loaded) and choose, the delay searched first up to
    ``largest_delay_s`` (None: not searched) (module docstring); ``samples``: the
    recordings' (:func:`~.._fit._samples.recorded`), where the model's nonlinear
    parameters are searched (given: kept there for a later fit). Returns the selection,
    and the recordings and the validation to go on with: as given where the loaded chain
    is kept, else the chosen chain's recordings on the samples compared and the splits
    they were compared by (:class:`OnSamples`); no selection (None) where fewer than two
    splits keep samples to fit and to predict once the ends are trimmed."""
    # the chosen model's nonlinear parameters held where the loaded signals put them
    model = fit_model(estimator, model, recorded(robot, recordings)[1] if samples is None
                      else samples, limits, warn=False).model
    trim = common_trim(recordings, chains, largest_delay_s or 0.0)

    def made_by(chain: SignalChain) -> list[Measurements]:
        return [r.with_chain(chain, trim_s=trim, given=False) for r in recordings]

    first = made_by(chains[0])
    # the splits the model was chosen by, on the samples every chain keeps
    keep = np.concatenate([np.isin(r.times, m.times) for r, m in zip(recordings, first)])
    splits = restricted(validation.splits(recordings), keep)
    if len(splits) < 2:  # too short a recording to compare chains on: as loaded
        return None, recordings, validation
    settings = {**validation.settings(), "description": validation.describe()}
    rate = float(np.median([r.rate for r in first]))
    m = shifts_within(largest_delay_s or 0.0, rate)
    count = len(chains) + (largest_delay_s is not None)
    tried: list[tuple[SignalChain, list[Measurements], CrossValidation, tuple]] = []

    def validate(chain: SignalChain, recs: list[Measurements], samples: Samples,
                 delayed: bool = False) -> None:
        """``chain`` validated on its ``recs`` (``samples``); ``delayed``: with the delay
        searched on each split's training samples (none where none has the neighbours
        to shift by), ``chain`` its delay on all the samples."""
        found: dict[bytes, float] = {}  # by split (the splits are fitted at once)

        def made_for(train: np.ndarray) -> Samples:
            try:
                seconds = delay_of(samples, model, rate, m, limits, train).seconds
            except ValueError:
                seconds = 0.0
            found[train.tobytes()] = seconds
            return recorded(robot, made_by(eqx.tree_at(lambda c: c.delay_s, chain,
                                                         seconds)))[1]

        label = chain.label(recordings[0].recorded)
        each = split_seconds(train_rows(samples, splits), estimator, model)
        if not tried:
            fits.ahead(count * sum(each))
        cv = cross_validation_of(estimator, model, samples, splits, limits, settings,
                                 on_fit=fits.after(f"signals: {label}", each),
                                 made=made_for if delayed else None)
        tried.append((chain, recs, cv, tuple(found[t.tobytes()] for t in splits.train
                                             if t.tobytes() in found)))

    loaded = recorded(robot, first)[1]
    validate(chains[0], first, loaded)
    searches: list[tuple[str, DelayEstimate, bool, int]] = []

    def search(i: int, samples: Samples) -> bool:
        """The delay searched on chain ``i``'s ``samples``, that chain with it validated;
        whether it validates better."""
        chain, _, cv, _ = tried[i]
        found = delay_of(samples, model, rate, m, limits)
        late = eqx.tree_at(lambda c: c.delay_s, chain, found.seconds)
        kept, index = False, -1
        if not found.at_bound:
            validate(late, made_by(late), samples, delayed=True)
            kept, index = not DEFAULT.not_worse(cv, tried[-1][2]), len(tried) - 1
        searches.append((chain.label(recordings[0].recorded), found, kept, index))
        return kept

    # the loaded chain with the delay first: kept, every chain gets its own
    incumbent = int(search(0, loaded)) if largest_delay_s is not None else 0
    rest, searched = list(chains[1:]), {0}
    derived = next((i for i, c in enumerate(rest) if c.derive), None)
    if searches and searches[0][1].at_bound and derived is not None:
        # the loaded signals disagree in time among themselves (a logger's lagging
        # velocities): the delay searched on signals derived from the positions alone
        chain = rest.pop(derived)
        recs = made_by(chain)
        samples = recorded(robot, recs)[1]
        validate(chain, recs, samples)
        searched.add(len(tried) - 1)
        if search(len(tried) - 1, samples):
            incumbent = len(tried) - 1
    for chain in rest:
        recs = made_by(chain)
        samples = recorded(robot, recs)[1]
        if incumbent:
            chain = eqx.tree_at(lambda c: c.delay_s, chain,
                                delay_of(samples, model, rate, m, limits).seconds)
            validate(chain, made_by(chain), samples, delayed=True)
        else:
            validate(chain, recs, samples)
    scores = [cv for _, _, cv, _ in tried]
    best = min(scores, key=lambda cv: cv.score)
    chosen = incumbent if DEFAULT.not_worse(scores[incumbent], best) else scores.index(best)
    if searches and not incumbent and chosen not in searched:  # the chosen chain's own
        if search(chosen, recorded(robot, tried[chosen][1])[1]):
            chosen = len(tried) - 1
    selection = ChainSelection(
        tuple(c for c, _, _, _ in tried), tuple(cv for _, _, cv, _ in tried),
        tuple(c.label(recordings[0].recorded) for c, _, _, _ in tried), chosen, trim,
        f"{estimator.name}, {model.friction}", tuple(searches),
        tuple(d for _, _, _, d in tried))
    if chosen == 0:
        return selection, recordings, validation
    return selection, tried[chosen][1], OnSamples(validation, splits)
