"""The ``sedsabso-jax`` command: argument parsing and dispatch, nothing else.

* ``sedsabso-jax reproduce``: the paper's experiment end to end (tables, figures, JSON);
* ``sedsabso-jax identify --robot ... --data ...``: identify a robot from measured data;
* ``sedsabso-jax compare``: optimisers compared on BBOB and identification problems;
* ``sedsabso-jax base-parameters --robot PATH.urdf``: a robot's base-parameter table
  (``sedsabso-jax`` alone: the paper robot's, RS010N).

Bad input exits with status 2 and one line on stderr (``--debug`` shows the traceback);
warnings are one line each on stderr; result files are written atomically, so a failed
run leaves none.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings

#: ``identify`` chooses its estimator, weighting and friction model by cross-validation
#: over non-repeating stretches of the identification data unless told otherwise
#: (``sedsabso_jax/identification/validation.py``; README, "Real robots").
AUTO = "auto"
WEIGHTS = (AUTO, "residual", "limits", "equal")
#: ``compare``'s default line-up (sedsabso_jax/compare/run.py, kept equal by a test)
DEFAULT_ALGORITHMS = ("SEDSABSO", "BSO", "LDWPSO", "PSO", "CMA_ES")
DEFAULT_BUDGET = "500d"
#: ``identify --prior-strength cv``'s grid (identification/validation.py, kept equal by a test)
PRIOR_STRENGTHS = (0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)
BUILTIN_ROBOTS = ("rs010n", "kuka_lwr4", "staubli_tx40", "franka_panda")


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


def _cmd_compare(args) -> None:
    from .compare import report
    from .compare import run as compare

    def names(text):
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
    _check_writable(args.out, None)
    t0 = time.perf_counter()
    docs = compare.compare(settings, args.out, progress=_CompareProgress())
    written = report.write_report(docs, docs[0]["settings"], args.out,
                                  seconds=time.perf_counter() - t0)
    print(open(written[0], encoding="utf-8").read().split("## Every problem")[0].rstrip())
    print(f"written: {len(docs)} problem files in {os.path.join(args.out, 'problems')}, "
          + ", ".join(written))


class _CompareProgress(_Progress):
    """The progress bar with the time left at the pace so far."""

    def __call__(self, label: str, done: int, total: int, elapsed: float = 0.0) -> None:
        from .compare.run import estimated_seconds

        left = estimated_seconds(done, total, elapsed)
        eta = "" if left != left else f" ~{left / 60:.0f} min left"
        if self.show:
            super().__call__(f"{label}{eta}", done, total)
        else:  # a log file: one line per problem
            print(f"compare: {done}/{total} {elapsed:6.0f} s {label}{eta}", file=self.stream,
                  flush=True)


def _numbers(flag: str, text, n: int):
    """A comma-separated list of ``n`` numbers given with ``flag``."""
    if text is None:
        return None
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ValueError(f"{flag}: expected {n} comma-separated numbers, got {text!r}") from None
    if len(values) != n:
        raise ValueError(f"{flag}: expected {n} numbers (one per joint), got {len(values)}")
    return values


def _transmission(args, n: int):
    """The motors' transmission from --gear-ratios, --coupling, --position-offsets and
    --drive-gains, or None."""
    from .measurements.transmission import Transmission

    ratios = _numbers("--gear-ratios", args.gear_ratios, n)
    if ratios is None:
        for flag, value in (("--motor-side", args.motor_side), ("--coupling", args.coupling),
                            ("--position-offsets", args.position_offsets),
                            ("--drive-gains", args.drive_gains)):
            if value:
                raise ValueError(f"{flag} needs --gear-ratios (one per joint, motor turns per "
                                 f"joint turn)")
        return None
    coupling = {}
    for spec in args.coupling or []:
        try:
            pair, ratio = spec.split("=")
            motor, joint = (int(v) for v in pair.split(":"))
            coupling[(motor, joint)] = float(ratio)
        except ValueError:
            raise ValueError(f"--coupling: expected MOTOR:JOINT=RATIO (numbered from 1), e.g. "
                             f"6:5=32, got {spec!r}") from None
    return Transmission.from_gear_ratios(
        ratios, coupling=coupling, offset=_numbers("--position-offsets",
                                                   args.position_offsets, n),
        drive_gains=_numbers("--drive-gains", args.drive_gains, n))


def _candidates(args, limits):
    """The (method, sigma) pairs and friction models the command chooses among."""
    from .identification.validation import FRICTION_CANDIDATES, WEIGHTING_CANDIDATES

    sigma = {"equal": None, "residual": "residual", "limits": "limits"}.get(args.weights)
    if args.weights == "limits" and limits is None:
        raise ValueError(f"--weights limits: no torque limits known for --robot {args.robot} "
                         f"(a URDF's <limit effort=...>)")
    if args.method == AUTO:
        weightings = [w for w in WEIGHTING_CANDIDATES
                      if args.weights == AUTO or w[1] == sigma]
    elif args.weights != AUTO:
        weightings = [(args.method, sigma)]
    elif args.method in ("SEDSABSO", "BSO", "LDWPSO"):
        weightings = [(args.method, None)]  # every swarm run is costly: no weighting search
    else:
        weightings = [(args.method, s) for s in (None, "residual", "limits")
                      if not (args.method == "WLS" and s is None)]
    frictions = FRICTION_CANDIDATES if args.friction == AUTO else (args.friction,)
    return frictions, weightings


def _prior_strength(text: str):
    """``--prior-strength``: a number >= 0, or ``cv``."""
    if text.strip().lower() == "cv":
        return "cv"
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected a number >= 0 or 'cv', got {text!r}")
    return value


def _cmd_identify(args) -> None:
    from .dynamics import robots
    from .dynamics.base_parameters import base_parameters
    from .dynamics.limits import joint_limits
    from .identification.identify import identify
    from .identification.report import IdentificationReport
    from .identification.validation import choose_prior_strength, cross_validate, select_model
    from .measurements.load import load_measurements

    _check_writable(args.out, args.json, args.urdf_out)
    if args.prior_strength != 0.0 and not args.physical:
        raise ValueError("--prior-strength needs --physical: the pull to the a-priori "
                         "parameters is part of the physically consistent fit")
    if args.prior_strength == "cv" and args.folds == 0:
        raise ValueError("--prior-strength cv chooses by cross-validation, which --folds 0 "
                         "turns off: give a number")
    if args.urdf_out is not None and not args.physical:
        raise ValueError("--urdf-out needs --physical: a simulator's URDF needs physically "
                         "consistent link parameters")
    robot = robots.load(args.robot, args.tip)
    load = dict(n_joints=robot.n_joints, cutoff_hz=args.cutoff_hz,
                filter_torques=args.filter_torques, downsample=args.downsample,
                resample_hz=args.resample_hz, trim_edges=not args.keep_edges)
    transmission = _transmission(args, robot.n_joints)
    data = load_measurements(args.data, **load)
    held_out = load_measurements(args.validate, **load) if args.validate else None
    if args.motor_side:
        data = transmission.to_joint_side(data)
        held_out = None if held_out is None else transmission.to_joint_side(held_out)
    limits = joint_limits(args.robot, robot).torque_limits
    frictions, weightings = _candidates(args, limits)
    choose = len(frictions) * len(weightings) > 1
    if args.folds == 0 and choose:
        raise ValueError("--folds 0 turns cross-validation off, so nothing can be chosen by "
                         "it: give --method, --weights and --friction")
    common = dict(limits=limits, physical=args.physical, runs=args.runs,
                  iterations=args.iterations, seed=args.seed, transmission=transmission,
                  base=base_parameters(robot))
    arrays = (data.times, data.q, data.qd, data.qdd, data.tau)
    selection = cv = None
    if choose:
        selection = select_model(robot, *arrays, frictions=frictions,
                                 weightings=weightings, folds=args.folds, **common)
        chosen = selection.chosen
        cv = next(c for s, c in selection.candidates if s is chosen)
    else:
        (method, sigma), = weightings
        chosen = {"method": method, "sigma": sigma, "friction": frictions[0]}
        if args.folds:
            cv = cross_validate(robot, *arrays, folds=args.folds, **common, **chosen)
    prior_selection = None
    if args.physical:
        strength = args.prior_strength
        if strength == "cv":
            prior_selection = choose_prior_strength(robot, *arrays, strengths=PRIOR_STRENGTHS,
                                                    folds=args.folds, **common, **chosen)
            strength = prior_selection.chosen
            cv = dict(prior_selection.candidates)[strength]
        elif strength and args.folds:
            cv = cross_validate(robot, *arrays, folds=args.folds, **common, **chosen,
                                prior_strength=strength)
        common["prior_strength"] = strength
    ident = identify(robot, data.q, data.qd, data.qdd, data.tau, **common, **chosen)
    report = IdentificationReport.evaluate(ident, data, held_out, limits,
                                           cross_validation=cv, selection=selection,
                                           prior_selection=prior_selection)
    settings = {"robot": args.robot, "data": os.path.abspath(args.data),
                "validate": None if args.validate is None else os.path.abspath(args.validate),
                "torque_limits": limits, "loading": {**load, "data_info": data.info},
                "motor_side": bool(args.motor_side)}
    written = report.write(settings, args.out, args.json, args.urdf_out)
    print(report.text())
    if written:
        print("written: " + ", ".join(written))


def _check_writable(out_dir, json_path, urdf_path=None) -> None:
    """Fail before the (long) run, not after it, when an output cannot be written."""
    for flag, path in (("--out", out_dir), ("--json", json_path), ("--urdf-out", urdf_path)):
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
    for flag, path in (("--json", json_path), ("--urdf-out", urdf_path)):
        if path is not None and os.path.isdir(path):
            raise ValueError(f"{flag} {path!r} is a directory; expected a file path")


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

    cp = sub.add_parser(
        "compare", parents=[common],
        help="compare optimisers on BBOB and identification problems, with statistics",
        description="Run algorithms (the paper's swarms and any evosax strategy) with equal "
        "budgets in fitness evaluations, many seeded runs per problem; write report.md "
        "(best algorithm, Mann-Whitney U with Holm correction, A12), summary.json, run-length "
        "ECDF figures and one JSON per problem with every run's final value and history. "
        "Finished problems in --out are not run again.")
    cp.add_argument("--suite", default="all",
                    help="bbob, identification or all (all)")
    cp.add_argument("--algorithms", default=",".join(DEFAULT_ALGORITHMS),
                    help="comma-separated: SEDSABSO, BSO, LDWPSO and evosax strategies "
                    f"by evosax's names, e.g. CMA_ES, PSO, DifferentialEvolution "
                    f"({','.join(DEFAULT_ALGORITHMS)})")
    cp.add_argument("--runs", type=_positive_int, default=100,
                    help="seeded runs per algorithm and problem (100)")
    cp.add_argument("--budget", default=DEFAULT_BUDGET,
                    help="fitness evaluations per run: N, or Nd for N times the dimension "
                    f"({DEFAULT_BUDGET})")
    cp.add_argument("--dimensions", default="5,10,20,40", help="BBOB dimensions (5,10,20,40)")
    cp.add_argument("--instances", type=_positive_int, default=5,
                    help="BBOB instances per function; runs are spread over them (5)")
    cp.add_argument("--seed", type=_non_negative_int, default=0, help="random seed (0)")
    cp.add_argument("--dtype", choices=("float64", "float32"), default="float64",
                    help="precision of the runs (float64)")
    cp.add_argument("--out", default="compare-results",
                    help="directory for the report, figures and problem files "
                    "(compare-results)")
    cp.set_defaults(func=_cmd_compare)

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
    ip.add_argument("--method", choices=(AUTO, *METHODS), default=AUTO,
                    help="estimator; auto (default): OLS or WLS, chosen by cross-validation")
    ip.add_argument("--friction", default=AUTO,
                    help=f"torque model: terms of {', '.join(FRICTION_TERMS)} joined by +; "
                    "auto (default): chosen by cross-validation among viscous-coulomb, "
                    "+offset, +offset+armature, +offset+quadratic+smooth")
    ip.add_argument("--weights", choices=WEIGHTS, default=AUTO,
                    help="row weights per joint: residual (Gautier's two-step WLS), limits "
                    "(1 / torque limit), equal; auto (default): chosen by cross-validation")
    ip.add_argument("--folds", type=_non_negative_int, default=5,
                    help="cross-validation folds over the motion's phase (5); they choose "
                    "what is auto and report the error on motion not fitted; 0: off")
    ip.add_argument("--motor-side", action="store_true",
                    help="--data and --validate hold motor angles and motor torques (or "
                    "currents, with --drive-gains): converted with --gear-ratios")
    ip.add_argument("--gear-ratios", default=None,
                    help="motor turns per joint turn, one per joint, comma-separated")
    ip.add_argument("--coupling", action="append", default=None, metavar="M:J=RATIO",
                    help="motor M also turns with joint J at RATIO (repeatable), e.g. 6:5=32")
    ip.add_argument("--position-offsets", default=None,
                    help="joint position of each encoder zero [rad], comma-separated")
    ip.add_argument("--drive-gains", default=None,
                    help="motor torque per unit of recorded current, one per motor")
    ip.add_argument("--physical", action="store_true",
                    help="physically consistent parameters (OLS/WLS): positive-definite "
                    "pseudo-inertia per link, friction >= 0")
    ip.add_argument("--prior-strength", type=_prior_strength, default=0.0, metavar="S|cv",
                    help="with --physical: pull toward the robot's a-priori parameters, in "
                    "multiples of the data term's mean curvature (0), or 'cv' to choose it "
                    "by cross-validation from " + ", ".join(f"{v:g}" for v in PRIOR_STRENGTHS))
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
    ip.add_argument("--resample-hz", type=_positive_float, default=None,
                    help="interpolate onto a uniform grid at this rate first (irregular logs)")
    ip.add_argument("--keep-edges", action="store_true",
                    help="keep the first and last 2 / cutoff seconds, where derived signals "
                    "show the filter's edge transients (dropped by default)")
    ip.add_argument("--json", default=None,
                    help="write the results JSON to this path (its directory is created)")
    ip.add_argument("--out", default=None,
                    help="directory for torque plots and identification.json (created)")
    ip.add_argument("--urdf-out", default=None,
                    help="write the robot's URDF with the identified link parameters and "
                    "joint friction (needs --physical)")
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


if __name__ == "__main__":
    sys.exit(main())
