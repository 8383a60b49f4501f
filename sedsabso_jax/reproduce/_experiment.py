"""The paper's experiment (Section 5) end to end: what ``sedsabso-jax reproduce`` runs.

Steps, on the built-in RS010N (``docs/explanation/paper-notes.md`` Sec. 6):

1. base parameters of the Table 2 robot (21 of 36): the true values;
2. an excitation trajectory designed by Eq. 9 under the Table 3 limits
   (:func:`sedsabso_jax.design_excitation`), sampled at ``samples`` points over
   its 10 s period;
3. simulated torques from the true parameters, with optional Gaussian noise (relative to
   each joint's RMS torque);
4. ``runs`` runs of SEDSABSO, BSO and LDWPSO with the paper's settings on Eq. 17, inside
   the scenario's search box; OLS, optimistix Levenberg-Marquardt and the exact L1
   optimum (linear programming) on the same data.

Scenarios (the search box, recorded in the results):

* ``paper``: a box around the TRUE base parameters, ``true +- max(10 % |true|, 0.1)``,
  the paper's own (unstated, "a small interval") scenario: only fair as a reproduction.
* ``prior``: a CAD-like prior, each base parameter off by a uniform factor in
  ``[-30 %, +30 %]`` (seeded), and a box ``prior +- max(50 % |prior|, 0.5)``; the box
  contains the truth (``|true - prior| <= 0.43 |prior|``) but is centred on the prior.

Timing (per swarm): ``time_mean_s`` is one run timed on its own after compilation,
``batched_time_s`` the ``runs`` runs in one compiled call (whose results are reported);
compilation is reported apart in ``compile_s``. On a single CPU device the batched runs go
in sequence inside the one compiled call (``minimise(batch="auto")``) and the single run
is timed through that same executable asked for one run
(:func:`~sedsabso_jax.optim._driver.time_one_of_many`); on a GPU the runs are vmapped and the
single run has its own executable.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Float

from .._output import jsonable
from .._version import __version__
from ..dynamics import _robots as robots
from ..dynamics._base_parameters import BaseParameters, base_parameters
from ..dynamics._limits import JointLimits
from ..dynamics._robot import Robot
from ..excitation._design import DesignSearch, ExcitationDesign, design_excitation
from ..measurements._container import Measurements
from ..measurements._simulate import simulate_measurements
from ..optim import _baselines as baselines
from ..optim._box import box_around
from ..optim._driver import minimise, time_one_of_many
from ..optim._fitness import L1Residual
from ..optim._registry import SWARMS, paper_solver
from ._work import step_seconds

SCENARIOS = ("paper", "prior")
BASELINES = ("OLS", "LM", "L1-LP")
#: ``paper`` box half-width: max(PAPER_BOX * |true|, PAPER_BOX_FLOOR)
PAPER_BOX, PAPER_BOX_FLOOR = 0.10, 0.1
#: ``prior``: relative error of the prior, box half-width max(PRIOR_BOX * |prior|, floor)
PRIOR_ERROR, PRIOR_BOX, PRIOR_BOX_FLOOR = 0.30, 0.50, 0.5
#: excitation period and duration [s]: one period of wf = 2 pi 0.1 rad/s
DURATION = 10.0
SCHEMA = "sedsabso-jax/reproduce/2"


@dataclasses.dataclass(frozen=True)
class Settings:
    """What ``reproduce`` runs (every field lands in ``results.json["settings"]``)."""

    runs: int = 10
    iterations: int = 600
    samples: int = 1000
    noise: float = 0.0
    scenario: str = "paper"
    seed: int = 0
    dtype: str = "float64"
    design_iterations: int | None = None  # None: the excitation module's default

    def check(self) -> None:
        for name in ("runs", "iterations", "samples"):
            value = getattr(self, name)
            if not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
        if self.samples < 30:
            raise ValueError(f"samples must be >= 30 (21 base parameters need enough rows of "
                             f"data to be identifiable), got {self.samples}")
        if not (np.isfinite(self.noise) and self.noise >= 0):
            raise ValueError(f"noise must be a finite number >= 0, got {self.noise!r}")
        if self.scenario not in SCENARIOS:
            raise ValueError(f"scenario must be one of {SCENARIOS}, got {self.scenario!r}")
        if self.dtype not in ("float32", "float64"):
            raise ValueError(f"dtype must be float32 or float64, got {self.dtype!r}")
        if not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ValueError(f"seed must be an integer >= 0, got {self.seed!r}")


def scenario_box(true: np.ndarray, scenario: str, seed: int
                 ) -> tuple[Float[np.ndarray, " p"] | None, Float[np.ndarray, " p"],
                            Float[np.ndarray, " p"]]:
    """``(prior, lower, upper)`` for a scenario (see the module docstring); ``prior`` is
    None in the ``paper`` scenario."""
    true = np.asarray(true, dtype=float)
    if scenario == "paper":
        return (None, *box_around(true, PAPER_BOX, PAPER_BOX_FLOOR))
    if scenario == "prior":
        rng = np.random.default_rng([seed, 1])
        prior = true * (1.0 + rng.uniform(-PRIOR_ERROR, PRIOR_ERROR, true.shape))
        return (prior, *box_around(prior, PRIOR_BOX, PRIOR_BOX_FLOOR))
    raise ValueError(f"scenario must be one of {SCENARIOS}, got {scenario!r}")


@dataclasses.dataclass
class Experiment:
    """The outcome of :func:`run`: ``results`` (the ``results.json`` document) and the
    arrays the figures need."""

    results: dict
    history_f: dict  # method -> (runs, iterations) best fitness per iteration
    history_n: dict  # method -> (iterations,) active population
    phases: dict  # method -> [(first, end, slots), ...]: its compiled phases
    l1_floor: float


@dataclasses.dataclass
class IdentificationProblem:
    """The experiment's problem: Eq. 17 on the simulated data, the scenario's box."""

    robot: Robot
    base: BaseParameters
    true: np.ndarray  # the true base parameters
    design: ExcitationDesign  # the excitation design (Eq. 9)
    data: Measurements  # the simulated measurements
    problem: L1Residual
    prior: np.ndarray | None
    lower: np.ndarray
    upper: np.ndarray


def build_problem(settings: Settings = Settings(),
                  progress: Callable[[str], None] | None = None) -> IdentificationProblem:
    """Steps 1-3 of the module docstring and the scenario's box: the problem the swarms
    solve (also one of ``sedsabso-jax compare``'s identification problems).
    ``progress(label)`` is called before each step."""
    settings.check()
    progress = progress or (lambda label: None)
    key = jax.random.key(settings.seed)
    progress("base parameters")
    robot = robots.rs010n()
    base = base_parameters(robot)
    true = np.asarray(base.values, dtype=float)

    progress("excitation design (Eq. 9)")
    search = DesignSearch() if settings.design_iterations is None else DesignSearch(
        iterations=settings.design_iterations)
    design = design_excitation(robot, JointLimits.rs010n(), duration=DURATION,
                               rate=settings.samples / DURATION, search=search,
                               key=jax.random.fold_in(key, 0), base=base)
    times = np.asarray(design.times, dtype=float)[: settings.samples]

    progress("simulated measurements")
    q, qd, qdd = (np.asarray(a, dtype=float) for a in design.trajectory(times))
    data = simulate_measurements(robot, q, qd, qdd, times, torque_noise=settings.noise,
                                 seed=settings.seed)
    problem = L1Residual.from_base(base, data.q, data.qd, data.qdd, data.tau)
    prior, lower, upper = scenario_box(true, settings.scenario, settings.seed)
    return IdentificationProblem(robot, base, true, design, data, problem, prior, lower,
                                 upper)


def _progress_noop(label: str, done: float, total: float) -> None:
    pass


def run(settings: Settings = Settings(),
        progress: Callable[[str, float, float], None] | None = None) -> Experiment:
    """Run the experiment; ``progress(label, done, total)`` is called before each step
    and once at the end (``done == total``), ``done`` and ``total`` the estimated seconds
    of the steps finished and of all (:func:`~._work.step_seconds`, known before)."""
    settings.check()
    progress = progress or _progress_noop
    seconds = step_seconds(settings, tuple(SWARMS), BASELINES)
    total = sum(seconds)
    step = iter(itertools.accumulate([0.0, *seconds]))
    dtype = jnp.float32 if settings.dtype == "float32" else jnp.float64
    key = jax.random.key(settings.seed)

    p = build_problem(settings, lambda label: progress(label, next(step), total))
    robot, base, true, design, data = p.robot, p.base, p.true, p.design, p.data
    problem, prior, lower, upper = p.problem, p.prior, p.lower, p.upper

    algorithms, history_f, history_n, phase_slots = {}, {}, {}, {}
    for i, name in enumerate(SWARMS, start=1):
        solver = paper_solver(name)
        progress(f"{name}: {settings.runs} runs", next(step), total)
        k = jax.random.fold_in(key, i)
        many = minimise(problem, solver, lower, upper, key=k, iterations=settings.iterations,
                        runs=settings.runs, dtype=dtype)
        single_compile_s, single_s = time_one_of_many(
            problem, solver, lower, upper, key=k, iterations=settings.iterations,
            runs=settings.runs, dtype=dtype)
        x, f = np.asarray(many.x, float), np.asarray(many.f, float)
        hf = np.asarray(many.history_f, float)
        history_f[name], history_n[name] = hf, np.asarray(many.history_n[0])
        phase_slots[name] = list(solver.plan(settings.iterations).phases)
        algorithms[name] = {
            "fitness_mean": float(f.mean()), "fitness_std": float(f.std()),
            "fitness_runs": f.tolist(),
            "time_mean_s": single_s, "batched_time_s": many.run_s,
            "compile_s": single_compile_s + (many.compile_s or 0.0),
            "max_abs_error": float(np.abs(x - true).max(axis=1).mean()),
            "params_mean": x.mean(axis=0).tolist(),
            "history_median": np.median(hf, axis=0).tolist(),
            "sa_accepted_mean": float(np.mean(many.sa_accepted)),
            "n_nonfinite": int(np.sum(many.n_nonfinite)),
        }

    for name, fn in (("OLS", baselines.ols), ("LM", baselines.least_squares),
                     ("L1-LP", baselines.l1_optimum)):
        progress(name, next(step), total)
        r = fn(problem)
        x = np.asarray(r.x, float)
        algorithms[name] = {
            "fitness_mean": float(r.f), "fitness_std": 0.0, "fitness_runs": [float(r.f)],
            "time_mean_s": r.run_s, "batched_time_s": None, "compile_s": r.compile_s,
            "max_abs_error": float(np.abs(x - true).max()), "params_mean": x.tolist(),
            "history_median": [],
        }
    l1_floor = algorithms["L1-LP"]["fitness_mean"]
    torque_l1 = float(np.abs(data.tau).sum())
    for entry in algorithms.values():
        entry["gap_to_l1_optimum"] = baselines.gap_to_optimum(
            entry["fitness_mean"], l1_floor, scale=torque_l1)

    progress("done", total, total)
    device = jax.devices()[0]
    results = {
        "schema": SCHEMA,
        "settings": {
            **dataclasses.asdict(settings),
            "robot": robot.name,
            "device": f"{device.platform}: {device.device_kind}",
            "n_devices": jax.device_count(),
            "search_box": {"lower": lower.tolist(), "upper": upper.tolist(),
                           "rule": _box_rule(settings.scenario)},
            "prior": None if prior is None else prior.tolist(),
            "excitation": design.summary(),
            "solvers": {name: _fields(paper_solver(name)) for name in SWARMS},
            "versions": _versions(),
        },
        "base_parameters": {"names": list(base.names), "expressions": list(base.expressions),
                            "true": true.tolist()},
        "torque_l1_norm": torque_l1,
        "algorithms": algorithms,
    }
    return Experiment(results, history_f, history_n, phase_slots, l1_floor)


def _box_rule(scenario: str) -> str:
    if scenario == "paper":
        return f"true +- max({PAPER_BOX:g} |true|, {PAPER_BOX_FLOOR:g})"
    return (f"prior = true (1 + U(-{PRIOR_ERROR:g}, {PRIOR_ERROR:g})); "
            f"prior +- max({PRIOR_BOX:g} |prior|, {PRIOR_BOX_FLOOR:g})")


def _fields(solver) -> dict:
    return jsonable(solver.hyperparameters())


def _versions() -> dict:
    import optimistix
    import scipy

    return {"sedsabso_jax": __version__, "jax": jax.__version__, "numpy": np.__version__,
            "scipy": scipy.__version__, "optimistix": optimistix.__version__}

