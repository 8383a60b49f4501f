"""The real-robot recordings kept in this folder (not installed with the package), as the
package reads them: converters from the sources' own layouts to measurement files, and the
settings each needs. Used by the tests and the benchmarks (``from data import
real_robots`` from the repository root); each folder's SOURCE.md gives origin, licence
and format.

    python data/real_robots.py OUT_DIR     # writes franka_panda.npz, staubli_tx40.npz
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
PANDA, TX40 = HERE / "franka_panda", HERE / "staubli_tx40"

#: The TX40's motor side: gear ratios, the coupled wrist (motor 6 turns with joint 5), and
#: the encoder zero of joints 2 and 3 (FIGAROH's identification script subtracts pi/2
#: from joint 2 and adds it to joint 3).
TX40_GEAR_RATIOS = (32.0, 32.0, 45.0, -48.0, 45.0, 32.0)
TX40_COUPLING = {(6, 5): 32.0}
TX40_OFFSET = (0.0, np.pi / 2, -np.pi / 2, 0.0, 0.0, 0.0)
#: The same, as ``sedsabso-jax identify`` flags.
TX40_FLAGS = ["--robot", "staubli_tx40", "--motor-side",
              "--gear-ratios", ",".join(f"{v:g}" for v in TX40_GEAR_RATIOS),
              "--coupling", "6:5=32",
              "--position-offsets", ",".join(repr(v) for v in TX40_OFFSET)]
#: The TX40 is recorded at 5 kHz (the files have no time column).
TX40_RATE_HZ = 5000.0


def tx40_joint_side(tmp) -> tuple:
    """The TX40 run on the joint side at 1 kHz (every 5th sample) and its transmission:
    ``(measurements, Transmission)``; the motor-side file is written under ``tmp``."""
    import sedsabso_jax as sj

    tr = sj.Transmission.from_gear_ratios(TX40_GEAR_RATIOS, coupling=TX40_COUPLING,
                                          offset=TX40_OFFSET)
    motor = sj.load_measurements(tx40_npz(Path(tmp) / "tx40.npz"), n_joints=6, downsample=5)
    return tr.to_joint_side(motor), tr


def panda_npz(path) -> Path:
    """The Panda run as a measurement file: times, positions, velocities (recorded) and
    torques (link-side sensors). The time stamps are kept as recorded (steps of 0.7 to
    8.8 ms): load it with ``resample_hz=1000``."""
    times = np.loadtxt(PANDA / "exciting_traj_time.txt")
    fields = {name: np.loadtxt(PANDA / f"exciting_traj_{name}.txt").reshape(-1, 7)
              for name in ("positions", "velocity", "torques")}
    np.savez(path, times=times, positions=fields["positions"],
             velocities=fields["velocity"], torques=fields["torques"])
    return Path(path)


def tx40_npz(path) -> Path:
    """The TX40 run as a MOTOR-side measurement file: times (5 kHz), motor angles and
    motor torques."""
    theta = np.loadtxt(TX40 / "pos_read_data.csv", delimiter=",", skiprows=1)
    tau_m = np.loadtxt(TX40 / "curr_data.csv", delimiter=",", skiprows=1)
    times = np.arange(theta.shape[0]) / TX40_RATE_HZ
    np.savez(path, times=times, positions=theta, torques=tau_m)
    return Path(path)


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    out.mkdir(parents=True, exist_ok=True)
    print(panda_npz(out / "franka_panda.npz"), tx40_npz(out / "staubli_tx40.npz"))
