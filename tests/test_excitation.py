"""Fourier excitation trajectories (Eq. 5-7), joint limits (Table 3, URDF) and the Eq. 9
design."""

from __future__ import annotations

import math
import os
from importlib import resources

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sedsabso_jax as sj
from sedsabso_jax import (
    FourierTrajectory,
    JointLimits,
    design_excitation,
    joint_limits_from_urdf,
)
from sedsabso_jax.excitation import (
    ExcitationDesign,
    check_trajectory,
    coefficient_box,
    condition_number,
    sampling_margin,
    violations,
)

KUKA_URDF = resources.files("sedsabso_jax") / "data" / "kuka_lwr4" / "kuka_lwr4.urdf"


def series(traj: FourierTrajectory, t):
    """Eq. 6 and its derivative written out in numpy, apart from the package's code."""
    k = np.arange(1, traj.n_harmonics + 1)
    ph = np.asarray(t)[..., None, None] * k * traj.wf  # (..., 1, N)
    a, b = np.asarray(traj.a), np.asarray(traj.b)
    qd = (a * np.cos(ph) - b * np.sin(ph)).sum(-1)
    qdd = (-a * k * traj.wf * np.sin(ph) - b * k * traj.wf * np.cos(ph)).sum(-1)
    return qd, qdd


def random_trajectory(rng, n=3, N=4, wf=2 * math.pi * 0.1) -> FourierTrajectory:
    return FourierTrajectory(rng.normal(size=(n, N)), rng.normal(size=(n, N)),
                             rng.normal(size=n), wf)


# --- the series ---------------------------------------------------------------------------


def test_derivatives_match_jacfwd(rng):
    traj = random_trajectory(rng, n=3, N=5, wf=1.3)
    times = jnp.asarray(rng.uniform(-20, 20, 7))
    q, qd, qdd = traj(times)
    dq = jax.vmap(jax.jacfwd(lambda t: traj(t)[0]))(times)
    dqd = jax.vmap(jax.jacfwd(lambda t: traj(t)[1]))(times)
    np.testing.assert_allclose(dq, qd, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(dqd, qdd, rtol=1e-12, atol=1e-12)
    # and qd(t) is Eq. 6 as written, for one joint and harmonic by hand
    # and qd, qdd are Eq. 6 and its derivative as written
    for ours, theirs in zip((qd, qdd), series(traj, times)):
        np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=1e-12)


def test_periodic_and_q0_is_the_mean(rng):
    traj = random_trajectory(rng, n=2, N=3, wf=0.7)
    T = traj.period
    assert T == pytest.approx(2 * math.pi / 0.7)
    for a, b in zip(traj(0.0), traj(T)):
        np.testing.assert_allclose(a, b, atol=1e-12)
    grid = T * np.arange(64) / 64
    q = traj(grid)[0]
    np.testing.assert_allclose(q.mean(0), traj.q0, atol=1e-12)  # q0 is the offset
    k = np.arange(1, 4)
    np.testing.assert_allclose(traj(0.0)[0], traj.q0 + (traj.b / (k * 0.7)).sum(1), atol=1e-12)


def test_shapes_jit_and_vector_round_trip(rng):
    traj = random_trajectory(rng, n=3, N=2)
    q, qd, qdd = traj(np.zeros((4, 5)))
    assert q.shape == qd.shape == qdd.shape == (4, 5, 3) and q.dtype == jnp.float64
    assert traj(1.5)[0].shape == (3,)
    jitted = jax.jit(lambda tr, t: tr(t))(traj, jnp.linspace(0, 1, 3))
    np.testing.assert_allclose(jitted[1], traj(jnp.linspace(0, 1, 3))[1], rtol=1e-14)
    x = traj.to_vector()
    assert x.shape == (3 * (2 * 2 + 1),)
    back = FourierTrajectory.from_vector(x, 3, 2, traj.wf)
    assert np.array_equal(back.a, traj.a) and np.array_equal(back.q0, traj.q0)
    # from_vector also traces under jit
    f = jax.jit(lambda x: FourierTrajectory.from_vector(x, 3, 2, traj.wf)(0.25)[0])
    np.testing.assert_allclose(f(x), traj(0.25)[0], rtol=1e-14)
    assert (traj.n_joints, traj.n_harmonics) == (3, 2)


def test_bad_series_inputs_are_named(rng):
    a = rng.normal(size=(3, 2))
    with pytest.raises(ValueError, match=r"b must have the shape of a, \(3, 2\), got \(3, 3\)"):
        FourierTrajectory(a, np.zeros((3, 3)), np.zeros(3))
    with pytest.raises(ValueError, match=r"q0 must have shape \(3,\).*got \(2,\)"):
        FourierTrajectory(a, a, np.zeros(2))
    with pytest.raises(ValueError, match="a contains NaN"):
        FourierTrajectory(np.full((3, 2), np.nan), a, np.zeros(3))
    with pytest.raises(ValueError, match="wf must be a positive"):
        FourierTrajectory(a, a, np.zeros(3), wf=-1.0)
    with pytest.raises(ValueError, match=r"x must have shape \(15,\).*got \(14,\)"):
        FourierTrajectory.from_vector(np.zeros(14), 3, 2)


# --- files --------------------------------------------------------------------------------


def test_save_load_round_trip_is_bit_identical(rng, tmp_path):
    traj = random_trajectory(rng, n=3, N=5, wf=0.123456789)
    path = tmp_path / "traj.npz"
    path.write_bytes(b"an older file that the atomic save replaces")
    traj.save(path)
    back = FourierTrajectory.load(path)
    for name in ("a", "b", "q0"):
        assert np.asarray(getattr(back, name)).tobytes() == np.asarray(
            getattr(traj, name)).tobytes()
    assert back.wf == traj.wf
    assert os.listdir(tmp_path) == ["traj.npz"]  # no temporary file left behind


UNPICKLED = []


def _record_unpickling():
    UNPICKLED.append(True)
    return "boom"


class _Evil:
    def __reduce__(self):
        return (_record_unpickling, ())


def _write(path, **arrays):
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


def _valid_arrays():
    return {"format": np.array("sedsabso-jax FourierTrajectory 1"), "a": np.zeros((2, 3)),
            "b": np.zeros((2, 3)), "q0": np.zeros(2), "wf": np.array(0.5)}


def test_object_arrays_are_refused_never_unpickled(tmp_path):
    path = tmp_path / "evil.npz"
    arrays = _valid_arrays()
    arrays["a"] = np.array([_Evil(), _Evil()], dtype=object)
    _write(path, **arrays)
    with pytest.raises(ValueError, match=r"evil\.npz.*key 'a'.*pickle"):
        FourierTrajectory.load(path)
    assert UNPICKLED == []
    np.save(tmp_path / "evil.npy", np.array([_Evil()], dtype=object))
    with pytest.raises(ValueError, match=r"evil\.npy.*not a valid \.npz"):
        FourierTrajectory.load(tmp_path / "evil.npy")
    assert UNPICKLED == []


@pytest.mark.parametrize("change, message", [
    (lambda d: d.pop("b"), r"missing keys \['b'\]"),
    (lambda d: d.update(extra=np.zeros(1)), r"unknown keys \['extra'\]"),
    (lambda d: d.update(q0=np.zeros(3)), r"q0 must have shape \(2,\).*got \(3,\)"),
    (lambda d: d.update(a=np.zeros(6)), r"key 'a' must be 2-D, got shape \(6,\)"),
    (lambda d: d.update(wf=np.array(np.nan)), r"key 'wf' contains NaN"),
    (lambda d: d.update(format=np.array("something else")), r"key 'format' must be"),
])
def test_bad_files_name_the_file_and_key(tmp_path, change, message):
    arrays = _valid_arrays()
    change(arrays)
    path = tmp_path / "bad.npz"
    _write(path, **arrays)
    with pytest.raises(ValueError, match=r"bad\.npz.*" + message):
        FourierTrajectory.load(path)


def test_unreadable_file(tmp_path, rng):
    (tmp_path / "junk.npz").write_bytes(b"not a zip file at all")
    with pytest.raises(ValueError, match="junk.npz"):
        FourierTrajectory.load(tmp_path / "junk.npz")
    random_trajectory(rng).save(tmp_path / "good.npz")
    raw = (tmp_path / "good.npz").read_bytes()
    (tmp_path / "cut.npz").write_bytes(raw[: len(raw) // 2])
    with pytest.raises(ValueError, match=r"cut\.npz' is not a valid \.npz"):
        FourierTrajectory.load(tmp_path / "cut.npz")
    (tmp_path / "flipped.npz").write_bytes(raw[:200] + bytes(50) + raw[250:])
    with pytest.raises(ValueError, match=r"flipped\.npz': key '\w+' is corrupt"):
        FourierTrajectory.load(tmp_path / "flipped.npz")
    with pytest.raises(ValueError, match="cannot read"):
        FourierTrajectory.load(tmp_path / "missing.npz")


# --- limits -------------------------------------------------------------------------------


def test_rs010n_limits_are_table_3():
    lim = JointLimits.rs010n()
    np.testing.assert_allclose(np.degrees(lim.q_min), [-180, -60, -180], rtol=1e-14)
    np.testing.assert_allclose(np.degrees(lim.q_max), [180, 140, 80], rtol=1e-14)
    np.testing.assert_allclose(np.degrees(lim.qd_max), [125, 100, 165], rtol=1e-14)
    np.testing.assert_allclose(np.degrees(lim.qdd_max), [45, 40, 75], rtol=1e-14)
    assert np.all(np.isnan(lim.tau_max)) and lim.names == ("J1", "J2", "J3")


def test_violations_name_joint_and_limit():
    lim = JointLimits.rs010n()
    q = np.zeros((4, 3))
    qd = np.zeros((4, 3))
    qdd = np.zeros((4, 3))
    qd[2, 1] = -math.radians(120.3)  # joint 2: 120.3 deg/s > 100 deg/s
    q[1, 2] = math.radians(-190.0)  # joint 3: below -180 deg
    qdd[:, 0] = math.radians(45.0)  # exactly on the limit: fine
    found = violations(lim, q, qd, qdd, times=np.arange(4) * 0.5)
    assert len(found) == 2
    assert found[0].startswith("joint 2 (J2) velocity") and "120.3 deg/s" in found[0]
    assert "at t = 1 s" in found[0] and "100 deg/s" in found[0]
    assert found[1].startswith("joint 3 (J3) position") and "below the minimum" in found[1]
    assert "-190 deg" in found[1] and "-180 deg" in found[1]
    assert violations(lim, q * 0, qd * 0, qdd) == []
    with pytest.raises(ValueError, match=r"qd must have shape \(\.\.\., 3\)"):
        violations(lim, q, qd[:, :2], qdd)
    with pytest.raises(ValueError, match="qdd contains NaN"):
        violations(lim, q, qd, qdd * np.nan)


def test_check_trajectory_raises_with_joint_and_limit():
    lim = JointLimits.rs010n()
    wf = 2 * math.pi * 0.1
    a = np.zeros((3, 1))
    a[2, 0] = math.radians(80.0) / wf  # joint 3: qdd amplitude 80 deg/s^2 > 75
    traj = FourierTrajectory(a, np.zeros((3, 1)), np.zeros(3), wf)
    with pytest.raises(ValueError, match=r"joint 3 \(J3\) acceleration.*80 deg/s\^2.*75 deg"):
        check_trajectory(traj, lim, np.arange(1000) / 100)
    centred = np.radians([0.0, 40.0, -50.0])
    check_trajectory(FourierTrajectory(a / 4, a * 0, centred, wf), lim, np.arange(100))


def test_bad_limits():
    with pytest.raises(ValueError, match="joint 2: q_min 1.0 must be below q_max 0.5"):
        JointLimits([0, 1], [1, 0.5], [1, 1])
    with pytest.raises(ValueError, match=r"qd_max must have shape \(2,\) like q_min"):
        JointLimits([0, 0], [1, 1], [1, 1, 1])
    with pytest.raises(ValueError, match="joint 1: qd_max must be > 0"):
        JointLimits([0, 0], [1, 1], [0, 1])
    with pytest.raises(ValueError, match="both finite or both infinite"):
        JointLimits([-np.inf, 0], [1, 1], [1, 1])


def test_kuka_urdf_limits_are_the_files_numbers():
    with resources.as_file(KUKA_URDF) as path:
        robot = sj.robots.kuka_lwr4()
        lim = joint_limits_from_urdf(path, robot, qdd_max=5.0)
    np.testing.assert_array_equal(lim.tau_max, [176, 176, 100, 100, 100, 38, 38])
    np.testing.assert_array_equal(lim.qd_max, [1.91986217719, 1.91986217719, 2.23402144255,
                                               2.23402144255, 3.56047167407, 3.21140582367,
                                               3.21140582367])
    np.testing.assert_array_equal(lim.q_max, [2.96705972839, 2.09439510239] * 3
                                  + [2.96705972839])
    np.testing.assert_array_equal(lim.q_min, -np.asarray(lim.q_max))
    np.testing.assert_array_equal(lim.qdd_max, np.full(7, 5.0))
    assert lim.names == robot.joint_names and all(lim.angular)


def test_urdf_without_limits(tmp_path):
    text = ('<?xml version="1.0"?><robot name="r"><link name="base"/><link name="l1"/>'
            '<link name="l2"/><joint name="j1" type="continuous"><parent link="base"/>'
            '<child link="l1"/><axis xyz="0 0 1"/></joint>'
            '<joint name="j2" type="prismatic"><parent link="l1"/><child link="l2"/>'
            '<axis xyz="1 0 0"/><limit lower="-0.5" upper="0.25" effort="0" velocity="0.3"/>'
            '</joint></robot>')
    path = tmp_path / "r.urdf"
    path.write_text(text)
    lim = joint_limits_from_urdf(path, sj.robots.from_urdf(path))
    np.testing.assert_array_equal(lim.q_min, [-np.inf, -0.5])
    np.testing.assert_array_equal(lim.q_max, [np.inf, 0.25])
    np.testing.assert_array_equal(lim.qd_max, [np.inf, 0.3])
    assert np.all(np.isnan(lim.tau_max)) and np.all(np.isinf(lim.qdd_max))
    assert lim.angular == (True, False)
    msg = violations(lim, np.array([[0.0, 0.3]]), np.zeros((1, 2)), np.zeros((1, 2)))
    assert msg == ["joint 2 (j2) position: q reaches 0.3 m, above the maximum 0.25 m; "
                   "1 of 1 samples"]


# --- design -------------------------------------------------------------------------------


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), N=st.integers(1, 6), S=st.integers(20, 80))
def test_sampling_margin_bounds_the_peaks_between_samples(seed, N, S):
    """What the design relies on: a limit met at S samples per period, tightened by
    sampling_margin, holds at every time."""
    rng = np.random.default_rng(seed)
    traj = random_trajectory(rng, n=2, N=N, wf=0.9)
    # make a sample miss the peak as badly as possible: shift the grid by half a step
    coarse = traj.period * (np.arange(S) + rng.uniform()) / S
    dense = traj.period * np.arange(20000) / 20000
    delta = sampling_margin(N, S)
    for fine, sampled in zip(series(traj, dense), series(traj, coarse)):  # qd, qdd
        peak, sampled = np.abs(fine).max(0), np.abs(sampled).max(0)
        assert np.all(peak * (1 - delta) <= sampled * (1 + 1e-12))


SMALL = {"search": sj.excitation.DesignSearch(solver=sj.LDWPSO(population_size=20),
                                              iterations=30, design_samples=50)}


@pytest.fixture(scope="module")
def small_design():
    robot = sj.robots.rs010n()
    base = sj.base_parameters(robot)
    return robot, base, design_excitation(robot, JointLimits.rs010n(), key=jax.random.key(3),
                                          base=base, **SMALL)


def test_design_is_feasible_and_beats_random_and_a_sine(small_design):
    robot, base, d = small_design
    assert isinstance(d, ExcitationDesign)
    lim = JointLimits.rs010n()
    assert d.times.shape == (1000,) and d.times[1] == pytest.approx(0.01)
    check_trajectory(d.trajectory, lim, d.times)
    # feasible at every time, not only at the samples (the sampling margin)
    check_trajectory(d.trajectory, lim, np.linspace(0, 10, 100_001))
    assert math.isfinite(d.cond) and d.cond < 1e3
    assert d.cond == pytest.approx(condition_number(base, *d.trajectory(d.times)))
    assert d.n_random == int(d.result.n_evaluations) and 0 < d.n_random_feasible < d.n_random
    assert d.cond <= d.random_cond
    # a naive excitation: one sine per joint at half the box, centred
    lo, hi = coefficient_box(lim)
    a = np.zeros((3, 5))
    a[:, 0] = hi[0:15:5] / 2
    sine = FourierTrajectory(a, 0 * a, (hi[30:] + lo[30:]) / 2)
    check_trajectory(sine, lim, d.times)
    assert d.cond < condition_number(base, *sine(d.times)) / 2
    text = repr(d)
    assert "RS010N" in text and "LDWPSO" in text and f"{d.cond:.6g}" in text


def test_design_is_reproducible(small_design):
    robot, base, d = small_design
    again = design_excitation(robot, JointLimits.rs010n(), key=jax.random.key(3), base=base,
                              **SMALL)
    assert np.array_equal(again.trajectory.to_vector(), d.trajectory.to_vector())
    assert again.cond == d.cond and again.random_cond == d.random_cond
    assert again.result.compile_s == 0.0  # the compiled swarm is reused


def test_design_input_errors(small_design):
    robot, base, _ = small_design
    lim = JointLimits.rs010n()
    with pytest.raises(ValueError, match="limits are for 2 joints, robot 'RS010N' has 3"):
        design_excitation(robot, JointLimits([0, 0], [1, 1], [1, 1]), base=base)
    with pytest.raises(ValueError, match="design_samples=8 is too few for 5 harmonics"):
        design_excitation(robot, lim, search=sj.excitation.DesignSearch(design_samples=8),
                          base=base)
    with pytest.raises(ValueError, match="duration must be a positive number"):
        design_excitation(robot, lim, duration=-1.0, base=base)
    with pytest.raises(TypeError, match="limits must be JointLimits"):
        design_excitation(robot, None, base=base)


def test_fitness_is_eq_9_and_the_graded_penalty_orders_infeasible_ones(small_design):
    import equinox as eqx

    from sedsabso_jax.excitation import PENALTY, DesignProblem, design_fitness

    robot, base, d = small_design
    lim = JointLimits.rs010n()
    x = d.trajectory.to_vector()  # feasible (also with the smaller margin of 100 samples)
    n_coef = 2 * 3 * 5
    X = jnp.stack([x, x.at[:n_coef].multiply(3.0), x.at[:n_coef].multiply(6.0)])
    values = {}
    for graded in (True, False):
        problem = DesignProblem.build(robot, base, lim, 5, d.trajectory.wf, 10.0, 100, graded)
        values[graded] = np.asarray(eqx.filter_jit(jax.vmap(design_fitness, (0, None)))(
            X, problem))
    t_design = 10.0 * np.arange(100) / 100
    cond = condition_number(base, *d.trajectory.sample(t_design))
    assert values[True][0] == values[False][0] == pytest.approx(cond, rel=1e-8)
    assert np.all(values[False][1:] >= PENALTY) and np.all(values[False][1:] < PENALTY + 1e6)
    assert values[True][2] > values[True][1] > 1.5 * PENALTY  # more excess, worse
