"""Terms real drives have that a fit recording may barely show, kept in the chosen model
unless they validate worse (:class:`KeptTerms`, :data:`KEPT_TERMS`).

Friction at rest (:class:`~.._model._presliding.Presliding`) acts where joints stand
still and reverse; an excitation recording barely rests, so a validation on it scores a
model with the term much as one without, and the one-standard-error rule, which prefers
fewer parameters, drops it (docs/explanation/identification-defaults.md). Every real
drive has friction at rest, so the default reverses the burden of proof for it: the term
is added to the model :func:`~._selection.select_model` chose (same estimator), and kept
unless its validation is worse than the chosen model's by more than the rule's margin
(:func:`~._cross_validation.not_worse`: the split-by-split excess above one standard
error and above :data:`~._cross_validation.TIE_FRACTION`). Where the data do show that
the term hurts, as with a plant whose joints hold nothing at rest and a model whose
state mimics its Coulomb jump, the validation says so and the term is dropped."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import equinox as eqx

from .._default._policy import DEFAULT
from .._model._term import AbstractTerm
from .._model._torque_model import TorqueModel
from ._cross_validation import CrossValidation, not_worse


def _alternatives(value: object) -> tuple[tuple[AbstractTerm, ...], ...]:
    """One term, one set of terms, or several sets: a tuple of sets."""
    if isinstance(value, AbstractTerm):
        return ((value,),)
    found: tuple = tuple(value)  # type: ignore[arg-type]
    if found and all(isinstance(t, AbstractTerm) for t in found):
        return (found,)
    return tuple((a,) if isinstance(a, AbstractTerm) else tuple(a) for a in found)


class KeptTerms(eqx.Module):
    """Terms added to the chosen model and kept unless they validate worse (module
    docstring). ``alternatives``: one term, a set of terms, or several sets (each tried
    in turn on the chosen model; of those not worse than it, the lowest-scoring is
    kept). A set whose terms the chosen model already has, all of them, is not tried."""

    alternatives: tuple[tuple[AbstractTerm, ...], ...] = eqx.field(converter=_alternatives)

    def __check_init__(self):
        if not self.alternatives or not all(
                a and all(isinstance(t, AbstractTerm) for t in a) for a in self.alternatives):
            raise TypeError(f"KeptTerms takes terms (Presliding(), ...), one set or "
                            f"several, got {self.alternatives!r}")

    def models(self, model: TorqueModel) -> tuple[TorqueModel, ...]:
        """``model`` with each alternative's terms added (one of each kind: a term of a
        kind the model has replaces it); none for an alternative the model already has."""
        out = []
        for terms in self.alternatives:
            if all(t in model.terms for t in terms):
                continue
            kinds = {type(t) for t in terms}
            kept = tuple(t for t in model.terms if type(t) not in kinds)
            out.append(dataclasses.replace(model, terms=kept + tuple(terms)))
        return tuple(out)

    def kept(self, chosen: CrossValidation, tried: Sequence[CrossValidation]) -> int | None:
        """The index into ``tried`` (the validations of :meth:`models`) of the model
        kept: the lowest-scoring of those not worse than ``chosen``; None: none is."""
        fine = [i for i, cv in enumerate(tried) if not_worse(cv, chosen)]
        return min(fine, key=lambda i: tried[i].score) if fine else None


#: What :func:`~sedsabso_jax.select_and_identify` adds to its choice by default
#: (:attr:`~.._default._policy.Default.kept_terms`).
KEPT_TERMS = KeptTerms(DEFAULT.kept_terms)
