"""The ``sedsabso-jax`` command.

``sedsabso-jax`` alone prints the paper robot's (RS010N) base-parameter table;
``sedsabso-jax base-parameters --robot PATH.urdf`` does the same for any robot.
Bad input exits with status 2 and one line on stderr (``--debug`` shows the traceback).
"""

from __future__ import annotations

import argparse
import os
import sys
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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
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
