"""How long each step of the experiment takes, estimated from its settings before it
runs, so that ``sedsabso-jax reproduce``'s progress and time left are right although its
steps differ a hundredfold (a swarm's compilation and runs against ordinary least
squares). Each step is ``(fixed, per unit)`` seconds, measured on 2 loaded cores with the
defaults (10 runs of 600 iterations, 1000 samples, 100 design iterations) and with 3 runs
of 200, 500 samples and 30 design iterations, each with the command's compilation cache
empty and filled (which halves the whole: the estimates lie between); the fixed part is
mostly compilation. Only their shares matter: the command's time left is the pace it
measures applied to them."""

from __future__ import annotations

from typing import Any

#: Per step: seconds, and seconds per unit of its work: the design's iterations x
#: samples / 1000, the samples, a swarm's runs x iterations x samples / 1000.
STEPS = {"base parameters": (1.2, 0.0), "excitation design": (10.4, 0.176),
         "simulated measurements": (6.0, 0.005), "SEDSABSO": (23.0, 0.0028),
         "BSO": (4.1, 0.00165), "LDWPSO": (4.0, 0.0011), "OLS": (0.8, 0.0),
         "LM": (0.0, 0.005), "L1-LP": (0.0, 0.00025)}
#: Writing the tables and figures: seconds, and per run x iteration / 1000 (the
#: figures' histories).
WRITE = (3.0, 0.25)


def step_seconds(settings: Any, swarms: tuple[str, ...], baselines: tuple[str, ...]
                 ) -> list[float]:
    """The estimated seconds of each step of :func:`~._experiment.run` with ``settings``
    (its :class:`~._experiment.Settings`) in its order: the base parameters, the
    excitation design, the simulated measurements, each of ``swarms``, each of
    ``baselines`` (a name with no estimate counts as a second)."""
    from ..excitation._design import DesignSearch

    design = settings.design_iterations or DesignSearch().iterations
    samples = settings.samples / 1000
    runs = settings.runs * settings.iterations * samples
    units = {"excitation design": design * samples, "simulated measurements": samples * 1000,
             "LM": samples * 1000, "L1-LP": samples * 1000,
             **{name: runs for name in swarms}}
    names = ("base parameters", "excitation design", "simulated measurements", *swarms,
             *baselines)
    return [STEPS.get(name, (1.0, 0.0))[0] + STEPS.get(name, (1.0, 0.0))[1]
            * units.get(name, 0.0) for name in names]


def write_seconds(settings: Any) -> float:
    """The estimated seconds of writing the tables and figures with ``settings`` (the
    experiment's :class:`~._experiment.Settings`)."""
    return WRITE[0] + WRITE[1] * settings.runs * settings.iterations / 1000
