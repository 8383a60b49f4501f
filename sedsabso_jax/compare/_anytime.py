"""The anytime measures of the BBOB problems, as cocopp gives them on the same COCO
folders: the average runtime (aRT) per (function, dimension, target), and the runtime
ECDF per dimension over the functions and COCO's 51 targets (the share of (run, target)
pairs reached within a number of evaluations per dimension). Both are computed from the
run lengths that cocopp reads off the ``.dat`` files (:mod:`._alignment`); the ECDF is
cocopp's ``pprldmany`` up to the budget (beyond it cocopp adds simulated restarts).
"""

from __future__ import annotations

import numpy as np

from .._output import columns_note, markdown_table
from ._bbob import parse_name
from ._statistics import COCO_TARGETS, average_runtime, ecdf

#: the targets of cocopp's tables (``pptable_targetsOfInterest``) and its final target
TABLE_TARGETS = (1e1, 1e0, 1e-1, 1e-2, 1e-3, 1e-5, 1e-7)
FINAL_TARGET = 1e-8
#: evaluations per dimension at which the report states the ECDF (and the budget)
ECDF_POINTS = (1, 10, 100)


def _lengths(alg: dict) -> np.ndarray:
    return np.array([[np.inf if v is None else v for v in row] for row in alg["run_lengths"]],
                    dtype=float)


def _index(target: float) -> int:
    return int(np.argmin(np.abs(np.log10(COCO_TARGETS) - np.log10(target))))


def summary(docs: list[dict]) -> dict:
    """aRT of every (problem, algorithm) at COCO's targets, with the successes, and the
    runtime ECDF of every (dimension, algorithm) on a grid of evaluations per dimension."""
    art: list[dict] = []
    by_dim: dict[int, dict[str, list]] = {}
    for doc in docs:
        p = doc["problem"]
        if p["suite"] != "bbob":
            continue
        for name, alg in doc["algorithms"].items():
            lengths = _lengths(alg)
            spent = np.full(len(lengths), float(alg["evaluations"]))
            function = (parse_name(p["name"]) or (0, 0))[0]
            art.append({"problem": p["name"], "function": function, "dim": p["dim"],
                        "algorithm": name, "runs": len(lengths),
                        "aRT": average_runtime(lengths, spent),
                        "successes": np.isfinite(lengths).sum(axis=0)})
            by_dim.setdefault(p["dim"], {}).setdefault(name, []).append(
                (lengths, alg["evaluations"]))
    ecdfs = {}
    for dim, algs in sorted(by_dim.items()):
        top = max(e for runs in algs.values() for _, e in runs)
        grid = np.unique(np.concatenate([np.geomspace(1, top, 100), [top]])) / dim
        ecdfs[str(dim)] = {"evaluations_per_dimension": grid,
                           "functions": {n: len(runs) for n, runs in algs.items()},
                           "share": {n: ecdf(np.concatenate([r.ravel() for r, _ in runs]),
                                             grid * dim)
                                     for n, runs in algs.items()}}
    return {"targets": COCO_TARGETS, "aRT": art, "ecdf": ecdfs}


def _g(x: float) -> str:
    return "inf" if not np.isfinite(x) else f"{x:.3g}"


def markdown(anytime: dict, labels: dict[str, str]) -> list[str]:
    """The report's section on the anytime measures (lines)."""
    if not anytime["aRT"]:
        return []
    cols = [f"1e{int(np.log10(t))}" for t in TABLE_TARGETS]
    lines = ["## Anytime: average runtime and runtime ECDF (as cocopp computes them)", "",
             "From the COCO folders in `coco/` (see *Reproduce with cocopp* below): aRT, the "
             "evaluations of all runs until each reached `f_opt + target` or ran out, over "
             "the number of runs that reached it (`inf`: none did); a target reached inside "
             "an iteration counts at the iteration's end.", ""]
    rows = []
    final = _index(FINAL_TARGET)
    for r in sorted(anytime["aRT"], key=lambda r: (r["dim"], r["function"],
                                                   list(labels).index(r["algorithm"]))):
        rows.append([str(r["dim"]), f"f{r['function']}", labels[r["algorithm"]],
                     *[_g(r["aRT"][_index(t)]) for t in TABLE_TARGETS],
                     f"{r['successes'][final]}/{r['runs']}"])
    head = ["d", "f", "algorithm", *cols, "solved 1e-8"]
    lines += ["### aRT (evaluations)", "",
              markdown_table(head, rows, align=["right", "left", "left", *["right"] * len(cols),
                                                "right"]), "",
              columns_note(("d", "the dimension"), ("f", "the BBOB function"),
                           ("algorithm", "the algorithm"),
                           (cols, "aRT to reach `f - f_opt` at or below that target"),
                           ("solved 1e-8", "the runs that reached 1e-8, of all runs")), ""]
    head = [f"{n} d" for n in ECDF_POINTS] + ["budget"]
    rows = []
    for dim, e in anytime["ecdf"].items():
        grid = np.asarray(e["evaluations_per_dimension"])
        for name, share in e["share"].items():
            at = [float(np.asarray(share)[np.searchsorted(grid, x, side="right") - 1])
                  if x >= grid[0] else 0.0 for x in (*ECDF_POINTS, grid[-1])]
            rows.append([f"{dim}-D ({e['functions'][name]} functions)", labels[name],
                         *[f"{v:.3f}" for v in at]])
    lines += ["### Runtime ECDF: share of (run, target) pairs reached", "",
              markdown_table(["dimension", "algorithm", *head], rows), "",
              columns_note(("dimension", "the functions of one dimension"),
                           ("algorithm", "the algorithm"),
                           (head, "the share of (function, run, target) triples reached "
                            "within that many evaluations times the dimension, over COCO's "
                            "51 targets 1e2 .. 1e-8 (cocopp's runtime ECDF up to the "
                            "budget)")), ""]
    return lines


def reproduce(algorithms: list[str], out: str = "OUT") -> list[str]:
    """The report's section on reproducing the BBOB figures and tables with cocopp."""
    folders = " ".join(f"{out}/coco/{a}" for a in algorithms)
    return ["## Reproduce with cocopp", "",
            "Each algorithm's runs are in COCO's format in `coco/ALGORITHM/` (what COCO's "
            "`bbob` observer writes). COCO's standard figures and tables, offline:", "",
            "```bash", f"python -m cocopp -o {out}/ppdata {folders}", "```", "",
            "Beside archived algorithms (needs internet; `cocopp.archives.bbob('cma')` lists "
            "the archived data sets whose names contain `cma`; a trailing `!` takes the "
            "first match):", "",
            "```bash", f"python -m cocopp -o {out}/ppdata {folders} 'bbob/2009/BIPOP-CMA-ES!'",
            "```", ""]
