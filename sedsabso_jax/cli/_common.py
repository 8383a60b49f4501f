"""What the subcommands share: their help's layout (argument groups, an epilog of examples
and exit statuses), argument types that say what they expected, the progress (a bar on a
terminal, lines elsewhere), and the checks, before JAX is imported, that the files named
can be read and the outputs written."""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Self, TextIO

if TYPE_CHECKING:
    from .._output import PathLike

#: The exit statuses, as the help states them.
EXIT_STATUS = ("exit status: 0 done; 1 a failure while running (solver, out of memory, an "
               "unexpected error); 2 a usage error or bad input (flags, files, values); "
               "130 interrupted")


class HelpFormatter(argparse.HelpFormatter):
    """Descriptions and epilogs wrapped paragraph by paragraph (blank lines apart), except
    paragraphs with indented lines (examples), which keep their lines."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        parts = []
        for part in text.split("\n\n"):
            parts.append("\n".join(indent + line for line in part.splitlines())
                         if "\n " in part else super()._fill_text(part, width, indent))
        return "\n\n".join(parts)


def epilog(*examples: str) -> str:
    """A subcommand's epilog: its examples (one command a line), then the exit statuses."""
    lines = "\n".join(f"  {e}" for e in examples)
    return f"examples:\n{lines}\n\n{EXIT_STATUS}"


def subcommand(sub: argparse._SubParsersAction, name: str, *, help: str, description: str,
               examples: Sequence[str]) -> argparse.ArgumentParser:
    """A subcommand's parser with the shared help layout; its ``-h`` and ``--debug`` come
    with :func:`add_run_options`, called after its other groups (the last group)."""
    parser: argparse.ArgumentParser = sub.add_parser(
        name, help=help, description=description, epilog=epilog(*examples),
        formatter_class=HelpFormatter, add_help=False)
    return parser


def add_run_options(parser: argparse.ArgumentParser, config: str | None = None
                    ) -> argparse._ArgumentGroup:
    """The ``run`` group: ``--config`` (``config``: an example line of the file), ``--debug``
    and ``-h``."""
    group = parser.add_argument_group("run")
    if config is not None:
        group.add_argument("--config", metavar="FILE", default=None,
                           help="read flags from a TOML (or YAML) file whose keys are the "
                           f"flags' names without the dashes, - or _ alike ({config}); a "
                           "flag given on the command line wins")
    # SUPPRESS: a subcommand's --debug does not reset the one given before it
    group.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                       help="show tracebacks on errors and warnings in full")
    group.add_argument("-h", "--help", action="help", help="show this help and exit")
    return group


class Progress:
    """``progress(label, done, total)`` drawn as a tqdm bar on ``stream`` (stderr), off
    when it is not a terminal; a new ``total`` starts a new bar. Close it (or use it as a
    context manager) when the work ends."""

    #: tqdm's ``bar_format`` (None: tqdm's own, with the count of ``unit``).
    bar_format: str | None = None

    def __init__(self, what: str, stream: TextIO | None = None, unit: str = "fit"):
        self.what, self.unit = what, unit
        self.stream = sys.stderr if stream is None else stream
        self.bar: Any = None

    def __call__(self, label: str, done: float, total: float) -> None:
        from tqdm import tqdm

        if self.bar is None or self.bar.total != total:
            self.close()
            # initial: work done before (compare's finished problems) sets no pace
            self.bar = tqdm(total=total, initial=done, desc=self.what, unit=self.unit,
                            postfix=label, file=self.stream, disable=None,
                            dynamic_ncols=True, leave=False, bar_format=self.bar_format)
        self.bar.set_postfix_str(label, refresh=False)
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()


#: Where the stream is not a terminal, :class:`LineProgress` writes a line each time this
#: share of the work is done, with the time left once this share has set the pace.
LINE_EVERY, PACE_SHARE = 0.1, 0.05


def duration(seconds: float) -> str:
    """``<1 s``, ``45 s`` under two minutes, else ``3.2 min``."""
    if seconds < 0.5:
        return "<1 s"
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


class LineProgress(Progress):
    """``progress(label, done, total)`` of a long call whose ``done`` and ``total`` are
    work (estimated seconds, not a count), followed by ``then`` seconds of the command's
    own (writing the results; :meth:`finish` when done). On a terminal a bar of the share
    done; elsewhere (a log file, a pipe, CI) a line each time another ``every`` of the
    work is done (0: at every call) and at its end, with the seconds so far and the time
    left: the pace so far applied to the call's work left, then ``then`` as it is (the
    pace of fits whose compilation a warm cache skips is not the pace of drawing
    figures). The pace is measured from the first call, once :data:`PACE_SHARE` of the
    work is done since: what comes before it (imports, compilation, the first regressor)
    is not the pace of the rest, nor is one small step. ``total`` may change between
    calls (the work ahead estimated again)."""

    bar_format = "{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}, {postfix}"

    def __init__(self, what: str, stream: TextIO | None = None, *, then: float = 0.0,
                 every: float = LINE_EVERY, clock: Callable[[], float] = time.perf_counter):
        super().__init__(what, stream, unit="s")
        self.then, self.every, self.clock, self.start = then, every, clock, clock()
        self.first: tuple[float, float] | None = None
        self.shown, self.total = -1, then  # the shares (in steps of every) shown so far

    def __call__(self, label: str, done: float, total: float) -> None:
        now, self.total = self.clock(), total + self.then
        if self.first is None:
            self.first = (now, done)
        if self.stream.isatty():
            if self.bar is not None:
                self.bar.total = self.total  # a revised estimate: the same bar
            super().__call__(label, done, self.total)
            return
        share = min(done / self.total, 1.0) if self.total > 0 else 1.0
        step = math.floor(share / self.every + 1e-9) if self.every > 0 else self.shown + 1
        if share < 1.0 and step <= self.shown:
            return
        self.shown = step
        start, done0 = self.first
        left = None
        if share < 1.0 and done - done0 >= PACE_SHARE * self.total and now > start:
            left = (now - start) / (done - done0) * max(total - done, 0.0) + self.then
        print(self.line(share, now - self.start, left, label), file=self.stream, flush=True)

    def line(self, share: float, elapsed: float, left: float | None, label: str) -> str:
        """One line: the share of the work done (rounded down), the seconds so far, the
        time left."""
        ahead = "" if left is None else f", {'' if left < 0.5 else '~'}{duration(left)} left"
        return f"{self.what}: {math.floor(100 * share):3d}%, {duration(elapsed)}{ahead}: {label}"

    def finish(self, label: str) -> None:
        """The command's own work done: the last line (off a terminal)."""
        if not self.stream.isatty():
            self.then = 0.0
            self(label, self.total, self.total)


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
                   urdf_path: PathLike | None = None, mjcf_path: PathLike | None = None
                   ) -> None:
    """Fail before the (long) run, not after it, when an output cannot be written: a file
    is made and removed where each output goes (its nearest existing directory), as
    permissions alone do not tell (root's, a read-only or virtual file system's)."""
    files = (("--json", json_path), ("--urdf-out", urdf_path), ("--mjcf-out", mjcf_path))
    for flag, path in (("--out", out_dir), *files):
        if path is None:
            continue
        existing = os.path.abspath(path if flag == "--out" else os.path.dirname(
            os.path.abspath(path)))
        while not os.path.exists(existing):  # the directories that will be created
            existing = os.path.dirname(existing)
        if not os.path.isdir(existing):
            raise ValueError(f"{flag} {path!r}: {existing!r} exists and is not a directory")
        try:
            fd, probe = tempfile.mkstemp(dir=existing, prefix=".sedsabso-jax-check.")
            os.close(fd)
            os.unlink(probe)
        except OSError as err:
            raise ValueError(f"{flag} {path!r}: cannot write in directory {existing!r} "
                             f"({err.strerror or err})") from None
    for flag, path in files:
        if path is not None and os.path.isdir(path):
            raise ValueError(f"{flag} {path!r} is a directory; expected a file path")


#: The flags naming files a command reads, by their destination: each file must exist and
#: be readable before the command starts (:func:`check_files`).
INPUT_FLAGS = {"data": "--data", "validate": "--validate", "loaded": "--loaded"}


def check_files(args: argparse.Namespace) -> None:
    """Fail at once, before JAX or the library is imported, when a file a flag names
    (:data:`INPUT_FLAGS`, a ``--robot`` URDF or MJCF, a ``--drive-gains`` JSON file) cannot be
    read or an output (``--out``, ``--json``, ``--urdf-out``, ``--mjcf-out``) cannot be
    written."""
    for dest, flag in INPUT_FLAGS.items():
        paths = getattr(args, dest, None)
        for path in [paths] if isinstance(paths, str) else paths or ():
            _readable(flag, path, "file")
    robot = getattr(args, "robot", None)
    if isinstance(robot, str) and robot.lower().endswith((".urdf", ".xml")):
        if not os.path.isfile(robot):  # the words of the robot's loader
            raise ValueError(f"--robot: no such file {robot!r}")
        _readable("--robot", robot, "URDF file" if robot.lower().endswith(".urdf")
                  else "MJCF file")
    gains = getattr(args, "drive_gains", None)
    if isinstance(gains, str) and gains.lower().endswith(".json"):
        _readable("--drive-gains", gains, "JSON file ('identify-gains --json' writes it)")
    json_path = getattr(args, "json", None)
    check_writable(getattr(args, "out", None), None if json_path == "-" else json_path,
                   getattr(args, "urdf_out", None), getattr(args, "mjcf_out", None))


def _readable(flag: str, path: str, expected: str) -> None:
    if not os.path.exists(path):
        raise FileNotFoundError(f"{flag} {path}: no such file")
    if os.path.isdir(path):
        raise IsADirectoryError(f"{flag} {path}: a directory; expected a {expected}")
    if not os.access(path, os.R_OK):
        raise PermissionError(f"{flag} {path}: the file cannot be read (permissions)")


#: The robots ``--robot`` knows by name (else a URDF or MJCF file).
BUILTIN_ROBOTS = ("rs010n", "kuka_lwr4", "staubli_tx40", "franka_panda")
