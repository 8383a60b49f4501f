"""``sedsabso-jax compare``: run algorithms on a suite with equal budgets in fitness
evaluations, many seeded runs per problem in one compiled call, and keep every run's
final value and history.

One JSON per problem (``DIR/problems/<name>.json``) is written atomically as soon as the
problem is done, so an interrupted comparison resumes where it stopped: a problem whose
file holds the same settings is read back, not run again; a file with other settings is
an error (use another ``--out``), never silently mixed in.

Seeds: run ``r`` of algorithm ``a`` on a problem uses ``jax.random.key(seed)`` folded with
the problem's and the algorithm's names (CRC-32) and the instance; the same settings give
the same numbers.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import time
import zlib
from collections.abc import Callable, Iterable

import jax
import numpy as np

from .._output import PathLike, jsonable, write_text
from .._version import __version__
from ..optim._budget import evaluation_counts, iterations_for_budget
from ..optim._driver import minimise
from ..optim._external import Evosax, evosax_names
from ..optim._fitness import BlackBox
from ..optim._registry import SWARMS
from ..optim._solver import AbstractSolver
from . import _problems as P
from ._statistics import run_lengths

SCHEMA = "sedsabso-jax/compare/1"
#: the default line-up: the paper's three swarms, evosax's PSO with evosax's own settings
#: (a textbook PSO from a general library) and CMA-ES, BBOB's reference method.
DEFAULT_ALGORITHMS = ("SEDSABSO", "BSO", "LDWPSO", "PSO", "CMA_ES")
#: evaluations per run, times the dimension: ``compare --suite all --runs 100`` took 27.8 min
#: on a quiet 2-core CPU (README, "compare")
DEFAULT_BUDGET = "500d"
#: BBOB targets on f - f_opt (COCO's 51 targets, 1e2 .. 1e-8); identification targets on
#: the relative excess over the exact optimum (1 .. 1e-8).
TARGETS = {"bbob": 10.0 ** np.linspace(2, -8, 51),
           "identification": 10.0 ** np.linspace(0, -8, 41)}
#: history kept per run: the best precision at this many log-spaced evaluation counts
CHECKPOINTS = 24


@dataclasses.dataclass(frozen=True)
class Settings:
    """What a comparison runs (all of it lands in every problem file)."""

    suite: str = "all"
    algorithms: tuple[str, ...] = DEFAULT_ALGORITHMS
    runs: int = 100
    budget: str = DEFAULT_BUDGET  # evaluations: "N" in all, or "Nd": N times the dimension
    seed: int = 0
    instances: int = P.BBOB_INSTANCES
    dimensions: tuple[int, ...] = P.BBOB_DIMENSIONS
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
        for name in ("runs", "seed", "instances"):
            v = getattr(self, name)
            low = 0 if name == "seed" else 1
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
                raise ValueError(f"{name} must be an integer >= {low}, got {v!r}")
        if self.suite != "identification" and self.runs < self.instances:
            raise ValueError(f"runs ({self.runs}) must be at least the number of BBOB "
                             f"instances ({self.instances}): each instance needs a run")
        parse_budget(self.budget)
        for d in self.dimensions:
            if isinstance(d, bool) or not isinstance(d, (int, np.integer)) or not 2 <= d <= 100:
                raise ValueError(f"BBOB dimensions must be integers from 2 to 100, got {d!r}")
        if self.dtype not in ("float32", "float64"):
            raise ValueError(f"dtype must be float32 or float64, got {self.dtype!r}")


def parse_budget(text: str | int) -> tuple[int, bool]:
    """``"20000"`` -> (20000, False): evaluations in all; ``"1000d"`` -> (1000, True): per
    dimension of the problem."""
    m = re.fullmatch(r"\s*([0-9]+)\s*(d?)\s*", str(text))
    if not m or int(m.group(1)) < 1:
        raise ValueError(f"budget: expected a number of fitness evaluations >= 1, in all "
                         f"(e.g. 20000) or per dimension (e.g. 1000d), got {text!r}")
    return int(m.group(1)), bool(m.group(2))


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


def _split_runs(runs: int, n: int) -> list[int]:
    return [runs // n + (i < runs % n) for i in range(n)]


def run_problem(problem: P.Problem, settings: Settings) -> dict:
    """All algorithms on one problem: the document written to its JSON file."""
    dim, budget = problem.dim, settings.evaluations(problem.dim)
    targets = TARGETS[problem.suite]
    dtype = jax.numpy.float32 if settings.dtype == "float32" else jax.numpy.float64
    out = {}
    for name in settings.algorithms:
        solver = solver_for(name)
        iterations = iterations_for_budget(solver, budget, dim)
        counts = evaluation_counts(solver, iterations, dim)
        grid = np.unique(np.geomspace(counts[0], counts[-1], CHECKPOINTS).round()).astype(int)
        finals, precisions, lengths, hist = [], [], [], []
        compile_s = run_s = 0.0
        runs = _split_runs(settings.runs, len(problem.instances))
        for i, (inst, n) in enumerate(zip(problem.instances, runs)):
            if n == 0:
                continue
            r = minimise(inst.fitness, solver, problem.lower, problem.upper,
                         key=_key(settings, problem.name, name, i), iterations=iterations,
                         runs=n, dtype=dtype, batch="vmap")
            compile_s += r.compile_s or 0.0
            run_s += r.run_s or 0.0
            f = np.asarray(r.f, dtype=float)
            h = inst.precision(np.asarray(r.history_f, dtype=float))
            finals.append(f)
            precisions.append(inst.precision(f))
            lengths.append(run_lengths(h, counts, targets))
            at = np.searchsorted(counts, grid, side="right") - 1  # last iteration within
            hist.append(np.minimum.accumulate(h, axis=-1)[:, np.maximum(at, 0)])
        out[name] = {
            "label": label(name), "iterations": int(iterations),
            "evaluations": int(counts[-1]), "compile_s": compile_s, "run_s": run_s,
            "final": np.concatenate(finals), "precision": np.concatenate(precisions),
            "run_lengths": np.concatenate(lengths),
            "history": {"evaluations": grid, "precision": np.concatenate(hist)},
            "instance_of_run": np.repeat(np.arange(len(runs)), runs),
        }
    return {"schema": SCHEMA, "settings": _settings_doc(settings), "problem": {
        "name": problem.name, "suite": problem.suite, "dim": dim,
        "description": problem.description, "budget": budget,
        "precision": problem.precision_label, "targets": targets,
        "f_opt": [inst.f_opt for inst in problem.instances],
        "scale": [inst.scale for inst in problem.instances]}, "algorithms": out}


def _settings_doc(settings: Settings) -> dict:
    """The settings that decide a problem's numbers (the suite does not)."""
    doc = dataclasses.asdict(settings)
    doc.pop("suite")
    doc.pop("dimensions")
    return jsonable({**doc, "version": __version__})


def problem_path(out_dir: PathLike, name: str) -> str:
    return os.path.join(out_dir, "problems", f"{name}.json")


def load_finished(path: PathLike, settings: Settings) -> dict | None:
    """A problem's document if its file exists with these settings; None if it does not
    exist. Raises ValueError when it holds other settings or cannot be read."""
    if not os.path.exists(path):
        return None
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except (OSError, json.JSONDecodeError) as err:
        raise ValueError(f"{path}: cannot be read as a comparison result ({err}); remove it "
                         f"to run that problem again") from None
    want = _settings_doc(settings)
    if doc.get("schema") != SCHEMA or doc.get("settings") != want:
        have = doc.get("settings", {})
        diff = sorted(k for k in set(want) | set(have) if want.get(k) != have.get(k))
        raise ValueError(f"{path} holds results of other settings ({', '.join(diff)}); use "
                         f"another --out, or the settings it was run with")
    return doc


def compare(settings: Settings, out_dir: PathLike,
            progress: Callable[[str, int, int, float], None] | None = None) -> list[dict]:
    """Run (or read back) every problem of the suite; returns their documents."""
    settings.check()
    names = P.problem_names(settings.suite, settings.dimensions)
    paths = [problem_path(out_dir, n) for n in names]
    docs = [load_finished(p, settings) for p in paths]  # bad files fail before any run
    todo = [n for n, d in zip(names, docs) if d is None]
    built = {n: P.load_problem(n, settings.instances) for n in todo}
    check_dimensions(settings, {p.dim for p in built.values()})
    t0 = time.perf_counter()
    done = sum(d is not None for d in docs)
    for k, (name, path) in enumerate(zip(names, paths)):
        if docs[k] is not None:
            continue
        if progress:
            progress(name, done, len(names), time.perf_counter() - t0)
        docs[k] = jsonable(run_problem(built.pop(name), settings))
        os.makedirs(os.path.dirname(path), exist_ok=True)
        # compact: a problem holds runs x checkpoints numbers per algorithm
        write_text(path, json.dumps(docs[k], allow_nan=False, separators=(",", ":")) + "\n")
        done += 1
    if progress:
        progress("done", len(names), len(names), time.perf_counter() - t0)
    return [d for d in docs if d is not None]  # every problem is done here


def estimated_seconds(done: int, total: int, elapsed: float) -> float:
    """Seconds left at the pace so far (nan before the first problem)."""
    return math.nan if done == 0 else elapsed / done * (total - done)
