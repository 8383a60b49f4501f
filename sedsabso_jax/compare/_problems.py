"""The problems ``sedsabso-jax compare`` runs: COCO's ``bbob`` suite (:mod:`._bbob`) and
the package's identification problems.

BBOB (Hansen et al., "Real-parameter black-box optimization benchmarking 2009: noiseless
functions definitions", INRIA RR-6829): the 24 functions f1-f24 in the box [-5, 5]^d,
COCO's numbered instances, one run per instance. All functions and instances of one
dimension go through ONE compiled fitness (the function and the instance are runtime
arguments), so an algorithm compiles once per dimension.

Identification (the paper's Eq. 17 over a box): ``rs010n-paper`` and ``rs010n-prior``,
the experiment of ``sedsabso-jax reproduce`` in its two scenarios; ``kuka-real``, the real
KUKA LWR4+ recording 1 with the identify command's default model (viscous + Coulomb
friction, base parameters) and its swarms' box around the URDF's parameters, every
``KUKA_STRIDE``-th sample. Their optimum is the exact L1 optimum inside the box (linear
programming), so the distance to it is known as for BBOB.

Precision, what targets and figures are read on: ``f - f_opt`` for BBOB,
``(f - f_opt) / sum |tau|`` for identification (the excess L1 residual over the exact
optimum as a share of the torques' L1 norm: scale-free, and meaningful on noise-free data,
where ``f_opt`` is rounding noise).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Iterable

import numpy as np
from jaxtyping import ArrayLike, Float

from ..dynamics._robots import kuka_lwr4
from ..identification._estimators._box_search import BoxSearch
from ..identification._model._torque_model import TorqueModel
from ..measurements._load import load_kuka_lwr4
from ..optim._fitness import BlackBox, L1Residual
from ..optim._linear import l1_solve_box
from ..optim._sedsabso import SEDSABSO
from ..reproduce._experiment import Settings, build_problem
from . import _bbob

SUITES = ("bbob", "identification", "all")
IDENTIFICATION = ("rs010n-paper", "rs010n-prior", "kuka-real")
#: every KUKA_STRIDE-th sample of the KUKA recording (5027 samples at 200 Hz -> 503)
KUKA_STRIDE = 10


@dataclasses.dataclass(frozen=True)
class Instance:
    """One instance: its fitness and the value the precision is measured from."""

    fitness: BlackBox | L1Residual
    f_opt: float
    scale: float  # precision = (f - f_opt) / scale
    number: int = 0  # COCO's instance number (BBOB)

    def precision(self, f: Float[ArrayLike, "*shape"]) -> Float[np.ndarray, "*shape"]:
        return (np.asarray(f, dtype=float) - self.f_opt) / self.scale


@dataclasses.dataclass(frozen=True)
class Problem:
    """A problem of the suite: BBOB's with one :class:`Instance` per COCO instance
    number, identification's with one."""

    name: str
    suite: str  # "bbob" or "identification"
    dim: int
    lower: np.ndarray
    upper: np.ndarray
    instances: tuple[Instance, ...]
    description: str

    @property
    def precision_label(self) -> str:
        return "f - f_opt" if self.suite == "bbob" else "(f - f_opt) / sum |tau|"


def bbob_problem(function: int, dim: int, instances: Iterable[int] = _bbob.DEFAULT_INSTANCES
                 ) -> Problem:
    """BBOB function f``function`` (1-24) in ``dim`` dimensions, COCO's ``instances``
    (each number once, in order of first appearance)."""
    _bbob.check([function], [dim], tuple(instances))
    out = [Instance(BlackBox(_bbob.value, _bbob.instance_args(function, i, dim)),
                    _bbob.f_opt(function, i, dim), 1.0, i) for i in dict.fromkeys(instances)]
    box = np.full(dim, _bbob.BOX)
    return Problem(_bbob.problem_name(function, dim), "bbob", dim, -box, box, tuple(out),
                   f"BBOB f{function} ({_bbob.FUNCTIONS[function - 1]}), d = {dim}")


def _identification_instance(W, b, lower, upper) -> Instance:
    x, _ = l1_solve_box(W, b, lower, upper)
    f_opt = float(np.abs(W @ x - b).sum())
    # relative to the torques' L1 norm, not to f_opt: noise-free data have f_opt ~ 1e-9
    return Instance(L1Residual(W, b), f_opt, float(np.abs(b).sum()))


def identification_problem(name: str) -> Problem:
    """One of :data:`IDENTIFICATION`."""
    if name in ("rs010n-paper", "rs010n-prior"):
        scenario = name.split("-")[1]
        p = build_problem(Settings(scenario=scenario))
        W, b = np.asarray(p.problem.W, float), np.asarray(p.problem.tau, float)
        inst = _identification_instance(W, b, p.lower, p.upper)
        return Problem(name, "identification", W.shape[1], p.lower, p.upper, (inst,),
                       f"RS010N, reproduce's {scenario!r} scenario (Eq. 17, "
                       f"{W.shape[0]} torque rows)")
    if name == "kuka-real":
        robot = kuka_lwr4()
        data = load_kuka_lwr4(1)
        model = TorqueModel.of(robot)
        sl = slice(None, None, KUKA_STRIDE)
        q, qd, qdd, tau = (np.asarray(a, float)[sl] for a in (data.q, data.qd, data.qdd,
                                                               data.tau))
        Y = np.asarray(model.regressor(q, qd, qdd))
        W, b = Y.reshape(-1, Y.shape[-1]), tau.reshape(-1)
        lower, upper, _ = BoxSearch(SEDSABSO.paper()).bounds(model)
        inst = _identification_instance(W, b, lower, upper)
        return Problem(name, "identification", W.shape[1], lower, upper, (inst,),
                       f"KUKA LWR4+ recording 1, every {KUKA_STRIDE}th sample (Eq. 17, "
                       f"{W.shape[0]} torque rows, viscous + Coulomb friction)")
    raise ValueError(f"unknown identification problem {name!r}; expected one of "
                     f"{IDENTIFICATION}")


def problem_names(suite: str, dimensions: Iterable[int] = _bbob.DIMENSIONS,
                  functions: Iterable[int] = range(1, 25)) -> list[str]:
    """The problems of ``suite`` (``bbob``, ``identification`` or ``all``), in run order."""
    if suite not in SUITES:
        raise ValueError(f"unknown suite {suite!r}; expected one of {', '.join(SUITES)}")
    out = []
    if suite in ("bbob", "all"):
        out += [_bbob.problem_name(f, d) for d in dimensions for f in functions]
    if suite in ("identification", "all"):
        out += list(IDENTIFICATION)
    return out


@functools.cache
def load_problem(name: str, instances: tuple[int, ...] = _bbob.DEFAULT_INSTANCES) -> Problem:
    """The problem called ``name`` (as :func:`problem_names` lists it), built once per
    process."""
    parsed = _bbob.parse_name(name)
    if parsed is not None:
        return bbob_problem(*parsed, tuple(instances))
    return identification_problem(name)
