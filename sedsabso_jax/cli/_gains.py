"""``sedsabso-jax identify-gains``: the flags become a robot, recordings of currents and a
torque model, then one library call (:func:`~sedsabso_jax.identify_drive_gains`) whose
gains are printed and written; ``--drive-gains FILE.json`` of ``identify`` and
``identify-payload`` reads the file."""

from __future__ import annotations

import argparse
import os

from . import _loading as files
from ._checks import check_signals, inputs_of, one_rate, refuse_overwriting
from ._common import add_run_options, positive_float, subcommand

#: The torque model unless --friction says otherwise: friction that grows with the load
#: is what moved the gains most in the simulation study (benchmarks/drive_gains.py).
DEFAULT_FRICTION = "viscous-coulomb+offset+load"


def _com(text: str | None) -> list[float] | None:
    if text is None:
        return None
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ValueError(f"--com: expected X,Y,Z in metres, got {text!r}") from None
    if len(values) != 3:
        raise ValueError(f"--com: expected 3 numbers X,Y,Z in metres, got {len(values)}")
    return values


def _currents(paths: list[str], load: dict, transmission) -> list:
    """The files, positions on the joint side, the torque columns the recorded currents
    as they are (per motor with a transmission)."""
    from ..measurements._container import Measurements

    data = files.load_all(paths, load, False, None)
    if transmission is None:
        return data
    return [Measurements(j.times, j.q, j.qd, j.qdd, d.tau, source=d.source, info=j.info)
            for d, j in ((d, transmission.to_joint_side(d)) for d in data)]


def run(args: argparse.Namespace) -> None:
    """The subcommand: check the flags, load, one call, print, write."""
    from .._output import write_json
    from ..dynamics import _robots as robots
    from ..identification._gains._identify_gains import identify_drive_gains
    from ..identification._gains._solvers import GAIN_METHODS
    from ..identification._model._order import parse_friction
    from ..identification._model._torque_model import TorqueModel

    refuse_overwriting({"--json": args.json}, inputs_of(args, "--data", "--loaded"))
    if args.drive_gains is not None:
        raise ValueError("--drive-gains: identify-gains finds the drive gains; its --data "
                         "and --loaded hold the recorded currents as they are")
    com = _com(args.com)
    terms = parse_friction(args.friction)
    robot = robots.load(args.robot, args.tip)
    load = files.loading(args, robot.n_joints)
    transmission = files.transmission_of(args, robot.n_joints)
    unloaded = _currents(args.data, load, transmission)
    loaded = _currents(args.loaded, load, transmission)
    one_rate([("--data", unloaded), ("--loaded", loaded)])
    check_signals(args.robot, robot, [unloaded, loaded], torques=False)  # currents
    count = len(unloaded) + len(loaded) if args.offset_per_recording else 1
    model = TorqueModel.of(robot, terms, transmission=transmission, recordings=count)
    with files.urdf_source(args.robot) as urdf:
        gains = identify_drive_gains(robot, unloaded, loaded, args.link, args.mass, com,
                                     model=model, method=GAIN_METHODS[args.method](),
                                     transmission=transmission, urdf=urdf)
    print(gains.text())
    if args.json is not None:
        command = {"robot": args.robot, "link": args.link, "mass": args.mass, "com": com,
                   "data": [os.path.abspath(p) for p in args.data],
                   "loaded": [os.path.abspath(p) for p in args.loaded],
                   "loading": load, "motor_side": bool(args.motor_side)}
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        path = write_json(args.json, {**gains.as_dict(), "command": command})
        print(f"written: {path}")


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The ``identify-gains`` subcommand's flags, in groups."""
    from ._vocabulary import DEFAULT_GAIN_METHOD, FRICTION_TERMS, GAIN_METHODS

    pp = subcommand(
        sub, "identify-gains",
        help="identify drive gains (torque per unit of current) with a weighed payload",
        description="Identify each joint's drive gain (torque per unit of the recorded "
        "current) together with the robot's torque model and the payload's unknown moments, "
        "from recordings of currents without a payload (--data) and with one of known mass "
        "(--loaded, --mass, --link; --com when its centre of mass is known) (Gautier & "
        "Briot 2014). The torque columns of the files hold the currents. It prints each "
        "gain with its standard deviation and whether the data calibrate it, and writes "
        "--json, which 'identify' and 'identify-payload' read with --drive-gains FILE.json "
        "(sedsabso-jax identify --robot R --data currents.npz --drive-gains gains.json). "
        "Files as for 'identify'; flags may also come from a --config file.",
        examples=["sedsabso-jax identify-gains --robot kuka_lwr4 --data currents.npz "
                  "--loaded weighed.npz --link lwr_7_link --mass 3.02 --json gains.json",
                  "sedsabso-jax identify-gains --robot arm.urdf --data a.csv --loaded b.csv "
                  "--link tool0 --mass 2.5 --com 0,0,0.04 --friction offset+load+presliding"])
    inp = pp.add_argument_group("input", "the robot, its data, and how the data are loaded")
    files.add_robot(inp)
    inp.add_argument("--data", metavar="FILE", nargs="+", required=True,
                     help="recordings of currents WITHOUT the payload (.npz or .csv)")
    inp.add_argument("--loaded", metavar="FILE", nargs="+", required=True,
                     help="recordings of currents WITH the payload (one sampling rate with "
                     "--data)")
    inp.add_argument("--link", metavar="LINK", required=True,
                     help="the link carrying the payload: a moving link of --robot, or (with "
                     "a URDF) a link fixed to one (a flange, tool0)")
    inp.add_argument("--mass", metavar="KG", type=positive_float, required=True,
                     help="the payload's weighed mass [kg]")
    inp.add_argument("--com", metavar="X,Y,Z", default=None,
                     help="the payload's centre of mass [m] in --link's frame, when known "
                     "(else estimated)")
    files.add_loading(inp)
    files.add_motors(pp, "--data and --loaded")
    model = pp.add_argument_group("torque model", "fitted with the gains")
    model.add_argument("--friction", metavar="TERMS", default=DEFAULT_FRICTION,
                       help=f"terms of {', '.join(FRICTION_TERMS)} joined by + "
                       f"({DEFAULT_FRICTION}); searched ones (presliding:fit) are refused")
    model.add_argument("--offset-per-recording", action="store_true",
                       help="one torque offset per joint and file")
    est = pp.add_argument_group("estimator")
    est.add_argument("--method", choices=GAIN_METHODS, default=DEFAULT_GAIN_METHOD,
                     help=f"how the equations are solved ({DEFAULT_GAIN_METHOD}: the maximum "
                     f"likelihood for noise in the currents; ordinary least squares is "
                     f"biased by it)")
    out = pp.add_argument_group("outputs", "written atomically: a failed run leaves none")
    out.add_argument("--json", metavar="PATH", default=None,
                     help="write the gains as JSON (drive_gains, drive_gains_std, "
                     "calibrated, the payload's moments, the fit); its directory is created")
    add_run_options(pp, config="mass = 3.02")
    pp.set_defaults(func=run)
