"""Which machine a benchmark ran on, for its JSON: JAX's device (platform, kind, count),
the CPU model from ``/proc/cpuinfo`` and its core count, and the versions."""

from __future__ import annotations

import os
import platform

import jax


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``; ``platform.processor()`` elsewhere)."""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def device_info() -> dict:
    device = jax.devices()[0]
    return {"platform": device.platform, "device_kind": device.device_kind,
            "device_count": jax.device_count(), "cpu_model": cpu_model(),
            "cpu_count": os.cpu_count(), "jax": jax.__version__,
            "python": platform.python_version()}


def describe(info: dict) -> str:
    """One line: ``cpu (AMD EPYC, 2 cores)`` or ``gpu NVIDIA H100 (host: ...)``."""
    host = f"{info['cpu_model']}, {info['cpu_count']} cores"
    if info["platform"] == "cpu":
        return f"cpu ({host})"
    return f"{info['platform']} {info['device_kind']} x{info['device_count']} (host: {host})"
