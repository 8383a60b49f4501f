"""The commands' checks of their input before any work, in the command's words: flags that
contradict each other, outputs that would overwrite an input or each other, the
recordings' sampling rates, the signals against the robot's joint limits. The library's
own checks of the data (:mod:`sedsabso_jax.identification._data_checks`) follow in the
call the command makes."""

from __future__ import annotations

import argparse
import os
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING

from . import _vocabulary as words

if TYPE_CHECKING:
    from ..dynamics._robot import Robot
    from ..measurements._container import Measurements

#: ``identify``'s swarm flags and their defaults: only a box search (SEDSABSO, BSO,
#: LDWPSO) reads them.
SWARM_FLAGS = {"runs": 1, "iterations": 600, "seed": 0}


def refuse_contradictions(args: argparse.Namespace) -> None:
    """``identify``'s flags that contradict each other (one is ignored by the other): a
    one-line ValueError naming both and why."""
    from ..identification._estimators._estimator import Estimator

    if not args.friction_at_rest and args.friction != "auto":
        raise ValueError(f"--no-friction-at-rest acts on --friction auto only: --friction "
                         f"{args.friction} is fitted as given (leave out presliding to fit "
                         f"no friction at rest)")
    if not args.searched_scales and args.friction != "auto":
        raise ValueError(f"--no-searched-scales acts on --friction auto only: --friction "
                         f"{args.friction} is fitted as given (smooth:fit searches the "
                         f"scales, smooth keeps them at 0.02 rad/s)")
    if args.folds == 0 and args.validation != "pooled":
        raise ValueError(f"--folds 0 turns validation off: --validation {args.validation} "
                         f"would not be used")
    if args.folds not in (0, words.FOLDS) and args.validation in ("speed", "recordings"):
        raise ValueError(f"--folds {args.folds} sets the folds of the motion's phase, which "
                         f"--validation {args.validation} does not use")
    given = [f"--{k}" for k, default in SWARM_FLAGS.items() if getattr(args, k) != default]
    searched = args.method != "auto" and hasattr(Estimator.named(args.method), "iterations")
    if given and not searched:
        method = ("auto (OLS or WLS)" if args.method == "auto" else args.method)
        raise ValueError(f"{', '.join(given)}: only a swarm's search reads "
                         f"{'them' if len(given) > 1 else 'it'} (--method SEDSABSO, BSO or "
                         f"LDWPSO); --method {method} solves in closed form")


def refuse_overwriting(outputs: dict[str, str | None], inputs: Sequence[tuple[str, str]]
                       ) -> None:
    """That no output file (``{flag: path}``) is an input file (``(flag, path)``) or
    another output: a ValueError naming both flags."""
    def same(a: str, b: str) -> bool:
        return os.path.realpath(a) == os.path.realpath(b)

    given = [(flag, path) for flag, path in outputs.items() if path is not None]
    for k, (flag, path) in enumerate(given):
        for in_flag, in_path in inputs:
            if same(path, in_path):
                kind = "MJCF" if in_path.lower().endswith(".xml") else "URDF"
                what = f"{kind} (--robot)" if in_flag == "--robot" else f"{in_flag} {in_path}"
                raise ValueError(f"{flag} {path} is the input {what}: write the results to "
                                 f"another file")
        for other, other_path in given[k + 1:]:
            if same(path, other_path):
                raise ValueError(f"{flag} and {other} name the same file {path}: give each "
                                 f"its own")


def one_rate(groups: Sequence[tuple[str, Sequence[Measurements]]]) -> None:
    """That the recordings of ``groups`` (``(flag, recordings)``) share one sampling rate
    (within the library's tolerance), else a ValueError that points to --resample-hz."""
    from ..identification._recordings import RATE_TOLERANCE

    found = [(flag, d) for flag, data in groups for d in data]
    rates = [d.rate for _, d in found]
    if len(rates) < 2 or max(rates) <= (1 + RATE_TOLERANCE) * min(rates):
        return
    listed = ", ".join(f"{flag} {d.source}: {r:.4g} Hz" for (flag, d), r in zip(found, rates))
    raise ValueError(f"the recordings have different sampling rates ({listed}): give "
                     f"--resample-hz HZ to load them all at one rate (e.g. --resample-hz "
                     f"{min(rates):.4g})")


def check_signals(spec: str, robot: Robot,
                  groups: Sequence[Sequence[Measurements | None]], *,
                  torques: bool = True) -> None:
    """The recordings' positions, speeds and (``torques``) torques against the joint
    limits of ``--robot spec`` (a URDF's ``<limit>``, an MJCF's ranges, the built-in
    robots' tables; None entries: no recording):
    :func:`~sedsabso_jax.identification._data_checks.check_limits`."""
    from ..dynamics._limits import joint_limits
    from ..identification._data_checks import check_limits

    with warnings.catch_warnings():  # a continuous joint's missing limit: said elsewhere
        warnings.simplefilter("ignore")
        limits = joint_limits(spec, robot)
    where = (f" in {os.path.basename(spec)}" if spec.lower().endswith((".urdf", ".xml"))
             else f" of --robot {spec}")
    for data in groups:
        check_limits(robot, [d for d in data if d is not None], limits, where,
                     torques=torques)


def inputs_of(args: argparse.Namespace, *flags: str) -> list[tuple[str, str]]:
    """``(flag, path)`` of each input file the ``flags`` give (one path or several), and
    ``--robot``'s where it is a URDF or MJCF file."""
    found = [("--robot", args.robot)] if str(getattr(args, "robot", "")).lower().endswith(
        (".urdf", ".xml")) else []
    for flag in flags:
        value = getattr(args, flag.lstrip("-").replace("-", "_"), None)
        for path in [value] if isinstance(value, str) else value or []:
            found.append((flag, path))
    return found
