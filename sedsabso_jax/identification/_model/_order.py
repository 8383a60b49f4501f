"""The package's terms in the order of their columns, declared here, and the command
line's ``--friction`` text of a set of terms (:func:`parse_friction`,
:func:`friction_text`).

The base regressor already holds each joint's viscous and Coulomb friction
``FV_j qd_j + FC_j sign(qd_j)`` (the paper's Eq. 1); a term adds columns or reshapes them::

    Offset()             + OFF_j                        a constant torque (a sensor's zero)
    Quadratic()          + FQ_j qd_j |qd_j|             velocity-squared friction
    SmoothCoulomb(v)     sign(qd_j) -> tanh(qd_j / v)   Coulomb friction without the jump
    Armature()           + K_m^T IA_m (K_m . qdd)       rotor inertia of motor m
    CoupledMotorFriction() + K_m^T (FVM_m u_m + FCM_m sign(u_m)), u_m = K_m . qd:
                                                        friction of a motor m that turns
                                                        with several joints
    Stribeck(v_s)        + FS_j exp(-(qd_j / v_s)^2) c_j(qd)   friction above Coulomb's
                                                        near rest (Stribeck's curve)
    LoadFriction()       + FL_j |tau_load_j| c_j(qd)    Coulomb friction growing with the
                                                        torque the joint transmits
    Presliding(q_c)      + FP_j z_j(q; q_c)             friction held at rest: Dahl's state
                                                        along the recorded positions

A term of your own (a final subclass of :class:`~._term.AbstractTerm`, in your own file)
goes into a model as these do; its columns come after the package's, in the order
given. The command line knows the words of :data:`TERMS`, declared one line each in
``sedsabso_jax/_terms.py`` (:data:`~sedsabso_jax._terms.DECLARED`).
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable

from ..._terms import BASE_FRICTION as BASE_FRICTION
from ..._terms import DECLARED
from ..._terms import FRICTION_TERMS as FRICTION_TERMS
from ._term import AbstractTerm


def _declared() -> tuple[type[AbstractTerm], ...]:
    """The classes of :data:`~sedsabso_jax._terms.DECLARED`, each named by its word."""
    out = []
    for word, module, name in DECLARED:
        cls = getattr(importlib.import_module(f".{module}", __package__), name)
        if not (isinstance(cls, type) and issubclass(cls, AbstractTerm) and cls.name == word):
            raise TypeError(f"sedsabso_jax/_terms.py declares {word!r} as {module}.{name}, "
                            f"which is not a term named {word!r}")
        out.append(cls)
    return tuple(out)


#: The package's terms, in the order of their columns.
TERMS: tuple[type[AbstractTerm], ...] = _declared()
_NAMED = {t.name: t for t in TERMS}


def canonical_order(terms: object) -> object:
    """``terms`` (one term, or several) as a tuple in column order: the package's terms
    in :data:`TERMS`' order, then any others in the order given; anything but terms is
    left for the model's check to name."""
    if isinstance(terms, AbstractTerm):
        terms = (terms,)
    found = tuple(terms) if isinstance(terms, (tuple, list)) else terms
    if not isinstance(found, tuple) or not all(isinstance(t, AbstractTerm) for t in found):
        return found
    rank = {cls: i for i, cls in enumerate(TERMS)}
    return tuple(sorted(found, key=lambda t: rank.get(type(t), len(TERMS))))


def friction_text(terms: Iterable[AbstractTerm]) -> str:
    """The ``a+b`` text of ``terms`` (in column order): ``viscous-coulomb+offset+...``."""
    return "+".join((BASE_FRICTION, *(t.text for t in terms)))


def parse_friction(text: str) -> tuple[AbstractTerm, ...]:
    """The terms of the command line's ``--friction`` text: words of
    :data:`FRICTION_TERMS` joined by ``+`` (``"viscous-coulomb+offset+quadratic"``; the
    base regressor's ``viscous-coulomb`` is always in the model, so ``"offset"`` is the
    same), each ``word`` or ``word:option`` (``smooth:fit``, ``smooth:0.05``,
    ``stribeck:fit``, ``load:viscous``, ``presliding:fit``), each once, in column
    order."""
    if not isinstance(text, str) or not text:
        raise ValueError(f"friction must be a string of terms joined by '+' from "
                         f"{FRICTION_TERMS}, got {text!r}")
    given: dict[str, str | None] = {}
    for part in (p.strip() for p in text.split("+")):
        word, _, option = part.partition(":")
        word = word.strip()
        if word in given:
            raise ValueError(f"friction term {word!r} is given twice in {text!r}: each term "
                             f"once")
        given[word] = option.strip() or None
    unknown = set(given) - set(FRICTION_TERMS)
    if unknown:
        raise ValueError(f"unknown friction term(s) {sorted(unknown)}; known: {FRICTION_TERMS} "
                         f"(joined by '+', e.g. 'viscous-coulomb+offset')")
    if given.get(BASE_FRICTION) is not None:
        raise ValueError(f"{BASE_FRICTION} takes no option, got "
                         f"{BASE_FRICTION}:{given[BASE_FRICTION]}")
    return tuple(_NAMED[name].parse(given[name]) for name in FRICTION_TERMS[1:]
                 if name in given)
