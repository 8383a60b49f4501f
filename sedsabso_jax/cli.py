"""The ``sedsabso-jax`` command: argument parsing and dispatch, nothing else.

* ``sedsabso-jax reproduce``: the paper's experiment end to end (tables, figures, JSON);
* ``sedsabso-jax identify --robot ... --data ...``: identify a robot from measured data;
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
import time
import warnings

#: ``identify``'s default estimator and friction model: the combination that validates
#: best on held-out real data in ``benchmarks/kuka_real.py`` (README, "Real robot").
DEFAULT_METHOD = "WLS"
DEFAULT_FRICTION = "viscous-coulomb+offset+quadratic+smooth"
DEFAULT_METHOD_WHY = "best held-out NRMS on the KUKA LWR4+ data"
WEIGHTS = ("auto", "residual", "limits", "equal")
BUILTIN_ROBOTS = ("rs010n", "kuka_lwr4")


def _cmd_base_parameters(args) -> None:
    from .dynamics import robots
    from .reproduce.report import base_parameter_table

    robot = robots.load(args.robot, args.tip)
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


def _number(kind: type, minimum: float, strict: bool):
    """An argparse type: ``kind`` (int or float), finite, ``> minimum`` if ``strict`` else
    ``>= minimum``; a bad value gets one line saying what was expected."""
    what = "an integer" if kind is int else "a finite number"
    expected = f"expected {what} {'>' if strict else '>='} {minimum:g}"

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{expected}, got {text!r}") from None
        ok = value > minimum if strict else value >= minimum
        if not (ok and value < float("inf")):  # NaN fails both comparisons
            raise argparse.ArgumentTypeError(f"{expected}, got {text}")
        return value

    return parse


_positive_int = _number(int, 1, strict=False)
_non_negative_int = _number(int, 0, strict=False)
_positive_float = _number(float, 0, strict=True)
_non_negative_float = _number(float, 0, strict=False)


def _cmd_reproduce(args) -> None:
    from .reproduce import experiment, report

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


def _cmd_identify(args) -> None:
    from .dynamics import robots
    from .dynamics.limits import joint_limits
    from .identification.identify import identify
    from .identification.report import IdentificationReport
    from .measurements.load import load_measurements

    _check_writable(args.out, args.json)
    robot = robots.load(args.robot, args.tip)
    load = dict(n_joints=robot.n_joints, cutoff_hz=args.cutoff_hz,
                filter_torques=args.filter_torques, downsample=args.downsample)
    data = load_measurements(args.data, **load)
    held_out = load_measurements(args.validate, **load) if args.validate else None
    limits = joint_limits(args.robot, robot).torque_limits
    sigma = {"auto": "limits" if limits is not None and args.method == "WLS" else None,
             "equal": None}.get(args.weights, args.weights)
    if sigma == "limits" and limits is None:
        raise ValueError(f"--weights limits: no torque limits known for --robot {args.robot} "
                         f"(a URDF's <limit effort=...>)")
    ident = identify(robot, data.q, data.qd, data.qdd, data.tau, method=args.method,
                     friction=args.friction, physical=args.physical, limits=limits,
                     sigma=sigma, runs=args.runs, iterations=args.iterations, seed=args.seed)
    report = IdentificationReport.evaluate(ident, data, held_out, limits)
    settings = {"robot": args.robot, "data": os.path.abspath(args.data),
                "validate": None if args.validate is None else os.path.abspath(args.validate),
                "torque_limits": limits, "loading": {**load, "data_info": data.info}}
    written = report.write(settings, args.out, args.json)
    print(report.text())
    if written:
        print("written: " + ", ".join(written))


def _check_writable(out_dir, json_path) -> None:
    """Fail before the (long) run, not after it, when an output cannot be written."""
    for flag, path in (("--out", out_dir), ("--json", json_path)):
        if path is None:
            continue
        existing = os.path.abspath(path if flag == "--out" else os.path.dirname(
            os.path.abspath(path)))
        while not os.path.exists(existing):  # the directories that will be created
            existing = os.path.dirname(existing)
        if not os.path.isdir(existing):
            raise ValueError(f"{flag} {path!r}: {existing!r} exists and is not a directory")
        if not os.access(existing, os.W_OK):
            raise ValueError(f"{flag} {path!r}: directory {existing!r} is not writable")
    if json_path is not None and os.path.isdir(json_path):
        raise ValueError(f"--json {json_path!r} is a directory; expected a file path")


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors as ONE line on stderr (exit status 2)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    from .identification.identify import METHODS
    from .identification.model import FRICTION_TERMS

    common = argparse.ArgumentParser(add_help=False)
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

    ip = sub.add_parser(
        "identify", parents=[common],
        help="identify a robot's base parameters from measured data",
        description="Identify base parameters from joint data (.npz with keys positions, "
        "velocities, accelerations, torques, times; or .csv with a header time,q1..,qd1..,"
        "qdd1..,tau1..) and validate on held-out data.")
    ip.add_argument("--robot", required=True,
                    help=f"one of {', '.join(BUILTIN_ROBOTS)} or a .urdf file")
    ip.add_argument("--tip", default=None, help="URDF tip link, for trees that branch")
    ip.add_argument("--data", required=True, help="identification data (.npz or .csv)")
    ip.add_argument("--validate", default=None, help="held-out data (.npz or .csv)")
    ip.add_argument("--method", choices=METHODS, default=DEFAULT_METHOD,
                    help=f"estimator (default {DEFAULT_METHOD}: {DEFAULT_METHOD_WHY})")
    ip.add_argument("--friction", default=DEFAULT_FRICTION,
                    help=f"friction model: terms of {', '.join(FRICTION_TERMS)} joined by + "
                    f"(default {DEFAULT_FRICTION})")
    ip.add_argument("--weights", choices=WEIGHTS, default="auto",
                    help="row weights per joint: residual (Gautier's two-step WLS), limits "
                    "(1 / torque limit), equal; auto = limits for WLS when the robot has "
                    "torque limits, else the method's default")
    ip.add_argument("--physical", action="store_true",
                    help="physically consistent parameters (OLS/WLS): positive-definite "
                    "pseudo-inertia per link, friction >= 0")
    ip.add_argument("--runs", type=_positive_int, default=1,
                    help="swarm runs, the best kept (1)")
    ip.add_argument("--iterations", type=_positive_int, default=600,
                    help="swarm iterations (600)")
    ip.add_argument("--seed", type=_non_negative_int, default=0, help="random seed (0)")
    ip.add_argument("--cutoff-hz", type=_positive_float, default=None,
                    help="low-pass cutoff where velocities/accelerations are derived or "
                    "torques filtered (default 10 Hz)")
    ip.add_argument("--filter-torques", action="store_true", help="low-pass the torques")
    ip.add_argument("--downsample", type=_positive_int, default=1,
                    help="keep every k-th sample after filtering (1)")
    ip.add_argument("--json", default=None,
                    help="write the results JSON to this path (its directory is created)")
    ip.add_argument("--out", default=None,
                    help="directory for torque plots and identification.json (created)")
    ip.set_defaults(func=_cmd_identify)
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
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command in ("reproduce", "identify"):
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


if __name__ == "__main__":
    sys.exit(main())
