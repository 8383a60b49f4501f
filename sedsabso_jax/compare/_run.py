"""``sedsabso-jax compare``'s runs: one TASK is one algorithm on one problem, a batch of
seeded runs (all of a BBOB problem's instances) through the compiled code the process
keeps per (algorithm, dimension); its result is one document, kept as one JSON file
(:mod:`._campaign` runs the tasks, in this process or on Dask workers).

Seeds: the runs of algorithm ``a`` on instance ``i`` of a problem use
``jax.random.key(seed)`` folded with the problem's and the algorithm's names (CRC-32) and
``i`` (COCO's instance number on BBOB, 0 on the identification problems), split into the
runs; the same settings give the same numbers wherever a task runs.
"""

from __future__ import annotations

import dataclasses
import math
import re
import zlib
from collections.abc import Callable, Iterable

import equinox as eqx
import jax
import numpy as np

from .._output import jsonable
from .._version import __version__
from ..optim._budget import evaluation_counts, iterations_for_budget
from ..optim._driver import minimise
from ..optim._external import Evosax, evosax_names
from ..optim._fitness import BlackBox
from ..optim._registry import SWARMS
from ..optim._solver import AbstractSolver
from . import _alignment, _bbob, _cocodata
from . import _problems as P
from ._statistics import COCO_TARGETS, run_lengths

SCHEMA = "sedsabso-jax/compare-task/1"
#: the default line-up: the paper's three swarms, evosax's PSO with evosax's own settings
#: (a textbook PSO from a general library) and CMA-ES, BBOB's reference method.
DEFAULT_ALGORITHMS = ("SEDSABSO", "BSO", "LDWPSO", "PSO", "CMA_ES")
#: evaluations per run, times the dimension
DEFAULT_BUDGET = "500d"
#: targets on the precision: COCO's 51 on BBOB (1e2 .. 1e-8, as cocopp aligns them), 41 on
#: the relative excess over the exact optimum of the identification problems (1 .. 1e-8)
TARGETS = {"bbob": COCO_TARGETS, "identification": 10.0 ** np.linspace(0, -8, 41)}
#: history kept per run: the best precision at this many log-spaced evaluation counts
CHECKPOINTS = 24


def _canonical_names(value: Iterable[str]) -> tuple[str, ...]:
    """The algorithms' names as given, files under the bare evosax name."""
    return tuple(canonical(a) for a in value)


def _numbers(name: str) -> Callable[[object], object]:
    """The converter of a list of numbers: text (``"1-5,7"``) parsed, a sequence as a
    tuple, anything else as given."""
    def convert(value: object) -> object:
        if isinstance(value, str):
            return _bbob.parse_numbers(value, name)
        return tuple(value) if isinstance(value, Iterable) else value
    return convert


class Settings(eqx.Module):
    """What a comparison runs: the suite, the algorithms, and per task the budget and the
    runs (all of it lands in every task file that it decides)."""

    suite: str = "all"
    algorithms: tuple[str, ...] = eqx.field(default=DEFAULT_ALGORITHMS,
                                            converter=_canonical_names)
    runs: int = 100  # per identification problem; BBOB: one per instance
    budget: str = DEFAULT_BUDGET  # evaluations: "N" in all, or "Nd": N times the dimension
    seed: int = 0
    functions: tuple[int, ...] = eqx.field(
        default=tuple(range(1, len(_bbob.FUNCTIONS) + 1)), converter=_numbers("functions"))
    dimensions: tuple[int, ...] = eqx.field(default=_bbob.DIMENSIONS,
                                            converter=_numbers("dimensions"))
    instances: tuple[int, ...] = eqx.field(default=_bbob.DEFAULT_INSTANCES,
                                           converter=_numbers("instances"))
    dtype: str = "float64"

    def evaluations(self, dim: int) -> int:
        """The budget in fitness evaluations for a problem of dimension ``dim``."""
        value, per_dim = parse_budget(self.budget)
        return value * dim if per_dim else value

    def check(self) -> None:
        """Everything that does not need the problems built: names, numbers."""
        if self.suite not in P.SUITES:
            raise ValueError(f"unknown suite {self.suite!r}; expected one of "
                             f"{', '.join(P.SUITES)}")
        if not self.algorithms:
            raise ValueError("no algorithm given")
        for name in self.algorithms:
            solver_for(name)
        if len(set(self.algorithms)) != len(self.algorithms):
            raise ValueError(f"an algorithm is named twice: {', '.join(self.algorithms)}")
        for name in ("runs", "seed"):
            v = getattr(self, name)
            low = 0 if name == "seed" else 1
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
                raise ValueError(f"{name} must be an integer >= {low}, got {v!r}")
        parse_budget(self.budget)
        for name in ("functions", "dimensions", "instances"):
            if not isinstance(getattr(self, name), tuple):
                raise ValueError(f"{name}: expected numbers, e.g. (1, 2, 3) or '1-3', got "
                                 f"{getattr(self, name)!r}")
        if self.suite != "identification":
            _bbob.check(self.functions, self.dimensions, self.instances)
        if self.dtype not in ("float32", "float64"):
            raise ValueError(f"dtype must be float32 or float64, got {self.dtype!r}")

    def tasks(self) -> list[Task]:
        """Every (problem, algorithm) of the comparison, in run order."""
        names = P.problem_names(self.suite, self.dimensions, self.functions)
        return [Task(p, a) for p in names for a in self.algorithms]


@dataclasses.dataclass(frozen=True)
class Task:
    """One algorithm on one problem: a batch of seeded runs, one result file."""

    problem: str
    algorithm: str

    @property
    def suite(self) -> str:
        return "bbob" if _bbob.parse_name(self.problem) else "identification"

    @property
    def dim(self) -> int | None:
        parsed = _bbob.parse_name(self.problem)
        return None if parsed is None else parsed[1]


def parse_budget(text: str | int) -> tuple[int, bool]:
    """``"20000"`` -> (20000, False): evaluations in all; ``"1000d"`` -> (1000, True): per
    dimension of the problem."""
    m = re.fullmatch(r"\s*([0-9]+)\s*(d?)\s*", str(text))
    if not m or int(m.group(1)) < 1:
        raise ValueError(f"budget: expected a number of fitness evaluations >= 1, in all "
                         f"(e.g. 20000) or per dimension (e.g. 1000d), got {text!r}")
    return int(m.group(1)), bool(m.group(2))


def canonical(name: str) -> str:
    """An algorithm's name in files and folders: ``evosax:PSO`` is ``PSO``."""
    return name if name in SWARMS else name.removeprefix("evosax:")


def solver_for(name: str) -> AbstractSolver:
    """The solver called ``name``: a swarm of the paper (its Sec. 5.2 settings) or an
    evosax strategy (its own defaults; ``evosax:NAME`` also works)."""
    if name in SWARMS:
        return SWARMS[name].paper()
    bare = name.removeprefix("evosax:")
    try:
        known = evosax_names()
    except ImportError:
        known = ()
        if bare not in SWARMS:
            raise ValueError(f"algorithm {name!r} is not one of the swarms {tuple(SWARMS)}, "
                             f"and evosax strategies need evosax: pip install "
                             f"'sedsabso-jax[compare]'") from None
    if bare not in known:
        raise ValueError(f"unknown algorithm {name!r}; expected one of {', '.join(SWARMS)} "
                         f"or an evosax strategy ({', '.join(known)})")
    return Evosax(bare)


def label(name: str) -> str:
    """How an algorithm is named in reports: its solver's label."""
    return solver_for(name).label


def describe(name: str, dim: int) -> str:
    """An algorithm and its settings in one line (the COCO files' comment)."""
    solver = solver_for(name)
    where = ("the paper's settings (Actuators 2022, 11(1), 2, Sec. 5.2)" if name in SWARMS
             else "evosax's default settings")
    return (f"{solver.label}: {solver!r} with {where}, population {solver.population(dim)} "
            f"in {dim}-D")


def check_dimensions(settings: Settings, dims: Iterable[int]) -> None:
    """Every algorithm can run in every dimension within the budget: one generation fits
    and a run of two iterations traces (nothing is compiled). Raises ValueError naming
    the algorithm and the dimension."""
    for name in settings.algorithms:
        solver = solver_for(name)
        for d in sorted(set(dims)):
            try:
                iterations_for_budget(solver, settings.evaluations(d), d)
            except ValueError as err:
                raise ValueError(f"{label(name)}: {err} (--budget {settings.budget})") from None
            lower, upper = np.zeros(d), np.ones(d)
            f = BlackBox(lambda x, a: (x ** 2).sum())
            try:
                jax.eval_shape(lambda k, s=solver, lo=lower, hi=upper: _trace(s, f, lo, hi, k),
                               jax.random.key(0))
            except Exception as err:  # noqa: BLE001 - any failure to trace: say which
                first = str(err).strip().splitlines()[0] if str(err).strip() else type(err)
                raise ValueError(f"{label(name)} cannot run in {d} dimensions: {first}"
                                 ) from None


def _trace(solver, fitness, lower, upper, key):
    return solver.run(fitness, jax.numpy.asarray(lower), jax.numpy.asarray(upper), key, 2)


def _key(settings: Settings, problem: str, algorithm: str, instance: int):
    key = jax.random.key(settings.seed)
    for text in (problem, algorithm):
        key = jax.random.fold_in(key, zlib.crc32(text.encode()) & 0x7FFFFFFF)
    return jax.random.fold_in(key, instance)


def _runs_per_instance(problem: P.Problem, settings: Settings) -> list[int]:
    if problem.suite != "bbob":
        return [settings.runs]
    return [settings.instances.count(inst.number) for inst in problem.instances]


def run_algorithm(problem: P.Problem, name: str, settings: Settings) -> dict:
    """One algorithm's seeded runs on every instance of ``problem``: the runs' final
    values, precisions, run lengths to the targets and histories; on BBOB also the
    lines of COCO's ``.dat`` and ``.tdat`` files."""
    dim, budget = problem.dim, settings.evaluations(problem.dim)
    targets = TARGETS[problem.suite]
    dtype = jax.numpy.float32 if settings.dtype == "float32" else jax.numpy.float64
    solver = solver_for(name)
    iterations = iterations_for_budget(solver, budget, dim)
    counts = evaluation_counts(solver, iterations, dim)
    grid = np.unique(np.geomspace(counts[0], counts[-1], CHECKPOINTS).round()).astype(int)
    at = np.maximum(np.searchsorted(counts, grid, side="right") - 1, 0)  # last iteration within
    finals, precisions, hist, lengths = [], [], [], []
    numbers, f_opts, dat, tdat = [], [], [], []
    compile_s = run_s = 0.0
    for inst, n in zip(problem.instances, _runs_per_instance(problem, settings)):
        r = minimise(inst.fitness, solver, problem.lower, problem.upper,
                     key=_key(settings, problem.name, name, inst.number), iterations=iterations,
                     runs=n, dtype=dtype, batch="vmap")
        if not np.all(np.asarray(r.n_evaluations) == counts[-1]):
            raise RuntimeError(f"{label(name)} spent {np.asarray(r.n_evaluations)} evaluations "
                               f"on {problem.name}, not the {counts[-1]} of its iterations")
        compile_s += r.compile_s or 0.0
        run_s += r.run_s or 0.0
        best = np.minimum.accumulate(np.asarray(r.history_f, dtype=float), axis=-1)
        finals.append(np.asarray(r.f, dtype=float))
        precisions.append(inst.precision(finals[-1]))
        hist.append(inst.precision(best)[:, at])
        numbers += [inst.number] * n
        f_opts += [inst.f_opt] * n
        if problem.suite == "bbob":
            for run in best:
                lines = _cocodata.run_lines(counts, run, inst.f_opt, dim)
                dat.append(lines[0])
                tdat.append(lines[1])
        else:
            lengths.append(run_lengths(inst.precision(best), counts, targets))
    if problem.suite == "bbob":  # as cocopp reads them off the .dat lines
        lengths = [_alignment.run_lengths(
            [np.array([(k, _cocodata.printed_precision(f, fo)) for k, f in lines])
             for lines, fo in zip(dat, f_opts)], targets)]
    out = {
        "label": label(name), "iterations": int(iterations),
        "evaluations": int(counts[-1]), "compile_s": compile_s, "run_s": run_s,
        "final": np.concatenate(finals), "precision": np.concatenate(precisions),
        "run_lengths": np.concatenate(lengths),
        "history": {"evaluations": grid, "precision": np.concatenate(hist)},
        "instance_of_run": numbers,
    }
    if problem.suite == "bbob":
        out["coco"] = {"comment": describe(name, dim), "f_opt": f_opts, "dat": dat,
                       "tdat": tdat}
    return out


def problem_doc(problem: P.Problem, settings: Settings) -> dict:
    """The problem's part of a result document."""
    return {"name": problem.name, "suite": problem.suite, "dim": problem.dim,
            "description": problem.description, "budget": settings.evaluations(problem.dim),
            "precision": problem.precision_label, "targets": TARGETS[problem.suite],
            "f_opt": [inst.f_opt for inst in problem.instances],
            "scale": [inst.scale for inst in problem.instances],
            "instances": [inst.number for inst in problem.instances]}


def run_task(task: Task, settings: Settings) -> dict:
    """One task's document (what its JSON file holds), computed wherever it runs."""
    problem = P.load_problem(task.problem, settings.instances)
    return jsonable({"schema": SCHEMA, "settings": task_settings(settings, task),
                     "problem": problem_doc(problem, settings),
                     "algorithms": {task.algorithm: run_algorithm(problem, task.algorithm,
                                                                  settings)}})


def run_problem(problem: P.Problem, settings: Settings) -> dict:
    """Every algorithm of ``settings`` on one problem, in this process: the document of
    its tasks merged (their ``algorithms`` side by side)."""
    return jsonable({"schema": SCHEMA, "settings": task_settings(settings, None),
                     "problem": problem_doc(problem, settings),
                     "algorithms": {a: run_algorithm(problem, a, settings)
                                    for a in settings.algorithms}})


def task_settings(settings: Settings, task: Task | None) -> dict:
    """The settings that decide a task's numbers (``task`` None: those of any task)."""
    doc: dict = {"budget": settings.budget, "seed": settings.seed, "dtype": settings.dtype,
                 "version": __version__}
    if task is not None:
        doc["algorithm"] = task.algorithm
        doc.update({"instances": list(settings.instances)} if task.suite == "bbob"
                   else {"runs": settings.runs})
    return doc


def estimated_seconds(done: int, total: int, elapsed: float) -> float:
    """Seconds left at the pace so far (nan before the first problem)."""
    return math.nan if done == 0 else elapsed / done * (total - done)
