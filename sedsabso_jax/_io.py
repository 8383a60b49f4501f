"""Atomic file output: write to a temporary file in the target's directory, then rename.

``os.replace`` is atomic on POSIX and Windows within one file system, so a reader sees
either the old file or the complete new one, never a half-written file, and a failure
while writing leaves the old file (or no file) and no temporary file behind.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO


def atomic_write(path, write: Callable[[BinaryIO], None]) -> Path:
    """Call ``write(f)`` on a binary file object opened on a temporary file beside
    ``path``; flush and fsync it, give it the permissions of the file it replaces (0644
    for a new one), then move it over ``path``. On any failure the temporary file is
    removed and an existing ``path`` is left as it was."""
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise FileNotFoundError(f"{path}: directory {directory} does not exist")
    mode = (path.stat().st_mode & 0o777) if path.is_file() else 0o644
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path


def write_text(path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return atomic_write(path, lambda f: f.write(text.encode("utf-8")))


def write_json(path, obj) -> Path:
    """Write ``obj`` as indented JSON to ``path`` atomically (NaN refused: not JSON)."""
    return write_text(path, json.dumps(obj, indent=2, allow_nan=False) + "\n")
