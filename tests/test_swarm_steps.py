"""One step of each swarm against a NumPy reference written out here from the equations
(the paper's Eq. 10-16, ``docs/explanation/paper-notes.md``), with fixed draws: a wrong update rule,
sign, clamp, schedule or bookkeeping changes the numbers, not only the outcome.

The reference never calls the package's swarm code: it takes the state before the step and
the random draws, and computes the state after it."""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.optim import BeetleStep
from sedsabso_jax.optim._population import initial_positions, set_active, shrink
from sedsabso_jax.optim._sedsabso import SEDSABSOState

D, SLOTS, M = 3, 5, 8
TEMPERATURE = 0.5  # of the same order as the candidates' fitness differences


#: The beetles' antennae sit at x +- A V: A = d / 2, d = delta / c (Eq. 13) with the paper's
#: delta = 0.05, c = 2.
A = 0.05 / 2 / 2


def problem(seed=0, upper=2.0):
    """A tiny Eq. 17 problem f(x) = sum |W x - tau|, its box, and a start state with one
    slot inactive, positions near the box's walls and velocities that exceed a small Vmax."""
    rng = np.random.default_rng(seed)
    W, tau = rng.standard_normal((M, D)), rng.standard_normal(M)
    fitness = sj.L1Residual(W, tau)
    lo, hi = -np.ones(D), upper * np.ones(D)
    x, v = initial_positions(jnp.asarray(lo), jnp.asarray(hi), jax.random.key(seed), SLOTS,
                             jnp.asarray(0.8 * (hi - lo)))
    x = np.asarray(x).copy()
    x[0] = hi - 1e-3  # steps out of the box: clipped
    s = _with(None, fitness, x=x, v=v, active=np.array([True, True, False, True, True]))
    return fitness, W, tau, lo, hi, s


def _with(s, fitness, antenna=A, **changes):
    """The state (``s`` with numpy replacements, or ``changes`` alone) with every swarm's
    fields (SEDSABSO's, which hold BSO's and LDWPSO's); fitness, antenna differences
    f(x + a v) - f(x - a v) (a = ``antenna``), personal bests and the guide follow."""
    x = np.asarray(changes["x"] if "x" in changes else s.x)
    v = np.asarray(changes["v"] if "v" in changes else s.v)
    value = lambda X: np.asarray(fitness.value(fitness.embed(jnp.asarray(X))))  # noqa: E731
    f = value(x)
    active = np.asarray(changes["active"] if "active" in changes else s.active)
    g = int(np.argmin(np.where(active, f, np.inf)))
    trials = jnp.zeros((4, x.shape[1]))  # SEDSABSO's draws and candidates, q = 4 here
    return SEDSABSOState(
        x=jnp.asarray(x), v=jnp.asarray(v),
        antennae=jnp.asarray(value(x + antenna * v) - value(x - antenna * v)),
        antennae_bad=jnp.zeros(len(x), jnp.int32), pbest_x=jnp.asarray(x),
        pbest_f=jnp.asarray(f), active=jnp.asarray(active),
        slot_nonfinite=jnp.zeros(len(x), jnp.int32), guide_x=jnp.asarray(x[g]),
        guide_f=jnp.asarray(f[g]), best_x=jnp.asarray(x[g]), best_f=jnp.asarray(f[g]),
        temperature=jnp.asarray(changes.get("temperature", getattr(s, "temperature", 3.0)),
                                jnp.float64),
        sa_accepted=jnp.int32(0), n_evaluations=jnp.int32(SLOTS), n_nonfinite=jnp.int32(0),
        key=jax.random.key(0), t=jnp.int32(0), iterations=10, round=0, asked=False,
        trial_r=trials, trial_u=trials[:, 0], candidates=trials)


def step(solver, fitness, s, t, lo, hi, randomness, iterations=10):
    """Iteration ``t`` of ``iterations`` from an iteration's randomness (what
    ``solver.randomness`` gives: keys, or for SEDSABSO ``(keys, r, u)``), drawn for the
    state's population: its rounds, without the slots' reordering of a phase's start."""
    draws = solver.draw(randomness, s.x.shape, s.x.dtype)
    s = dataclasses.replace(s, t=jnp.int32(t), iterations=iterations)
    return solver.update(fitness, s, draws, jnp.asarray(lo), jnp.asarray(hi))


def as_numpy(s) -> dict:
    return {f.name: np.asarray(getattr(s, f.name)) for f in dataclasses.fields(s)
            if f.name != "key"}


# ------------------------------------------------------------------------ references
def f_ref(X, W, tau):
    return np.abs(X @ W.T - tau).sum(-1)


def velocity_ref(s, r1, r2, w, c1, c2, vmax):
    """Eq. 11 (and the PSO update): inertia, cognitive and social terms, clamped."""
    v = w * s["v"] + c1 * r1 * (s["pbest_x"] - s["x"]) + c2 * r2 * (s["guide_x"] - s["x"])
    return np.clip(v, -vmax, vmax)


def bests_ref(s, x, f):
    """Personal bests of the active slots; the swarm's best among them; the best ever."""
    s = dict(s)
    better = s["active"] & (f < s["pbest_f"])
    s["pbest_f"] = np.where(better, f, s["pbest_f"])
    s["pbest_x"] = np.where(better[:, None], x, s["pbest_x"])
    masked = np.where(s["active"], s["pbest_f"], np.inf)
    i = int(np.argmin(masked))
    if masked[i] < s["best_f"]:
        s["best_x"], s["best_f"] = s["pbest_x"][i], masked[i]
    s["x"] = x
    return s, (s["pbest_x"][i], masked[i])


def bso_ref(s, W, tau, lo, hi, r1, r2, p):
    """Eq. 10-13: antennae at x +- V d/2 (d = delta / c), a step of delta V toward the
    better antenna (away from it with the authors' literal sign), then the velocity and
    position updates, clipped."""
    d = p.delta / p.c
    side = np.sign(f_ref(s["x"] + s["v"] * d / 2, W, tau) - f_ref(s["x"] - s["v"] * d / 2, W, tau))
    xi = p.delta * s["v"] * (side if p.literal_sign else -side)[:, None]
    v = velocity_ref(s, r1, r2, p.w, p.c1, p.c2, p.vmax_fraction * (hi - lo))
    x = np.clip(s["x"] + p.lam * v + (1 - p.lam) * xi, lo, hi)
    s = dict(s, v=v, n_evaluations=s["n_evaluations"] + 3 * s["active"].sum())
    return bests_ref(s, x, f_ref(x, W, tau))


def sedsabso_ref(s, W, tau, lo, hi, r1, r2, r, u, p):
    """One SEDSABSO iteration: the beetle step; the guide becomes the swarm's best if that
    is better; q candidates P_g (1 + s r_k) (Eq. 14), clipped to the box, each accepted in
    turn as the guide when exp(-(f_k - f_guide) / T) > u_k; the best ever kept apart; then
    T <- decay T."""
    s, (gx, gf) = bso_ref(s, W, tau, lo, hi, r1, r2, p.beetle)
    if gf < s["guide_f"]:
        s["guide_x"], s["guide_f"] = gx, gf
    cand = np.clip(gx * (1 + p.perturbation_scale * r), lo, hi)
    fc = f_ref(cand, W, tau)
    accepted = []
    for k in range(len(u)):
        if math.exp(-(fc[k] - s["guide_f"]) / s["temperature"]) > u[k]:
            s["guide_x"], s["guide_f"] = cand[k], fc[k]
            accepted.append(k)
    k = int(np.argmin(fc))
    if fc[k] < s["best_f"]:
        s["best_x"], s["best_f"] = cand[k], fc[k]
    s["sa_accepted"] = s["sa_accepted"] + len(accepted)
    s["n_evaluations"] = s["n_evaluations"] + len(u)
    s["temperature"] = s["temperature"] * p.decay
    return s, accepted, fc


def assert_state(actual, expected, keys=("x", "v", "pbest_x", "pbest_f", "guide_x",
                                         "guide_f", "best_x", "best_f", "n_evaluations")):
    a = as_numpy(actual)
    for k in keys:
        np.testing.assert_allclose(a[k], expected[k], rtol=1e-12, atol=1e-12, err_msg=k)


# ------------------------------------------------------------------------------ BSO
@pytest.mark.parametrize("literal_sign", [False, True])
def test_bso_step(literal_sign):
    fitness, W, tau, lo, hi, s = problem()
    solver = sj.BSO(population_size=SLOTS,
                    beetle=BeetleStep(vmax_fraction=0.1, literal_sign=literal_sign))
    keys = jax.random.split(jax.random.key(7))
    r1 = np.asarray(jax.random.uniform(keys[0], (SLOTS, D), jnp.float64))
    r2 = np.asarray(jax.random.uniform(keys[1], (SLOTS, D), jnp.float64))
    expected, (gx, gf) = bso_ref(as_numpy(s), W, tau, lo, hi, r1, r2, solver.beetle)
    expected["guide_x"], expected["guide_f"] = gx, gf  # BSO's guide: the swarm's best
    after = step(solver, fitness, s, 0, lo, hi, keys)
    assert_state(after, expected)
    # the clamp and the box both acted, and the inactive slot's personal best is frozen
    vmax = solver.beetle.vmax_fraction * (hi - lo)
    assert np.any(np.isclose(np.abs(expected["v"]), vmax))
    assert np.any(np.isclose(expected["x"], hi)) or np.any(np.isclose(expected["x"], lo))
    np.testing.assert_array_equal(np.asarray(after.pbest_f)[2], np.asarray(s.pbest_f)[2])
    # the new positions' antennae, carried to the next iteration: Eq. 12-13 at x', v'
    x, v = np.asarray(after.x), np.asarray(after.v)
    np.testing.assert_allclose(np.asarray(after.antennae),
                               f_ref(x + A * v, W, tau) - f_ref(x - A * v, W, tau),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(np.asarray(after.antennae_bad), 0)


def test_bso_moves_toward_the_better_antenna():
    """f(x) = |x| in one dimension, V = 1 at x = 1, no velocity term: the antenna step goes
    to smaller |x| (to larger |x| with the authors' literal sign)."""
    fitness = sj.L1Residual(np.ones((1, 1)), np.zeros(1))
    lo, hi = jnp.full(1, -10.0), jnp.full(1, 10.0)
    s = _with(None, fitness, x=np.ones((1, 1)), v=np.ones((1, 1)), active=np.array([True]))
    zeros = jnp.zeros((1, 1))
    for literal, sign in ((False, -1.0), (True, 1.0)):
        beetle = BeetleStep(w=0.0, lam=0.0, literal_sign=literal)
        x, _ = beetle.move(s, zeros, zeros, lo, hi)
        assert float(x[0, 0]) == pytest.approx(1.0 + sign * beetle.delta)


def test_antennae_sit_at_half_the_distance_delta_over_c():
    """Eq. 13: the antennae are x +- V d / 2 with d = delta / c. For f(x) = cos(100 x) the
    sign of f(xl) - f(xr) = -2 sin(100 x) sin(100 d / 2) depends on d: at x = 0.01, V = 1,
    d / 2 = 0.0125 says the right antenna is better (d = delta c would say the left)."""
    fitness = sj.BlackBox(lambda x, args: jnp.cos(100.0 * x[0]))
    lo, hi = jnp.full(1, -1.0), jnp.full(1, 1.0)
    # the antenna step alone; V stays 1
    solver = sj.BSO(population_size=1, beetle=BeetleStep(w=1.0, lam=0.0))
    s = solver.init(fitness, lo, hi, jax.random.key(0), 10)
    # the antennae as the solver places them (solver.beetle.antenna), at x = 0.01, V = 1
    s = _with(s, fitness, antenna=solver.beetle.antenna, x=np.full((1, 1), 0.01), v=np.ones((1, 1)),
              active=np.array([True]))
    zeros = jnp.zeros((1, 1))
    after = solver.update(fitness, s, (zeros, zeros), lo, hi)
    d = solver.beetle.delta / solver.beetle.c
    side = np.sign(np.cos(100 * (0.01 + d / 2)) - np.cos(100 * (0.01 - d / 2)))
    assert side == -1.0  # the antenna at x + V d/2 is the better one
    assert float(after.x[0, 0]) == pytest.approx(0.01 + solver.beetle.delta)
    # and the new position's antennae, computed in the step, sit at d / 2 too
    x, v = float(after.x[0, 0]), float(after.v[0, 0])
    assert v == 1.0
    assert float(after.antennae[0]) == pytest.approx(
        np.cos(100 * (x + d / 2 * v)) - np.cos(100 * (x - d / 2 * v)), abs=1e-12)


# --------------------------------------------------------------------------- LDWPSO
@pytest.mark.parametrize("t, w", [(0, 0.9), (9, 0.4), (3, 0.9 - 0.5 * 3 / 9)])
def test_ldwpso_step_and_inertia_schedule(t, w):
    fitness, W, tau, lo, hi, s = problem(1)
    solver = sj.LDWPSO(population_size=SLOTS, vmax_fraction=0.3)
    keys = jax.random.split(jax.random.key(t))
    r1 = np.asarray(jax.random.uniform(keys[0], (SLOTS, D), jnp.float64))
    r2 = np.asarray(jax.random.uniform(keys[1], (SLOTS, D), jnp.float64))
    ref = as_numpy(s)
    v = velocity_ref(ref, r1, r2, w, 2.0, 2.0, 0.3 * (hi - lo))
    ref["n_evaluations"] = ref["n_evaluations"] + ref["active"].sum()
    x = np.clip(ref["x"] + v, lo, hi)
    expected, (gx, gf) = bests_ref(dict(ref, v=v), x, f_ref(x, W, tau))
    expected["guide_x"], expected["guide_f"] = gx, gf
    after = step(solver, fitness, s, t, lo, hi, keys)
    assert_state(after, expected)


# ------------------------------------------------------------------------- SEDSABSO
def sedsabso_case():
    fitness, W, tau, lo, hi, s = problem(2, upper=5.0)
    s = _with(s, fitness, temperature=TEMPERATURE)
    solver = sj.SEDSABSO(population_size=SLOTS, beetle=BeetleStep(vmax_fraction=0.2),
                         temperature=TEMPERATURE, n_trials=4)
    return fitness, W, tau, lo, hi, s, solver


def draws(seed):
    key = jax.random.key(seed)
    k12 = jax.random.split(key)
    r1, r2 = (np.asarray(jax.random.uniform(k, (SLOTS, D), jnp.float64)) for k in k12)
    rng = np.random.default_rng(seed)
    r, u = rng.uniform(size=(4, D)), rng.uniform(size=4)
    return k12, r1, r2, r, u


def test_sedsabso_step_two_iterations():
    """Two iterations against the reference: Eq. 14's candidates, the Metropolis choice of
    the guide, the guide steering the NEXT iteration's velocities, the best ever kept
    apart from the guide, counts and cooling."""
    fitness, W, tau, lo, hi, s, solver = sedsabso_case()
    ref = as_numpy(s)
    patterns = []
    for it, seed in enumerate((11, 12)):
        k12, r1, r2, r, u = draws(seed)
        ref, accepted, fc = sedsabso_ref(ref, W, tau, lo, hi, r1, r2, r, u, solver)
        s = step(solver, fitness, s, it, lo, hi, (k12, jnp.asarray(r), jnp.asarray(u)))
        assert_state(s, ref, keys=("x", "v", "pbest_f", "guide_x", "guide_f", "best_x",
                                   "best_f", "n_evaluations", "sa_accepted", "temperature"))
        patterns.append((accepted, fc, ref["guide_f"], ref["best_f"]))
    # the case is not degenerate: candidates were accepted and refused, and a worse
    # candidate became the guide while the best ever stayed below it
    accepted_any = [k for acc, *_ in patterns for k in acc]
    assert accepted_any and len(accepted_any) < 8
    assert any(guide_f > best_f for _, _, guide_f, best_f in patterns)
    assert float(s.temperature) == pytest.approx(TEMPERATURE * 0.93 ** 2)


def test_metropolis_compares_with_the_current_guide():
    """The trials run in turn against the CURRENT guide: after a much worse candidate is
    accepted (u_0 tiny), a later candidate that improves on it is accepted whatever u_k,
    even though it is worse than the swarm's best."""
    fitness, W, tau, lo, hi, s, solver = sedsabso_case()
    k12, r1, r2, r, _ = draws(11)
    u = np.array([1e-12, 0.999999, 0.999999, 0.999999])
    ref, accepted, fc = sedsabso_ref(as_numpy(s), W, tau, lo, hi, r1, r2, r, u, solver)
    _, (_, gf) = bso_ref(as_numpy(s), W, tau, lo, hi, r1, r2, solver.beetle)
    later = [k for k in accepted if k > 0]
    assert accepted[0] == 0 and later and all(gf < fc[k] < fc[0] for k in later)
    out = step(solver, fitness, s, 0, lo, hi, (k12, jnp.asarray(r), jnp.asarray(u)))
    assert int(out.sa_accepted) == len(accepted)
    np.testing.assert_allclose(np.asarray(out.guide_x), ref["guide_x"], rtol=1e-12)


def test_sedsabso_candidates_are_eq_14():
    """cand_k = clip(P_g (1 + s r_k), lower, upper), P_g the swarm's best after the beetle
    step: at a temperature where exp(-df / T) ~ 1, u_k = 0.5 accepts candidate k and
    u = 2 refuses the others, so the guide shows each candidate exactly."""
    fitness, W, tau, lo, hi, s, _ = sedsabso_case()
    s = _with(s, fitness, temperature=1e12)
    k12, r1, r2, r, _ = draws(3)
    for scale in (1.0, 0.25):
        solver = sj.SEDSABSO(population_size=SLOTS, beetle=BeetleStep(vmax_fraction=0.2),
                             temperature=1e12, n_trials=4, perturbation_scale=scale)
        beetles, (gx, _) = bso_ref(as_numpy(s), W, tau, lo, hi, r1, r2, solver.beetle)
        cand = np.clip(gx * (1 + scale * r), lo, hi)
        assert np.any(cand == hi) or np.any(cand == lo)  # the clip acts on this draw
        for k in range(4):
            u = np.full(4, 2.0)
            u[k] = 0.5
            out = step(solver, fitness, s, 0, lo, hi, (k12, jnp.asarray(r), jnp.asarray(u)))
            assert int(out.sa_accepted) == 1
            np.testing.assert_allclose(np.asarray(out.guide_x), cand[k], rtol=1e-12)


def test_guide_and_best_are_kept_apart():
    """A hot temperature accepts every candidate: the guide is the last candidate, worse
    than the swarm's best, and the reported best is still the best point seen."""
    fitness, W, tau, lo, hi, s, _ = sedsabso_case()
    s = _with(s, fitness, temperature=1e12)
    solver = sj.SEDSABSO(population_size=SLOTS, beetle=BeetleStep(vmax_fraction=0.2),
                         temperature=1e12, n_trials=4)
    k12, r1, r2, r, _ = draws(5)
    out = step(solver, fitness, s, 0, lo, hi, (k12, jnp.asarray(r), jnp.zeros(4) + 0.5))
    cand_f = f_ref(np.asarray(out.guide_x)[None], W, tau)[0]
    assert int(out.sa_accepted) == 4
    assert float(out.guide_f) == pytest.approx(cand_f)
    assert float(out.best_f) < float(out.guide_f)
    assert float(out.best_f) == pytest.approx(f_ref(np.asarray(out.best_x)[None], W, tau)[0])


def test_temperature_cools_geometrically():
    fitness, W, tau, lo, hi, s, solver = sedsabso_case()
    one = jax.jit(lambda s, k12, r, u: step(solver, fitness, s, 0, lo, hi, (k12, r, u)))
    for k in range(1, 8):
        k12, _, _, r, u = draws(k)
        s = one(s, k12, jnp.asarray(r), jnp.asarray(u))
        assert float(s.temperature) == pytest.approx(TEMPERATURE * 0.93 ** k, rel=1e-12)


# ------------------------------------------------------------------------ population
def test_the_worst_personal_bests_leave_first():
    fitness, W, tau, lo, hi, s = problem(3)
    pbest_f = jnp.asarray([5.0, 1.0, 3.0, 2.0, 4.0])
    s = dataclasses.replace(s, pbest_f=pbest_f, active=jnp.ones(SLOTS, bool))
    kept = set_active(s, 3)
    np.testing.assert_array_equal(np.asarray(kept.active), [False, True, True, True, False])
    fewer = set_active(kept, 2)  # an inactive slot never returns
    np.testing.assert_array_equal(np.asarray(fewer.active), [False, True, False, True, False])
    packed = shrink(fewer, 3)  # best first, active before inactive
    np.testing.assert_array_equal(np.asarray(packed.pbest_f)[:2], [1.0, 2.0])
    np.testing.assert_array_equal(np.asarray(packed.active), [True, True, False])
    np.testing.assert_array_equal(np.asarray(packed.x)[0], np.asarray(s.x)[1])


@pytest.mark.parametrize("K", [7, 600])
def test_population_is_eq_15_16_in_a_run(K):
    """N(t) = round(N_start exp(-(Inf_min + (Inf_max - Inf_min) t / (K - 1)))), written out
    here, against the active count a run records (decreasing form of Eq. 16)."""
    expected = [round(90 * math.exp(-(0.3 + 0.6 * t / (K - 1)))) for t in range(K)]
    r = sj.minimise(lambda x, a: jnp.sum(x ** 2), sj.SEDSABSO(n_phases=2), -np.ones(2),
                    np.ones(2), key=jax.random.key(0), iterations=K)
    np.testing.assert_array_equal(np.asarray(r.history_n), expected)
    assert expected[0] == 67 and expected[-1] == 37


def test_a_swarm_defined_later_is_named_in_swarms():
    """A swarm that gives ``paper()`` registers itself when its class is defined, after the
    package was imported too: ``sj.optim.SWARMS`` and the names the package resolves
    (:func:`~sedsabso_jax.optim._registry.paper_solver`) read the registry when asked."""
    from sedsabso_jax.optim._registry import paper_solver
    from sedsabso_jax.optim._swarm import REGISTERED

    assert list(sj.optim.SWARMS)[:3] == ["SEDSABSO", "BSO", "LDWPSO"]

    class SlowPSO(sj.LDWPSO):
        @classmethod
        def paper(cls):
            return cls(population_size=7)

    try:
        assert "SlowPSO" in sj.optim.SWARMS and sj.optim.SWARMS["SlowPSO"] is SlowPSO
        assert paper_solver("SlowPSO").population_size == 7
    finally:
        del REGISTERED["SlowPSO"]
    assert "SlowPSO" not in sj.optim.SWARMS


def test_a_swarm_written_outside_the_package_from_public_names():
    """A swarm of one's own, one class from ``sj.optim``'s public names only (a PSO of
    constant inertia): it registers itself by giving ``paper()``, runs under
    ``sj.minimise`` and gives LDWPSO's numbers with the inertia held (the same updates)."""
    import dataclasses

    from sedsabso_jax.optim._swarm import REGISTERED

    O = sj.optim

    class ConstantPSO(O.AbstractSwarm):
        population_size: int = 20
        w: float = 0.6

        @classmethod
        def paper(cls):
            return cls()

        def vmax(self, lower, upper):
            return 0.5 * (upper - lower)

        def evaluations(self, n_active):
            return n_active

        def propose(self, k, s, draws, lower, upper):
            r1, r2 = draws
            v = jnp.clip(self.w * s.v + 2.0 * r1 * (s.pbest_x - s.x)
                         + 2.0 * r2 * (s.guide_x - s.x), -self.vmax(lower, upper),
                         self.vmax(lower, upper))
            return dataclasses.replace(s, x=jnp.clip(s.x + v, lower, upper), v=v)

        def absorb(self, k, s, raw):
            if k == O.INITIAL:
                return O.initial_bests(s, raw)
            s, (gx, gf) = O.absorb_positions(s, raw, 1)
            return dataclasses.replace(s, guide_x=gx, guide_f=gf)

    try:
        assert sj.optim.SWARMS["ConstantPSO"] is ConstantPSO
        lo, hi = -jnp.ones(3), jnp.ones(3)
        sphere = lambda x, args: jnp.sum((x - 0.3) ** 2)  # noqa: E731
        mine = sj.minimise(sphere, ConstantPSO(), lo, hi, key=jax.random.key(0),
                           iterations=40)
        theirs = sj.minimise(sphere, sj.LDWPSO(population_size=20, w_start=0.6, w_end=0.6),
                             lo, hi, key=jax.random.key(0), iterations=40)
        np.testing.assert_array_equal(mine.x, theirs.x)
        assert float(mine.f) < 1e-4
    finally:
        del REGISTERED["ConstantPSO"]
