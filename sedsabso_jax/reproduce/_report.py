"""Tables and figures of ``sedsabso-jax reproduce``, with the paper's numbers beside ours.

Every file is written atomically (temporary file, then rename): an earlier result is never
half-overwritten and a failed run leaves no partial file.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from .. import _output, paper
from .._output import PathLike, to_json, write_text
from ..dynamics._base_parameters import base_parameters
from ..dynamics._robot import Robot
from ..identification._default._report import PARAMETER_UNITS
from ..optim._baselines import ROUNDING
from ._experiment import Experiment

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: colour per method, shared by the figures
COLOURS = {"SEDSABSO": "tab:red", "BSO": "tab:blue", "LDWPSO": "tab:green"}


def _parameter_columns(name: str, value: str, source: str) -> list[tuple]:
    """Definitions of the columns a base-parameter table and Table 5 share."""
    return [("#", "row number"),
            (name, "the base parameter (Eq. 3-4), `R` appended where others are regrouped "
             "onto it"),
            ("expression", "the standard parameters it combines, coefficients in m or m^2"),
            (value, f"its value {source} {PARAMETER_UNITS}")]


def base_parameter_table(robot: Robot, *, paper_columns: bool = False) -> str:
    """Markdown table: name, expression, value from the robot's parameters; with
    ``paper_columns`` (the built-in RS010N) the paper's Table 5 beside it."""
    base = base_parameters(robot)
    values = np.asarray(base.values)
    value = "value (Table 2)" if paper_columns else "value"
    head = ["#", "base parameter", "expression", value]
    defs = _parameter_columns("base parameter", value, "from the paper's Table 2"
                              if paper_columns else "from the robot's parameters")
    if paper_columns:
        head += ["paper's Table 5 expression", "paper's Table 5 value"]
        defs += [(head[-2:], "the paper's theoretical expression and value as published, in "
                  "its notation (inconsistent with Table 2, see sedsabso_jax/paper.py)")]
    rows = []
    for i, (name, expr, v) in enumerate(zip(base.names, base.expressions, values), 1):
        row = [str(i), name, expr, f"{v:.4f}"]
        if paper_columns:
            label, published = paper.TABLE5_THEORETICAL.get(name, ("", None))
            row += [label, "" if published is None else f"{published:g}"]
        rows.append(row)
    return "\n".join([
        f"{robot.name}: {base.rank} base parameters of {robot.n_params} "
        f"({robot.n_joints} joints x 12)", "", _output.markdown_table(head, rows), "",
        _output.columns_note(*defs)])


def _g(x, digits: int = 3) -> str:
    return "" if x is None else f"{x:.{digits}g}"


def _rounding(x, scale: float | None) -> bool:
    """Whether ``x`` lies below :data:`~sedsabso_jax.optim._baselines.ROUNDING` of
    ``scale`` (None: unknown): on noise-free data the baselines' fitness and errors are
    the rounding of float64 and the LP's tolerance, whose digits differ between
    processors."""
    return x is not None and scale is not None and abs(x) < ROUNDING * scale


def _above(x, scale: float | None, digits: int = 3) -> str:
    """``x`` to ``digits`` significant digits, or ``0`` where it is rounding
    (:func:`_rounding`)."""
    return "0" if _rounding(x, scale) else _g(x, digits)


def _fixed(x: float) -> str:
    """``x`` to 4 decimals, without the sign of a value that rounds to 0."""
    text = f"{x:.4f}"
    return "0.0000" if float(text) == 0 else text


def _settings_line(results: dict) -> str:
    s = results["settings"]
    exc = s["excitation"]
    return (f"RS010N, {s['samples']} samples, noise {s['noise']:g}, scenario `{s['scenario']}` "
            f"(box {s['search_box']['rule']}), {s['runs']} runs x {s['iterations']} "
            f"iterations, seed {s['seed']}, {s['dtype']}, device {s['device']}; excitation "
            f"cond(W_b) = {exc['cond']:.4g}.")


def _document(title: str, results: dict, head, rows, note: str) -> str:
    table = _output.markdown_table(head, rows)
    return "\n".join([title, "", _settings_line(results), "", table, "", note, ""])


#: The methods of Tables 4 and 5.
METHODS = ("a swarm (SEDSABSO, BSO, LDWPSO, over its runs) or a baseline (OLS: ordinary least "
           "squares, LM: Levenberg-Marquardt least squares by optimistix, L1-LP: the exact "
           "minimum of Eq. 17 by linear programming)")


def table4(results: dict) -> str:
    """Markdown: per method the mean and spread of the final fitness (Eq. 17), time per
    run, batched time, compilation, largest base-parameter error, relative gap to the L1
    optimum; the paper's Table 4 beside it."""
    head = ["method", "fitness mean [N m]", "fitness std [N m]", "time/run [s]",
            "all runs batched [s]", "compile [s]", "max abs error", "relative gap to L1 optimum",
            "paper's fitness mean", "paper's time/run [s]"]
    rows = []
    torques, l1 = results.get("torque_l1_norm"), results["algorithms"].get("L1-LP")
    size = float(np.max(np.abs(results["base_parameters"]["true"])))
    for name, a in results["algorithms"].items():
        fit, secs = paper.TABLE4.get(name, (None, None))
        excess = None if l1 is None else a["fitness_mean"] - l1["fitness_mean"]
        gap = "0" if _rounding(excess, torques) else _g(a["gap_to_l1_optimum"], 3)
        rows.append([name, _above(a["fitness_mean"], torques, 4),
                     _above(a["fitness_std"], torques), _g(a["time_mean_s"], 3),
                     _g(a["batched_time_s"], 3), _g(a["compile_s"], 3),
                     _above(a["max_abs_error"], size), gap, _g(fit), _g(secs, 4)])
    note = _output.columns_note(
        ("method", METHODS),
        (("fitness mean [N m]", "fitness std [N m]"), "mean and standard deviation (ddof 0, "
         "0 for a baseline) over the runs of Eq. 17, the sum over samples and joints of "
         "|W_b p - tau|, at a run's final p; `0` below 1e-9 sum |tau| (the rounding of "
         "noise-free data, whose digits differ between processors)"),
        ("time/run [s]", "one run on its own after compilation (a baseline: its solve)"),
        ("all runs batched [s]", "all runs in one compiled call, whose results are shown"),
        ("compile [s]", "JAX compilation (a swarm's two calls, LM's solver, none for OLS "
         "and L1-LP)"),
        ("max abs error", "a run's largest |p_i - p_true_i| over the base parameters, each "
         "in its own unit (table5.md), averaged over the runs; `0` below 1e-9 of the "
         "largest |p_true_i|"),
        ("relative gap to L1 optimum", "(fitness mean - f_L1) / max(f_L1, 1e-9 sum |tau|), "
         "no unit, with f_L1 the L1-LP row's fitness and sum |tau| the torques' L1 norm (on "
         "noise-free data f_L1 is rounding noise, and 1e6 means an excess of 1e-3 sum |tau|);"
         " `0` where the excess is below 1e-9 sum |tau|"),
        (("paper's fitness mean", "paper's time/run [s]"), "the paper's Table 4 as published "
         "(MATLAB 9.1, i7-8550U, 10 runs, other data, excitation and search box: compare "
         "orders of magnitude, not digits)"))
    return _document("# Table 4: final fitness and time per run", results, head, rows, note)


def table5(results: dict) -> str:
    """Markdown: per base parameter its name, expression, true value, each method's value
    (mean over runs) and absolute error; the paper's Table 5 beside it."""
    bp = results["base_parameters"]
    methods = list(results["algorithms"])
    head = ["#", "name", "expression", "true"]
    for m in methods:
        head += [m, f"{m} err"]
    paper_heads = ["paper's SEDSABSO", "paper's BSO", "paper's LDWPSO"]
    head += ["paper's theoretical", *paper_heads]
    rows = []
    size = float(np.max(np.abs(bp["true"])))
    for i, (name, expr, true) in enumerate(zip(bp["names"], bp["expressions"], bp["true"])):
        row = [str(i + 1), name, expr, _fixed(true)]
        for m in methods:
            v = results["algorithms"][m]["params_mean"][i]
            row += [_fixed(v), _above(abs(v - true), size, 2)]
        _, theo = paper.TABLE5_THEORETICAL.get(name, ("", None))
        ident = paper.TABLE5_IDENTIFIED.get(name, (None, None, None))
        row += [_g(theo, 4), *(_g(v, 4) for v in ident)]
        rows.append(row)
    defs = _parameter_columns("name", "true", "from the paper's Table 2")
    note = _output.columns_note(
        *defs,
        (methods, "the method's value, the mean over a swarm's runs: " + METHODS),
        ([f"{m} err" for m in methods], "|value - true|, in the parameter's unit; `0` "
         "below 1e-9 of the largest |true| (rounding)"),
        ("paper's theoretical", "the paper's Table 5 theoretical value as published"),
        (paper_heads, "the paper's Table 5 identified values as published (inconsistent "
         "with Table 2 in places, see sedsabso_jax/paper.py: context, not a target)"))
    return _document("# Table 5: identified base parameters", results, head, rows, note)


def figure_population(history_n: dict, phases: dict) -> Figure:
    """Figure 5: the active population N(t) of SEDSABSO against BSO's constant N, with the
    areas (total beetle-iterations, i.e. work) shaded and given in the legend; for a swarm
    with ``phases`` (``[(first, end, slots), ...]``, its compiled phases), the slots
    actually computed."""
    plt = _output.pyplot()
    fig, ax = plt.subplots(figsize=(7, 4), constrained_layout=True)
    for name in ("SEDSABSO", "BSO"):
        if name not in history_n:
            continue
        n = np.asarray(history_n[name])
        t = np.arange(1, n.size + 1)
        ax.step(t, n, where="post", color=COLOURS[name], lw=2,
                label=f"{name}: N from {n[0]} to {n[-1]}, work {n.sum():,} beetle-iterations")
        ax.fill_between(t, 0, n, step="post", color=COLOURS[name], alpha=0.15)
        if len(phases.get(name, ())) > 1:  # what is computed: each phase's static slots
            slots = np.concatenate([np.full(b - a, k) for a, b, k in phases[name]])
            ax.step(t, slots, where="post", color=COLOURS[name], lw=1, ls="--",
                    label=f"{name} slots computed ({len(phases[name])} compiled phases), "
                          f"work {slots.sum():,}")
    ax.set_xlabel("iteration")
    ax.set_ylabel("active beetles N(t)")
    ax.set_title("Population size (paper's Fig. 5): Eq. 15-16 against constant N")
    top = max(int(np.max(history_n[k])) for k in ("SEDSABSO", "BSO") if k in history_n)
    ax.set_ylim(0, 1.45 * top)  # room for the legend above the curves
    ax.legend(loc="upper right")
    ax.grid(alpha=0.3)
    return fig


def figure_convergence(history_f: dict, l1_floor: float) -> Figure:
    """Figure 6: best fitness against iteration (log scale), median and min-max band over
    the runs per swarm, the exact L1 optimum as a horizontal line."""
    plt = _output.pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    lowest = np.inf
    for name, hf in history_f.items():
        hf = np.atleast_2d(np.asarray(hf))
        t = np.arange(1, hf.shape[1] + 1)
        colour = COLOURS.get(name)
        ax.plot(t, np.median(hf, axis=0), color=colour, lw=2,
                label=f"{name}: median of {hf.shape[0]} runs (band: min-max)")
        ax.fill_between(t, hf.min(axis=0), hf.max(axis=0), color=colour, alpha=0.2)
        lowest = min(lowest, float(hf.min()))
    ax.set_yscale("log")
    bottom = lowest / 3.0
    if l1_floor >= bottom:
        ax.axhline(l1_floor, color="k", ls="--", lw=1.5,
                   label=f"exact L1 optimum (LP): {l1_floor:.3g}")
    else:  # noise-free data: the optimum is ~0, far below every swarm; say so, keep the scale
        ax.axhline(bottom, color="k", ls=":", lw=1)
        ax.annotate(f"exact L1 optimum (LP) = {l1_floor:.2g}, far below this axis",
                    (0.99, 0.02), xycoords="axes fraction", ha="right", va="bottom")
        ax.set_ylim(bottom=bottom)
    ax.set_xlabel("iteration")
    ax.set_ylabel("best fitness, Eq. 17 [N m]")
    ax.set_title("Convergence (paper's Fig. 6)")
    ax.legend(loc="upper right")
    ax.grid(alpha=0.3, which="both")
    return fig


def write_outputs(experiment: Experiment, out_dir: PathLike | None,
                  json_path: PathLike | None = None) -> list[str]:
    """Write table4.md, table5.md, fig5_population.png, fig6_convergence.png and
    results.json into ``out_dir`` (created if missing), and results.json also to
    ``json_path`` if given (its directory created if missing). Everything is rendered
    before the first file is written, so an error leaves no partial set of results
    behind. Returns the paths written."""
    results = experiment.results
    text = to_json(results)  # fails before writing
    t4, t5 = table4(results), table5(results)
    fig5 = figure_population(experiment.history_n, experiment.phases)
    fig6 = figure_convergence(experiment.history_f, experiment.l1_floor)
    written = []
    if out_dir is not None:
        os.makedirs(out_dir, exist_ok=True)
        for name, content in (("table4.md", t4), ("table5.md", t5), ("results.json", text)):
            path = os.path.join(out_dir, name)
            write_text(path, content)
            written.append(path)
        for name, fig in (("fig5_population.png", fig5), ("fig6_convergence.png", fig6)):
            path = os.path.join(out_dir, name)
            _output.save_figure(fig, path)
            written.append(path)
    else:
        _output.pyplot().close("all")
    if json_path is not None:
        os.makedirs(os.path.dirname(os.path.abspath(json_path)), exist_ok=True)
        write_text(json_path, text)
        written.append(os.fspath(json_path))
    return written
