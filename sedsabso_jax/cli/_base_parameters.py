"""``sedsabso-jax base-parameters``: a robot's base parameters as a table, and as JSON."""

from __future__ import annotations

import argparse
import os
import sys
from typing import TYPE_CHECKING, Any

from ._checks import inputs_of, refuse_overwriting
from ._common import BUILTIN_ROBOTS, add_run_options, subcommand

if TYPE_CHECKING:
    from ..dynamics._robot import Robot

DESCRIPTION = (
    "Print a robot's base parameters: the combinations of its standard inertial parameters "
    "(12 per link: inertia XX YY ZZ XY XZ YZ, mass M, first moments MX MY MZ, Coulomb and "
    "viscous friction FC FV) that "
    "the joint torques determine. Parameters that never act alone are regrouped on one that "
    "remains (its name gets an R: ZZ1R = ZZ1 + YY2 + ...); those that never act are dropped. "
    "The table lists each base parameter, its expression in the standard parameters and its "
    "value for the robot's own parameters (for the built-in RS010N, the paper's Table 5 "
    "beside it). --json writes the same as a JSON document.")


def document(robot: Robot, paper_columns: bool) -> dict[str, Any]:
    """The base parameters of ``robot`` as plain JSON values (``--json``): what the table
    shows, plus the standard parameters' names, the standard parameter each base one is
    kept in (its index) and the map from them to the base ones."""
    import numpy as np

    from .. import paper
    from ..dynamics._base_parameters import base_parameters

    base = base_parameters(robot)
    rows = []
    for i, (name, expr, value, column) in enumerate(
            zip(base.names, base.expressions, np.asarray(base.values), base.indices), 1):
        row: dict[str, Any] = {"number": i, "name": name, "expression": expr,
                               "value": float(value), "standard_parameter": column}
        if paper_columns:
            label, published = paper.TABLE5_THEORETICAL.get(name, ("", None))
            row["paper_table5"] = {"expression": label or None, "value": published}
        rows.append(row)
    return {"robot": robot.name, "n_joints": robot.n_joints,
            "standard_parameters": list(robot.param_names),
            "n_standard_parameters": robot.n_params, "n_base_parameters": base.rank,
            "base_parameters": rows,
            # base = matrix @ standard: one row per base parameter
            "matrix": np.asarray(base.matrix).tolist()}


def run(args: argparse.Namespace) -> None:
    from .._output import to_json, write_text
    from ..dynamics import _robots as robots
    from ..reproduce._report import base_parameter_table

    to_stdout = args.json == "-"
    if args.json is not None and not to_stdout:
        refuse_overwriting({"--json": args.json}, inputs_of(args))
    robot = robots.load(args.robot, args.tip)
    paper_columns = args.robot == "rs010n"
    if args.json is None or not to_stdout:
        print(base_parameter_table(robot, paper_columns=paper_columns))
    if args.json is not None:
        text = to_json(document(robot, paper_columns))
        if to_stdout:
            sys.stdout.write(text)
        else:
            os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
            print(f"written: {write_text(args.json, text)}")


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The ``base-parameters`` subcommand's flags."""
    bp = subcommand(sub, "base-parameters", help="print a robot's base-parameter table",
                    description=DESCRIPTION,
                    examples=["sedsabso-jax base-parameters --robot kuka_lwr4",
                              "sedsabso-jax base-parameters --robot arm.urdf --tip tool0 "
                              "--json -"])
    robot = bp.add_argument_group("robot")
    robot.add_argument("--robot", metavar="NAME|FILE", default="rs010n",
                       help=f"one of {', '.join(BUILTIN_ROBOTS)} , a .urdf file or a "
                       f"MuJoCo MJCF .xml file (default rs010n)")
    robot.add_argument("--tip", metavar="LINK", default=None,
                       help="URDF tip link (MJCF: tip body), for trees that branch")
    out = bp.add_argument_group("outputs")
    out.add_argument("--json", default=None, metavar="PATH",
                     help="also write the base parameters as JSON to PATH (written "
                     "atomically; its directory is created); '-': to stdout, instead of "
                     "the table")
    add_run_options(bp)
    bp.set_defaults(func=run)
