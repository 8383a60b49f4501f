"""The path of one call: the package's frames on the stack when the first linear solve runs.

    python tools/stops.py [--library] [--target optim/_linear.py:solve] [-- ARGS ...]

Runs ``sedsabso-jax identify ARGS`` (default: the shipped KUKA run 1, the default
identification) in this process, or with ``--library`` the one call
``sj.identify(robot, data)``, and stops at the first call of the target function (a file
of the package and a function name; default: :meth:`~sedsabso_jax.optim.Factorization.solve`,
the least-squares solve). It prints the package's frames on the stack from the entry point
to the target, one line each (``file:line function``), and counts them (the "stops") and
the files they are in. Frames of other packages (JAX, NumPy, equinox) are left out.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import sedsabso_jax

PACKAGE = Path(sedsabso_jax.__file__).resolve().parent  # the checkout on PYTHONPATH


class Found(BaseException):
    """Raised by the profiler at the target, carrying the stack."""

    def __init__(self, frames: list[tuple[str, int, str]]):
        super().__init__()
        self.frames = frames


def _package_frames(frame) -> list[tuple[str, int, str]]:
    out = []
    while frame is not None:
        path = Path(frame.f_code.co_filename)
        if PACKAGE in path.parents:
            out.append((str(path.relative_to(PACKAGE)), frame.f_lineno, frame.f_code.co_name))
        frame = frame.f_back
    return out[::-1]


def trace(entry, target: tuple[str, str]) -> list[tuple[str, int, str]]:
    """The package's frames when ``entry()`` first calls ``target`` (file, function)."""
    file, name = target

    def profile(frame, event, arg):
        if event == "call" and frame.f_code.co_name == name \
                and frame.f_code.co_filename.endswith(file):
            raise Found(_package_frames(frame))

    sys.setprofile(profile)
    try:
        entry()
    except Found as found:
        return found.frames
    finally:
        sys.setprofile(None)
    raise SystemExit(f"{file}:{name} was never called")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--library", action="store_true", help="trace sj.identify, not the command")
    p.add_argument("--target", default="optim/_linear.py:solve")
    p.add_argument("args", nargs=argparse.REMAINDER)
    a = p.parse_args(argv)
    kuka = PACKAGE / "data" / "kuka_lwr4"
    if a.library:
        import jax

        jax.config.update("jax_enable_x64", True)
        import sedsabso_jax as sj
        from sedsabso_jax.measurements._load import load_kuka_lwr4

        robot, data = sj.robots.load("kuka_lwr4"), load_kuka_lwr4(1)

        def entry():
            sj.identify(robot, data)
    else:
        from sedsabso_jax.cli._main import main as cli

        args = [x for x in a.args if x != "--"] or [
            "--robot", "kuka_lwr4", "--data", str(kuka / "measurements_1.npz")]

        def entry():
            cli(["identify", *args])
    file, _, name = a.target.rpartition(":")
    frames = trace(entry, (file, name))
    for f, line, fn in frames:
        print(f"{f}:{line} {fn}")
    files = {f for f, _, _ in frames}
    print(f"{len(frames)} stops in {len(files)} files")
    return 0


if __name__ == "__main__":
    sys.exit(main())
