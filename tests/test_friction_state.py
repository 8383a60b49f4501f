"""Friction at rest: Dahl's presliding state integrated along the recording
(:class:`sj.Presliding`). The state against an independent integration on a ten times
finer grid, kept at rest and restarted per recording, the associative scan equal to the
sequential one; a subset's columns are the whole recording's, taken; a simulated
point-to-point plant's displacements and coefficients recovered from noisy torques and
predicted better by the validation; the compiled search problem's loss against a plain
least-squares fit (all samples, a subset, a population, its Jacobian); the command
line's word."""

from __future__ import annotations

import dataclasses
import json
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.identification import Projection, dahl_state, increments, parse_friction
from sedsabso_jax.identification._fit._samples import Samples

QC, FP = np.array([0.01, 0.02, 0.04]), np.array([3.0, 2.0, 1.0])


def point_to_point(n, moves=24, rate=100.0, seed=0, fine=10):
    """Minimum-jerk moves between random targets, each followed by a rest, sampled at
    ``fine`` times ``rate``: (q, qd, qdd, dt)."""
    rng = np.random.default_rng(seed)
    pieces, here = [], np.zeros(n)
    for _ in range(moves):
        target = rng.uniform(-1.0, 1.0, n)
        s = np.linspace(0.0, 1.0, int(rng.uniform(0.8, 1.6) * rate * fine))
        pieces.append(here + (target - here) * (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)[:, None])
        pieces.append(np.repeat(target[None], int(rng.uniform(0.3, 0.8) * rate * fine), 0))
        here = target
    q = np.concatenate(pieces)
    dt = 1.0 / (rate * fine)
    qd = np.gradient(q, dt, axis=0)
    qd[np.abs(qd) < 1e-12] = 0.0
    return q, qd, np.gradient(qd, dt, axis=0), dt


def dahl_loop(q, q_c):
    """Dahl's state along ``q`` by a plain loop of the exact update (from z = 0)."""
    z = np.zeros_like(q)
    for k in range(1, len(q)):
        s = np.sign(q[k] - q[k - 1])
        z[k] = s + (z[k - 1] - s) * np.exp(-np.abs(q[k] - q[k - 1]) / q_c)
    return z


@pytest.fixture(scope="module")
def plant():
    """rs010n moving point to point (a third of the time at rest) with presliding friction
    FP z(q; QC) integrated on a 1 kHz grid, sampled at 100 Hz, 1 % noise."""
    robot = sj.robots.rs010n()
    qf, qdf, qddf, dt = point_to_point(3)
    z = dahl_loop(qf, QC)[::10]
    q, qd, qdd = qf[::10], qdf[::10], qddf[::10]
    t = np.arange(len(q)) * dt * 10
    tau = sj.simulate_measurements(robot, q, qd, qdd, t).tau + FP * z
    tau = tau + 0.01 * np.sqrt(np.mean(tau ** 2, 0)) * np.random.default_rng(1).standard_normal(
        tau.shape)
    return robot, sj.base_parameters(robot), sj.Measurements(t, q, qd, qdd, tau), z


def test_the_state_is_dahls_kept_at_rest_and_restarted_per_recording(plant):
    """The columns FP_j are z_j on joint j's row: the fine grid's state at the samples
    (the update is exact while the direction holds within a sample), unchanged while the
    joint stands still (and not zero: a torque held), from 0 again at a new recording."""
    robot, base, data, z = plant
    model = sj.TorqueModel.of(robot, (sj.Presliding(tuple(QC)),), base=base)
    assert not model.nonlinear() and model.names[-3:] == ("FP1", "FP2", "FP3")
    Y = model.regressor(data.q, data.qd, data.qdd)
    np.testing.assert_allclose(Y[:, np.arange(3), np.arange(3) + base.rank], z, atol=1e-9)
    assert np.all(Y[:, [1, 2, 0], np.arange(3) + base.rank] == 0.0)  # own row only
    rest = np.all(np.diff(data.q, axis=0) == 0.0, axis=1)
    assert rest.mean() > 0.2 and np.all(z[1:][rest] == z[:-1][rest])
    assert np.abs(z[1:][rest]).mean() > 0.5
    recording = np.repeat([0, 1], [300, len(data.q) - 300])
    Y2 = model.regressor(data.q, data.qd, data.qdd, recording)
    np.testing.assert_allclose(Y2[300:, np.arange(3), np.arange(3) + base.rank],
                               dahl_loop(data.q[300:], QC), atol=1e-12)


def test_the_associative_scan_is_the_sequential_one(plant):
    """The state as a prefix composition of affine maps (parallel in time) equals the
    sequential scan, restarts included."""
    _, _, data, _ = plant
    recording = np.repeat([0, 1, 2], [200, 500, len(data.q) - 700])
    dq, start = increments(data.q, recording)
    a = np.asarray(dahl_state(dq, start, QC, sequential=True))
    b = np.asarray(dahl_state(dq, start, QC, sequential=False))
    np.testing.assert_allclose(b, a, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(a[start], 0.0)


def test_a_split_reads_the_state_of_the_whole_recording(plant):
    """Cross-validation's training and test samples: their rows (and predictions) are
    the whole recording's, taken; a split of a split too."""
    robot, base, data, _ = plant
    model = sj.TorqueModel.of(robot, (sj.Presliding(0.02),), base=base)
    samples = Samples(data.q, data.qd, data.qdd, data.tau)
    keep = np.arange(len(data.q)) % 3 != 0
    inner = np.arange(keep.sum()) % 2 == 0
    part = samples.split(keep)
    # the splits' own rows first, before the whole's are kept (and then taken)
    rows, inner_rows = part.rows(model), part.split(inner).rows(model)
    values = np.random.default_rng(0).standard_normal(model.dim)
    predicted = part.predict(model, values)
    whole = samples.rows(model)
    np.testing.assert_array_equal(rows, whole[keep])
    np.testing.assert_array_equal(inner_rows, whole[keep][inner])
    np.testing.assert_allclose(predicted, whole[keep] @ values)
    np.testing.assert_array_equal(model.regressor(data.q, data.qd, data.qdd, rows=keep),
                                  whole[keep])
    for bad in (keep[1:], keep.astype(int)):
        with pytest.raises(ValueError, match=r"rows must be \(\d+,\) booleans"):
            model.regressor(data.q, data.qd, data.qdd, rows=bad)


def test_one_sample_has_the_rows_of_many(plant):
    """A single sample ``(n,)`` gets the row a batch gives it, with a Coulomb shape of
    one scale per joint too."""
    robot, base, data, _ = plant
    model = sj.TorqueModel.of(robot, (sj.SmoothCoulomb(velocity=(0.01, 0.02, 0.03)),
                                      sj.Offset()), base=base)
    many = model.regressor(data.q[:5], data.qd[:5], data.qdd[:5])
    np.testing.assert_allclose(model.regressor(data.q[3], data.qd[3], data.qdd[3]), many[3],
                               rtol=1e-12, atol=1e-12)


def test_the_plant_is_recovered_and_validated(plant):
    """presliding:fit on the plant: each displacement q_c and coefficient FP within 10 %
    (the displacements' standard deviations covering the error), and the phase folds
    predict better with it than without."""
    robot, base, data, _ = plant
    model = sj.TorqueModel.of(robot, (sj.Presliding(fitted=True),), base=base)
    fit = sj.identify(robot, data, sj.OLS(), model)
    found_ = fit.settings["searched"]["parameters"]
    found = np.array([found_[f"q_c{j + 1}"]["value"] for j in range(3)])
    std = np.array([found_[f"q_c{j + 1}"]["std"] for j in range(3)])
    np.testing.assert_allclose(found, QC, rtol=0.1)
    assert np.all(np.abs(found - QC) < 5 * std) and not any(s["at_bound"]
                                                            for s in found_.values())
    assert {s["unit"] for s in found_.values()} == {"rad"}
    np.testing.assert_allclose(fit.values[[fit.names.index(f"FP{j + 1}") for j in range(3)]],
                               FP, rtol=0.1)
    assert fit.model.friction == "viscous-coulomb+presliding:fit"
    physical = sj.identify(robot, data, sj.PhysicallyConsistent(sj.OLS()), model)
    urdf = physical.urdf()  # the coefficients and the displacements found, in a comment
    assert "presliding:fit" in urdf and "FP3 = " in urdf and "q_c3 = " in urdf
    plain = sj.cross_validate(robot, data, sj.OLS(), sj.TorqueModel.of(robot, base=base))
    held = sj.cross_validate(robot, data, sj.OLS(), model)
    assert held.score < 0.85 * plain.score


def _least_squares_loss(Y, tau, w):
    """The mean square of the weighted residual of a plain least-squares fit."""
    W, b = (Y * w[:, None]).reshape(-1, Y.shape[-1]), (tau * w).reshape(-1)
    x = np.linalg.lstsq(W, b, rcond=None)[0]
    return np.mean((W @ x - b) ** 2)


class SharedDrag(sj.identification.AbstractScale):
    """A term of the test's own: one column reaching every joint's row, ``sum_j
    tanh(qd_j / v)`` on each (a drag the joints share), its ``v`` searched."""

    velocity: float | tuple[float, ...] = sj.identification.scale(
        0.05, bounds=(1e-3, 1.0), unit="rad/s", symbol="v_shared")
    fitted: bool = True
    name: ClassVar[str] = "shared"
    nonnegative: ClassVar[bool] = False

    def names(self, model):
        return ("DRAG",)

    def nonlinear(self, model):  # one velocity for the joints together
        found = super().nonlinear(model)
        return sj.identification.Nonlinear(found.names[:1], found.values[:1],
                                           found.lower[:1], found.upper[:1], found.unit)

    def with_nonlinear(self, values):
        if isinstance(values, jax.core.Tracer):  # a trial inside the compiled search
            return eqx.tree_at(lambda t: t.velocity, self, values[0])
        return dataclasses.replace(self, velocity=float(values[0]))

    def columns(self, model, s):
        return jnp.sum(jnp.tanh(s.qd / self.per_joint(model.robot.n_joints)), -1,
                       keepdims=True)[..., None, :] * jnp.ones((model.robot.n_joints, 1))


MODELS = {"presliding:fit": lambda: parse_friction("presliding:fit"),
          "offset+smooth:fit+stribeck:0.05": lambda: parse_friction(
              "offset+smooth:fit+stribeck:0.05"),
          "a column on every row": lambda: (SharedDrag(),),
          # IA1, IA2 the base regressor spans (regrouped): not in the fixed block
          "armature+presliding:fit": lambda: parse_friction("armature+presliding:fit")}


@pytest.mark.parametrize("friction", list(MODELS))
def test_the_search_problem_is_the_least_squares_fit(plant, friction):
    """The compiled problem's loss at log-parameters u is the mean square residual of a
    plain least-squares fit of the model with those parameters (weighted per joint), on
    all samples and on a subset (whose state is the whole recording's); vmapped over a
    population it is the loss of each; the mean square of its residual is its loss, and
    the residual's Jacobian (forward mode through the columns) matches central
    differences. A state's displacements, and a Coulomb shape that moves the Coulomb
    columns and the Stribeck columns that read it, alike; and beside columns the base
    regressor spans (an exact dependency among the columns no trial moves)."""
    robot, base, data, _ = plant
    samples = Samples(data.q, data.qd, data.qdd, data.tau)
    model = sj.TorqueModel.of(robot, MODELS[friction](), base=base)
    w = np.array([1.0, 2.0, 0.5])
    problem = Projection.of(model, samples, w)
    loss = eqx.filter_jit(lambda pr, u: pr.loss(u))        # eager, a scan a step a time
    residual = eqx.filter_jit(lambda u: problem.residual(u))
    k = sum(len(f.values) for _, f in model.nonlinear())
    u = np.log(np.array([0.015, 0.03, 0.02]))[:k]
    Y = samples.rows(model.with_nonlinear(np.exp(u)), every_column=True)
    assert float(loss(problem, jnp.asarray(u))) == pytest.approx(
        _least_squares_loss(Y, data.tau, w), rel=1e-7)
    keep = np.arange(len(data.q)) % 4 != 1
    part = Projection.of(model, samples.split(keep), w)
    assert float(loss(part, jnp.asarray(u))) == pytest.approx(
        _least_squares_loss(Y[keep], data.tau[keep], w), rel=1e-7)
    # the split as a mask over the whole recordings, or its indices: the same problem
    for chosen in (keep, np.flatnonzero(keep)):
        masked = Projection.of(model, samples, w, keep=chosen)
        np.testing.assert_array_equal(masked.mask, part.mask)
        assert float(loss(masked, jnp.asarray(u))) == float(loss(part, jnp.asarray(u)))
    population = jnp.asarray(u + np.random.default_rng(0).normal(0, 0.5, (5, k)))
    losses = eqx.filter_jit(lambda u: jax.vmap(problem.loss)(u))  # jit of a closure
    np.testing.assert_allclose(losses(population),
                               [loss(problem, p) for p in population], rtol=1e-9)
    r = residual(jnp.asarray(u))
    assert float(jnp.mean(r ** 2)) == pytest.approx(float(loss(problem, jnp.asarray(u))),
                                                    rel=1e-7)
    J = eqx.filter_jit(lambda u: jax.jacfwd(residual)(u))(jnp.asarray(u))
    h = 1e-5
    e = np.eye(k)[k - 1]
    fd = (residual(jnp.asarray(u + h * e)) - residual(jnp.asarray(u - h * e))) / (2 * h)
    np.testing.assert_allclose(J[:, k - 1], fd, atol=1e-5 * np.abs(fd).max())


def test_a_term_that_reads_a_fit_is_searched_by_one_compilation(plant):
    """Friction growing with the load reads a fit's rigid-body values, which differ
    between a validation's splits; with the smooth Coulomb's scales searched its columns
    move. Its search problems of two such fits are one compiled call (each split's
    compiling anew made the scales cost minutes: the values are the call's arguments),
    and each problem's loss is the least-squares fit of its own model."""
    from sedsabso_jax.identification._search._problem import _population, losses

    robot, base, data, _ = plant
    samples = Samples(data.q, data.qd, data.qdd, data.tau)
    model = sj.TorqueModel.of(robot, parse_friction("smooth:fit+load"), base=base)
    rng = np.random.default_rng(2)
    # two fits' values: each joint's load point its own
    models = [model.reading(model.prior_values * rng.uniform(0.5, 1.5, model.dim))
              for _ in range(2)]
    assert models[0].terms[-1].load_point != models[1].terms[-1].load_point
    w = np.array([1.0, 2.0, 0.5])
    u = np.log([0.01, 0.03, 0.05])
    found = []
    for m in models:
        problem = Projection.of(m, samples, w)
        found.append(losses(problem, u[None])[0])
        if len(found) == 1:
            compiled = _population._cached._cache_size()
        Y = samples.rows(m.with_nonlinear(np.exp(u)), every_column=True, cache=False)
        assert found[-1] == pytest.approx(_least_squares_loss(Y, data.tau, w), rel=1e-7)
    assert _population._cached._cache_size() == compiled
    assert found[0] != pytest.approx(found[1], rel=1e-6)


def test_a_single_trial_and_a_pair_are_one_compiled_call(plant):
    """A search evaluates single trials (its start, a step) and pairs (a sweep's
    candidates) besides its grids: a single trial is evaluated beside a copy of itself,
    so that the two sizes are one compilation (about 1.5 s each for the KUKA LWR4+),
    and its loss is the pair's first."""
    from sedsabso_jax.identification._search._problem import _population, losses

    robot, base, data, _ = plant
    # a length no other test's problem has: its compilations are this test's alone
    samples = Samples(*(x[:-7] for x in (data.q, data.qd, data.qdd, data.tau)))
    model = sj.TorqueModel.of(robot, (sj.Presliding(fitted=True),), base=base)
    problem = Projection.of(model, samples, np.ones(3))
    u = np.log([0.002, 0.004, 0.001])
    pair = losses(problem, np.stack([u, u + 0.5]))
    compiled = _population._cached._cache_size()
    single = losses(problem, u[None])
    assert _population._cached._cache_size() == compiled
    assert single.shape == (1,) and single[0] == pytest.approx(pair[0], rel=1e-12)
    assert pair[1] != pytest.approx(pair[0], rel=1e-6)


def test_a_search_is_kept_per_row_weights(plant):
    """A validation fits each split with several estimators: their searches are one where
    the search weighs the rows alike (OLS, Gautier's WLS: equal), another where it weighs
    them otherwise (WLS by the limits)."""
    from sedsabso_jax.identification._fit._fit import fit

    robot, base, data, _ = plant
    samples = Samples(data.q, data.qd, data.qdd, data.tau)
    model = sj.TorqueModel.of(robot, (sj.Presliding(fitted=True),), base=base)
    limits = np.array([500.0, 200.0, 10.0])
    ols, wls, by_limits = (fit(e, model, samples, limits) for e in (
        sj.OLS(), sj.WLS(), sj.WLS("limits")))
    assert ols.report["searched"] is wls.report["searched"]
    assert by_limits.report["searched"]["loss"] != ols.report["searched"]["loss"]


def test_the_word_and_the_command(tmp_path, capsys, plant):
    from sedsabso_jax.cli import main

    assert parse_friction("offset+presliding:fit")[1] == sj.Presliding(fitted=True)
    assert parse_friction("presliding:0.01,0.02,0.03")[0].text == "presliding:0.01,0.02,0.03"
    assert sj.Presliding().text == "presliding"
    robot, _, data, _ = plant
    path = data.save(tmp_path / "d.npz")
    out = tmp_path / "fit.json"
    common = ["identify", "--robot", "rs010n", "--data", str(path), "--method", "OLS",
              "--weights", "equal", "--no-physical", "--folds", "0"]
    assert main([*common, "--friction", "presliding:fit", "--json", str(out)]) == 0
    settings = json.loads(out.read_text())["settings"]
    assert settings["friction"] == "viscous-coulomb+presliding:fit"
    assert set(settings["searched"]["parameters"]) == {"q_c1", "q_c2", "q_c3"}
    for bad in ("presliding:0", "presliding:-1", "presliding:x", "presliding:0.1,0.2"):
        bad_out = tmp_path / "bad.json"
        capsys.readouterr()
        assert main([*common, "--friction", bad, "--json", str(bad_out)]) == 2, bad
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and "presliding" in err.lower(), err
        assert not bad_out.exists()
