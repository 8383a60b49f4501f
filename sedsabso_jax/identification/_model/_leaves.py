"""A torque model's searched parameters as leaves of its tree: :func:`partition` splits a
model as ``equinox.partition`` does, each term's searched values (an array ``(k,)`` in the
field that holds them, :attr:`~._term.Nonlinear.field`) on one side and everything else on
the other, so that ``equinox.combine`` puts a trial's values back; :func:`with_nonlinear`
puts values in those fields (a trial's as array leaves, found values as floats);
:func:`tree_key`, a tree's key by its structure and its leaves' values."""

from __future__ import annotations

import dataclasses
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._term import AbstractTerm


def placed(term: AbstractTerm, field: str, values: Any) -> AbstractTerm:
    """``term`` with ``values`` in its ``field``: traced values (a trial inside a compiled
    search) as they are, an array leaf; others as floats, through the field's converter
    and the term's checks."""
    if isinstance(values, jax.core.Tracer):
        return eqx.tree_at(lambda t: getattr(t, field), term, values)
    return dataclasses.replace(term, **{field: tuple(float(v) for v in np.asarray(values))})


def partition(model: Any) -> tuple[Any, Any]:
    """``(searched, rest)`` of ``model`` (a :class:`~._torque_model.TorqueModel`): in
    ``searched`` each term's searched values, an array ``(k,)`` at the field that holds them
    (their start, :meth:`~._torque_model.TorqueModel.nonlinear`), every other leaf None;
    ``rest`` the model without them. ``equinox.combine(searched, rest)`` is the model with
    the values of ``searched``, taken as they are (arrays, or traced values)."""
    found = model.nonlinear()
    own = [model.terms[i].name for i, f in found if f.field is None]
    if own:
        raise TypeError(f"terms {own} place their searched values themselves "
                        f"(with_nonlinear): partition needs the field that holds them "
                        f"(Nonlinear(..., field=NAME) from nonlinear(model))")

    def fields(m: Any) -> tuple:
        return tuple(getattr(m.terms[i], f.field) for i, f in found)

    leaves = eqx.tree_at(fields, model, tuple(jnp.asarray(f.values) for _, f in found))
    spec = eqx.tree_at(fields, jax.tree_util.tree_map(lambda _: False, leaves),
                       (True,) * len(found))
    return eqx.partition(leaves, spec)


def with_nonlinear(model: Any, values: Any) -> Any:
    """``model`` with its searched parameters at ``values`` (those of its
    :meth:`~._torque_model.TorqueModel.nonlinear`, concatenated), each term's in the field
    that holds them (:func:`placed`), or placed by the term itself where it names none."""
    terms, k = list(model.terms), 0
    for i, found in model.nonlinear():
        part = values[k:k + len(found.values)]
        terms[i] = (terms[i].with_nonlinear(part) if found.field is None
                    else placed(terms[i], found.field, part))
        k += len(found.values)
    if k != np.shape(values)[0]:
        raise ValueError(f"expected {k} nonlinear parameters, got {np.shape(values)[0]}")
    # the terms in their places (each checked itself): floats or traced values alike
    return eqx.tree_at(lambda m: m.terms, model, tuple(terms))


def tree_key(tree: Any) -> tuple:
    """A hashable key of ``tree`` (a pytree: a term, a base, a search; for a model its
    :attr:`~._torque_model.TorqueModel.structure`, since a model's own tree also carries
    the answers it has cached) by its structure and values: its tree structure (the
    classes, their static fields) and each leaf's value (an array's shape, dtype and
    bytes). Two trees with equal keys compute the same columns, whatever their
    ``settings()`` say."""
    leaves, treedef = jax.tree_util.tree_flatten(tree)
    return (treedef, tuple(_leaf_key(x) for x in leaves))


def _leaf_key(x: Any) -> Any:
    if isinstance(x, (np.ndarray, jax.Array)) and not isinstance(x, jax.core.Tracer):
        a = np.asarray(x)
        return (a.shape, a.dtype.str, a.tobytes())
    return x
