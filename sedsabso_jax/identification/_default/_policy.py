"""The default choice as one value (:class:`Default`, :data:`DEFAULT`): every constant and
rule that ``sedsabso-jax identify`` and :func:`~sedsabso_jax.select_and_identify` choose
by unless told. Changing the default is editing :class:`Default`'s fields; the names the
package exports for them (``FRICTION_CANDIDATES``, ``ESTIMATOR_CANDIDATES``,
``PRIOR_STRENGTHS``, ``DEFAULT_FOLDS``, ``KEPT_TERMS``, ...) are read from
:data:`DEFAULT`. Why each value: docs/explanation/identification-defaults.md."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import equinox as eqx
import numpy as np

from ...measurements._chain import Recorded, SignalChain
from ...measurements._signal import edge_seconds, median_rate
from .._estimators._estimator import Estimator, Sigma
from .._estimators._least_squares import OLS, WLS
from .._fit._delay import LARGEST_DELAY_S
from .._model._actuators import Armature
from .._model._friction import SMOOTH_VELOCITY, SmoothCoulomb
from .._model._load import LoadFriction
from .._model._offset import Offset
from .._model._presliding import LARGEST_AT_REST, Presliding
from .._model._scales import AbstractScale
from .._model._term import AbstractTerm

#: ``method`` and ``sigma`` (``--method``, ``--weights``, ``--friction``) left to
#: validation.
AUTO = "auto"


class Default(eqx.Module):
    """The default choice: its candidates, kept terms, splits and rule.

    Candidates, simplest first: ``frictions`` (the torque models' terms beyond the base
    regressor's viscous and Coulomb friction: Coulomb friction without the jump at rest,
    then a torque offset, armature, Coulomb friction growing with the load),
    ``estimators`` (OLS, Gautier's WLS, WLS by the limits), ``sigmas`` (the weightings a
    fixed estimator is tried with; None: equal) and ``prior_strengths`` (the pulls of a
    physically consistent fit toward the a-priori parameters, multiples of the data
    term's mean curvature, none first).

    Kept terms: ``kept_terms``, added to the chosen model and kept unless they validate
    worse (friction at rest, its displacements searched up to ``largest_at_rest``, rad
    or m). Screened terms: ``screened_terms``, their scales searched in the chosen model
    where they validate better (the smooth Coulomb's, from ``noise_floor`` times the
    velocities' noise up where the recordings' times give it, from ``smallest_smooth``
    where they do not, rad/s or m/s).

    Splits: ``folds`` phase folds (a lag whose normalised autocorrelation reaches
    ``repeat_correlation`` is a repeat of the motion); speed splits fit below
    ``fit_below`` and predict above ``predict_above`` of each joint's peak speed, the
    ``peak_quantile`` quantile of ``|qd|``.

    Signal chains (:class:`~._choice.DefaultValidation`'s ``signals``): the loaded
    one, recorded and derived velocities and accelerations at each of ``cutoffs`` Hz
    (:meth:`chains`), then the torques' delay searched up to ``largest_delay_s`` either
    way.

    Rule: one standard error (Hastie, Tibshirani & Friedman, *The Elements of
    Statistical Learning*, 2009, Sec. 7.10) of the split-by-split excess, with excesses
    below ``tie_fraction`` of the best error counted as ties (:meth:`not_worse`);
    simpler is fewer parameters, then physically consistent, then earlier
    (:meth:`simplest`)."""

    frictions: tuple[tuple[AbstractTerm, ...], ...] = (
        (SmoothCoulomb(),), (Offset(), SmoothCoulomb()),
        (Offset(), Armature(), SmoothCoulomb()), (Offset(), SmoothCoulomb(), LoadFriction()),
        (Offset(), Armature(), SmoothCoulomb(), LoadFriction()))
    estimators: tuple[Estimator, ...] = (OLS(), WLS("residual"), WLS("limits"))
    sigmas: tuple[str | None, ...] = (None, "residual", "limits")
    prior_strengths: tuple[float, ...] = (0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)
    largest_at_rest: float = LARGEST_AT_REST
    smallest_smooth: float = SMOOTH_VELOCITY
    noise_floor: float = 6.0
    folds: int = 5
    repeat_correlation: float = 0.95
    fit_below: float = 0.7
    predict_above: float = 0.8
    peak_quantile: float = 0.995
    tie_fraction: float = 0.01
    cutoffs: tuple[float, ...] = (5.0, 10.0)
    largest_delay_s: float = LARGEST_DELAY_S
    auto: ClassVar[str] = AUTO

    def chains(self, recorded: Sequence[Recorded], loaded: SignalChain
               ) -> tuple[SignalChain, ...]:
        """The signal chains chosen among for recordings of ``recorded`` signals,
        ``loaded`` (the chain they were loaded with) first: velocities and accelerations
        recorded where there are, then derived, each at every one of :attr:`cutoffs`
        that lies below every recording's Nyquist frequency and leaves it 4 ringing
        times long; chains that make the same signals of every recording once."""
        out, seen = [], set()
        for chain in (loaded, *(SignalChain(c, derive) for derive in (False, True)
                                for c in self.cutoffs)):
            filtered = [r for r in recorded if chain.filters(r)]
            if any(not (chain.cutoff_hz < median_rate(r.times) / 2 and 4 * edge_seconds(
                    chain.cutoff_hz) < r.times[-1] - r.times[0]) for r in filtered):
                continue
            key = (tuple(chain.label(r) for r in recorded), chain.filter_torques)
            if key not in seen:
                seen.add(key)
                out.append(chain)
        return tuple(out)

    @property
    def kept_terms(self) -> tuple[tuple[AbstractTerm, ...], ...]:
        """The kept terms' alternatives (one: friction at rest, displacements searched)."""
        return ((Presliding(fitted=True, largest=self.largest_at_rest),),)

    @property
    def screened_terms(self) -> tuple[AbstractScale, ...]:
        """The terms whose scales are searched where they validate better: the smooth
        Coulomb's, from ``smallest_smooth`` up (the candidates' own) where the
        recordings do not give the velocities' noise
        (:meth:`~.._validation._screened_terms.ScreenedTerms.at_noise`)."""
        return (SmoothCoulomb(fitted=True, smallest=self.smallest_smooth),)

    def estimator_candidates(self, method: str | None = None, sigma: Sigma = AUTO,
                             **options: Any) -> tuple[Estimator, ...]:
        """The estimators chosen among (``--method``, ``--weights``): ``method`` None:
        :attr:`estimators`, or those with weighting ``sigma``; a registered name with
        ``sigma`` :data:`AUTO`: it with each of :attr:`sigmas` (WLS without None, its
        residual weighting; a costly one, a box search, with equal weights only); a name
        and a ``sigma``: it alone. ``sigma``: :data:`AUTO`, None or ``"equal"``,
        ``"residual"``, ``"limits"``; ``options``: the named estimator's (``runs``,
        ``iterations``, ``seed``, ...; those it lacks are ignored)."""
        if sigma != AUTO and sigma != "equal" and sigma not in self.sigmas:
            raise ValueError(f"sigma must be {AUTO!r}, 'equal' (None), 'residual' or "
                             f"'limits', got {sigma!r}")
        if method is None:
            wanted = None if sigma == "equal" else sigma
            return tuple(e for e in self.estimators if sigma == AUTO or e.sigma == wanted)
        first = Estimator.named(method, **options)
        if sigma == "equal":  # None where that is equal weights, else explicit
            sigma = None if first.default_weighting == "equal" else "equal"
        if sigma != AUTO:
            return (Estimator.named(method, sigma=sigma, **options),)
        if first.costly:
            return (first,)
        return tuple(Estimator.named(method, sigma=s, **options) for s in self.sigmas
                     if s is not None or first.default_weighting == "equal")

    def not_worse(self, cv: Any, best: Any) -> bool:
        """Whether ``cv``'s mean excess over ``best`` (two
        :class:`~.._validation._cross_validation.CrossValidation`), split by split, is at most one
        standard error of that excess, or below :attr:`tie_fraction` of the best error."""
        excess = cv.fold_scores - best.fold_scores
        k = len(excess)
        se = float(np.std(excess, ddof=1) / np.sqrt(k)) if k > 1 else 0.0
        return float(np.mean(excess)) <= max(se, self.tie_fraction * best.score)

    def simplest(self, scores: Sequence[Any], physical: Sequence[bool]) -> int:
        """The index of the candidate the rule picks among ``scores`` (each candidate's
        validation, with ``n_parameters``; ``physical``: whether its fit is physically
        consistent): the simplest of those :meth:`not_worse` than the lowest-scoring."""
        best = min(scores, key=lambda cv: cv.score)
        order = sorted(range(len(scores)), key=lambda i: (scores[i].n_parameters,
                                                          not physical[i], i))
        return next(i for i in order if self.not_worse(scores[i], best))


#: The default choice.
DEFAULT = Default()
