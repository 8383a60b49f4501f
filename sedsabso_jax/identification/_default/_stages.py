"""The lines of a report that say what a fit's stages did (:mod:`~.._fit._fit`)."""

from __future__ import annotations


def stage_lines(settings: dict) -> list[str]:
    """What the fit's stages did (:mod:`~.._fit._fit`): the nonlinear parameters it
    searched (value, standard deviation, unit, on a bound, not determined; the method and
    its trials, or that they were held at the values given) and where the load of
    friction growing with it came from."""
    lines = []
    searched = settings.get("searched") or {}
    if searched:
        def one(name: str, s: dict) -> str:
            notes = ", ".join(n for n, on in (("on a bound", s["at_bound"]), (
                "not determined", not s.get("determined", True))) if on)
            std = "" if s["std"] is None else f" +- {s['std']:.2g}"
            return f"{name} = {s['value']:.4g}{std} {s['unit']}" + f" ({notes})" * bool(notes)

        found = ", ".join(one(name, s) for name, s in searched["parameters"].items())
        how = (f"searched ({searched['method']}, {searched['evaluations']} trials)"
               if searched["evaluations"] else f"{searched['method']}, not searched")
        lines.append(f"nonlinear parameters {how}: {found}")
    load = settings.get("load")
    if load:
        if "settled" in load:
            state = "settled" if load["settled"] else "NOT settled"
            lines.append(f"friction growing with the load: the fit's own rigid-body torque "
                         f"after {load['iterations']} fits ({state})")
        else:
            lines.append("friction growing with the load: the rigid-body torque of a least-"
                         "squares fit without it")
    return ["", *lines] if lines else []
