"""Joint measurements beyond the package root's names (``Measurements``,
``load_measurements``, ``load_kuka_lwr4``, ``simulate_measurements``,
``simulate_measurements_along``, ``Transmission``): the signal processing the loaders
use (:class:`SignalChain` on :class:`Recorded` signals), their record in words, and the
transmission's coupled motors. Builds on
:mod:`sedsabso_jax.dynamics` only."""

from __future__ import annotations

from ._chain import Recorded as Recorded
from ._chain import SignalChain as SignalChain
from ._load import recorded_signals as recorded_signals
from ._signal import DEFAULT_CUTOFF_HZ as DEFAULT_CUTOFF_HZ
from ._signal import describe_signals as describe_signals
from ._signal import differentiate as differentiate
from ._signal import lowpass as lowpass
from ._signal import median_rate as median_rate
from ._signal import position_noise as position_noise
from ._signal import velocity_noise as velocity_noise
from ._transmission import coupled_motors as coupled_motors

__all__ = [
    "DEFAULT_CUTOFF_HZ", "lowpass", "differentiate", "median_rate", "coupled_motors",
    "describe_signals", "SignalChain", "Recorded", "recorded_signals", "position_noise",
    "velocity_noise",
]
