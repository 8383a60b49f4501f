"""What ``sedsabso-jax compare`` writes from the problems' documents: ``report.md`` (which
algorithm is best where, which differences are significant, and on BBOB the anytime
measures as cocopp gives them, :mod:`._anytime`), ``summary.json`` (every problem's
statistics and the anytime measures) and ECDF figures of run lengths (PNG).

The best algorithm of a problem has the lowest median final precision (ties: the lower
mean); "significant" is a two-sided Mann-Whitney U test at 0.05 after Holm's correction
over all pairs of algorithms of that problem (:mod:`._statistics`).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import jax
import numpy as np

from .._output import (
    PathLike,
    columns_note,
    markdown_table,
    pyplot,
    save_figure,
    to_json,
    write_text,
)
from . import _anytime
from ._bbob import ranges
from ._statistics import ALPHA, ecdf, effect_size_label, pairwise, summary

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _array(values) -> np.ndarray:
    """A JSON list back to floats: None (NaN or Inf when written) as +Inf."""
    return np.array([np.inf if v is None else v for v in np.ravel(np.asarray(
        values, dtype=object))], dtype=float).reshape(np.shape(values))


def problem_statistics(doc: dict) -> dict:
    """Summary, pairwise tests and the best algorithm of one problem's document."""
    algs = doc["algorithms"]
    prec = {name: _array(a["precision"]) for name, a in algs.items()}
    stats = {name: summary(v) for name, v in prec.items()}
    best = min(prec, key=lambda n: (stats[n]["median"], float(np.mean(
        np.minimum(prec[n], np.finfo(float).max)))))
    tests = pairwise(prec)
    tied = [t["b"] if t["a"] == best else t["a"] for t in tests
            if best in (t["a"], t["b"]) and not t["significant"]]
    return {"problem": doc["problem"]["name"], "suite": doc["problem"]["suite"],
            "dim": doc["problem"]["dim"], "best": best, "tied_with_best": tied,
            "algorithms": stats, "tests": tests}


def _test(stats: dict, a: str, b: str) -> dict | None:
    for t in stats["tests"]:
        if {t["a"], t["b"]} == {a, b}:
            a12 = t["a12"] if t["a"] == a else 1.0 - t["a12"]
            return {**t, "a12_a_vs_b": a12}
    return None


def _verdict(stats: dict, a: str, b: str, labels: dict) -> str:
    t = _test(stats, a, b)
    if t is None:
        return "-"
    size = effect_size_label(t["a12_a_vs_b"])
    if not t["significant"]:
        return f"n.s. (p {t['p_holm']:.2g})"
    who = "better" if t["better"] == a else "worse"
    return f"{who}, p {t['p_holm']:.1g}, A12 {t['a12_a_vs_b']:.2f} ({size})"


def _g(x: float) -> str:
    return "inf" if not np.isfinite(x) else f"{x:.3g}"


def _group(stats: dict) -> str:
    return f"BBOB d = {stats['dim']}" if stats["suite"] == "bbob" else "identification"


def render(docs: list[dict], settings: dict, seconds: float | None = None,
           out: str = "OUT") -> tuple[str, dict]:
    """``(report.md text, summary document)``; ``out``: the output directory as the
    report's commands name it."""
    algorithms = list(docs[0]["algorithms"])
    labels = {n: docs[0]["algorithms"][n]["label"] for n in algorithms}
    all_stats = [problem_statistics(d) for d in docs]
    peers = [p for p in ("BSO", "PSO", "LDWPSO") if p in algorithms and p != "SEDSABSO"]
    versus = [p for p in ("BSO", "PSO") if p in peers] or peers[:2]

    lines = ["# Comparison of optimisers", ""]
    device = jax.devices()[0]
    bbob = any(d["problem"]["suite"] == "bbob" for d in docs)
    runs = ([f"one seeded run per BBOB instance (COCO's {_instances(settings)})"]
            if bbob else []) + ([f"{settings['runs']} seeded runs per identification problem"]
                                if any(d["problem"]["suite"] != "bbob" for d in docs) else [])
    lines += [f"{len(docs)} problems; for every algorithm {', '.join(runs)}; budget "
              f"{settings['budget']} fitness evaluations (`d`: times the "
              f"dimension), seed {settings['seed']}, {settings['dtype']}, device "
              f"{device.platform}: {device.device_kind}, sedsabso-jax "
              f"{settings['version']}." + (f" Wall time {seconds / 60:.1f} min."
                                           if seconds else ""), ""]
    lines += ["Precision: `f - f_opt` on BBOB (COCO's functions and numbered instances); on "
              "identification problems the excess over the exact L1 optimum in "
              "the box as a share of the torques' L1 norm, `(f - f_opt) / sum |tau|`; no "
              "unit either way. Best: lowest median final precision. Significance: "
              f"two-sided Mann-Whitney U, Holm-corrected over all pairs of a problem, "
              f"alpha = {ALPHA}; A12: probability that a run of the first ends below a "
              "run of the second.", ""]

    # wins per group
    groups: dict[str, list] = {}
    for s in all_stats:
        groups.setdefault(_group(s), []).append(s)
    names = [labels[a] for a in algorithms]
    rows = []
    for g, ss in groups.items():
        wins = {a: sum(s["best"] == a for s in ss) for a in algorithms}
        rows.append([f"{g} ({len(ss)})", *[str(wins[a]) for a in algorithms]])
    lines += ["## Best algorithm: problems won (lowest median)", "",
              markdown_table(["problems", *names], rows), "", columns_note(
                  ("problems", "a group of problems (BBOB at dimension d, or the "
                   "identification problems), their number in parentheses"),
                  (names, "the problems of the group on which the algorithm has the lowest "
                   "median final precision (ties: the lower mean)")), ""]
    if "SEDSABSO" in algorithms and versus:
        head = [f"SEDSABSO vs {labels[p]}: better / n.s. / worse" for p in versus]
        rows = []
        for g, ss in groups.items():
            cells = []
            for p in versus:
                ts = [t for s in ss if (t := _test(s, "SEDSABSO", p)) is not None]
                better = sum(t["significant"] and t["better"] == "SEDSABSO" for t in ts)
                worse = sum(t["significant"] and t["better"] == p for t in ts)
                cells.append(f"{better} / {len(ts) - better - worse} / {worse}")
            rows.append([g, *cells])
        lines += [f"## SEDSABSO against {' and '.join(labels[p] for p in versus)} "
                  "(significant at 0.05 after Holm)", "",
                  markdown_table(["problems", *head], rows), "", columns_note(
                      ("problems", "a group of problems"),
                      (head, "the numbers of its problems on which SEDSABSO ends significantly "
                       "lower (better), not significantly different (n.s.) and significantly "
                       "higher (worse), by the test above")), ""]

    # per-problem table
    medians = [f"{labels[a]} median [IQR]" for a in algorithms]
    against = [f"SEDSABSO vs {labels[p]}" for p in versus if "SEDSABSO" in algorithms]
    rows = []
    for s in all_stats:
        cells = []
        for a in algorithms:
            st = s["algorithms"][a]
            cell = f"{_g(st['median'])} [{_g(st['iqr'])}]"
            cells.append(f"**{cell}**" if a == s["best"] else cell)
        best = labels[s["best"]] + (f" (tied: {', '.join(labels[t] for t in s['tied_with_best'])})"
                                    if s["tied_with_best"] else "")
        vs = ([_verdict(s, "SEDSABSO", p, labels) for p in versus]
              if "SEDSABSO" in algorithms else [])
        rows.append([s["problem"], best, *cells, *vs])
    notes = [("problem", "the problem's name"),
             ("best", "the algorithm with the lowest median final precision (tied: those "
              "not significantly different from it)"),
             (medians, "median [interquartile range q3 - q1] of the final precision over "
              "the runs, in bold for the best (inf: runs that ended on non-finite values)")]
    if against:
        notes.append((against, "`better` or `worse` where SEDSABSO ends significantly lower "
                      "or higher, with the Holm-adjusted p and A12, the probability that a "
                      "SEDSABSO run ends below a run of the other (ties half), in Vargha and "
                      "Delaney's words (negligible, small, medium, large from |A12 - 0.5| of "
                      "0, 0.06, 0.14, 0.21), else `n.s.` (not significant) with its p"))
    lines += ["## Every problem: final precision", "",
              markdown_table(["problem", "best", *medians, *against], rows), "",
              columns_note(*notes), ""]
    lines += ["Figures: `ecdf_*.png`, the share of (run, target) pairs reached against "
              "fitness evaluations / dimension (COCO's run-length ECDF); targets 1e2 .. 1e-8 "
              "on BBOB, 1 .. 1e-8 (relative) on identification.", ""]
    anytime = _anytime.summary(docs)
    lines += _anytime.markdown(anytime, labels)
    if bbob:
        lines += _anytime.reproduce(algorithms, out)
    summary_doc = {"settings": settings, "problems": all_stats, "anytime": anytime}
    return "\n".join(lines), summary_doc


def _instances(settings: dict) -> str:
    """COCO instance numbers as ranges: ``1-5, 101-110``."""
    return ranges(settings.get("instances", []), ", ")


def ecdf_figure(docs: list[dict], title: str) -> Figure:
    """One ECDF of run lengths per algorithm over every (problem, run, target) of
    ``docs`` (of one dimension each, as COCO aggregates)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    algorithms = list(docs[0]["algorithms"])
    dim = docs[0]["problem"]["dim"]
    top = max(max(a["evaluations"] for a in d["algorithms"].values()) for d in docs)
    grid = np.geomspace(1, top, 200)
    for name in algorithms:
        lengths = np.concatenate([_array(d["algorithms"][name]["run_lengths"]).ravel()
                                  for d in docs])
        ax.step(grid / dim, ecdf(lengths, grid), where="post",
                label=docs[0]["algorithms"][name]["label"])
    ax.set_xscale("log")
    ax.set_ylim(0, 1)
    ax.set_xlabel("fitness evaluations / dimension")
    ax.set_ylabel("share of (run, target) pairs reached")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    return fig


def figures(docs: list[dict]) -> dict:
    """File name -> figure: one ECDF per BBOB dimension (all 24 functions) and one per
    identification problem."""
    out = {}
    by_dim: dict[int, list] = {}
    for d in docs:
        if d["problem"]["suite"] == "bbob":
            by_dim.setdefault(d["problem"]["dim"], []).append(d)
        else:
            out[f"ecdf_{d['problem']['name']}.png"] = ecdf_figure(
                [d], f"{d['problem']['name']} (d = {d['problem']['dim']})")
    for dim, ds in sorted(by_dim.items()):
        out[f"ecdf_bbob_d{dim:02d}.png"] = ecdf_figure(
            ds, f"BBOB, {len(ds)} functions, d = {dim}")
    return out


def write_report(docs: list[dict], settings: dict, out_dir: PathLike,
                 seconds: float | None = None) -> list[str]:
    """Render everything, then write report.md, summary.json and the figures."""
    text, summary_doc = render(docs, settings, seconds, os.fspath(out_dir))
    summary_text = to_json(summary_doc)
    figs = figures(docs)
    written = []
    for name, content in (("report.md", text), ("summary.json", summary_text)):
        written.append(os.fspath(write_text(os.path.join(out_dir, name), content)))
    for name, fig in figs.items():
        path = os.path.join(out_dir, name)
        save_figure(fig, path)
        written.append(path)
    return written
