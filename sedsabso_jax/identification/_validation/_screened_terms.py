"""Scales the default searches only where they validate better (:class:`ScreenedTerms`,
:data:`SCREENED_TERMS`, :func:`with_screened`): the smooth Coulomb's velocity scales.

Validating a model with every joint's smooth Coulomb scale searched in every split
costs several times the default's identification. The default searches them from
:attr:`~.._default._policy.Default.noise_floor` (6) times the velocities' noise up
(:meth:`ScreenedTerms.at_noise`; from the candidates' own 0.02 rad/s where the
recordings do not give it): a sharper jump flips with that noise wherever a joint
rests, which an excitation recording cannot show. They are screened first, cheaply:
with the chosen model's searched values held where a fit to all the data puts them, the
scales are searched on all the data, and the two models are validated by the same
splits with nothing searched in them. Only where the scales
validate better by the default's rule (:meth:`~.._default._policy.Default.not_worse`:
the choice's split-by-split excess over them above one standard error) is the choice
with them searched validated as any candidate is (each split's own search, starting
from the scales found), and it is kept where that validation is better by the same
rule. The screen is optimistic for the scales (searched on the very samples it
predicts), which the second validation is not: it decides. Why and the measurements:
docs/explanation/identification-defaults.md."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import equinox as eqx
import numpy as np

from ...measurements._container import Measurements
from ...measurements._signal import DEFAULT_CUTOFF_HZ, velocity_noise
from .._default._policy import DEFAULT
from .._estimators._estimator import Estimator, checked_estimator
from .._fit._fit import fit as fit_model
from .._fit._samples import Samples
from .._model._scales import AbstractScale
from .._model._term import AbstractTerm
from .._model._torque_model import TorqueModel
from .._options import as_float, check_number
from .._search._methods import HELD, AbstractSearch, CoordinateSearch
from .._work import fit_seconds
from ._cross_validation import CrossValidation
from ._progress import Fits, split_seconds, train_rows
from ._splits import Splits


def _terms(value: Any) -> tuple:
    """One term or several: a tuple."""
    return (value,) if isinstance(value, AbstractTerm) else tuple(value)


class ScreenedTerms(eqx.Module):
    """Terms whose scales are searched only where they validate better (module
    docstring). ``terms``: scale terms with ``fitted=True``, each taking the place of the
    chosen model's term of its kind where that one's scale is not searched (a model
    without such a term is not screened); their scales start from the model's.
    ``search``: how the screen searches them on all the data (coarse, without Newton's
    polish: the validation that decides searches them again in each split).
    ``noise_floor``: a velocity scale's smallest (a term whose box narrows from below,
    :attr:`~.._model._scales.AbstractScale.narrowed_by`, ``smooth:fit:SMALLEST``) is
    this many times the velocities' noise where the recordings give it
    (:meth:`at_noise`); None: the terms' own. ``noise``: that noise, rad/s (None: not
    measured)."""

    terms: tuple[AbstractScale, ...] = eqx.field(converter=_terms)
    search: AbstractSearch = CoordinateSearch(newton=0)
    noise_floor: float | None = eqx.field(default=None, converter=as_float)
    noise: float | None = None

    def __check_init__(self):
        if not self.terms or not all(isinstance(t, AbstractScale) and t.fitted
                                     for t in self.terms):
            raise TypeError(f"ScreenedTerms takes scale terms with fitted=True "
                            f"(SmoothCoulomb(fitted=True), ...), got {self.terms!r}")
        if not isinstance(self.search, AbstractSearch) or not self.search.searches:
            raise TypeError(f"ScreenedTerms' search must be a search method "
                            f"(CoordinateSearch(), ...), got {self.search!r}")
        if self.noise_floor is not None:
            check_number("ScreenedTerms' noise_floor", self.noise_floor, strict=True)

    def at_noise(self, recordings: Sequence[Measurements]) -> ScreenedTerms:
        """These terms with each velocity scale's smallest at :attr:`noise_floor` times
        the velocities' noise of ``recordings`` (the largest joint's and recording's:
        :func:`~sedsabso_jax.measurements.velocity_noise` of the positions, at each
        recording's chain's cutoff), at least the scale's declared lower bound, and
        :attr:`noise` set; as they are without a floor, or where a recording's times
        cannot give it (too few samples, or a rate below twice the cutoff: arrays
        without times)."""
        if self.noise_floor is None:
            return self
        try:
            noise = max(float(np.max(velocity_noise(
                m.times, m.q, DEFAULT_CUTOFF_HZ if m.chain is None else m.chain.cutoff_hz)))
                for m in recordings)
        except ValueError:
            return self

        def floored(t: AbstractScale) -> AbstractScale:
            if t.narrowed_by is None or t.narrowed_by[1] != 0:
                return t
            lo, hi = t.declared().bounds
            smallest = max(lo, self.noise_floor * noise)  # type: ignore[operator]
            return dataclasses.replace(t, **{t.narrowed_by[0]: min(smallest,
                                                                    np.nextafter(hi, 0))})

        return dataclasses.replace(self, terms=tuple(floored(t) for t in self.terms),
                                   noise=noise)

    def searched(self, model: TorqueModel, start: TorqueModel | None = None
                 ) -> TorqueModel | None:
        """``model`` with these terms in place of its terms of their kinds, their scales
        starting from ``start``'s terms of those kinds (default: ``model``'s); None where
        ``model`` has no such term whose scale is not searched."""
        kinds: dict[type, AbstractScale] = {type(t): t for t in self.terms}

        def open_(t: AbstractTerm) -> bool:  # a term of theirs whose scale is not searched
            return isinstance(t, AbstractScale) and type(t) in kinds and not t.fitted

        if not any(open_(t) for t in model.terms):
            return None
        given = {type(t): t for t in (model if start is None else start).terms}

        def made(t: AbstractTerm) -> AbstractTerm:
            source = given[type(t)]
            if not open_(t) or not isinstance(source, AbstractScale):
                return t
            return dataclasses.replace(kinds[type(t)], **{source.declared().name:
                                                          source.scale})

        return dataclasses.replace(model, terms=tuple(made(t) for t in model.terms))

    def trial(self, held: TorqueModel) -> TorqueModel | None:
        """``held`` (a fit's model, its searched values held) with every scale it
        searched fixed at its value and these terms' searched by :attr:`search`; None
        where it has none of these terms' kinds unsearched."""
        fixed = tuple(t.fixed() if isinstance(t, AbstractScale) and t.fitted else t
                      for t in held.terms)
        return self.searched(dataclasses.replace(held, terms=fixed, search=self.search))


#: What :func:`~sedsabso_jax.select_and_identify` screens by default
#: (:attr:`~.._default._policy.Default.screened_terms`: the smooth Coulomb's velocity
#: scales, from 6 times the velocities' noise up, or from 0.02 rad/s).
SCREENED_TERMS = ScreenedTerms(DEFAULT.screened_terms, noise_floor=DEFAULT.noise_floor)


@dataclasses.dataclass(frozen=True, eq=False)
class Screen:
    """The screen of a choice (module docstring): ``found``, the choice's fit with the
    screened scales searched on all the data (the other searched values held);
    ``without`` and ``with_found``, the choice's fit and ``found`` validated with every
    searched value held; ``passed``: ``found`` validates better, and the choice with
    the scales searched was validated (``kept``: and it validates better); ``noise``:
    the velocities' noise that set the scales' smallest, ``noise_floor`` times it
    (:meth:`ScreenedTerms.at_noise`; None: the terms' own smallest)."""

    found: TorqueModel
    without: CrossValidation
    with_found: CrossValidation
    passed: bool
    kept: bool = False
    noise: float | None = None
    noise_floor: float | None = None

    def smallest(self) -> float:
        """The smallest scale searched (the lower end of the screened terms' box)."""
        return min(self.found.terms[i].search_bounds()[0]  # type: ignore[attr-defined]
                   for i, _ in self.found.nonlinear()
                   if self.found.terms[i].fitted)  # type: ignore[attr-defined]

    def scales(self) -> dict[str, float]:
        """The scales found, by name."""
        return {n: float(v) for i, nl in self.found.nonlinear()
                if self.found.terms[i].fitted  # type: ignore[attr-defined]
                for n, v in zip(nl.names, nl.values)}

    def line(self) -> str:
        unit = next(nl.unit for i, nl in self.found.nonlinear()
                    if self.found.terms[i].fitted)  # type: ignore[attr-defined]
        found = ", ".join(f"{n} = {v:.4g}" for n, v in self.scales().items())
        rule = "by more than one standard error of the split-by-split difference"
        then = (f"lower {rule}, so validated with them searched in each split (the last "
                f"row): " + ("lower again, kept" if self.kept else "not lower, not kept")
                if self.passed else f"not lower {rule}, not tried further")
        smallest = self.smallest()
        if self.noise is None:
            why = "the terms' own"
        else:  # the floor, or the end of the terms' box where the floor lies outside it
            floor = self.noise_floor * self.noise  # type: ignore[operator]
            noise = f"{self.noise_floor:g} x the velocities' noise, {self.noise:.2g} {unit}"
            why = (noise if abs(smallest - floor) <= 1e-9 * floor else
                   f"the terms' own lower bound, above {noise}" if smallest > floor else
                   f"just below the terms' upper bound: {noise} lies above it")
        return (f"scales searched where they validate better, from {smallest:.2g} "
                f"{unit} up ({why}): on all the data, every "
                f"other searched value held, {found} {unit}; validated with every "
                f"searched value held, {self.with_found.score:.4f} +- "
                f"{self.with_found.standard_error:.4f} against the choice's "
                f"{self.without.score:.4f} +- {self.without.standard_error:.4f}: {then}")

    def as_dict(self) -> dict:
        return {"scales": self.scales(), "held_score": self.without.score,
                "held_fold_scores": self.without.fold_scores.tolist(),
                "screened_score": self.with_found.score,
                "screened_fold_scores": self.with_found.fold_scores.tolist(),
                "passed": self.passed, "kept": self.kept, "smallest": self.smallest(),
                "noise": self.noise, "noise_floor": self.noise_floor, "line": self.line()}


def screen_seconds(screened: ScreenedTerms, estimator: Estimator, model: TorqueModel,
                   samples: Samples, splits: Splits) -> float:
    """The estimated seconds of screening ``model`` (:func:`with_screened`): the scales'
    search on all the data and two validations with nothing searched (0: not screened)."""
    trial = screened.trial(model)
    if trial is None:
        return 0.0
    held = dataclasses.replace(model, search=HELD)
    return fit_seconds(estimator, trial, samples.q.size) + 2 * sum(
        split_seconds(train_rows(samples, splits), estimator, held))


def with_screened(screened: ScreenedTerms, index: int, tried: list, options: list,
                  prepared: Any, limits: np.ndarray | None, fits: Fits
                  ) -> tuple[int, Screen | None]:
    """Screen candidate ``index`` of ``tried`` and ``options`` (:func:`~._selection.
    select_model`'s) with ``screened`` on ``prepared`` (its
    :class:`~._selection.Prepared` samples and splits) (module docstring); where the
    screen passes, the candidate with the scales searched is validated (appended). The
    index of the candidate kept, and the screen (None: not screened)."""
    estimator, model = options[index]
    samples, splits = prepared.samples, prepared.splits
    if screened.trial(model) is None or not model.searched_by.searches:
        return index, None  # nothing to screen, or a model whose values are held
    held = fit_model(estimator, model, samples, limits, warn=False).model
    trial = screened.trial(held)
    assert trial is not None
    rows = train_rows(samples, splits)
    search_s = fit_seconds(estimator, trial, samples.q.size)
    each = split_seconds(rows, estimator, held)
    fits.ahead(search_s + 2 * sum(each))
    label = f"{estimator.name}, {model.friction}"
    searched_on_all = fits.after(f"{label}: scales searched", [search_s])
    found = fit_model(estimator, trial, samples, limits, warn=False).model
    if searched_on_all is not None:
        searched_on_all()
    without, with_found = (prepared.validate(estimator, m, limits,
                                             fits.after(f"{label}: {what}", each))
                           for m, what in ((held, "held"), (found, "scales held")))
    if DEFAULT.not_worse(without, with_found):
        return index, Screen(found, without, with_found, False, noise=screened.noise,
                             noise_floor=screened.noise_floor)
    searched = screened.searched(model, found)
    assert searched is not None
    checked_estimator(estimator).check(searched, limits)
    each = split_seconds(rows, estimator, searched)
    fits.ahead(sum(each))
    tried.append(({**tried[index][0], "friction": searched.friction, "screened": True},
                  prepared.validate(estimator, searched, limits, fits.after(
                      f"{estimator.name}, {searched.friction} (kept where better)", each))))
    options.append((estimator, searched))
    kept = not DEFAULT.not_worse(tried[index][1], tried[-1][1])
    return (len(tried) - 1 if kept else index), Screen(
        found, without, with_found, True, kept, screened.noise, screened.noise_floor)
