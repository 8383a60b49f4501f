"""``sj.minimise`` across hosts: with multi-process JAX (``jax.distributed.initialize``)
the sharding of ``runs`` spans the global device mesh, every process gets every run's
result, and the best values are one process's. Two CPU processes on this machine, each
with two host devices, talking through JAX's CPU collectives (gloo)."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import textwrap

import jax
import jax.numpy as jnp
import numpy as np

import sedsabso_jax as sj

WORKER = textwrap.dedent("""
    import json, sys
    import jax
    jax.config.update("jax_enable_x64", True)
    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    jax.distributed.initialize(coordinator_address=sys.argv[2], num_processes=2,
                               process_id=int(sys.argv[1]))
    import jax.numpy as jnp
    import numpy as np
    import sedsabso_jax as sj

    f = lambda x, a: jnp.sum((x - 0.3) ** 2)
    out = {"process": jax.process_index(), "devices": jax.device_count(),
           "local": jax.local_device_count()}
    for runs in (6, 8):  # padded to 8 runs over the 4 devices, or not
        r = sj.minimise(f, sj.BSO(population_size=8), -np.ones(3), np.ones(3),
                        key=jax.random.key(0), iterations=30, runs=runs)
        out[runs] = {"f": np.asarray(r.f).tolist(), "x": np.asarray(r.x).tolist()}
    print(json.dumps(out))
    jax.distributed.shutdown()
""")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def test_runs_span_the_devices_of_two_processes():
    address = f"localhost:{_free_port()}"
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=2",
               JAX_PLATFORMS="cpu")
    procs = [subprocess.Popen([sys.executable, "-c", WORKER, str(i), address], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for i in range(2)]
    outs = []
    for p in procs:
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err[-3000:]
        outs.append(json.loads(out.strip().splitlines()[-1]))
    assert [o["process"] for o in outs] == [0, 1]
    assert all(o["devices"] == 4 and o["local"] == 2 for o in outs)  # a global mesh of 4
    for runs in ("6", "8"):
        assert outs[0][runs]["f"] == outs[1][runs]["f"]  # every process has every run
        one = sj.minimise(lambda x, a: jnp.sum((x - 0.3) ** 2), sj.BSO(population_size=8),
                          -np.ones(3), np.ones(3), key=jax.random.key(0), iterations=30,
                          runs=int(runs))
        np.testing.assert_allclose(outs[0][runs]["f"], np.asarray(one.f), rtol=1e-9)
        np.testing.assert_allclose(outs[0][runs]["x"], np.asarray(one.x), rtol=1e-9,
                                   atol=1e-12)
