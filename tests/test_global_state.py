"""Importing the package changes nothing in the user's JAX (every configuration value, and
so evosax's default dtypes); with JAX's 64-bit mode off, the optimisers run in float32 and
float64 work stops with one line saying how to turn the mode on. Each check runs in a
fresh interpreter: this test process turned the mode on (conftest.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

IMPORT_EVERYTHING = """
import sedsabso_jax, sedsabso_jax.cli, sedsabso_jax.compare._run, sedsabso_jax.compare._report
import sedsabso_jax.reproduce._experiment, sedsabso_jax.reproduce._report
"""


def _run(code: str, cache: bool = False) -> subprocess.CompletedProcess:
    """``code`` in a fresh Python with a bare environment; ``cache``: keeping compiled
    programs where the tests do (conftest), for a check that is not about JAX's settings."""
    env = {"JAX_PLATFORMS": "cpu", "PATH": "/usr/bin:/bin"}
    if cache:
        env |= {k: v for k, v in os.environ.items() if k in (
            "JAX_COMPILATION_CACHE_DIR", "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS")}
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=300, env=env)


def test_import_changes_no_jax_configuration_nor_evosax_dtypes():
    pytest.importorskip("evosax")
    run = _run(textwrap.dedent("""
        import json, jax, jax.numpy as jnp
        from evosax.algorithms import algorithms

        def state():
            params = {name: jax.tree.map(lambda a: str(jnp.asarray(a).dtype),
                                         algorithms[name](population_size=4,
                                                          solution=jnp.zeros(3)).default_params)
                      for name in ("PSO", "CMA_ES")}
            return {"config": {k: repr(v) for k, v in jax.config.values.items()},
                    "evosax": {k: [str(v) for v in jax.tree.leaves(p)]
                               for k, p in params.items()},
                    "default_float": str(jnp.zeros(1).dtype)}

        before = state()
    """) + IMPORT_EVERYTHING + textwrap.dedent("""
        after = state()
        changed = sorted(k for k in before["config"]
                         if before["config"][k] != after["config"].get(k))
        print(json.dumps({"changed": changed, "same": before == after,
                          "evosax": after["evosax"]["PSO"], "float": after["default_float"]}))
    """))
    assert run.returncode == 0, run.stderr[-2000:]
    out = json.loads(run.stdout.strip().splitlines()[-1])
    assert out["changed"] == [] and out["same"], out
    assert out["float"] == "float32" and set(out["evosax"]) == {"float32"}


def test_float64_work_without_x64_is_one_clear_line():
    run = _run("""
        import jax, jax.numpy as jnp, numpy as np
        import sedsabso_jax as sj
        for make in (lambda: sj.robots.rs010n(),
                     lambda: sj.minimise(lambda x, a: jnp.sum(x ** 2), sj.LDWPSO(), -np.ones(2),
                                         np.ones(2), key=jax.random.key(0), iterations=3,
                                         dtype=jnp.float64)):
            try:
                make()
            except Exception as err:
                print(type(err).__name__, "|", str(err).replace("\\n", " NEWLINE "))
            else:
                print("no error")
    """)
    assert run.returncode == 0, run.stderr[-2000:]
    lines = run.stdout.strip().splitlines()
    assert len(lines) == 2, run.stdout
    for line in lines:
        kind, message = line.split(" | ")
        assert kind == "Float64Required" and "NEWLINE" not in message
        assert "jax.config.update('jax_enable_x64', True)" in message
    assert lines[0].split(" | ")[1].startswith("a robot model")


def test_optimisers_run_in_float32_when_x64_is_off():
    run = _run("""
        import jax, jax.numpy as jnp, numpy as np
        import sedsabso_jax as sj
        W, tau = np.random.default_rng(0).standard_normal((2, 40, 3))[0], np.zeros(40)
        for fitness in (lambda x, a: jnp.sum(x ** 2), sj.L1Residual(W, tau)):
            for solver in (sj.SEDSABSO(n_phases=2), sj.BSO(), sj.LDWPSO()):
                r = sj.minimise(fitness, solver, -np.ones(3), np.ones(3),
                                key=jax.random.key(0), iterations=30)
                assert r.x.dtype == jnp.float32 and r.f.dtype == jnp.float32, r
                assert float(r.f) < float(r.history_f[0]) or float(r.f) == 0.0
        print("float32 ok", jax.config.jax_enable_x64)
    """, cache=True)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "float32 ok False" in run.stdout
