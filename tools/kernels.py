"""Micro-benchmarks behind the swarms' kernel choices on the CPU (each a ``lax.scan`` of
the kernel alone; all compiled first, then run in turn ``--repeats`` times, so that the
shared machine's slow spells hit all alike; fastest run, microseconds per iteration;
RS010N's Eq. 17 sizes: 21 base parameters, 3000 residual rows):

- the product ``X W^T`` with ``W`` an argument stored ``(m, d)`` or transposed ``(d, m)``,
  or a constant of the compiled code (3 rows: SEDSABSO's annealing candidates; 50 rows:
  a population);
- Eq. 17 for 50 members: the product then ``|r|`` summed by a product with ones, or by a
  reduction that XLA fuses with the product (:meth:`~sedsabso_jax.L1Residual.evaluate`);
- BSO's evaluation (``f(x)`` and ``f(x + a v) - f(x - a v)`` from ``|r + a g| - |r - a
  g|``, :meth:`~sedsabso_jax.L1Residual.evaluate_with_antennae`): ``|r|`` and the
  antenna terms from one pass over ``r = W x - tau``, or ``f`` fused on its own;
- one iteration's draws ``r1, r2`` (2 x 50 x 21) from JAX's ``jax.random.uniform`` (a
  5-trip loop on the CPU) and from the package's written-out threefry
  (:func:`~sedsabso_jax.optim._swarm.uniforms`), both bit for bit the same numbers.

    python -m tools.kernels [--repeats 15] [--json out.json]

A developer tool, not a benchmark of the public API: it times the implementation's own
private kernels (``sedsabso_jax.optim._fitness``, ``_swarm``), so it follows them when
they change. Results: ``benchmarks/results/kernels_*.json``.

The machine is shared and its state changes the picture: products parallelise over both
cores when the machine is quiet; compare rows of one run only.
"""

from __future__ import annotations

import argparse
import json
import time

import jax
import jax.numpy as jnp
import numpy as np

from benchmarks.device import describe, device_info
from sedsabso_jax.optim._fitness import _antenna_terms, _matmul
from sedsabso_jax.optim._random import uniforms

M, D, LENGTH = 3000, 21, 300


def timed(fn, args, repeats):
    """A callable timing one run of ``fn`` (a whole scan), compiled and warmed up here."""
    exe = jax.jit(fn).lower(*args).compile()
    jax.block_until_ready(exe(*args))

    def once():
        t0 = time.perf_counter()
        jax.block_until_ready(exe(*args))
        return time.perf_counter() - t0
    return once


def loop(kernel):
    """A scan of ``kernel(X, V, *data) -> (f, g)`` whose output feeds the next X, V."""
    def run(X, V, *data):
        def body(c, _):
            X, V = c
            f, g = kernel(X, V, *data)
            return (X * 0.999 + 1e-12 * f[:, None], V * 0.999 + 1e-12 * g[:, None]), None
        return jax.lax.scan(body, (X, V), None, length=LENGTH)[0]
    return run


def ones_sum(A):
    return _matmul(A, jnp.ones(A.shape[-1], A.dtype))


def bso_one_pass(X, V, W, tau, a=0.0125):
    R = _matmul(X, W.T) - tau
    return ones_sum(jnp.abs(R)), ones_sum(_antenna_terms(R, _matmul(V, W.T), a))


def bso_f_fused(X, V, W, tau, a=0.0125):
    f = jnp.sum(jnp.abs(_matmul(X, W.T) - tau), -1)
    return f, ones_sum(_antenna_terms(_matmul(X, W.T) - tau, _matmul(V, W.T), a))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    jax.config.update("jax_enable_x64", True)
    rng = np.random.default_rng(0)
    info = device_info()
    cases = []

    def row(what, dtype, once):
        cases.append((what, jnp.dtype(dtype).name, once))

    print(f"device: {describe(info)}, jax {info['jax']}; {LENGTH} iterations per loop, "
          f"fastest of {args.repeats}")
    W0, tau0 = rng.standard_normal((M, D)), rng.standard_normal(M)
    for dtype in (jnp.float64, jnp.float32):
        W, WT = jnp.asarray(W0, dtype), jnp.asarray(np.ascontiguousarray(W0.T), dtype)
        Wc, tau = np.asarray(W0, jnp.dtype(dtype)), jnp.asarray(tau0, dtype)
        for n in (3, 50):
            X, V = (jnp.asarray(rng.standard_normal((n, D)), dtype) for _ in range(2))
            row(f"X W^T, {n} rows, W an argument (m, d)", dtype,
                timed(loop(lambda X, V, W: (_matmul(X, W.T)[:, :2].T)), (X, V, W),
                      args.repeats))
            row(f"X W^T, {n} rows, W an argument (d, m)", dtype,
                timed(loop(lambda X, V, WT: _matmul(X, WT)[:, :2].T), (X, V, WT),
                      args.repeats))
            row(f"X W^T, {n} rows, W a constant", dtype,
                timed(loop(lambda X, V: _matmul(X, Wc.T)[:, :2].T), (X, V), args.repeats))
        X, V = (jnp.asarray(rng.standard_normal((50, D)), dtype) for _ in range(2))
        row("Eq. 17, 50 rows: product, |r| summed by ones", dtype,
            timed(loop(lambda X, V, W, tau: (ones_sum(jnp.abs(_matmul(X, W.T) - tau)),) * 2),
                  (X, V, W, tau), args.repeats))
        row("Eq. 17, 50 rows: product and sum fused", dtype,
            timed(loop(lambda X, V, W, tau: (jnp.sum(jnp.abs(_matmul(X, W.T) - tau), -1),) * 2),
                  (X, V, W, tau), args.repeats))
        row("Eq. 17, 50 rows: fused, W a constant", dtype,
            timed(loop(lambda X, V, tau: (jnp.sum(jnp.abs(_matmul(X, Wc.T) - tau), -1),) * 2),
                  (X, V, tau), args.repeats))
        row("BSO evaluation, 50 rows: |r| and antennae, one pass", dtype,
            timed(loop(bso_one_pass), (X, V, W, tau), args.repeats))
        row("BSO evaluation, 50 rows: f fused, antennae a pass", dtype,
            timed(loop(bso_f_fused), (X, V, W, tau), args.repeats))
        keys = jax.random.split(jax.random.key(0), 2 * LENGTH).reshape(LENGTH, 2)
        draw_jax = jax.vmap(lambda k: jax.vmap(lambda k1: jax.random.uniform(
            k1, (50, D), dtype))(k))
        draw_ours = jax.vmap(lambda k: uniforms(k, (50, D), dtype))
        assert np.array_equal(np.asarray(draw_jax(keys)), np.asarray(draw_ours(keys)))
        row("r1, r2 (2 x 50 x 21): jax.random.uniform", dtype,
            timed(draw_jax, (keys,), args.repeats))
        row("r1, r2 (2 x 50 x 21): threefry written out", dtype,
            timed(draw_ours, (keys,), args.repeats))
    times = [[] for _ in cases]
    for _ in range(args.repeats):
        for t, (_, _, once) in zip(times, cases):
            t.append(once())
    rows = []
    for t, (what, dtype, _) in zip(times, cases):
        us = min(t) / LENGTH * 1e6
        rows.append({"kernel": what, "dtype": dtype, "us_per_iteration": us,
                     "us_median": float(np.median(t)) / LENGTH * 1e6})
        print(f"{what:52s} {dtype:7s} {us:8.1f} us (median {rows[-1]['us_median']:.1f})")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"device": info, "iterations_per_loop": LENGTH, "rows": rows}, fh,
                      indent=2)


if __name__ == "__main__":
    main()
