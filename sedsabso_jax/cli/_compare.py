"""``sedsabso-jax compare``: optimisers compared on BBOB and identification problems."""

from __future__ import annotations

import argparse
import os
import time
from typing import TextIO

from ._common import (
    Progress,
    add_run_options,
    check_writable,
    non_negative_int,
    positive_int,
    subcommand,
)


class CompareProgress(Progress):
    """A bar per problem on a terminal; elsewhere (a log file) one line per problem with
    the time left at the pace so far."""

    def __init__(self, stream: TextIO | None = None):
        super().__init__("compare", stream, unit="problem")

    def __call__(self, label: str, done: int, total: int, elapsed: float = 0.0) -> None:
        from ..compare._run import estimated_seconds

        if self.stream.isatty():
            super().__call__(label, done, total)
            return
        left = estimated_seconds(done, total, elapsed)
        eta = "" if left != left else f" ~{left / 60:.0f} min left"
        print(f"compare: {done}/{total} {elapsed:6.0f} s {label}{eta}", file=self.stream,
              flush=True)


def run(args: argparse.Namespace) -> None:
    from ..compare import _report as report
    from ..compare import _run as compare

    def names(text: str) -> tuple[str, ...]:
        return tuple(v.strip() for v in text.split(",") if v.strip())

    try:
        dims = tuple(int(v) for v in names(args.dimensions))
    except ValueError:
        raise ValueError(f"--dimensions: expected comma-separated integers, e.g. 5,10,20,40, "
                         f"got {args.dimensions!r}") from None
    settings = compare.Settings(suite=args.suite, algorithms=names(args.algorithms),
                                runs=args.runs, budget=args.budget, seed=args.seed,
                                instances=args.instances, dimensions=dims, dtype=args.dtype)
    settings.check()
    if settings.suite != "identification":
        try:
            import evosax  # noqa: F401  (BBOB's functions)
        except ImportError:
            raise ValueError("the BBOB suite needs evosax: pip install 'sedsabso-jax[compare]' "
                             "(or use --suite identification)") from None
    check_writable(args.out, None)
    t0 = time.perf_counter()
    with CompareProgress() as progress:
        docs = compare.compare(settings, args.out, progress=progress)
    written = report.write_report(docs, docs[0]["settings"], args.out,
                                  seconds=time.perf_counter() - t0)
    print(open(written[0], encoding="utf-8").read().split("## Every problem")[0].rstrip())
    print(f"written: {len(docs)} problem files in {os.path.join(args.out, 'problems')}, "
          + ", ".join(written))


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The ``compare`` subcommand's flags (its defaults are ``compare``'s own)."""
    from ..compare._run import DEFAULT_ALGORITHMS, DEFAULT_BUDGET

    cp = subcommand(
        sub, "compare",
        help="compare optimisers on BBOB and identification problems, with statistics",
        description="Run algorithms (the paper's swarms and any evosax strategy) with equal "
        "budgets in fitness evaluations, many seeded runs per problem; write report.md "
        "(best algorithm, Mann-Whitney U with Holm correction, A12), summary.json, run-length "
        "ECDF figures and one JSON per problem with every run's final value and history. "
        "Finished problems in --out are not run again.",
        examples=["sedsabso-jax compare --suite identification --runs 20",
                  "sedsabso-jax compare --algorithms SEDSABSO,CMA_ES --dimensions 5,10 "
                  "--out cmp"])
    problems = cp.add_argument_group("problems")
    problems.add_argument("--suite", default="all",
                          help="bbob, identification or all (all)")
    problems.add_argument("--dimensions", default="5,10,20,40",
                          help="BBOB dimensions (5,10,20,40)")
    problems.add_argument("--instances", type=positive_int, default=5,
                          help="BBOB instances per function; runs are spread over them (5)")
    algorithms = cp.add_argument_group("algorithms")
    algorithms.add_argument("--algorithms", default=",".join(DEFAULT_ALGORITHMS),
                            help="comma-separated: SEDSABSO, BSO, LDWPSO and evosax "
                            "strategies by evosax's names, e.g. CMA_ES, PSO, "
                            f"DifferentialEvolution ({','.join(DEFAULT_ALGORITHMS)})")
    algorithms.add_argument("--runs", type=positive_int, default=100,
                            help="seeded runs per algorithm and problem (100)")
    algorithms.add_argument("--budget", default=DEFAULT_BUDGET,
                            help="fitness evaluations per run: N, or Nd for N times the "
                            f"dimension ({DEFAULT_BUDGET})")
    algorithms.add_argument("--seed", type=non_negative_int, default=0,
                            help="random seed (0)")
    algorithms.add_argument("--dtype", choices=("float64", "float32"), default="float64",
                            help="precision of the runs (float64)")
    outputs = cp.add_argument_group("outputs")
    outputs.add_argument("--out", default="compare-results",
                         help="directory for the report, figures and problem files "
                         "(compare-results)")
    add_run_options(cp, config="runs = 20")
    cp.set_defaults(func=run)
