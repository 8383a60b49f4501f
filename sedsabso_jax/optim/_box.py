"""Search boxes: checking bounds, and the one rule for a box around a point.

The identification problems search a box around a point ``c`` (the true base parameters in
the paper's scenario, an a-priori estimate otherwise)::

    c +- max(fraction |c|, floor)            (elementwise)

``fraction`` makes the box relative to each parameter's size, ``floor`` keeps parameters
near zero searchable.
"""

from __future__ import annotations

import numpy as np
from jaxtyping import ArrayLike, Float


def check_bounds(lower: Float[ArrayLike, " d"], upper: Float[ArrayLike, " d"],
                 dim: int | None = None
                 ) -> tuple[Float[np.ndarray, " d"], Float[np.ndarray, " d"]]:
    """``(lower, upper)`` as float arrays after checking them: 1-D, one length (``dim``
    if given), finite, ``lower < upper`` everywhere."""
    lower = np.asarray(lower, dtype=float)
    upper = np.asarray(upper, dtype=float)
    if lower.ndim != 1 or upper.shape != lower.shape:
        raise ValueError(f"bounds must be two 1-D arrays of one length; got lower {lower.shape}, "
                         f"upper {upper.shape}")
    if dim is not None and lower.shape[0] != dim:
        raise ValueError(f"bounds have length {lower.shape[0]}, the fitness has {dim} parameters")
    if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
        raise ValueError("bounds must be finite")
    bad = np.flatnonzero(lower >= upper)
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"bounds need lower < upper; at index {i}: lower {lower[i]:g} >= "
                         f"upper {upper[i]:g} ({bad.size} such indices)")
    return lower, upper


def box_around(centre: Float[ArrayLike, " d"], fraction: float, floor: float
               ) -> tuple[Float[np.ndarray, " d"], Float[np.ndarray, " d"]]:
    """``(lower, upper) = centre -+ max(fraction |centre|, floor)``; ``fraction, floor >= 0``
    and not both 0, ``centre`` finite."""
    fraction, floor = float(fraction), float(floor)
    if not (fraction >= 0 and floor >= 0 and fraction + floor > 0
            and np.isfinite(fraction + floor)):
        raise ValueError(f"box (fraction, floor) must be finite, >= 0 and not both 0, got "
                         f"({fraction:g}, {floor:g})")
    centre = np.asarray(centre, dtype=float)
    if centre.ndim != 1 or not np.all(np.isfinite(centre)):
        raise ValueError(f"the box centre must be a finite 1-D array, got shape {centre.shape}")
    half = np.maximum(fraction * np.abs(centre), floor)
    return centre - half, centre + half
