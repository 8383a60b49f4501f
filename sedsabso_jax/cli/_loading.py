"""What the commands that read joint data share: the robot's flags, how the files are
loaded (filtering, resampling, the motor side) and the robot's URDF file."""

from __future__ import annotations

import argparse
import contextlib
import os
from collections.abc import Sequence
from contextlib import AbstractContextManager
from typing import TYPE_CHECKING, Any

from ._common import BUILTIN_ROBOTS, positive_float, positive_int

if TYPE_CHECKING:
    from ..measurements._container import Measurements
    from ..measurements._transmission import Transmission


def numbers(flag: str, text, n: int):
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


def drive_gains(args: argparse.Namespace, n: int) -> list[float] | None:
    """``--drive-gains``: ``n`` comma-separated numbers, or a JSON file ``identify-gains
    --json`` wrote (its ``drive_gains``, recorded on the side ``--motor-side`` says)."""
    import json

    from ..identification._data_checks import check_gains

    text = args.drive_gains
    if text is None:
        return None
    if not (text.lower().endswith(".json") or os.path.isfile(text)):
        return check_gains(numbers("--drive-gains", text, n), n, "--drive-gains").tolist()
    from ..identification._gains._result import read_gains

    try:
        with open(text, encoding="utf-8") as f:
            doc = json.load(f)
    except FileNotFoundError:
        raise FileNotFoundError(f"--drive-gains {text}: no such file") from None
    except (OSError, ValueError) as err:
        raise ValueError(f"--drive-gains {text}: not a JSON file ({err})") from None
    gains = check_gains(read_gains(doc, n, f"--drive-gains {text}"), n,
                        f"--drive-gains {text}")
    side = bool(doc.get("motor_side", False))
    if side != bool(args.motor_side):
        raise ValueError(f"--drive-gains {text}: the gains are the "
                         f"{'motors' if side else 'joints'}' (identify-gains "
                         f"{'with' if side else 'without'} --motor-side): "
                         f"{'give' if side else 'leave out'} --motor-side")
    return gains.tolist()


def transmission_of(args: argparse.Namespace, n: int) -> Transmission | None:
    """The motors' transmission from --gear-ratios, --coupling, --position-offsets and
    --drive-gains (with --motor-side), or None."""
    from ..measurements._transmission import Transmission

    ratios = numbers("--gear-ratios", args.gear_ratios, n)
    if ratios is None:
        for flag, value in (("--motor-side", args.motor_side), ("--coupling", args.coupling),
                            ("--position-offsets", args.position_offsets)):
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
        ratios, coupling=coupling, offset=numbers("--position-offsets",
                                                  args.position_offsets, n),
        drive_gains=drive_gains(args, n) if args.motor_side else None)


def urdf_source(robot: str) -> AbstractContextManager[Any]:
    """The URDF file ``--robot`` names (a built-in's shipped file); None for the RS010N and
    the Panda, which have none."""
    from ..dynamics import _robots as robots

    shipped = {"kuka_lwr4": robots.kuka_lwr4_urdf, "staubli_tx40": robots.staubli_tx40_urdf}
    if robot in shipped:
        return shipped[robot]()
    return contextlib.nullcontext(robot if robot.lower().endswith(".urdf") else None)


def loading(args: argparse.Namespace, n_joints: int) -> dict[str, Any]:
    """The options of ``load_measurements`` that the loading flags give, and the joint-side
    ``drive_gains`` (--drive-gains without --motor-side) that :func:`load_all` applies."""
    out = dict(n_joints=n_joints, cutoff_hz=args.cutoff_hz,
               filter_torques=args.filter_torques, downsample=args.downsample,
               resample_hz=args.resample_hz, trim_edges=not args.keep_edges)
    if getattr(args, "drive_gains", None) is not None and not args.motor_side:
        out["drive_gains"] = drive_gains(args, n_joints)
    return out


def load_all(paths: Sequence[str], load: dict[str, Any], motor_side: bool,
             transmission: Transmission | None) -> list[Measurements]:
    """The files at ``paths``, loaded with ``load`` (:func:`loading`), on the joint side:
    motor side through ``transmission``, or their torque columns times the joint-side
    ``drive_gains`` of ``load``."""
    import numpy as np

    from ..measurements._container import Measurements
    from ..measurements._load import load_measurements

    options = dict(load)
    gains = options.pop("drive_gains", None)
    data = [load_measurements(path, **options) for path in paths]
    if motor_side:
        assert transmission is not None  # transmission_of: --motor-side needs --gear-ratios
        data = [transmission.to_joint_side(d) for d in data]
    elif gains is not None:
        n = len(gains)
        data = [Measurements(d.times, d.q, d.qd, d.qdd, d.tau * gains, source=d.source,
                             info=dict(d.info, drive_gains=list(gains)),
                             recorded=None if d.recorded is None else d.recorded.linear(
                                 np.eye(n), np.zeros(n), np.diag(gains),
                                 dict(d.recorded.info, drive_gains=list(gains))))
                for d in data]
    return data


def add_robot(group: argparse._ArgumentGroup) -> None:
    """``--robot`` and ``--tip``."""
    group.add_argument("--robot", metavar="NAME|FILE", required=True,
                       help=f"one of {', '.join(BUILTIN_ROBOTS)}, a .urdf file or a MuJoCo "
                       "MJCF .xml file")
    group.add_argument("--tip", metavar="LINK", default=None,
                       help="URDF tip link (MJCF: tip body), for trees that branch")


def add_loading(group: argparse._ArgumentGroup) -> None:
    """The flags of how files are loaded: filtering, resampling, edges."""
    group.add_argument("--cutoff-hz", metavar="HZ", type=positive_float, default=None,
                       help="low-pass cutoff where velocities/accelerations are derived or "
                       "torques filtered (default 10 Hz, identify chooses among 5 and "
                       "10 Hz; given, identify keeps it)")
    group.add_argument("--filter-torques", action="store_true", help="low-pass the torques")
    group.add_argument("--downsample", metavar="K", type=positive_int, default=1,
                       help="keep every k-th sample after filtering (1)")
    group.add_argument("--resample-hz", metavar="HZ", type=positive_float, default=None,
                       help="interpolate onto a uniform grid at this rate first (irregular "
                       "logs)")
    group.add_argument("--keep-edges", action="store_true",
                       help="keep the first and last 2 / cutoff seconds, where derived "
                       "signals show the filter's edge transients (dropped by default)")


def add_motors(parser: argparse.ArgumentParser, files: str) -> None:
    """The ``motors`` group; ``files``: the flags whose files it converts."""
    motors = parser.add_argument_group("motors", "data recorded on the motor side")
    motors.add_argument("--motor-side", action="store_true",
                        help=f"{files} hold motor angles and motor torques (or "
                        "currents, with --drive-gains): converted with --gear-ratios")
    motors.add_argument("--gear-ratios", metavar="LIST", default=None,
                        help="motor turns per joint turn, one per joint, comma-separated")
    motors.add_argument("--coupling", action="append", default=None, metavar="M:J=RATIO",
                        help="motor M also turns with joint J at RATIO (repeatable), e.g. "
                        "6:5=32")
    motors.add_argument("--position-offsets", metavar="LIST", default=None,
                        help="joint position of each encoder zero [rad], comma-separated")
    motors.add_argument("--drive-gains", metavar="LIST|FILE.json", default=None,
                        help="torque per unit of recorded current, one per motor (with "
                        "--motor-side) or joint (without: the torque columns hold currents), "
                        "comma-separated, or the JSON file 'identify-gains --json' wrote")
