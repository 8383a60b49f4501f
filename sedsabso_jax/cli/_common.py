"""What the subcommands share: argument types that say what they expected, the progress
bar, and the check that outputs can be written before a long run."""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable
from typing import TextIO

from .._output import PathLike


class Progress:
    """A one-line progress bar on stderr, shown only when stderr is a terminal."""

    def __init__(self, stream: TextIO | None = None, width: int = 24):
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


def number(kind: type[int] | type[float], minimum: float, strict: bool
           ) -> Callable[[str], float]:
    """An argparse type: ``kind`` (int or float), finite, ``> minimum`` if ``strict`` else
    ``>= minimum``; a bad value gets one line saying what was expected."""
    what = "an integer" if kind is int else "a finite number"
    expected = f"expected {what} {'>' if strict else '>='} {minimum:g}"

    def parse(text: str) -> float:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{expected}, got {text!r}") from None
        ok = value > minimum if strict else value >= minimum
        if not (ok and value < float("inf")):  # NaN fails both comparisons
            raise argparse.ArgumentTypeError(f"{expected}, got {text}")
        return value

    return parse


positive_int = number(int, 1, strict=False)
non_negative_int = number(int, 0, strict=False)
positive_float = number(float, 0, strict=True)
non_negative_float = number(float, 0, strict=False)


def check_writable(out_dir: PathLike | None, json_path: PathLike | None,
                   urdf_path: PathLike | None = None) -> None:
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


#: The robots ``--robot`` knows by name (else a URDF file).
BUILTIN_ROBOTS = ("rs010n", "kuka_lwr4", "staubli_tx40", "franka_panda")
