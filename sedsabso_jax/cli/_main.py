"""The ``sedsabso-jax`` command: argument parsing and dispatch, nothing else.

* ``sedsabso-jax reproduce``: the paper's experiment end to end (tables, figures, JSON);
* ``sedsabso-jax identify --robot ... --data ...``: identify a robot from measured data
  (:mod:`._identify`: one call of the library's ``select_and_identify``);
* ``sedsabso-jax identify-payload --robot ... --loaded ... --link ...``: a payload's
  inertial parameters (:mod:`._payload`: one call of the library's ``identify_payload``);
* ``sedsabso-jax identify-gains --robot ... --data ... --loaded ... --link ... --mass ...``:
  drive gains from a weighed payload (:mod:`._gains`: one call of the library's
  ``identify_drive_gains``);
* ``sedsabso-jax compare``: optimisers compared on BBOB and identification problems
  (:mod:`._compare`);
* ``sedsabso-jax base-parameters --robot PATH.urdf``: a robot's base-parameter table
  (:mod:`._base_parameters`; the paper robot's, RS010N, by default).

``sedsabso-jax`` alone prints the help. Errors are one line on stderr (``--debug`` shows
the traceback), with exit status 2 for usage errors and bad input, 1 for a failure while
running (:func:`main`); warnings are one line each on stderr; result files are written
atomically, so a failed run leaves none. ``--config FILE`` (:mod:`._config`) reads flags
from a file.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from typing import NoReturn

from .._version import __version__
from . import _base_parameters as base_parameters_command
from . import _compare as compare_command
from . import _config as config
from . import _gains as gains_command
from . import _identify as identify_command
from . import _payload as payload_command
from ._common import (
    EXIT_STATUS,
    HelpFormatter,
    LineProgress,
    add_run_options,
    check_files,
    non_negative_float,
    non_negative_int,
    positive_int,
    subcommand,
)

#: Exceptions that mean bad input (exit status 2); other exceptions are failures while
#: running (1). jaxlib's XlaRuntimeError (out of memory, ...) is a RuntimeError.
USAGE_ERRORS = (ValueError, TypeError, FileNotFoundError, IsADirectoryError,
                NotADirectoryError, PermissionError)


def _cmd_reproduce(args) -> None:
    from ..reproduce import _experiment as experiment
    from ..reproduce import _report as report
    from ..reproduce._work import write_seconds

    settings = experiment.Settings(runs=args.runs, iterations=args.iterations,
                                   samples=args.samples, noise=args.noise,
                                   scenario=args.scenario, seed=args.seed, dtype=args.dtype,
                                   design_iterations=args.design_iterations)
    settings.check()
    # a line at each step (a swarm's runs are one call)
    with LineProgress("reproduce", then=write_seconds(settings), every=0) as progress:
        exp = experiment.run(settings, progress=progress)
        written = report.write_outputs(exp, args.out, args.json)
        progress.finish("written")
    print(report.table4(exp.results))
    print("written: " + ", ".join(written))


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors as ONE line on stderr (exit status 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _add_reproduce(sub: argparse._SubParsersAction) -> None:
    rp = subcommand(
        sub, "reproduce",
        help="re-run the paper's experiment (Tables 4-5, Figures 5-6)",
        description="Re-run the paper's experiment on the RS010N: base parameters, excitation "
        "design (Eq. 9), simulated torques, SEDSABSO / BSO / LDWPSO with the paper's settings "
        "beside OLS, Levenberg-Marquardt and the exact L1 optimum.",
        examples=["sedsabso-jax reproduce", "sedsabso-jax reproduce --runs 3 --iterations "
                  "200 --noise 0.02 --out quick"])
    exp = rp.add_argument_group("experiment")
    exp.add_argument("--runs", type=positive_int, default=10, help="runs per swarm (10)")
    exp.add_argument("--iterations", type=positive_int, default=600,
                     help="iterations per run (600)")
    exp.add_argument("--samples", type=positive_int, default=1000,
                     help="samples over the 10 s excitation period (1000, i.e. 100 Hz)")
    exp.add_argument("--noise", type=non_negative_float, default=0.0,
                     help="Gaussian torque noise, std relative to each joint's RMS torque (0)")
    exp.add_argument("--scenario", choices=("paper", "prior"), default="paper",
                     help="search box: around the true values (paper) or a 30%%-off prior")
    exp.add_argument("--seed", type=non_negative_int, default=0, help="random seed (0)")
    exp.add_argument("--dtype", choices=("float64", "float32"), default="float64",
                     help="precision of the swarms (float64)")
    exp.add_argument("--design-iterations", type=positive_int, default=None,
                     help="iterations of the excitation design swarm (the module's default, "
                     "100)")
    out = rp.add_argument_group("outputs")
    out.add_argument("--out", default="reproduce-results",
                     help="directory for tables, figures and results.json (reproduce-results)")
    out.add_argument("--json", default=None, help="also write results.json to this path")
    add_run_options(rp, config="design-iterations = 50")
    rp.set_defaults(func=_cmd_reproduce)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="sedsabso-jax", formatter_class=HelpFormatter,
        description="Identify robot dynamic parameters (SEDSABSO, JAX): a robot's base "
        "parameters, identification from measured data, the paper's experiment, and "
        "optimisers compared. 'sedsabso-jax COMMAND --help' shows a command's flags.",
        epilog="examples:\n  sedsabso-jax base-parameters --robot kuka_lwr4\n"
        "  sedsabso-jax identify --robot kuka_lwr4 --data run1.npz --validate run2.npz\n\n"
        f"{EXIT_STATUS}")
    parser.add_argument("--version", action="version", version=f"sedsabso-jax {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show tracebacks on errors and warnings in full")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser, title="commands",
                                metavar="COMMAND")
    base_parameters_command.add_parser(sub)
    _add_reproduce(sub)
    compare_command.add_parser(sub)
    identify_command.add_parser(sub)
    payload_command.add_parser(sub)
    gains_command.add_parser(sub)
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
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    return where


def _start_jax(command: str) -> None:
    """Import JAX and turn its 64-bit mode on, before any JAX work: the command is an
    application (the library never turns it on, sedsabso_jax/_x64.py); the commands that
    compile much keep what they compile (:func:`_enable_compilation_cache`)."""
    import jax

    jax.config.update("jax_enable_x64", True)
    if command in ("reproduce", "identify", "identify-payload", "identify-gains",
                   "compare"):
        _enable_compilation_cache()


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """``warnings.showwarning`` for the command: one short line on stderr."""
    text = " ".join(str(message).split())
    print(f"sedsabso-jax: warning: {text}", file=sys.stderr if file is None else file)


def _one_line(err: BaseException) -> str:
    """The error's message on one line (XLA's run over many: the first), else its type."""
    lines = [line.strip() for line in str(err).splitlines() if line.strip()]
    return lines[0] if lines else type(err).__name__


def main(argv: list[str] | None = None) -> int:
    """Run the command; returns the exit status: 0 done, 1 a failure while running
    (RuntimeError, e.g. a solver's or XLA's out of memory; MemoryError; anything
    unexpected), 2 a usage error or bad input (:data:`USAGE_ERRORS`; argparse exits with
    2 itself), 130 interrupted. Each error is one line on stderr; ``--debug`` raises it.
    Parsing, the help and the checks of the files named (:func:`~._common.check_files`)
    import neither JAX nor the library: they answer at once."""
    parser = build_parser()
    args = config.parse_args(parser, sys.argv[1:] if argv is None else argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        check_files(args)  # before JAX is imported: a missing file is said at once
        _start_jax(args.command)
        with warnings.catch_warnings():
            warnings.simplefilter("default", UserWarning)
            if not args.debug:
                seen: set[tuple[str, type]] = set()

                def show(message, category, *where, **kw):  # each message once, wherever
                    if (str(message), category) not in seen:  # it comes from (a URDF is
                        seen.add((str(message), category))     # read more than once)
                        _one_line_warning(message, category, *where, **kw)

                warnings.showwarning = show
            args.func(args)
    except BrokenPipeError:  # output piped into e.g. `head`: stop quietly (Python docs recipe)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except KeyboardInterrupt:
        if args.debug:
            raise
        print("sedsabso-jax: interrupted", file=sys.stderr)
        return 130
    except USAGE_ERRORS as err:
        if args.debug:
            raise
        print(f"sedsabso-jax: error: {err}", file=sys.stderr)
        return 2
    except (RuntimeError, MemoryError) as err:
        if args.debug:
            raise
        print(f"sedsabso-jax: error: {_one_line(err)}", file=sys.stderr)
        return 1
    except Exception as err:  # unexpected: say what it was, --debug shows where
        if args.debug:
            raise
        print(f"sedsabso-jax: error: {type(err).__name__}: {_one_line(err)} (--debug shows "
              f"the traceback)", file=sys.stderr)
        return 1
    return 0


def __getattr__(name: str):
    """``DEFAULT_ALGORITHMS`` and ``DEFAULT_BUDGET``: ``compare``'s own (defined there)."""
    if name in ("DEFAULT_ALGORITHMS", "DEFAULT_BUDGET"):
        from ..compare import _run as run

        return getattr(run, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


if __name__ == "__main__":
    sys.exit(main())
