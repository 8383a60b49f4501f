"""The swarms by name: one registry for every place that turns a name into a solver (the
command line, :func:`~sedsabso_jax.identify`, the paper's experiment)."""

from __future__ import annotations

from ._bso import BSO
from ._ldwpso import LDWPSO
from ._sedsabso import SEDSABSO
from ._swarm import AbstractSwarm

#: Name -> solver class; each has ``.paper()``, the paper's settings (Sec. 5.2).
SWARMS: dict[str, type[SEDSABSO] | type[BSO] | type[LDWPSO]] = {
    "SEDSABSO": SEDSABSO, "BSO": BSO, "LDWPSO": LDWPSO}


def paper_solver(name: str) -> AbstractSwarm:
    """The swarm ``name`` with the paper's settings."""
    if name not in SWARMS:
        raise ValueError(f"unknown swarm {name!r}; expected one of {tuple(SWARMS)}")
    return SWARMS[name].paper()
