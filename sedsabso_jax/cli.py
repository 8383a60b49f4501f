"""The ``sedsabso-jax`` command.

* ``sedsabso-jax reproduce``: the paper's experiment end to end (tables, figures, JSON);
* ``sedsabso-jax base-parameters --robot PATH.urdf``: a robot's base-parameter table
  (``sedsabso-jax`` alone: the paper robot's, RS010N).

Bad input exits with status 2 and one line on stderr (``--debug`` shows the traceback);
result files are written atomically, so a failed run leaves none.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

BUILTIN_ROBOTS = ("rs010n", "kuka_lwr4")


def _load_robot(spec: str, tip: str | None):
    from . import robots

    if spec in BUILTIN_ROBOTS:
        if tip is not None:
            raise ValueError(f"--tip applies to URDF files, not to the built-in robot {spec!r}")
        return getattr(robots, spec)()
    if not spec.lower().endswith(".urdf"):
        raise ValueError(f"--robot must be one of {BUILTIN_ROBOTS} or a .urdf file, got {spec!r}")
    if not os.path.isfile(spec):
        raise ValueError(f"--robot: no such file {spec!r}")
    return robots.from_urdf(spec, tip=tip)


def base_parameter_table(robot, *, paper_columns: bool = False) -> str:
    """Markdown table: name, expression, value from the robot's parameters; with
    ``paper_columns`` (the built-in RS010N) the paper's Table 5 beside it."""
    import numpy as np

    from . import paper
    from .base_parameters import base_parameters

    base = base_parameters(robot)
    values = np.asarray(base.values)
    head = ["#", "base parameter", "expression", "value (Table 2)" if paper_columns else "value"]
    if paper_columns:
        head += ["paper's Table 5 expression", "paper's Table 5 value"]
    rows = []
    for i, (name, expr, value) in enumerate(zip(base.names, base.expressions, values), 1):
        row = [str(i), name, expr, f"{value:.4f}"]
        if paper_columns:
            label, published = paper.TABLE5_THEORETICAL.get(name, ("", None))
            row += [label, "" if published is None else f"{published:g}"]
        rows.append(row)
    widths = [max(len(r[k]) for r in [head, *rows]) for k in range(len(head))]
    fmt = lambda r: "| " + " | ".join(c.ljust(w) for c, w in zip(r, widths)) + " |"  # noqa: E731
    lines = [
        f"{robot.name}: {base.rank} base parameters of {robot.n_params} "
        f"({robot.n_joints} joints x 12)",
        "",
        fmt(head),
        "|" + "|".join("-" * (w + 2) for w in widths) + "|",
        *(fmt(r) for r in rows),
    ]
    if paper_columns:
        lines += [
            "",
            "Values are computed from the paper's Table 2. The paper's Table 5 column is shown",
            "as published; it is inconsistent with Table 2 (see sedsabso_jax/paper.py).",
        ]
    return "\n".join(lines)


def _cmd_base_parameters(args) -> None:
    robot = _load_robot(args.robot, args.tip)
    print(base_parameter_table(robot, paper_columns=args.robot == "rs010n"))


class _Progress:
    """A one-line progress bar on stderr, shown only when stderr is a terminal."""

    def __init__(self, stream=None, width: int = 24):
        self.stream = stream or sys.stderr
        self.show = self.stream.isatty()
        self.width = width
        self.t0 = time.perf_counter()

    def __call__(self, label: str, done: int, total: int) -> None:
        if not self.show:
            return
        k = round(self.width * done / total)
        bar = "#" * k + "." * (self.width - k)
        self.stream.write(f"\r[{bar}] {done}/{total} {time.perf_counter() - self.t0:5.1f} s "
                          f"{label:<36}")
        if done == total:
            self.stream.write("\n")
        self.stream.flush()


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {value}")
    return value


def _non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {value}")
    return value


def _non_negative_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}") from None
    if not (value >= 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text}")
    return value


def _cmd_reproduce(args) -> None:
    from . import experiment, report

    settings = experiment.Settings(runs=args.runs, iterations=args.iterations,
                                   samples=args.samples, noise=args.noise,
                                   scenario=args.scenario, seed=args.seed, dtype=args.dtype,
                                   design_iterations=args.design_iterations)
    settings.check()
    _check_writable(args.out, args.json)
    exp = experiment.run(settings, progress=_Progress())
    written = report.write_outputs(exp, args.out, args.json)
    print(report.table4(exp.results))
    print("written: " + ", ".join(written))


def _check_writable(out_dir, json_path) -> None:
    """Fail before the (long) run, not after it, when an output cannot be written."""
    if out_dir is not None and os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise ValueError(f"--out {out_dir!r} exists and is not a directory")
    if json_path is not None:
        parent = os.path.dirname(os.path.abspath(json_path))
        if not os.path.isdir(parent):
            raise ValueError(f"--json {json_path!r}: no such directory {parent!r}")
        if os.path.isdir(json_path):
            raise ValueError(f"--json {json_path!r} is a directory; expected a file path")


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors as ONE line on stderr (exit status 2)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="sedsabso-jax",
        description="Identify robot dynamic parameters (SEDSABSO, JAX). Without a command: "
        "print the RS010N base-parameter table.",
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    sub = parser.add_subparsers(dest="command")
    bp = sub.add_parser("base-parameters", help="print a robot's base-parameter table")
    bp.add_argument("--robot", default="rs010n",
                    help=f"one of {', '.join(BUILTIN_ROBOTS)} or a .urdf file (default rs010n)")
    bp.add_argument("--tip", default=None, help="URDF tip link, for trees that branch")
    bp.set_defaults(func=_cmd_base_parameters)

    rp = sub.add_parser(
        "reproduce", help="re-run the paper's experiment (Tables 4-5, Figures 5-6)",
        description="Re-run the paper's experiment on the RS010N: base parameters, excitation "
        "design (Eq. 9), simulated torques, SEDSABSO / BSO / LDWPSO with the paper's settings "
        "beside OLS, Levenberg-Marquardt and the exact L1 optimum.")
    rp.add_argument("--runs", type=_positive_int, default=10, help="runs per swarm (10)")
    rp.add_argument("--iterations", type=_positive_int, default=600,
                    help="iterations per run (600)")
    rp.add_argument("--samples", type=_positive_int, default=1000,
                    help="samples over the 10 s excitation period (1000, i.e. 100 Hz)")
    rp.add_argument("--noise", type=_non_negative_float, default=0.0,
                    help="Gaussian torque noise, std relative to each joint's RMS torque (0)")
    rp.add_argument("--scenario", choices=("paper", "prior"), default="paper",
                    help="search box: around the true values (paper) or a 30%%-off prior")
    rp.add_argument("--seed", type=_non_negative_int, default=0, help="random seed (0)")
    rp.add_argument("--dtype", choices=("float64", "float32"), default="float64",
                    help="precision of the swarms (float64)")
    rp.add_argument("--design-iterations", type=_positive_int, default=None,
                    help="iterations of the excitation design swarm (the module's default, 100)")
    rp.add_argument("--out", default="reproduce-results",
                    help="directory for tables, figures and results.json (reproduce-results)")
    rp.add_argument("--json", default=None, help="also write results.json to this path")
    rp.set_defaults(func=_cmd_reproduce)
    parser.set_defaults(func=_cmd_base_parameters, robot="rs010n", tip=None)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings():
            if not args.debug:
                warnings.simplefilter("ignore", UserWarning)
            args.func(args)
    except BrokenPipeError:  # output piped into e.g. `head`: stop quietly (Python docs recipe)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except (ValueError, TypeError, OSError, RuntimeError) as err:
        if args.debug:
            raise
        print(f"sedsabso-jax: error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
