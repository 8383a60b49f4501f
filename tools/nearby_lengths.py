"""What recordings of nearby lengths cost the base regressor in one process: the KUKA
LWR4+'s base regressor of 20 random recordings of 3000 to 3703 samples (a validation's
outer splits are such), timed with compilation (nothing warmed up), the programs compiled
and the process's memory maps before and after (Linux). For comparing two checkouts:

    PYTHONPATH=OLD python tools/nearby_lengths.py; python tools/nearby_lengths.py
"""

from __future__ import annotations

import json
import os
import time

import jax

jax.config.update("jax_enable_x64", True)
import numpy as np  # noqa: E402

import sedsabso_jax as sj  # noqa: E402
from sedsabso_jax.dynamics._regressor import _regressor_jit  # noqa: E402


def maps() -> int:
    with open(f"/proc/{os.getpid()}/maps") as f:
        return sum(1 for _ in f)


def main() -> None:
    base = sj.base_parameters(sj.robots.kuka_lwr4())
    q, qd, qdd = np.random.default_rng(0).normal(size=(3, 3703, 7))
    before, t0 = maps(), time.perf_counter()
    for T in range(3000, 3704, 37):
        base.regressor(q[:T], qd[:T], qdd[:T]).block_until_ready()
    print(json.dumps({"package": sj.__file__, "seconds": round(time.perf_counter() - t0, 1),
                      "compiled": _regressor_jit._cache_size(),
                      "maps_before": before, "maps_after": maps()}))


if __name__ == "__main__":
    main()
