"""The ``sedsabso-jax`` command: ``main(argv)`` runs it (the console script), and
``build_parser()`` is its argument parser. It parses and dispatches only: each command is
one call of the library (``sedsabso_jax.select_and_identify``,
``sedsabso_jax.identify_payload``, ``sedsabso_jax.identify_drive_gains``,
``sedsabso_jax.reproduce``, ``sedsabso_jax.compare``)."""

from __future__ import annotations

from ._main import build_parser as build_parser
from ._main import main as main

__all__ = ["main", "build_parser"]
