"""``sedsabso-jax compare``: optimisers compared on COCO's BBOB suite and identification
problems, in this process or on Dask workers."""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
import time
from typing import TextIO

from . import _common
from ._common import Progress, add_run_options, subcommand


class CompareProgress(Progress):
    """A bar of tasks on a terminal; elsewhere (a log file) one line per finished task
    with the time left at the pace so far."""

    def __init__(self, stream: TextIO | None = None):
        super().__init__("compare", stream, unit="task")

    def __call__(self, label: str, done: float, total: float, elapsed: float = 0.0) -> None:
        from ..compare._run import estimated_seconds

        if self.stream.isatty():
            super().__call__(label, done, total)
            return
        left = estimated_seconds(int(done), int(total), elapsed)  # counts of tasks
        eta = "" if left != left else f" ~{left / 60:.0f} min left"
        print(f"compare: {done}/{total} {elapsed:6.0f} s {label}{eta}", file=self.stream,
              flush=True)


def run(args: argparse.Namespace) -> None:
    from ..compare import _report as report
    from ..compare import _run as compare
    from ..compare._campaign import compare as campaign

    def names(text: str) -> tuple[str, ...]:
        return tuple(v.strip() for v in text.split(",") if v.strip())

    if args.runs is not None and args.suite == "bbob":
        raise ValueError(f"--runs {args.runs} has no effect with --suite bbob, which runs once "
                         "per instance: drop --runs, or name instances k times for k runs")
    runs = {} if args.runs is None else {"runs": args.runs}  # else Settings' default
    settings = compare.Settings(suite=args.suite, algorithms=names(args.algorithms),
                                budget=args.budget, seed=args.seed,
                                functions=args.functions, dimensions=args.dimensions,
                                instances=args.instances, dtype=args.dtype, **runs)
    settings.check()
    t0 = time.perf_counter()
    with CompareProgress() as progress:
        docs = campaign(settings, args.out, progress=progress, workers=args.workers,
                        scheduler=args.scheduler, scheduler_timeout=args.scheduler_timeout)
    written = report.write_report(docs, report_settings(settings), args.out,
                                  seconds=time.perf_counter() - t0)
    print(open(written[0], encoding="utf-8").read().split("## Every problem")[0].rstrip())
    tasks = len(settings.tasks())
    coco = os.path.join(args.out, "coco")
    print(f"written: {tasks} task files in {os.path.join(args.out, 'tasks')}, "
          + (f"COCO folders in {coco}, " if settings.suite != "identification" else "")
          + ", ".join(written))
    if settings.suite != "identification" and missing("cocopp"):
        print("sedsabso-jax: note: COCO's figures and tables (python -m cocopp, see "
              "report.md) need cocopp: pip install 'sedsabso-jax[compare]'", file=sys.stderr)


def missing(module: str) -> bool:
    """Whether ``module`` cannot be imported (found without importing it)."""
    try:
        return importlib.util.find_spec(module) is None
    except (ImportError, ValueError):  # ValueError: a None placeholder in sys.modules
        return True


def report_settings(settings) -> dict:
    """What the report states of the settings."""
    from .._version import __version__

    return {"algorithms": list(settings.algorithms), "runs": settings.runs,
            "budget": settings.budget, "seed": settings.seed, "dtype": settings.dtype,
            "functions": list(settings.functions), "dimensions": list(settings.dimensions),
            "instances": list(settings.instances), "version": __version__}


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The ``compare`` subcommand's flags (its defaults are ``compare``'s own)."""
    from ._vocabulary import BBOB_DIMENSIONS, BBOB_FUNCTIONS, BBOB_INSTANCES
    from ._vocabulary import COMPARE_ALGORITHMS as DEFAULT_ALGORITHMS
    from ._vocabulary import COMPARE_BUDGET as DEFAULT_BUDGET

    functions, instances = BBOB_FUNCTIONS, BBOB_INSTANCES
    dimensions = ",".join(map(str, BBOB_DIMENSIONS))

    cp = subcommand(
        sub, "compare",
        help="compare optimisers on COCO's BBOB suite and identification problems",
        description="Run algorithms (the paper's swarms and any evosax strategy) with equal "
        "budgets in fitness evaluations: on COCO's bbob suite one run per instance, written "
        "in COCO's format for cocopp (OUT/coco/ALGORITHM), on the identification problems "
        "many seeded runs; write report.md (best algorithm, Mann-Whitney U with Holm "
        "correction, A12; on BBOB aRT and runtime ECDFs as cocopp computes them), "
        "summary.json, run-length ECDF figures and one JSON per task (an algorithm on a "
        "problem). Finished tasks in --out are not run again. Tasks run in this process, "
        "on --workers processes or on a Dask cluster (--scheduler).",
        examples=["sedsabso-jax compare --suite identification --runs 20",
                  "sedsabso-jax compare --suite bbob --algorithms SEDSABSO,CMA_ES "
                  "--dimensions 2,5 --workers 2 --out cmp",
                  "sedsabso-jax compare --suite bbob --scheduler tcp://10.0.0.5:8786"])
    problems = cp.add_argument_group("problems")
    problems.add_argument("--suite", default="all",
                          help="bbob, identification or all (all)")
    problems.add_argument("--functions", default=functions,
                          help=f"BBOB functions, numbers and ranges ({functions})")
    problems.add_argument("--dimensions", default=dimensions,
                          help=f"BBOB dimensions, of COCO's {dimensions} (all)")
    problems.add_argument("--instances", default=instances,
                          help=f"COCO's BBOB instance numbers, one run each ({instances}: "
                          "COCO's since 2023)")
    algorithms = cp.add_argument_group("algorithms")
    algorithms.add_argument("--algorithms", default=",".join(DEFAULT_ALGORITHMS),
                            help="comma-separated: SEDSABSO, BSO, LDWPSO and evosax "
                            "strategies by evosax's names, e.g. CMA_ES, PSO, "
                            f"DifferentialEvolution ({','.join(DEFAULT_ALGORITHMS)})")
    # default None: --runs given with --suite bbob (on the command line or in --config)
    # is refused, not ignored
    algorithms.add_argument("--runs", type=_common.positive_int, default=None,
                            help="seeded runs per algorithm and identification problem "
                            "(100); refused with --suite bbob, one run per instance")
    algorithms.add_argument("--budget", default=DEFAULT_BUDGET,
                            help="fitness evaluations per run: N, or Nd for N times the "
                            f"dimension ({DEFAULT_BUDGET})")
    algorithms.add_argument("--seed", type=_common.non_negative_int, default=0,
                            help="random seed (0)")
    algorithms.add_argument("--dtype", choices=("float64", "float32"), default="float64",
                            help="precision of the runs (float64)")
    execution = cp.add_argument_group("execution")
    where = execution.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_common.positive_int, default=None, metavar="N",
                       help="run the tasks on N worker processes on this machine, a Dask "
                       "LocalCluster (default: "
                       "in this process)")
    where.add_argument("--scheduler", metavar="ADDRESS", default=None,
                       help="send the tasks to a running Dask scheduler, e.g. "
                       "tcp://10.0.0.5:8786 (one dask-jobqueue starts)")
    execution.add_argument("--scheduler-timeout", type=_common.positive_float, default=20.0,
                           metavar="SECONDS",
                           help="how long to try to reach the scheduler, Dask's handshake "
                           "included (20)")
    outputs = cp.add_argument_group("outputs")
    outputs.add_argument("--out", default="compare-results",
                         help="directory for the report, figures, task files and COCO "
                         "folders (compare-results)")
    add_run_options(cp, config="runs = 20")
    cp.set_defaults(func=run)
