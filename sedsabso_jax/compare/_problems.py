"""The problems ``sedsabso-jax compare`` runs: the BBOB noiseless suite through evosax's
JAX implementation, and the package's identification problems.

BBOB (Hansen et al., "Real-parameter black-box optimization benchmarking 2009: noiseless
functions definitions", INRIA RR-6829): the 24 functions f1-f24 in the box [-5, 5]^d,
each instance a seeded draw of evosax's ``MetaBBOBProblem`` (optimum ``x_opt`` in
[-4, 4]^d, value ``f_opt``, rotations ``R, Q``). evosax's instances are not COCO's
numbered ones, so values are comparable within this package, not with COCO's archive. All
24 functions of one dimension go through ONE compiled fitness (``lax.switch`` on the
function's index, a runtime argument), so an algorithm compiles once per dimension.

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
from collections.abc import Callable, Iterable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..dynamics._robots import kuka_lwr4
from ..identification._box_search import BoxSearch
from ..identification._model import TorqueModel
from ..measurements._load import load_kuka_lwr4
from ..optim._fitness import BlackBox, L1Residual
from ..optim._linear import l1_solve_box
from ..optim._sedsabso import SEDSABSO
from ..reproduce._experiment import Settings, build_problem

SUITES = ("bbob", "identification", "all")
BBOB_DIMENSIONS = (5, 10, 20, 40)
BBOB_INSTANCES = 5
IDENTIFICATION = ("rs010n-paper", "rs010n-prior", "kuka-real")
#: every KUKA_STRIDE-th sample of the KUKA recording (5027 samples at 200 Hz -> 503)
KUKA_STRIDE = 10


@functools.cache
def bbob_functions() -> tuple[str, ...]:
    """evosax's names of f1-f24, in BBOB's order."""
    from evosax.problems.bbob.bbob_fns import bbob_fns

    return tuple(bbob_fns)


#: evosax's Gallagher functions, f21 (101 peaks) and f22 (21 peaks), by 0-based index:
#: (peaks, the first peak's alpha, the other peaks' range, x_opt's factor)
GALLAGHER = {20: (101, 1000.0, 5.0, 1.0), 21: (21, 1000.0 ** 2, 4.9, 3.92 / 4.0)}


@functools.cache
def _branches():
    from evosax.problems.bbob.bbob_fns import bbob_fns

    def evosax_branch(fn: Callable[..., Any]) -> Callable[..., Any]:
        return lambda x, x_opt, R, Q, peaks: fn(x, x_opt, R, Q, x.shape[0])

    def gallagher_branch(which: int) -> Callable[..., Any]:
        return lambda x, x_opt, R, Q, peaks: _gallagher(x, R, *peaks[which])

    out = [evosax_branch(bbob_fns[name]) for name in bbob_functions()]
    for which, index in enumerate(sorted(GALLAGHER)):
        out[index] = gallagher_branch(which)
    return tuple(out)


def bbob_value(x: Float[Array, " d"], args: tuple[Any, ...]) -> Float[Array, ""]:
    """BBOB function ``args[0]`` (0-based: f1 is 0) of instance ``args[1:]`` at ``x``:
    the function, its boundary penalty and ``f_opt``."""
    fid, x_opt, f_opt, R, Q, peaks = args
    value, penalty = jax.lax.switch(fid, _branches(), x, x_opt, R, Q, peaks)
    return value + penalty + f_opt


def gallagher_peaks(index: int, x_opt: Float[ArrayLike, " d"], R: Float[ArrayLike, "d d"],
                    Q: Float[Array, "d d"]
                    ) -> tuple[Float[Array, "peaks d"], Float[Array, "peaks d"],
                               Float[Array, " peaks"]]:
    """The peaks of evosax's Gallagher function ``index`` (20: f21, 21: f22) of one
    instance: ``(R y_i, the diagonal of C_i, w_i)`` per peak, drawn as evosax draws them
    (Hansen et al. 2009, p. 13). evosax draws them, and multiplies three d x d matrices per
    peak, inside every evaluation (d = 40, 101 peaks: 0.5 MFLOP a point); drawn once per
    instance, an evaluation is one product ``R x`` and a pass over the peaks."""
    from evosax.problems.bbob.bbob_fns import lambda_alpha

    n, alpha0, spread, scale = GALLAGHER[index]
    x_opt = jnp.asarray(x_opt) * scale
    d = x_opt.shape[0]
    key = jax.random.fold_in(jax.random.key(0), Q[0, 0])
    k = jnp.arange(n)
    w = jnp.where(k == 0, 10.0, 1.1 + 8.0 * (k - 1.0) / (n - 2.0))
    alpha_set = jnp.power(1000.0, 2.0 * jnp.arange(n - 1) / (n - 2))
    key, sub = jax.random.split(key)
    alpha = jnp.concatenate([jnp.array([alpha0]), jax.random.permutation(sub, alpha_set)])
    c = jax.vmap(lambda a: jnp.diag(lambda_alpha(a, d, d)) / a ** 0.25)(alpha)
    key, sub = jax.random.split(key)
    mask = jnp.ones(d, bool)
    perms = jax.vmap(lambda kk: jax.random.choice(kk, jnp.arange(d), shape=(d,),
                                                  replace=False, p=mask))(
        jax.random.split(sub, n))
    c = jnp.take_along_axis(c, perms, axis=1)
    key, sub = jax.random.split(key)
    y = jax.random.uniform(sub, (n, d), minval=-spread, maxval=spread).at[0].set(x_opt)
    return y @ jnp.asarray(R).T, c, w


def _gallagher(x, R, Ry, c, w):
    """Gallagher's Gaussian peaks function at ``x`` from its peaks
    (:func:`gallagher_peaks`): ``(osz(10 - max_i w_i exp(-z_i^T C_i z_i / 2d))^2,
    penalty)`` with ``z_i = R (x - y_i)``."""
    from evosax.problems.bbob.bbob_fns import f_pen, transform_osz

    d = x.shape[0]
    z = R @ x - Ry
    peak = w * jnp.exp(-jnp.sum(c * z * z, axis=-1) / (2 * d))
    return jnp.square(transform_osz(10.0 - jnp.max(peak))), f_pen(x, d)


@dataclasses.dataclass(frozen=True)
class Instance:
    """One instance: its fitness and the value the precision is measured from."""

    fitness: BlackBox | L1Residual
    f_opt: float
    scale: float  # precision = (f - f_opt) / scale

    def precision(self, f: Float[ArrayLike, "*shape"]) -> Float[np.ndarray, "*shape"]:
        return (np.asarray(f, dtype=float) - self.f_opt) / self.scale


@dataclasses.dataclass(frozen=True)
class Problem:
    """A problem of the suite; runs are spread evenly over its instances."""

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


@functools.cache
def _meta(dim: int):
    """evosax's BBOB meta-problem of dimension ``dim`` (its parameter draw compiles once
    per object: one per dimension)."""
    from evosax.problems.bbob.meta_bbob import MetaBBOBProblem

    return MetaBBOBProblem(fn_names=list(bbob_functions()), min_num_dims=dim,
                           max_num_dims=dim)


@functools.cache
def _instance(dim: int, k: int):
    """Instance ``k`` of dimension ``dim``, shared by the 24 functions: ``x_opt, f_opt, R,
    Q`` and the Gallagher peaks."""
    p = _meta(dim).sample_params(jax.random.key(k + 1))
    x_opt, R, Q = (jnp.asarray(a, float) for a in (p.x_opt, p.R, p.Q))
    peaks = tuple(gallagher_peaks(i, x_opt, R, Q) for i in sorted(GALLAGHER))
    return x_opt, jnp.asarray(p.f_opt, float), R, Q, peaks


def bbob_problem(index: int, dim: int, instances: int = BBOB_INSTANCES) -> Problem:
    """BBOB function f``index + 1`` in ``dim`` dimensions, ``instances`` seeded instances
    (instance k draws evosax's parameters from ``jax.random.key(k + 1)``: the same
    ``x_opt, f_opt, R, Q`` for every function, as COCO's instance numbers)."""
    from evosax.problems.bbob.bbob_fns import fn_names_dict

    names = bbob_functions()
    out = []
    for k in range(instances):
        x_opt, f_opt, R, Q, peaks = _instance(dim, k)
        args = (jnp.int32(index), x_opt, f_opt, R, Q, peaks)
        out.append(Instance(BlackBox(bbob_value, args), float(f_opt), 1.0))
    box = np.full(dim, 5.0)
    return Problem(f"bbob-f{index + 1:02d}-{names[index]}-d{dim:02d}", "bbob", dim, -box, box,
                   tuple(out), f"BBOB f{index + 1} {fn_names_dict[names[index]]}, d = {dim}")


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


def problem_names(suite: str, dimensions: Iterable[int] = BBOB_DIMENSIONS) -> list[str]:
    """The problems of ``suite`` (``bbob``, ``identification`` or ``all``), in run order."""
    if suite not in SUITES:
        raise ValueError(f"unknown suite {suite!r}; expected one of {', '.join(SUITES)}")
    out = []
    if suite in ("bbob", "all"):
        names = bbob_functions()
        out += [f"bbob-f{i + 1:02d}-{names[i]}-d{d:02d}" for d in dimensions
                for i in range(len(names))]
    if suite in ("identification", "all"):
        out += list(IDENTIFICATION)
    return out


def load_problem(name: str, instances: int = BBOB_INSTANCES) -> Problem:
    """The problem called ``name`` (as :func:`problem_names` lists it)."""
    if name.startswith("bbob-f"):
        index, dim = int(name[6:8]) - 1, int(name.rsplit("-d", 1)[1])
        return bbob_problem(index, dim, instances)
    return identification_problem(name)
