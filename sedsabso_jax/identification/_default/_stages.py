"""The lines of a report that say what a fit's stages did (:mod:`~.._fit._fit`)."""

from __future__ import annotations

import math
from collections.abc import Sequence

from ..._output import to_its_std
from .._model._term import AbstractTerm


def stage_lines(settings: dict, terms: Sequence[AbstractTerm]) -> list[str]:
    """What the fit's stages did (:mod:`~.._fit._fit`): the nonlinear parameters it
    searched (value to its standard deviation's second significant digit, that deviation,
    unit, on a bound, not determined; the method and its trials, or that they were held
    at the values given) and what its ``terms`` read of the fit (each term's
    :meth:`~.._model._term.AbstractTerm.read_line`)."""
    lines = []
    searched = settings.get("searched") or {}
    if searched:
        def one(name: str, s: dict) -> str:
            notes = ", ".join(n for n, on in (("on a bound", s["at_bound"]), (
                "not determined", not s.get("determined", True))) if on)
            finite = s["std"] is not None and math.isfinite(s["std"])
            value = to_its_std(s["value"], s["std"]) if finite else f"{s['value']:.4g}"
            std = "" if s["std"] is None else f" +- {s['std']:.2g}"
            return f"{name} = {value}{std} {s['unit']}" + f" ({notes})" * bool(notes)

        found = ", ".join(one(name, s) for name, s in searched["parameters"].items())
        how = (f"searched ({searched['method']}, {searched['evaluations']} trials)"
               if searched["evaluations"] else f"{searched['method']}, not searched")
        lines.append(f"nonlinear parameters {how}: {found}")
    lines += [line for term in terms if term.name in settings
              for line in [term.read_line(settings[term.name])] if line]
    return ["", *lines] if lines else []
