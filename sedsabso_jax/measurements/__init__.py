"""Joint measurements: the container, file formats, signal processing, loading and
simulation. Builds on :mod:`sedsabso_jax.dynamics` only (simulated torques).

- :mod:`.container`: :class:`Measurements` (checked, read-only arrays);
- :mod:`.formats`: ``.npz`` and ``.csv`` reading and writing;
- :mod:`.signal`: zero-phase low-pass, velocities and accelerations from positions;
- :mod:`.load`: :func:`load_measurements`, :func:`load_kuka_lwr4`;
- :mod:`.simulate`: :func:`simulate_measurements`, :func:`simulate_measurements_along`.
"""

from .container import Measurements as Measurements
from .load import load_kuka_lwr4 as load_kuka_lwr4
from .load import load_measurements as load_measurements
from .signal import DEFAULT_CUTOFF_HZ as DEFAULT_CUTOFF_HZ
from .signal import differentiate as differentiate
from .signal import lowpass as lowpass
from .signal import median_rate as median_rate
from .simulate import simulate_measurements as simulate_measurements
from .simulate import simulate_measurements_along as simulate_measurements_along
