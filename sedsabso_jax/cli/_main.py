"""The ``sedsabso-jax`` command: argument parsing and dispatch, nothing else.

* ``sedsabso-jax reproduce``: the paper's experiment end to end (tables, figures, JSON);
* ``sedsabso-jax identify --robot ... --data ...``: identify a robot from measured data
  (:mod:`._identify`: one call of the library's ``select_and_identify``);
* ``sedsabso-jax compare``: optimisers compared on BBOB and identification problems
  (:mod:`._compare`);
* ``sedsabso-jax base-parameters --robot PATH.urdf``: a robot's base-parameter table
  (``sedsabso-jax`` alone: the paper robot's, RS010N).

Bad input exits with status 2 and one line on stderr (``--debug`` shows the traceback);
warnings are one line each on stderr; result files are written atomically, so a failed
run leaves none.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from typing import NoReturn

from . import _compare as compare_command
from . import _identify as identify_command
from ._common import (
    BUILTIN_ROBOTS,
    Progress,
    check_writable,
    non_negative_float,
    non_negative_int,
    positive_int,
)


def _cmd_base_parameters(args) -> None:
    from ..dynamics import _robots as robots
    from ..reproduce._report import base_parameter_table

    robot = robots.load(args.robot, args.tip)
    print(base_parameter_table(robot, paper_columns=args.robot == "rs010n"))


def _cmd_reproduce(args) -> None:
    from ..reproduce import _experiment as experiment
    from ..reproduce import _report as report

    settings = experiment.Settings(runs=args.runs, iterations=args.iterations,
                                   samples=args.samples, noise=args.noise,
                                   scenario=args.scenario, seed=args.seed, dtype=args.dtype,
                                   design_iterations=args.design_iterations)
    settings.check()
    check_writable(args.out, args.json)
    exp = experiment.run(settings, progress=Progress())
    written = report.write_outputs(exp, args.out, args.json)
    print(report.table4(exp.results))
    print("written: " + ", ".join(written))


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors as ONE line on stderr (exit status 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    common = _Parser(add_help=False)
    # SUPPRESS: a subcommand's --debug does not reset the one given before it
    common.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                        help="show tracebacks on errors and warnings in full")
    parser = _Parser(
        prog="sedsabso-jax",
        description="Identify robot dynamic parameters (SEDSABSO, JAX). Without a command: "
        "print the RS010N base-parameter table.",
    )
    parser.add_argument("--debug", action="store_true",
                        help="show tracebacks on errors and warnings in full")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser)
    bp = sub.add_parser("base-parameters", parents=[common],
                        help="print a robot's base-parameter table")
    bp.add_argument("--robot", default="rs010n",
                    help=f"one of {', '.join(BUILTIN_ROBOTS)} or a .urdf file (default rs010n)")
    bp.add_argument("--tip", default=None, help="URDF tip link, for trees that branch")
    bp.set_defaults(func=_cmd_base_parameters)

    rp = sub.add_parser(
        "reproduce", parents=[common],
        help="re-run the paper's experiment (Tables 4-5, Figures 5-6)",
        description="Re-run the paper's experiment on the RS010N: base parameters, excitation "
        "design (Eq. 9), simulated torques, SEDSABSO / BSO / LDWPSO with the paper's settings "
        "beside OLS, Levenberg-Marquardt and the exact L1 optimum.")
    rp.add_argument("--runs", type=positive_int, default=10, help="runs per swarm (10)")
    rp.add_argument("--iterations", type=positive_int, default=600,
                    help="iterations per run (600)")
    rp.add_argument("--samples", type=positive_int, default=1000,
                    help="samples over the 10 s excitation period (1000, i.e. 100 Hz)")
    rp.add_argument("--noise", type=non_negative_float, default=0.0,
                    help="Gaussian torque noise, std relative to each joint's RMS torque (0)")
    rp.add_argument("--scenario", choices=("paper", "prior"), default="paper",
                    help="search box: around the true values (paper) or a 30%%-off prior")
    rp.add_argument("--seed", type=non_negative_int, default=0, help="random seed (0)")
    rp.add_argument("--dtype", choices=("float64", "float32"), default="float64",
                    help="precision of the swarms (float64)")
    rp.add_argument("--design-iterations", type=positive_int, default=None,
                    help="iterations of the excitation design swarm (the module's default, 100)")
    rp.add_argument("--out", default="reproduce-results",
                    help="directory for tables, figures and results.json (reproduce-results)")
    rp.add_argument("--json", default=None, help="also write results.json to this path")
    rp.set_defaults(func=_cmd_reproduce)

    compare_command.add_parser(sub, [common])
    identify_command.add_parser(sub, [common])
    parser.set_defaults(func=_cmd_base_parameters, robot="rs010n", tip=None)
    return parser


def _enable_compilation_cache() -> str | None:
    """Keep compiled XLA programs between runs of the command (JAX's persistent cache):
    a second ``reproduce`` skips most compilation. Location: ``$SEDSABSO_JAX_CACHE``
    (``off`` disables it), else ``$XDG_CACHE_HOME/sedsabso-jax/xla`` or
    ``~/.cache/sedsabso-jax/xla``. Returns the directory used, or None."""
    import jax

    where = os.environ.get("SEDSABSO_JAX_CACHE")
    if where is not None and where.strip().lower() in ("off", "0", "no", ""):
        return None
    if where is None:
        root = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"),
                                                                ".cache")
        where = os.path.join(root, "sedsabso-jax", "xla")
    try:
        os.makedirs(where, exist_ok=True)
    except OSError:  # read-only home: run without the cache
        return None
    jax.config.update("jax_compilation_cache_dir", where)
    return where


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """``warnings.showwarning`` for the command: one short line on stderr."""
    text = " ".join(str(message).split())
    print(f"sedsabso-jax: warning: {text}", file=sys.stderr if file is None else file)


def main(argv: list[str] | None = None) -> int:
    import jax

    # an application: the command turns JAX's 64-bit mode on for itself (the library never
    # does, sedsabso_jax/_x64.py), before any JAX work
    jax.config.update("jax_enable_x64", True)
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command in ("reproduce", "identify", "compare"):
        _enable_compilation_cache()
    try:
        with warnings.catch_warnings():
            if not args.debug:
                warnings.showwarning = _one_line_warning
            warnings.simplefilter("default", UserWarning)  # each distinct warning once
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


def __getattr__(name: str):
    """``DEFAULT_ALGORITHMS`` and ``DEFAULT_BUDGET``: ``compare``'s own (defined there)."""
    if name in ("DEFAULT_ALGORITHMS", "DEFAULT_BUDGET"):
        from ..compare import _run as run

        return getattr(run, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


if __name__ == "__main__":
    sys.exit(main())
