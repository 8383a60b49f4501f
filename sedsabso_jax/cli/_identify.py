"""``sedsabso-jax identify``: the flags become a robot, data, the candidates and the
library's :class:`~sedsabso_jax.identification.Choice` (checked before any data are
loaded), then one library call (:func:`~sedsabso_jax.select_and_identify`'s, by that
Choice) whose report is printed and written."""

from __future__ import annotations

import argparse
import math
import os
import threading
from typing import Any

from . import _vocabulary as words
from ._checks import (
    check_signals,
    inputs_of,
    one_rate,
    refuse_contradictions,
    refuse_overwriting,
)
from ._common import (
    LineProgress,
    add_run_options,
    non_negative_int,
    positive_int,
    subcommand,
)
from ._loading import (
    add_loading,
    add_motors,
    add_robot,
    load_all,
    loading,
    transmission_of,
    urdf_source,
)
from ._vocabulary import AUTO

WEIGHTS = (AUTO, "residual", "limits", "equal")
#: The seconds of writing the report (on 2 cores; not paced as the library's estimates,
#: :class:`~._common.LineProgress`): its text and JSON, and with --out each figure
#: (1.3-1.6 s measured for the KUKA LWR4+'s; matplotlib's import, 2 s, is made while the
#: fits run).
WRITE_SECONDS, FIGURE_SECONDS = 0.3, 1.5


def writing_seconds(figures: int) -> float:
    """The estimated seconds of writing the report with ``figures`` figures."""
    return WRITE_SECONDS + FIGURE_SECONDS * figures


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


def _choice(args: argparse.Namespace, physical: bool | None, candidates: int) -> Any:
    """The library's :class:`~sedsabso_jax.identification.Choice` of the flags (its rules
    checked, named by the flags), before any data are loaded."""
    from ..identification._default._choice import Choice, DefaultValidation
    from ..identification._validation._kept_terms import KEPT_TERMS
    from ..identification._validation._screened_terms import SCREENED_TERMS
    from ..identification._validation._splits import PhaseFolds, RecordingFolds, SpeedSplits

    validation: Any = None  # --folds 0: none
    if args.folds != 0 and args.validation == "pooled":
        auto = args.friction == AUTO and not args.mujoco_terms
        validation = DefaultValidation(
            args.folds, KEPT_TERMS if auto and args.friction_at_rest else None,
            SCREENED_TERMS if auto and args.searched_scales else None,
            signals=AUTO if args.signals == "auto" else None)
    elif args.folds != 0 and args.validation == "phase":
        validation = PhaseFolds(args.folds)
    elif args.folds != 0:
        validation = SpeedSplits() if args.validation == "speed" else RecordingFolds()
    return Choice(validation, physical, args.prior_strength, candidates, len(args.data),
                  args.offset_per_recording, flags=True)


def _validate_files(paths: list[str] | None) -> list[str]:
    """``--validate``'s files, none given twice."""
    paths = list(paths or [])
    for k, path in enumerate(paths):
        if any(os.path.realpath(path) == os.path.realpath(p) for p in paths[:k]):
            raise ValueError(f"--validate: {path} is given twice: give each held-out file once")
    return paths


def run(args: argparse.Namespace) -> None:
    """The subcommand: check the flags, load, build the objects, one call, print, write."""
    from .._output import pyplot
    from ..dynamics import _robots as robots
    from ..dynamics._limits import joint_limits
    from ..identification._default._held_out import named_recordings
    from ..identification._default._policy import DEFAULT
    from ..identification._default._select_and_identify import chosen_and_identified
    from ..identification._fit._simulator import held_frictions, import_mujoco
    from ..identification._model._candidates import candidate_models
    from ..identification._model._order import parse_friction
    from ..identification._recordings import recordings_of

    refuse_contradictions(args)
    refuse_overwriting({"--json": args.json, "--urdf-out": args.urdf_out,
                        "--mjcf-out": args.mjcf_out},
                       inputs_of(args, "--data", "--validate"))
    simulator = args.urdf_out is not None or args.mjcf_out is not None
    for flag, value in (("--urdf-out", args.urdf_out), ("--mjcf-out", args.mjcf_out)):
        if value is not None and args.physical is False:
            raise ValueError(f"{flag} needs physically consistent link parameters, which "
                             f"--no-physical rules out")
    if args.mjcf_out is not None or args.mujoco_terms:
        import_mujoco()  # before the long run: the written model is checked in MuJoCo
    # a simulator's model needs physically consistent link parameters
    physical = True if simulator else args.physical
    frictions = DEFAULT.frictions if args.friction == AUTO else (
        parse_friction(args.friction),)
    if args.mujoco_terms:
        if args.friction != AUTO and held_frictions(frictions) != frictions:
            raise ValueError(f"--mujoco-terms: --friction {args.friction} has terms MuJoCo "
                             f"cannot hold in full; give only offset and armature beside "
                             f"viscous-coulomb, or leave --friction auto")
        frictions = held_frictions(frictions)
    estimators = DEFAULT.estimator_candidates(None if args.method == AUTO else args.method,
                                              args.weights, runs=args.runs,
                                              iterations=args.iterations, seed=args.seed)
    choice = _choice(args, physical, len(frictions) * len(estimators))
    with urdf_source(args.robot) as source:
        if (args.urdf_out is not None and source is not None
                and os.path.realpath(args.urdf_out) == os.path.realpath(source)):
            raise ValueError(f"--urdf-out {args.urdf_out} is the input URDF: write the "
                             f"identified robot to another file")
    robot = robots.load(args.robot, args.tip)
    load = loading(args, robot.n_joints)
    transmission = transmission_of(args, robot.n_joints)
    data = load_all(args.data, load, args.motor_side, transmission)
    validate = _validate_files(args.validate)
    held_out = (dict(zip(validate, load_all(validate, load, args.motor_side, transmission)))
                if validate else None)  # each named by its file as given
    one_rate([("--data", data)])
    data = recordings_of(robot, data)  # one rate and the robot's joints, or exit 2 now
    # degrees for radians, torques in another unit, ...
    check_signals(args.robot, robot, [data, list((held_out or {}).values())])
    limits = joint_limits(args.robot, robot).torque_limits
    if limits is None and all(e.needs_limits for e in estimators):
        raise ValueError(f"--weights limits: no torque limits known for --robot {args.robot} "
                         f"(a URDF's <limit effort=...>)")
    models = candidate_models(robot, frictions, transmission=transmission,
                              recordings=len(data) if args.offset_per_recording else 1)
    # every fit, the evaluation, the files
    figures = 0 if args.out is None else (1 + len(validate)) * (1 + (args.mjcf_out is not None))
    if figures:  # matplotlib's import (2 s) while the fits run, not after them
        threading.Thread(target=pyplot, name="import matplotlib", daemon=True).start()
    with LineProgress("identify", then=writing_seconds(figures)) as progress:
        report = chosen_and_identified(robot, data, choice, models, estimators,
                                       held=dict(named_recordings(robot, held_out)),
                                       limits=limits, progress=progress)
        if args.mjcf_out is not None:
            options = {"limits": joint_limits(args.robot, robot),
                       "timestep": 1.0 / report.data.rate}
            report = report.with_mjcf(**options)
            held = held_frictions(frictions)
            if not args.mujoco_terms and args.friction == AUTO and held != frictions:
                # beside the choice, the one among the terms MuJoCo holds (not written)
                made = chosen_and_identified(
                    robot, data, _choice(argparse.Namespace(**{**vars(args),
                                                                "mujoco_terms": True}),
                                         True, len(held) * len(estimators)),
                    candidate_models(robot, held, transmission=transmission,
                                     recordings=models[0].recordings),
                    estimators, held=dict(named_recordings(robot, held_out)),
                    limits=limits)
                report = report.beside_made_for_mujoco(made.with_mjcf(**options))
    paths = [os.path.abspath(p) for p in args.data]
    settings = {"robot": args.robot, "data": paths[0] if len(paths) == 1 else paths,
                "validate": (None if not validate else os.path.abspath(validate[0])
                             if len(validate) == 1 else [os.path.abspath(p) for p in validate]),
                "torque_limits": limits, "loading": {**load, "data_info": report.data.info},
                "motor_side": bool(args.motor_side)}
    with urdf_source(args.robot) as source:
        written = report.write(settings, args.out, args.json, args.urdf_out,
                               urdf_source=source, mjcf_path=args.mjcf_out)
    text = report.text()
    progress.finish("written" if written else "done")
    print(text)
    if written:
        print("written: " + ", ".join(written))


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The ``identify`` subcommand's flags, in groups."""
    from ._vocabulary import ESTIMATORS, FRICTION_CANDIDATES, FRICTION_TERMS, PRIOR_STRENGTHS

    ip = subcommand(
        sub, "identify",
        help="identify a robot's base parameters from measured data",
        description="Identify base parameters from joint data (.npz with keys positions, "
        "velocities, accelerations, torques, times; or .csv with a header time,q1..,qd1..,"
        "qdd1..,tau1..) and validate on held-out data. What is left 'auto' is chosen by "
        "validation (--validation), physically consistent or not unless --physical or "
        "--no-physical. Flags may also come from a --config file; the command line wins.",
        examples=["sedsabso-jax identify --robot kuka_lwr4 --data run1.npz --validate "
                  "run2.npz",
                  "sedsabso-jax identify --robot kuka_lwr4 --data a.npz --validate b.npz "
                  "c.npz",
                  "sedsabso-jax identify --config identify.toml --physical --out results"])
    inp = ip.add_argument_group("input", "the robot, its data, and how the data are loaded")
    add_robot(inp)
    inp.add_argument("--data", metavar="FILE", required=True, nargs="+",
                     help="identification data (.npz or .csv); several files (one robot, one "
                     "sampling rate) are fitted together")
    add_loading(inp)
    add_motors(ip, "--data and --validate")
    model = ip.add_argument_group("torque model")
    candidates = ", ".join(FRICTION_CANDIDATES)
    model.add_argument("--friction", metavar="TERMS", default=AUTO,
                       help=f"terms of {', '.join(FRICTION_TERMS)} joined by +, each "
                       "TERM or TERM:OPTION (smooth:fit and stribeck:fit search each "
                       "joint's velocity scale, smooth:0.05 and stribeck:0.1 fix it, "
                       "load:viscous adds viscous friction growing with the load); auto "
                       f"(default): chosen by validation among {candidates}, then "
                       "friction at rest (presliding:fit:0.02) added and kept unless it "
                       "validates worse, then the smooth Coulomb's velocity scales "
                       "(smooth:fit) searched where they validate better")
    model.add_argument("--no-friction-at-rest", dest="friction_at_rest",
                       action="store_false",
                       help="with --friction auto, do not add friction at rest to the choice")
    model.add_argument("--no-searched-scales", dest="searched_scales", action="store_false",
                       help="with --friction auto, do not search the smooth Coulomb's "
                       "velocity scales (kept at 0.02 rad/s)")
    est = ip.add_argument_group("estimator")
    est.add_argument("--method", choices=(AUTO, *ESTIMATORS), default=AUTO,
                     help="estimator; auto (default): OLS or WLS, chosen by validation")
    est.add_argument("--weights", choices=WEIGHTS, default=AUTO,
                     help="row weights per joint: residual (Gautier's two-step WLS), limits "
                     "(1 / torque limit), equal; auto (default): chosen by validation")
    est.add_argument("--physical", action=argparse.BooleanOptionalAction, default=None,
                     help="only physically consistent parameters (OLS/WLS): positive-definite "
                     "pseudo-inertia per link, friction >= 0; --no-physical: only "
                     "unconstrained ones; neither (default): both, chosen by validation")
    est.add_argument("--prior-strength", type=_prior_strength, default=0.0, metavar="S|cv",
                     help="with --physical: pull toward the robot's a-priori parameters, in "
                     "multiples of the data term's mean curvature (0), or 'cv' to choose it "
                     "by validation from " + ", ".join(f"{v:g}" for v in PRIOR_STRENGTHS))
    est.add_argument("--runs", metavar="N", type=positive_int, default=1,
                     help="swarm runs, the best kept (1)")
    est.add_argument("--iterations", metavar="N", type=positive_int, default=600,
                     help="swarm iterations (600)")
    est.add_argument("--seed", metavar="N", type=non_negative_int, default=0,
                     help="random seed (0)")
    val = ip.add_argument_group("validation")
    val.add_argument("--validate", metavar="FILE", default=None, nargs="+",
                     help="held-out data (.npz or .csv), one file or several: each judges the "
                     "fit alone, never fits or chooses it; the report gives each (by its "
                     "file name) and their mean")
    val.add_argument("--validation", choices=("pooled", "speed", "phase", "recordings"),
                     default="pooled",
                     help="what chooses what is auto and predicts the error on new motions: "
                     "pooled (default): the phase folds (or, for several --data files, "
                     "leave one out) and the speed splits together; speed: for each joint, "
                     f"fit where it moves below {words.FIT_BELOW:g} of its peak speed and predict "
                     f"above {words.PREDICT_ABOVE:g}; "
                     "phase: folds of the motion's phase; recordings: leave one --data file "
                     "out")
    val.add_argument("--signals", choices=("auto", "as-loaded"), default="auto",
                     help="qd, qdd recorded or derived (5, 10 Hz) and the torques' delay: "
                     "auto (default) chooses by validation")
    val.add_argument("--folds", metavar="K", type=non_negative_int, default=words.FOLDS,
                     help=f"folds over the motion's phase ({words.FOLDS}); 0: no validation "
                     "at all")
    val.add_argument("--offset-per-recording", action="store_true",
                     help="one torque offset per joint and --data file (a sensor zero that "
                     "moved between them); new motions get their mean")
    out = ip.add_argument_group("outputs", "written atomically: a failed run leaves none")
    out.add_argument("--json", metavar="PATH", default=None,
                     help="write the results JSON to this path (its directory is created)")
    out.add_argument("--out", metavar="DIR", default=None,
                     help="directory for torque plots and identification.json (created)")
    out.add_argument("--urdf-out", metavar="PATH", default=None,
                     help="write the input URDF with the identified inertials and joint "
                     "friction, all else kept (a new URDF for a DH robot); only physically "
                     "consistent candidates are tried")
    out.add_argument("--mjcf-out", metavar="PATH", default=None,
                     help="write the identified robot as a MuJoCo model (MJCF: inertials, "
                     "joint damping, frictionloss and armature, a torque actuator per joint "
                     "whose bias is the torque offset) and report its error in MuJoCo; "
                     "only physically consistent candidates are tried (the mujoco extra)")
    out.add_argument("--mujoco-terms", action="store_true",
                     help="try only the friction models MuJoCo holds in full (no smooth "
                     "Coulomb, load or presliding friction): the model made for --mjcf-out")
    add_run_options(ip, config="prior_strength = 1e-3")
    ip.set_defaults(func=run)
