"""What the default chooses among and by, and the rules between its options, stated
once: the estimators (:func:`estimator_candidates`), the validation
(:class:`DefaultValidation`) and :class:`Choice`, which the command line builds from its
flags before it loads any data."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any, ClassVar, cast

import equinox as eqx

from ...measurements._chain import SignalChain
from ...measurements._container import Measurements
from .._estimators._estimator import Estimator, Sigma
from .._estimators._least_squares import PhysicallyConsistent
from .._options import as_float, as_int, check_count
from .._validation._kept_terms import KEPT_TERMS, KeptTerms
from .._validation._screened_terms import SCREENED_TERMS, ScreenedTerms
from .._validation._splits import PhaseFolds, Pooled, RecordingFolds, SpeedSplits, Validation
from ._policy import AUTO, DEFAULT


def estimator_candidates(method: str | None = None, sigma: Sigma = AUTO, **options: Any
                         ) -> tuple[Estimator, ...]:
    """The estimators the default chooses among
    (:meth:`~._policy.Default.estimator_candidates` of :data:`~._policy.DEFAULT`)."""
    return DEFAULT.estimator_candidates(method, sigma, **options)


def _signals(value: object) -> object:
    """AUTO, None, or a tuple of chains (one chain: a tuple of it)."""
    if value is None or isinstance(value, str | tuple):
        return value
    if isinstance(value, SignalChain):
        return (value,)
    try:
        return tuple(value)  # type: ignore[arg-type]
    except TypeError:
        return value  # __check_init__ names it


class DefaultValidation(eqx.Module):
    """What :func:`~sedsabso_jax.select_and_identify` chooses by unless told, made for
    the recordings (:meth:`of`): ``Pooled((PhaseFolds(folds), SpeedSplits()))``, with
    :class:`~sedsabso_jax.RecordingFolds` (leave one recording out) instead of the phase folds
    for several recordings (``interpolation``: that part given, e.g.
    :class:`~sedsabso_jax.GivenFolds`); then, where it chooses among several torque models,
    ``kept`` (:class:`~sedsabso_jax.identification.KeptTerms`, default
    :data:`~sedsabso_jax.identification.KEPT_TERMS`: friction at rest with its
    displacements searched; None: nothing) added to the choice and kept unless it
    validates worse, and then ``screened``
    (:class:`~sedsabso_jax.identification.ScreenedTerms`, default
    :data:`~sedsabso_jax.identification.SCREENED_TERMS`: the smooth Coulomb's scales;
    None: nothing) searched where they validate better. After them, ``signals``: the
    signal chains chosen among (:func:`~._signals.choose_chain`; :data:`AUTO`, the default:
    :meth:`~._policy.Default.chains` and the torques' delay, where every recording keeps
    its recorded signals and was loaded without choosing a chain, else none; None: none,
    the signals as given; one :class:`~sedsabso_jax.measurements.SignalChain` or
    several, the first kept unless another validates better, no delay searched)."""

    folds: int = eqx.field(default=DEFAULT.folds, converter=as_int)
    kept: KeptTerms | None = KEPT_TERMS
    screened: ScreenedTerms | None = SCREENED_TERMS
    interpolation: Validation | None = None
    signals: Any = eqx.field(default=AUTO, converter=_signals)
    kind: ClassVar[str] = "default"
    min_recordings: ClassVar[int] = 1

    def __check_init__(self):
        check_count("folds", self.folds, 2)
        if self.kept is not None and not isinstance(self.kept, KeptTerms):
            raise TypeError(f"kept must be KeptTerms(...) or None, got {self.kept!r}")
        if self.screened is not None and not isinstance(self.screened, ScreenedTerms):
            raise TypeError(f"screened must be ScreenedTerms(...) or None, got "
                            f"{self.screened!r}")
        if self.interpolation is not None and not isinstance(self.interpolation, Validation):
            raise TypeError(f"interpolation must be a Validation (PhaseFolds(), "
                            f"GivenFolds(labels), ...) or None, got {self.interpolation!r}")
        if not (self.signals is None or self.signals == AUTO or (
                isinstance(self.signals, tuple) and self.signals
                and all(isinstance(c, SignalChain) for c in self.signals))):
            raise TypeError(f"signals must be {AUTO!r}, None or SignalChain(...)s, got "
                            f"{self.signals!r}")

    def of(self, recordings: Sequence[Measurements]) -> Validation:
        """The validation of ``recordings``."""
        interpolation: Validation = (
            self.interpolation if self.interpolation is not None
            else RecordingFolds() if len(recordings) > 1 else PhaseFolds(self.folds))
        return Pooled((interpolation, SpeedSplits()))

    def chains(self, recordings: Sequence[Measurements]) -> tuple[SignalChain, ...]:
        """The signal chains chosen among for ``recordings`` (the first: as they were
        loaded, or the first given); none: the signals as given. A ValueError where
        chains are given and a recording keeps no recorded signals."""
        if self.signals is None or (self.signals == AUTO and any(
                r.recorded is None or r.info.get("chain", {}).get("given", True)
                for r in recordings)):
            return ()
        if self.signals == AUTO:
            loaded = recordings[0].chain
            assert loaded is not None  # recorded, with a chain in its info
            found = DEFAULT.chains([r.recorded for r in recordings  # type: ignore[misc]
                                    ], loaded)
            return found if len(found) > 1 else ()  # one: the loaded, nothing to choose
        bare = [r.source for r in recordings if r.recorded is None]
        if bare:
            raise ValueError(f"{', '.join(bare)}: keeps no recorded signals to apply a signal "
                             f"chain to: load it with load_measurements or recorded_signals")
        return tuple(self.signals)


#: How :class:`Choice`'s messages name the options: as
#: :func:`~sedsabso_jax.select_and_identify`'s arguments, or as the command's flags.
_SPELLING = {
    "physical": ("physical=True", "--physical"),
    "prior_strength": ("prior_strength", "--prior-strength"),
    "prior_cv": ("prior_strength='cv'", "--prior-strength cv"),
    "no_validation": ("validation=None", "--folds 0"),
    "one_candidate": ("give one estimator and one torque model", "give --method, --weights "
                      "and --friction (the fit is unconstrained unless --physical)"),
    "offset_per_recording": ("one torque offset per recording", "--offset-per-recording"),
    "validation": ("validation", "--validation recordings"),
    "several": ("several recordings", "several --data files")}


class Choice(eqx.Module):
    """How :func:`~sedsabso_jax.select_and_identify` chooses, with the rules between its
    options stated once and checked when built (a one-line ValueError naming the options
    as the library's arguments, or with ``flags`` as the command's flags): the command
    line builds one from its flags before it loads any data, and hands it on
    (:func:`~._select_and_identify.chosen_and_identified`).

    ``validation``: what chooses (a :class:`~sedsabso_jax.Validation`, a
    :class:`DefaultValidation`, or None: nothing is validated, one candidate is fitted);
    ``physical``: only physically consistent fits (True), only unconstrained ones (False),
    or both (None); ``prior_strength``: a number, or ``"cv"`` to choose it by validation;
    ``candidates``: torque models x estimators given; ``recordings``: the recordings
    fitted together; ``offset_per_recording``: whether a model has one offset each."""

    validation: Validation | DefaultValidation | None = DefaultValidation()
    physical: bool | None = None
    prior_strength: float | str = eqx.field(default=0.0, converter=as_float)
    candidates: int = 1
    recordings: int = 1
    offset_per_recording: bool = False
    flags: bool = False

    def __check_init__(self):
        n = {k: v[self.flags] for k, v in _SPELLING.items()}
        if self.physical not in (None, True, False):
            raise ValueError(f"physical must be None (both, chosen by validation), True or "
                             f"False, got {self.physical!r}")
        if self.prior_strength != "cv" and not (isinstance(self.prior_strength, float)
                                                and self.prior_strength >= 0):
            raise ValueError(f"{n['prior_strength']} must be a number >= 0 or 'cv', got "
                             f"{self.prior_strength!r}")
        if self.prior_strength != 0.0 and self.physical is not True:
            raise ValueError(f"{n['prior_strength']} needs {n['physical']}: the pull to the "
                             f"a-priori parameters is part of the physically consistent fit")
        if self.prior_strength == "cv" and self.validation is None:
            raise ValueError(f"{n['prior_cv']} chooses by validation, which "
                             f"{n['no_validation']} turns off: give a number")
        if self.validation is None and self.candidates > 1:
            raise ValueError(f"{n['no_validation']} turns validation off, so nothing can be "
                             f"chosen by it: {n['one_candidate']}")
        if self.offset_per_recording and self.recordings < 2:
            raise ValueError(f"{n['offset_per_recording']} needs {n['several']}")
        if self.validation is not None and self.recordings < self.validation.min_recordings:
            raise ValueError(f"{n['validation']} ({self.validation.kind}) needs "
                             f"{n['several']}")

    def validation_of(self, recordings: Sequence[Measurements]) -> Validation | None:
        """The validation for ``recordings`` (None: none)."""
        return None if self.validation is None else self.validation.of(recordings)

    def estimators(self, estimators: tuple[Estimator, ...]) -> tuple[Estimator, ...]:
        """The candidates to fit: each estimator as given (``physical`` False, or nothing
        validated with ``physical`` None), physically consistent (True, fitted with a
        number ``prior_strength``), or both (None: the physically consistent form of each
        least-squares estimator after it)."""
        if self.physical is False or (self.physical is None and self.validation is None):
            return estimators
        if self.physical:
            physical = tuple(cast(PhysicallyConsistent, e.physically_consistent())
                             for e in estimators)
            if isinstance(self.prior_strength, str):  # "cv": chosen after the model
                return physical
            return tuple(dataclasses.replace(e, prior_strength=self.prior_strength)
                         for e in physical)
        # a least-squares fit (on normal equations) has a physically consistent form
        return tuple(f for e in estimators for f in (
            (e, e.physically_consistent()) if e.normal_equations and not e.physical else (e,)))
