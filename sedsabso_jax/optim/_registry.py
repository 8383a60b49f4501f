"""The swarms by name: one registry for every place that turns a name into a solver (the
command line, :func:`~sedsabso_jax.identify`, the paper's experiment). A swarm registers
itself (:meth:`~._swarm.AbstractSwarm.__init_subclass__`) by giving ``paper()``; the
package's swarm modules are imported here, found by that method in their text."""

from __future__ import annotations

import importlib
from pathlib import Path

from ._swarm import REGISTERED, AbstractSwarm


def _import_swarms() -> dict[str, type[AbstractSwarm]]:
    for path in sorted(Path(__file__).parent.glob("_*.py")):
        if path != Path(__file__) and "def paper(cls)" in path.read_text(encoding="utf-8"):
            importlib.import_module(f"{__package__}.{path.stem}")
    return dict(sorted(REGISTERED.items(), key=lambda kv: (kv[1].registry_order, kv[0])))


#: Name -> solver class; each has ``.paper()``, the paper's settings (Sec. 5.2).
SWARMS: dict[str, type[AbstractSwarm]] = _import_swarms()


def paper_solver(name: str) -> AbstractSwarm:
    """The swarm ``name`` with the paper's settings."""
    if name not in SWARMS:
        raise ValueError(f"unknown swarm {name!r}; expected one of {tuple(SWARMS)}")
    return SWARMS[name].paper()
