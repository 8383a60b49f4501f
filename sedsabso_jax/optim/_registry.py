"""The swarms by name: one registry for every place that turns a name into a solver (the
command line, :func:`~sedsabso_jax.identify`, the paper's experiment). A swarm registers
itself (:meth:`~._swarm.AbstractSwarm.__init_subclass__`) by giving ``paper()``; the
package's own are found by importing its modules."""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Iterator, Mapping
from pathlib import Path

from ._swarm import REGISTERED, AbstractSwarm


class _Swarms(Mapping[str, type[AbstractSwarm]]):
    """The registered swarms, read when asked (a swarm defined later is in it), ordered by
    their ``registry_order``, then name."""

    def __getitem__(self, name: str) -> type[AbstractSwarm]:
        return REGISTERED[name]

    def __iter__(self) -> Iterator[str]:
        return iter(sorted(REGISTERED, key=lambda k: (REGISTERED[k].registry_order, k)))

    def __len__(self) -> int:
        return len(REGISTERED)

    def __repr__(self) -> str:
        return f"SWARMS({', '.join(self)})"


#: Name -> solver class; each has ``.paper()``, the paper's settings (Sec. 5.2).
SWARMS: Mapping[str, type[AbstractSwarm]] = _Swarms()

for _module in pkgutil.iter_modules([str(Path(__file__).parent)]):
    importlib.import_module(f"{__package__}.{_module.name}")


def paper_solver(name: str) -> AbstractSwarm:
    """The swarm ``name`` with the paper's settings."""
    if name not in SWARMS:
        raise ValueError(f"unknown swarm {name!r}; expected one of {tuple(SWARMS)}")
    return SWARMS[name].paper()
