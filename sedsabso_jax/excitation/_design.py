"""Excitation design (the paper's Eq. 9), with a random-search baseline.

Design (:func:`design_excitation`): minimise over ``x = [a, b, q0]`` (``n (2N + 1)``
numbers, :meth:`FourierTrajectory.to_vector`) Eq. 9,
``cond(W_b) + 1e8 [a limit is violated]``, ``W_b`` the base regressor stacked over the
samples (Eq. 8) and ``cond = sigma_max / sigma_min``, with one of the package's swarms
(the paper used MATLAB's GA) through :func:`~sedsabso_jax.minimise`, which evaluates
the population (regressor and condition number of every member) under ``vmap``. The
paper gives no N, wf, duration or rate; the choices here:

- ``N = 5``, ``wf = 2 pi 0.1`` rad/s: the 10 s experiment is exactly one period, and the
  highest harmonic (0.5 Hz) still moves visibly under Table 3's acceleration limits (45
  deg/s^2 allow a velocity amplitude of 72 deg/s at the fundamental, 14 deg/s at k = 5).
- 10 s at 100 Hz: ``times = arange(1000) / 100`` (the end point is the start again).
- The swarm's condition number is taken on ``design_samples = 100`` equally spaced times
  over the duration (the regressor's cost grows with the samples); the reported one is
  recomputed by an SVD on the 1000 samples. They agree to about 1 % (69.0 vs 68.7 for the
  default RS010N design), the regressor's harmonics being far below the 100-sample grid's
  Nyquist rate. In the fitness the condition number comes from the eigenvalues of
  ``W^T W`` (21 x 21 for RS010N), several times faster under ``vmap`` than an SVD of ``W``.
- The limits are checked at ``design_samples`` times over one period, each limit tightened
  by :func:`._fitness.sampling_margin` (1.2 % for N = 5 and 100 samples). By Bernstein's inequality
  a design that passes holds its limits at EVERY time, not only at the samples, so the
  final :func:`._checks.check_trajectory` on the 100 Hz grid (or any finer one) passes.
- Penalty: a feasible trajectory scores exactly Eq. 9. An infeasible one scores at least
  ``1e8`` (``1e8 + cond``), plus (``graded_penalty=True``, the default) ``1e8`` times its
  summed relative excess over the limits, so that the swarm is drawn back to feasibility;
  with the constant penalty alone, the infeasible majority of a swarm is ranked by its
  condition number, which rewards larger motions, and a run can end with no feasible
  member (seen with LDWPSO in a box 1.4 times wider than :func:`coefficient_box`'s).
  ``graded_penalty=False`` gives the paper's constant ``P``.
- Search box: :func:`coefficient_box`.
- Solver: :func:`default_solver`, LDWPSO with 40 particles for 100 iterations (4040
  evaluations). On RS010N with Table 3, seeds 0, 1, 2, about 4000 evaluations each, this
  box: LDWPSO(40) x 100 gave cond 69.0, 64.8, 72.9; BSO(20) x 67: 74.9, 70.1, 81.4;
  SEDSABSO(population_size=40, one phase) x 60: 89.7, 75.5, 85.0. The best random feasible draw
  of the default's budget (4040): 150.0, 141.7, 181.9. LDWPSO also compiles fastest:
  every place a swarm evaluates the fitness inlines the regressor into the compiled loop, twice for
  LDWPSO (initial population, step), five times for SEDSABSO (initial population, two
  antennae, new positions, SA candidates), and compilation dominates a design's time on
  a CPU.
  Measured on the shared 2-core CPU (load about 3.5): the default RS010N design takes
  18.6 s from a fresh process, base parameters included (swarm compile 5.4 s, swarm run
  2.0 s, random baseline 6.1 s with its own compilation), 4-5 s when called again.

:func:`design_excitation` also runs the random baseline: as many uniform draws from the
same box as the swarm made evaluations, scored by the same fitness; its best feasible
draw's condition number on the full grid is ``ExcitationDesign.random_cond``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import PRNGKeyArray

from .._output import jsonable
from ..dynamics._base_parameters import BaseParameters, base_parameters
from ..dynamics._limits import JointLimits
from ..dynamics._regressor import check_memory_budget, sample_bytes
from ..dynamics._robot import Robot
from ..optim._box import check_bounds
from ..optim._driver import minimise
from ..optim._ldwpso import LDWPSO
from ..optim._result import Result
from ..optim._swarm import AbstractSwarm
from ._checks import check_trajectory
from ._fitness import PENALTY, DesignProblem, condition_number, design_fitness
from ._trajectory import DEFAULT_WF, FourierTrajectory, check_wf

#: Defaults of :func:`design_excitation` (see the module docstring).
DEFAULT_HARMONICS = 5
DEFAULT_DURATION = 10.0
DEFAULT_RATE = 100.0
DEFAULT_DESIGN_SAMPLES = 100
DEFAULT_ITERATIONS = 100
#: Random draws per compiled batch of the random baseline on the CPU: small batches stay
#: in cache (4040 draws on the 2-core CPU: 1.8 s in batches of 40, 2.5 s of 128, 3.2 s
#: of 256).
RANDOM_BATCH = 40


def random_batch(draws: int, n_joints: int, design_samples: int,
                 memory_budget: int | None = None) -> int:
    """Random draws per compiled batch of the random baseline: :data:`RANDOM_BATCH` on the
    CPU; on an accelerator all ``draws`` at once, or as many as ``memory_budget`` bytes
    allow (each draw evaluates the regressor at ``design_samples`` times twice; at least
    one draw)."""
    budget = check_memory_budget(memory_budget)
    if jax.default_backend() == "cpu":
        return RANDOM_BATCH
    per_draw = 2 * design_samples * sample_bytes(n_joints)
    return int(max(1, min(draws, budget // per_draw)))


@eqx.filter_jit
def _random_batch(problem: DesignProblem, lower, upper, key, size: int, valid):
    """``size`` uniform draws in the box, of which the first ``valid`` count: the best
    (x, fitness) among them and how many were feasible."""
    X = lower + (upper - lower) * jax.random.uniform(key, (size, lower.shape[0]), lower.dtype)
    f = jax.vmap(lambda x: design_fitness(x, problem))(X)
    f = jnp.where(jnp.isfinite(f) & (jnp.arange(size) < valid), f, jnp.inf)
    i = jnp.argmin(f)
    return X[i], f[i], jnp.sum(f < PENALTY)


def coefficient_box(limits: JointLimits, n_harmonics: int = DEFAULT_HARMONICS,
                    wf: float = DEFAULT_WF) -> tuple[np.ndarray, np.ndarray]:
    """Bounds ``(lower, upper)`` on :meth:`FourierTrajectory.to_vector` derived from the
    limits.

    Harmonic ``k`` of joint ``j`` alone, with amplitude ``r``, moves the joint by ``r / (k
    wf)``, at speed ``r`` and acceleration ``r k wf``; the largest amplitude that keeps all
    three inside the limits is ``c_jk = min(qd_max, qdd_max / (k wf), R k wf)``, ``R``
    half the position range (pi when unbounded). The box is ``|a_k|, |b_k| <= c_jk /
    sqrt(2 N)``: each harmonic's amplitude ``sqrt(a_k^2 + b_k^2)`` is then at most
    ``c_jk / sqrt(N)``, so the root-sum-square of the N amplitudes is at most ``c_jk``.
    About a third of the box is feasible for RS010N (Table 3, N = 5), and on RS010N the
    swarm found better designs in this box than in ones 1.4 times wider or 1.1 times
    narrower (measured, 3-4 seeds each). ``q0``: the middle half of the position range
    (``[-pi/2, pi/2]`` when unbounded), leaving room for the motion about it.
    """
    n = limits.n_joints
    N = int(n_harmonics)
    if N < 1:
        raise ValueError(f"n_harmonics must be >= 1, got {n_harmonics!r}")
    wf = check_wf(wf)
    q_min, q_max = np.asarray(limits.q_min), np.asarray(limits.q_max)
    bounded = np.isfinite(q_min) & np.isfinite(q_max)
    half = np.where(bounded, (q_max - q_min) / 2, math.pi)
    mid = np.where(bounded, (q_max + q_min) / 2, 0.0)
    kw = wf * np.arange(1, N + 1)
    c = np.minimum.reduce([
        np.broadcast_to(np.asarray(limits.qd_max)[:, None], (n, N)),
        np.asarray(limits.qdd_max)[:, None] / kw,
        half[:, None] * kw,
    ]) / math.sqrt(2 * N)
    upper = np.concatenate([c.ravel(), c.ravel(), mid + half / 2])
    lower = np.concatenate([-c.ravel(), -c.ravel(), mid - half / 2])
    return lower, upper


@dataclass(frozen=True, eq=False)
class ExcitationDesign:
    """What :func:`design_excitation` returns.

    Attributes:
        trajectory: the designed trajectory (feasible at ``times``).
        cond: its cond(W_b) over ``times``.
        random_cond: cond(W_b) over ``times`` of the best feasible trajectory among as many
            uniform random draws from the same box as the swarm made evaluations
            (``inf`` when none was feasible).
        times: the sample times (``duration * rate`` of them, from 0, endpoint excluded).
        result: the swarm's :class:`~sedsabso_jax.Result` (fitness on the design grid).
        random_trajectory: that best random trajectory (None when none was feasible).
        design_cond: the trajectory's cond on the design grid (what the swarm minimised).
        n_random: random draws made; n_random_feasible: how many were feasible.
        design_samples: size of the design grid.
        random_s: wall time of the random baseline (compilation included).
    """

    trajectory: FourierTrajectory
    cond: float
    random_cond: float
    times: np.ndarray
    result: Result
    random_trajectory: FourierTrajectory | None
    design_cond: float
    n_random: int
    n_random_feasible: int
    design_samples: int
    random_s: float
    robot_name: str = ""

    def summary(self) -> dict:
        """JSON-ready figures of the design (for results files)."""
        tr = self.trajectory
        return {"n_harmonics": tr.n_harmonics, "wf": tr.wf, "period_s": tr.period,
                "samples": len(self.times),
                "rate_hz": float(1.0 / (self.times[1] - self.times[0]))
                if len(self.times) > 1 else None,
                "cond": float(self.cond), "random_cond": jsonable(self.random_cond),
                "design_samples": self.design_samples, "design_cond": float(self.design_cond),
                "solver": self.result.method, "evaluations": int(self.result.n_evaluations),
                "n_random": self.n_random, "n_random_feasible": self.n_random_feasible,
                "a": np.asarray(tr.a).tolist(), "b": np.asarray(tr.b).tolist(),
                "q0": np.asarray(tr.q0).tolist()}

    def __repr__(self) -> str:
        tr = self.trajectory
        dt = float(self.times[1] - self.times[0]) if len(self.times) > 1 else float("nan")
        return (
            f"ExcitationDesign({self.robot_name!r}, N={tr.n_harmonics}, wf={tr.wf:.6g} rad/s "
            f"(period {tr.period:.6g} s), {len(self.times)} samples at {1 / dt:.6g} Hz: "
            f"cond {self.cond:.6g} (design grid of {self.design_samples}: "
            f"{self.design_cond:.6g}); best random feasible {self.random_cond:.6g} "
            f"({self.n_random_feasible} of {self.n_random} draws feasible); "
            f"{self.result.method} {int(self.result.n_evaluations)} evaluations, compile "
            f"{self.result.compile_s:.2f} s, run {self.result.run_s:.2f} s, random "
            f"{self.random_s:.2f} s)"
        )


def default_solver() -> LDWPSO:
    """The default swarm of :func:`design_excitation`: LDWPSO with 40 particles (the
    paper's LDWPSO settings otherwise); the module docstring compares it with BSO and
    SEDSABSO on this problem."""
    return LDWPSO(population_size=40)


class DesignSearch(eqx.Module):
    """How :func:`design_excitation` searches (module docstring): ``solver``, any of the
    package's swarms (None: :func:`default_solver`), run for ``iterations``; the condition
    number taken at ``design_samples`` equally spaced times of the experiment;
    ``graded_penalty`` orders infeasible trajectories by how far they break the limits
    (False: the paper's constant penalty)."""

    solver: AbstractSwarm | None = None
    iterations: int = DEFAULT_ITERATIONS
    design_samples: int = DEFAULT_DESIGN_SAMPLES
    graded_penalty: bool = True

    def __check_init__(self) -> None:
        if self.solver is not None and not isinstance(self.solver, AbstractSwarm):
            raise TypeError(f"solver must be one of the package's swarms (SEDSABSO, BSO, "
                            f"LDWPSO), got {type(self.solver).__name__}")
        for name in ("iterations", "design_samples"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
                    or value < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
        if not isinstance(self.graded_penalty, (bool, np.bool_)):
            raise TypeError(f"graded_penalty must be True or False, got "
                            f"{self.graded_penalty!r}")

    @property
    def swarm(self) -> AbstractSwarm:
        """The solver, or :func:`default_solver`."""
        return default_solver() if self.solver is None else self.solver


def design_excitation(robot: Robot, limits: JointLimits, *, n_harmonics: int = DEFAULT_HARMONICS,
                      wf: float = DEFAULT_WF, duration: float = DEFAULT_DURATION,
                      rate: float = DEFAULT_RATE, search: DesignSearch = DesignSearch(),
                      key: PRNGKeyArray | int | None = None,
                      base: BaseParameters | None = None,
                      memory_budget: int | None = None) -> ExcitationDesign:
    """Design an excitation trajectory by Eq. 9 with a swarm; compare with random search.

    The experiment samples ``times = arange(round(duration * rate)) / rate``. ``search``
    (:class:`DesignSearch`): the swarm and its iterations, and the design grid: the swarm's
    condition number is taken at ``search.design_samples`` equally spaced times over
    ``[0, duration)``, the limits at as many over one period with
    :func:`~._fitness.sampling_margin`, so the design meets them at every time;
    ``ExcitationDesign.cond`` is recomputed at ``times``. The search box is
    :func:`coefficient_box`. ``key``: a JAX PRNG key or an int seed (default 0), the same
    key giving the same design; ``base``: the robot's base
    parameters when already computed; ``memory_budget``: bytes the random baseline's
    batches and the final condition number may take at once on an accelerator (at least
    1 MB; see :func:`random_batch`); the CPU keeps its small cache-sized batches. Raises
    RuntimeError when the swarm found no feasible trajectory.
    """
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a Robot, got {type(robot).__name__}")
    if not isinstance(limits, JointLimits):
        raise TypeError(f"limits must be JointLimits, got {type(limits).__name__}")
    n = robot.n_joints
    if limits.n_joints != n:
        raise ValueError(f"limits are for {limits.n_joints} joints, robot {robot.name!r} has {n}")
    if not isinstance(n_harmonics, (int, np.integer)) or n_harmonics < 1:
        raise ValueError(f"n_harmonics must be an integer >= 1, got {n_harmonics!r}")
    if not isinstance(search, DesignSearch):
        raise TypeError(f"search must be a DesignSearch(solver=..., iterations=..., "
                        f"design_samples=...), got {type(search).__name__}")
    design_samples = int(search.design_samples)
    wf = check_wf(wf)
    for name, span in (("duration", duration), ("rate", rate)):
        if not (isinstance(span, (int, float, np.number)) and math.isfinite(span)
                and span > 0):
            raise ValueError(f"{name} must be a positive number, got {span!r}")
    n_samples = int(round(duration * rate))
    if n_samples < 2:
        raise ValueError(f"duration * rate must give at least 2 samples, got {n_samples}")
    check_memory_budget(memory_budget)
    base = base_parameters(robot) if base is None else base
    if not isinstance(base, BaseParameters) or base.robot.n_params != robot.n_params:
        raise ValueError(f"base must be the BaseParameters of robot {robot.name!r} "
                         f"({robot.n_params} parameters), got {base!r}")
    if design_samples * n < base.rank:
        raise ValueError(f"design_samples * n_joints = {design_samples * n} rows cannot "
                         f"determine {base.rank} base parameters; raise design_samples")
    if key is None or isinstance(key, (int, np.integer)):
        key = jax.random.key(0 if key is None else int(key))
    times = np.arange(n_samples) / rate
    problem = DesignProblem.build(robot, base, limits, int(n_harmonics), wf, duration,
                                  design_samples, bool(search.graded_penalty))
    lower, upper = check_bounds(*coefficient_box(limits, n_harmonics, wf))
    k_swarm, k_random = jax.random.split(key)
    result = minimise(design_fitness, search.swarm, lower, upper, key=k_swarm,
                      iterations=int(search.iterations), args=problem)
    if not float(result.f) < PENALTY:
        raise RuntimeError(
            f"no feasible excitation trajectory for {robot.name!r} in "
            f"{int(result.n_evaluations)} evaluations (best fitness {float(result.f):.6g}); "
            "give the swarm more iterations or a larger population")
    traj = FourierTrajectory.from_vector(result.x, n, n_harmonics, wf)
    check_trajectory(traj, limits, times)
    cond = condition_number(base, *traj.sample(times), memory_budget=memory_budget)

    # Random baseline: as many uniform draws from the same box as the swarm's evaluations,
    # in batches of a fixed size (one compilation), the best by the same fitness.
    t0 = time.perf_counter()
    budget = int(result.n_evaluations)
    batch = random_batch(budget, n, design_samples, memory_budget)
    lo, hi = jnp.asarray(lower), jnp.asarray(upper)
    best_x, best_f, n_feasible = None, math.inf, 0
    for i in range(math.ceil(budget / batch)):
        valid = jnp.int32(min(batch, budget - i * batch))
        x, f, nf = _random_batch(problem, lo, hi, jax.random.fold_in(k_random, i), batch, valid)
        n_feasible += int(nf)
        if float(f) < best_f:
            best_x, best_f = x, float(f)
    random_s = time.perf_counter() - t0
    random_traj, random_cond = None, math.inf
    if best_f < PENALTY:
        # best_x is set whenever best_f is below the penalty
        random_traj = FourierTrajectory.from_vector(best_x,  # type: ignore[arg-type]
                                                    n, n_harmonics, wf)
        random_cond = condition_number(base, *random_traj.sample(times),
                                       memory_budget=memory_budget)
    return ExcitationDesign(
        trajectory=traj, cond=cond, random_cond=random_cond, times=times, result=result,
        random_trajectory=random_traj, design_cond=float(result.f), n_random=budget,
        n_random_feasible=n_feasible, design_samples=design_samples, random_s=random_s,
        robot_name=robot.name,
    )

