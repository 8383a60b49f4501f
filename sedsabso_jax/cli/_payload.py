"""``sedsabso-jax identify-payload``: the flags become a robot, recordings and a torque
model, then one library call (:func:`~sedsabso_jax.identify_payload`)
whose payload is printed and written."""

from __future__ import annotations

import argparse
import os

from . import _loading as files
from ._checks import check_signals, inputs_of, one_rate, refuse_overwriting
from ._common import add_run_options, subcommand

#: The torque model of the joint fit unless --friction says otherwise.
DEFAULT_FRICTION = "viscous-coulomb+offset"


def run(args: argparse.Namespace) -> None:
    """The subcommand: check the flags, load, one call, print, write."""
    from .._output import write_json
    from ..dynamics import _robots as robots
    from ..identification._estimators._least_squares import OLS, WLS, PhysicallyConsistent
    from ..identification._model._order import parse_friction
    from ..identification._model._torque_model import TorqueModel
    from ..identification._payload._identify_payload import identify_payload

    refuse_overwriting({"--json": args.json}, inputs_of(args, "--data", "--loaded"))
    terms = parse_friction(args.friction)
    if not args.data and (args.friction != DEFAULT_FRICTION or args.offset_per_recording):
        raise ValueError("--friction and --offset-per-recording shape the joint fit with the "
                         "unloaded recordings: give them with --data")
    robot = robots.load(args.robot, args.tip)
    load = files.loading(args, robot.n_joints)
    transmission = files.transmission_of(args, robot.n_joints)
    loaded = files.load_all(args.loaded, load, args.motor_side, transmission)
    unloaded = files.load_all(args.data or [], load, args.motor_side, transmission)
    one_rate([("--data", unloaded), ("--loaded", loaded)])
    check_signals(args.robot, robot, [unloaded, loaded])
    model = None
    if unloaded:
        count = len(loaded) + len(unloaded) if args.offset_per_recording else 1
        model = TorqueModel.of(robot, terms, transmission=transmission, recordings=count)
    least_squares = WLS(passes=2) if args.weights == "residual" else OLS()
    estimator = (PhysicallyConsistent(least_squares, links=False) if args.physical
                 else least_squares)
    with files.urdf_source(args.robot) as urdf:
        payload = identify_payload(robot, loaded, args.link, unloaded=unloaded or None,
                                   estimator=estimator, model=model, urdf=urdf)
    print(payload.text())
    if args.json is not None:
        settings = {"robot": args.robot, "link": args.link,
                    "data": [os.path.abspath(p) for p in args.data or []],
                    "loaded": [os.path.abspath(p) for p in args.loaded],
                    "loading": load, "motor_side": bool(args.motor_side)}
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        path = write_json(args.json, {"payload": payload.as_dict(), "settings": settings})
        print(f"written: {path}")


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The ``identify-payload`` subcommand's flags, in groups."""
    from ._vocabulary import FRICTION_TERMS

    pp = subcommand(
        sub, "identify-payload",
        help="identify a payload's mass, centre of mass and inertia",
        description="Identify a payload fixed to a link (mass [kg], centre of mass [m] and "
        "inertia [kg m^2] in the link's frame, with standard deviations, physically "
        "consistent) from recordings with it (--loaded). With recordings without it "
        "(--data, ideally the same motion; samples need not align) the robot's torque model "
        "(--friction) is fitted together with the payload; without them the robot's own "
        "parameters (a URDF's, the built-in robot's) are taken as they are. Files as for "
        "'identify'; flags may also come from a --config file.",
        examples=["sedsabso-jax identify-payload --robot kuka_lwr4 --data run1.npz "
                  "--loaded loaded1.npz --link lwr_7_link --json payload.json",
                  "sedsabso-jax identify-payload --robot arm.urdf --loaded with.npz "
                  "--link tool0"])
    inp = pp.add_argument_group("input", "the robot, its data, and how the data are loaded")
    files.add_robot(inp)
    inp.add_argument("--data", metavar="FILE", nargs="+", default=None,
                     help="recordings WITHOUT the payload (.npz or .csv): the robot's model "
                     "is refitted with them; leave out to take the robot's own parameters")
    inp.add_argument("--loaded", metavar="FILE", nargs="+", required=True,
                     help="recordings WITH the payload (one sampling rate with --data)")
    inp.add_argument("--link", metavar="LINK", required=True,
                     help="the link carrying the payload: a moving link of --robot, or (with "
                     "a URDF) a link fixed to one (a flange, tool0), in whose frame the "
                     "payload is reported")
    files.add_loading(inp)
    files.add_motors(pp, "--data and --loaded")
    model = pp.add_argument_group("torque model", "of the joint fit with --data")
    model.add_argument("--friction", metavar="TERMS", default=DEFAULT_FRICTION,
                       help=f"terms of {', '.join(FRICTION_TERMS)} joined by + "
                       f"({DEFAULT_FRICTION})")
    model.add_argument("--offset-per-recording", action="store_true",
                       help="one torque offset per joint and file (a sensor zero that moved "
                       "between them)")
    est = pp.add_argument_group("estimator")
    est.add_argument("--weights", choices=("residual", "equal"), default="residual",
                     help="row weights per joint: residual (Gautier's two-step, default) or "
                     "equal")
    est.add_argument("--physical", action=argparse.BooleanOptionalAction, default=True,
                     help="a physically consistent payload (positive semidefinite "
                     "pseudo-inertia; the robot's links free; default); --no-physical: "
                     "the unconstrained estimate")
    out = pp.add_argument_group("outputs", "written atomically: a failed run leaves none")
    out.add_argument("--json", metavar="PATH", default=None,
                     help="write the payload as JSON (payload.mass [kg], payload.com [m], "
                     "payload.inertia [kg m^2], their std, the fit); its directory is "
                     "created")
    add_run_options(pp, config="weights = \"equal\"")
    pp.set_defaults(func=run)
