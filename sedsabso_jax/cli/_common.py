"""What the subcommands share: their help's layout (argument groups, an epilog of examples
and exit statuses), argument types that say what they expected, the progress bar, and the
check that outputs can be written before a long run."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any, Self, TextIO

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

    def __init__(self, what: str, stream: TextIO | None = None, unit: str = "fit"):
        self.what, self.unit = what, unit
        self.stream = sys.stderr if stream is None else stream
        self.bar: Any = None

    def __call__(self, label: str, done: int, total: int) -> None:
        from tqdm import tqdm

        if self.bar is None or self.bar.total != total:
            self.close()
            # initial: work done before (compare's finished problems) sets no pace
            self.bar = tqdm(total=total, initial=done, desc=self.what, unit=self.unit,
                            postfix=label, file=self.stream, disable=None,
                            dynamic_ncols=True, leave=False)
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
    """Fail before the (long) run, not after it, when an output cannot be written: a file
    is made and removed where each output goes (its nearest existing directory), as
    permissions alone do not tell (root's, a read-only or virtual file system's)."""
    import tempfile

    for flag, path in (("--out", out_dir), ("--json", json_path), ("--urdf-out", urdf_path)):
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
    for flag, path in (("--json", json_path), ("--urdf-out", urdf_path)):
        if path is not None and os.path.isdir(path):
            raise ValueError(f"{flag} {path!r} is a directory; expected a file path")


#: The robots ``--robot`` knows by name (else a URDF file).
BUILTIN_ROBOTS = ("rs010n", "kuka_lwr4", "staubli_tx40", "franka_panda")
