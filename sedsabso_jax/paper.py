"""Numbers published in the paper, kept apart from anything the package computes.

The paper's Eq. 3 and Table 5 "theoretical values" are not consistent with its Table 2
under any reading (NOTES_ON_THE_PAPER.md Sec. 1): e.g. Table 5 writes
``I_2x + (m2 + m3) a2^2`` where Eq. 3 writes ``I_2x + (m2 + m3) a2``, and several rows use
centre-of-mass coordinates where first moments belong. They are shown beside the values
computed from Table 2, labelled as the paper's, never used in a computation.
"""

from __future__ import annotations

#: Table 5, "Theoretical Value" column, keyed by the base parameter of
#: :func:`sedsabso_jax.base_parameters` on :func:`sedsabso_jax.robots.rs010n` that the row
#: stands for: (the paper's expression, as printed; the paper's value). Rows whose
#: printed parameter differs from ours are matched to the base parameter playing the same
#: role (ZZ3 <- "I3yy", MY3 <- "I3z"); their expressions show the difference.
TABLE5_THEORETICAL = {
    "ZZ1R": ("I1yy + I2yy + I3zz + 2*a1*I1x + m1*a1^2 - (m2+m3)*a2^2", 16.41),
    "FC1": ("F1c", 0.0),
    "FV1": ("F1v", 0.0),
    "XX2R": ("I2xx - I2yy + (m2+m3)*a2^2", 31.83),
    "XY2": ("I2xy", 6.14),
    "XZ2R": ("I2x - a2*(I2z - I3y)", 5.76),
    "YZ2": ("I2yz", -7.82),
    "ZZ2R": ("I2zz - (m2+m3)*a2^2", -37.29),
    "MX2R": ("I2x + (m2+m3)*a2^2", 47.37),
    "MY2": ("I2y", 0.16),
    "FC2": ("F2c", 0.0),
    "FV2": ("F2v", 0.0),
    "XX3R": ("I3xx - I3zz", -2.07),
    "XY3": ("I3xy", 3.34),
    "XZ3": ("I3xz", -3.42),
    "ZZ3": ("I3yy", 1.02),
    "YZ3": ("I3yz", -0.29),
    "MX3": ("I3x", 0.15),
    "MY3": ("I3z", -0.034),
    "FC3": ("F3c", 0.0),
    "FV3": ("F3v", 0.0),
}
