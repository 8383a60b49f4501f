"""The numbers published in the paper, in one place, as printed.

"A New Method for Identifying Kinetic Parameters of Industrial Robots", *Actuators* 2022,
11(1), 2, doi:10.3390/act11010002.

Data only: this module imports nothing from the package, so every layer may read it.
Tables 2 and 3 describe the RS010N (:func:`sedsabso_jax.robots.rs010n` and
:meth:`sedsabso_jax.JointLimits.rs010n` are built from them); Tables 4 and 5 are the
paper's results, shown beside ours and never used in a computation.

The paper's Eq. 3 and Table 5 "theoretical values" are not consistent with its Table 2
under any reading (``docs/explanation/paper-notes.md``, Sec. 1): e.g. Table 5 writes
``I_2x + (m2 + m3) a2^2`` where Eq. 3 writes ``I_2x + (m2 + m3) a2``, and several rows use
centre-of-mass coordinates where first moments belong.
"""

from __future__ import annotations

__all__ = ["TABLE2", "TABLE3_DEG", "TABLE4", "TABLE5_THEORETICAL", "TABLE5_IDENTIFIED"]

#: Table 2 (RS010N, links 1-3): inertia about the link-frame origin, in the link frame, in
#: kg m^2; mass in kg; centre of mass in mm (link frame); friction zero. Kept as published,
#: although ``Ixx`` of link 2 (-10.02) is not physically possible.
TABLE2 = {
    "Ixx": (36.33, -10.02, 7.74),
    "Iyy": (40.61, 7.05, 1.02),
    "Izz": (36.33, 11.61, 9.81),
    "Ixy": (0.00, 6.14, 3.34),
    "Ixz": (0.00, 5.93, -3.42),
    "Iyz": (0.00, -7.82, -0.29),
    "m": (18.33, 25.18, 20.47),
    "x_mm": (0.00, 122.41, 152.34),
    "y_mm": (110.11, 163.81, 90.24),
    "z_mm": (0.00, 73.36, -34.21),
    "Fc": (0.0, 0.0, 0.0),
    "Fv": (0.0, 0.0, 0.0),
}

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

#: Table 5, identified values, in the row order of :data:`TABLE5_THEORETICAL`:
#: (SEDSABSO, BSO, LDWPSO) as published.
TABLE5_IDENTIFIED = {
    "ZZ1R": (16.80, 16.89, 16.82),
    "FC1": (0.01, 0.35, -0.20),
    "FV1": (-0.07, -0.21, 0.22),
    "XX2R": (31.77, 31.92, 32.21),
    "XY2": (5.78, 5.12, 6.12),
    "XZ2R": (5.54, 6.22, 5.83),
    "YZ2": (-7.84, -7.72, -8.10),
    "ZZ2R": (-37.11, -37.30, -37.94),
    "MX2R": (47.29, 47.52, 47.27),
    "MY2": (0.13, 0.09, 0.27),
    "FC2": (0.14, -0.02, -0.08),
    "FV2": (-0.21, -0.23, -0.03),
    "XX3R": (-2.20, -2.40, -1.51),
    "XY3": (3.24, 3.25, 4.57),
    "XZ3": (-3.34, -2.95, -4.10),
    "ZZ3": (0.77, 1.12, -0.85),
    "YZ3": (0.10, -0.34, -1.42),
    "MX3": (0.11, 0.12, -0.04),
    "MY3": (0.00, -0.16, 0.04),
    "FC3": (0.18, -0.13, -1.20),
    "FV3": (0.06, -0.34, -0.1),
}

#: Table 4: mean fitness (Eq. 17) and mean time per run [s] over 10 runs of 600
#: iterations (MATLAB 9.1 on an i7-8550U).
TABLE4 = {
    "SEDSABSO": (0.95, 16.93),
    "BSO": (1.12, 17.31),
    "LDWPSO": (1.18, 12.73),
}

#: Table 3: RS010N joint limits (position [deg], velocity [deg/s], acceleration [deg/s^2]).
TABLE3_DEG = {
    "q_min": (-180.0, -60.0, -180.0),
    "q_max": (180.0, 140.0, 80.0),
    "qd_max": (125.0, 100.0, 165.0),
    "qdd_max": (45.0, 40.0, 75.0),
}
