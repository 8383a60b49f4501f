"""What every swarm shares: the solver contract for a population that moves with clamped
velocities, its state, and the operations on it (evaluation, personal and global bests, a
shrinking population).

A swarm is an immutable solver (an ``equinox.Module`` whose fields are its
hyperparameters) implementing :class:`AbstractSwarm`, itself an
:class:`~._solver.AbstractSolver`. Each swarm writes one iteration as :meth:`~AbstractSwarm.
update` (from given random draws) out of two halves, :meth:`~AbstractSwarm.move` (the new
positions) and the bookkeeping after their fitness is known; ``step``, ``ask``/``tell``
and ``run`` are built from them here.

A variable population (SEDSABSO's Eq. 15-16) uses a fixed number of slots with an active
mask. :meth:`~AbstractSwarm.run` splits the iterations into phases of static, shrinking
slot counts (:func:`phases`): at a phase's start the slots are reordered best first and
cut to the phase's count, so the work follows the active count while everything compiles
once. :meth:`~AbstractSwarm.step` keeps every slot (a state of one shape, for a loop the
user owns) and reorders at the same iterations, leaving the cut slots inactive: the
random draws are indexed by slot (:func:`uniforms`), so both give the same numbers.
"""

from __future__ import annotations

import abc
import contextvars
import dataclasses
import functools
import math
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import DTypeLike
from jaxtyping import Array, ArrayLike, Bool, Float, Int, PRNGKeyArray

from ._fitness import Fitness, finite_or_inf
from ._result import Result
from ._solver import AbstractSolver, Bounds

#: Whether a run traced now may draw each phase's random numbers before its loop
#: (:func:`predraws`); the driver sets it for a run compiled on its own on the CPU.
PREDRAW = contextvars.ContextVar("predraw", default=False)
#: Largest pre-drawn randomness per phase of one run (bytes), see :func:`predraws`.
PREDRAW_BYTES = 32 * 2**20


class SwarmState(eqx.Module):
    """One run's population. Inactive slots still move (masking them would cost more
    than moving them) but their personal bests are frozen and they never return: only
    active slots' personal bests can become the best. Nothing of the fitness's size is
    carried from one iteration to the next: a beetle's antenna difference (Eq. 12) at
    its current position is computed with that position's fitness, in the same pass,
    and carried as one number per slot.

    ``key`` is the chain the iterations draw from (iteration ``t`` uses ``split(key)[1]``
    and carries ``split(key)[0]``), ``t`` the iterations done of ``iterations``;
    ``stage`` and ``pending`` are the ask/tell bookkeeping (``"move"`` and ``None``
    between iterations)."""

    x: Float[Array, "slots d"]
    v: Float[Array, "slots d"]
    antennae: Float[Array, " slots"]  # f(x + a v) - f(x - a v) (beetles; 0 otherwise)
    antennae_bad: Int[Array, " slots"]  # how many of those two were NaN or Inf
    pbest_x: Float[Array, "slots d"]
    pbest_f: Float[Array, " slots"]
    active: Bool[Array, " slots"]
    slot_nonfinite: Int[Array, " slots"]  # non-finite evaluations of each active slot
    guide_x: Float[Array, " d"]  # global best that steers the velocities (SA guide)
    guide_f: Float[Array, ""]
    best_x: Float[Array, " d"]  # best point ever evaluated: what is reported
    best_f: Float[Array, ""]
    temperature: Float[Array, ""]
    sa_accepted: Int[Array, ""]
    n_evaluations: Int[Array, ""]
    n_nonfinite: Int[Array, ""]  # non-finite evaluations not in slot_nonfinite
    key: Any = None
    t: Int[Array, ""] = eqx.field(default_factory=lambda: jnp.int32(0))
    iterations: int = eqx.field(static=True, default=1)
    stage: str = eqx.field(static=True, default="move")
    pending: Any = None

    @property
    def nonfinite_total(self) -> Int[Array, ""]:
        """Every non-finite evaluation so far (counted per slot inside the loop, where a
        sum per iteration would cost a reduction; summed here)."""
        return self.n_nonfinite + jnp.sum(self.slot_nonfinite, dtype=jnp.int32)


class AbstractSwarm(AbstractSolver):
    """A population moving with velocities clamped to ``vmax_fraction (upper - lower)``.
    Subclasses give :attr:`n_slots`, :meth:`move`, :meth:`absorb` and, for a shrinking
    population, :meth:`schedule` and :attr:`n_phases`."""

    vmax_fraction: eqx.AbstractVar[float]

    @property
    @abc.abstractmethod
    def n_slots(self) -> int:
        """Population slots to allocate (the largest population of the run)."""

    @property
    def label(self) -> str:
        return type(self).__name__

    def population(self, dim: int) -> int:
        return int(self.n_slots)

    def schedule(self, iterations: int) -> np.ndarray:
        """Active population per iteration (static, never growing). Default: all
        :attr:`n_slots` throughout."""
        return np.full(iterations, self.n_slots)

    def population_schedule(self, iterations: int, dim: int) -> np.ndarray:
        return self.schedule(int(iterations))

    @property
    def n_phases(self) -> int:
        """Compiled phases of static slot count the iterations are split into."""
        return 1

    @property
    def antenna(self) -> float | None:
        """``a`` of the beetles' antennae at ``x +- a v`` (Eq. 13); None: no antennae."""
        return None

    @property
    def initial_temperature(self) -> float:
        return 0.0

    def evaluations(self, n_active: int | Int[np.ndarray, " t"]
                    ) -> int | Int[np.ndarray, " t"]:
        """Fitness evaluations one iteration makes with ``n_active`` members (a member's
        position counts once). Default: one per member."""
        return n_active

    def evaluation_counts(self, iterations: int, dim: int) -> np.ndarray:
        return self.n_slots + np.cumsum(self.evaluations(self.schedule(int(iterations))))

    def sa_accepted(self, state: SwarmState) -> Int[Array, ""]:
        return state.sa_accepted

    def n_nonfinite(self, state: SwarmState) -> Int[Array, ""]:
        return state.nonfinite_total

    def best(self, state: SwarmState) -> tuple[Float[Array, " d"], Float[Array, ""]]:
        return state.best_x, state.best_f

    # ---------------------------------------------------------------- randomness
    def randomness(self, key: PRNGKeyArray, dim: int, dtype: DTypeLike) -> Any:
        """What one iteration draws from, derived from the iteration's key: keys for the
        population's draws (their shape follows the phase) or small draws made up front.
        Default: two keys, for ``r1`` and ``r2`` of the velocity update."""
        return jax.random.split(key)

    def draw(self, randomness: Any, shape: tuple[int, ...], dtype: DTypeLike) -> Any:
        """One iteration's draws for a population of ``shape`` (slots, d), from what
        :meth:`randomness` returned: what :meth:`update` takes. Default: ``(r1, r2)``,
        uniform, one per slot and dimension."""
        return uniforms(randomness, shape, dtype)

    # ------------------------------------------------------- one iteration, in halves
    @abc.abstractmethod
    def move(self, state: SwarmState, draws: Any, lower: Bounds, upper: Bounds
             ) -> tuple[Array, Array]:
        """``(x, v)``: the new positions and velocities of every slot (nothing
        evaluated)."""

    @abc.abstractmethod
    def absorb(self, state: SwarmState, raw: Float[Array, " slots"],
               diff: Float[Array, " slots"] | None, diff_bad: Int[Array, " slots"] | None
               ) -> SwarmState:
        """The state after its new positions (``state.x``, ``state.v``) were evaluated:
        raw fitness ``raw``, and for beetles the antenna difference and its non-finite
        count; personal, global and best-ever updated."""

    def finish(self, state: SwarmState) -> SwarmState:
        """The end of an iteration: ``t`` advanced, the ask/tell bookkeeping cleared."""
        return replace(state, t=state.t + 1, stage="move", pending=None)

    def evaluate_moved(self, fitness: Fitness, x: Float[Array, "slots d"],
                       v: Float[Array, "slots d"]
                       ) -> tuple[Float[Array, " slots"], Float[Array, " slots"] | None,
                                  Int[Array, " slots"] | None]:
        """``(raw, diff, diff_bad)`` of new positions, from the fitness object (for
        beetles with the antennae, in one pass for Eq. 17)."""
        a = self.antenna
        if a is None:
            return fitness.evaluate(x), None, None
        return fitness.evaluate_with_antennae(x, v, a)

    def update(self, fitness: Fitness, state: SwarmState, draws: Any, lower: Bounds,
               upper: Bounds) -> SwarmState:
        """Iteration ``state.t`` with the given draws (what :meth:`draw` returns): move,
        evaluate with ``fitness``, update the bests. ``state.key`` is not touched."""
        x, v = self.move(state, draws, lower, upper)
        raw, diff, diff_bad = self.evaluate_moved(fitness, x, v)
        state = eqx.tree_at(lambda s: (s.x, s.v), state, (x, v))
        return self.finish(self.absorb(state, raw, diff, diff_bad))

    # --------------------------------------------------------------------- contract
    def start(self, lower: Bounds, upper: Bounds, key: PRNGKeyArray, iterations: int
              ) -> SwarmState:
        key, k0 = jax.random.split(key)
        x, v = initial_positions(lower, upper, k0, self.n_slots,
                                 self.vmax_fraction * (upper - lower))
        state = initial_from(x, v, jnp.zeros(self.n_slots, x.dtype), None, None,
                             self.initial_temperature)
        return replace(state, key=key, iterations=int(iterations), stage="start")

    def init(self, fitness: Fitness, lower: Bounds, upper: Bounds, key: PRNGKeyArray,
             iterations: int) -> SwarmState:
        """The initial population, uniform in the box, velocities uniform in ``+-Vmax``,
        evaluated (with the beetles' antennae), the worst beyond N(0) inactive."""
        key, k0 = jax.random.split(key)
        state = initial_state(fitness, lower, upper, k0, self.n_slots,
                              self.vmax_fraction * (upper - lower), self.initial_temperature,
                              antenna=self.antenna)
        state = set_active(state, int(self.schedule(int(iterations))[0]))
        return replace(state, key=key, iterations=int(iterations))

    def step(self, fitness: Fitness, state: SwarmState, lower: Bounds, upper: Bounds
             ) -> SwarmState:
        """One iteration on a state of constant shape: the phases' reordering and the
        re-ranking where N(t) falls, at the iterations :meth:`run` does them."""
        state, draws = self._draws_for_step(state)
        return self.update(fitness, state, draws, lower, upper)

    def _draws_for_step(self, state):
        state = self.prepare(state)
        key, sub = jax.random.split(state.key)
        dim, dtype = state.x.shape[-1], state.x.dtype
        draws = self.draw(self.randomness(sub, dim, dtype), state.x.shape, dtype)
        return replace(state, key=key), draws

    def prepare(self, state: SwarmState) -> SwarmState:
        """Before iteration ``state.t`` on a full-size state: at a phase's start the
        slots reordered best first and those beyond the phase's count made inactive
        (what :meth:`run`'s cut does), and where N(t) falls the worst leave."""
        plan = self.plan(state.iterations)
        t = state.t
        if plan.starts.any():
            state = _when(jnp.asarray(plan.starts)[t],
                          lambda s: reorder(s, jnp.asarray(plan.slots)[t]), state)
        if plan.drops.any():
            state = _when(jnp.asarray(plan.drops)[t],
                          lambda s: set_active(s, jnp.asarray(plan.n_active, jnp.int32)[t]),
                          state)
        return state

    def points(self, x: Float[Array, "slots d"], v: Float[Array, "slots d"]
               ) -> Float[Array, "k d"]:
        """The points one iteration evaluates for positions ``x``: ``x`` itself, and for
        beetles stacked with its antennae ``x + a v`` and ``x - a v``."""
        a = self.antenna
        return x if a is None else jnp.concatenate([x, x + a * v, x - a * v])

    def split_values(self, values: Float[Array, " k"], n: int
                     ) -> tuple[Float[Array, " n"], Float[Array, " n"] | None,
                                Int[Array, " n"] | None]:
        """``(raw, diff, diff_bad)`` from the fitness of :meth:`points`."""
        if self.antenna is None:
            return values, None, None
        return values[:n], *antenna_difference(values[n:2 * n], values[2 * n:])

    def ask(self, state: SwarmState, lower: Bounds, upper: Bounds
            ) -> tuple[Float[Array, "k d"], SwarmState]:
        if state.stage == "start":
            return self.points(state.x, state.v), replace(state, stage="started")
        if state.stage != "move":
            raise ValueError(f"{self.label}.ask: the state waits for tell (stage "
                             f"{state.stage!r}); call tell with the last points' fitness")
        state, draws = self._draws_for_step(state)
        x, v = self.move(state, draws, lower, upper)
        state = replace(state, x=x, v=v, stage="evaluate", pending=draws)
        return self.points(x, v), state

    def tell(self, state: SwarmState, fitness_values: Float[ArrayLike, " k"], lower: Bounds,
             upper: Bounds) -> SwarmState:
        n = state.x.shape[0]
        values = jnp.asarray(fitness_values, state.x.dtype).reshape(-1)
        want = self.points(state.x, state.v).shape[0]
        if values.shape[0] != want:
            raise ValueError(f"{self.label}.tell: expected {want} fitness values (one per "
                             f"point asked), got {values.shape[0]}")
        raw, diff, diff_bad = self.split_values(values, n)
        if state.stage == "started":
            x, v = state.x, state.v
            s = initial_from(x, v, raw, diff, diff_bad, self.initial_temperature)
            s = set_active(s, int(self.schedule(state.iterations)[0]))
            return replace(s, key=state.key, iterations=state.iterations)
        if state.stage != "evaluate":
            raise ValueError(f"{self.label}.tell: no points were asked for (stage "
                             f"{state.stage!r}); call ask first")
        return self.after_evaluate(self.absorb(state, raw, diff, diff_bad))

    def after_evaluate(self, state: SwarmState) -> SwarmState:
        """After :meth:`tell` took the moved population's fitness: the end of the
        iteration (SEDSABSO asks for its annealing candidates first)."""
        return self.finish(state)

    # -------------------------------------------------------------- the fast run
    def plan(self, iterations: int) -> Plan:
        """The static phase plan of a run of ``iterations`` (see :class:`Plan`)."""
        return _plan(self, int(iterations))

    def run(self, fitness: Fitness, lower: Bounds, upper: Bounds, key: PRNGKeyArray,
            iterations: int) -> Result:
        """One run in phases of static, shrinking slot counts (module docstring), each a
        ``lax.scan`` of :meth:`update`; the numbers of ``init`` + ``iterations`` ``step``,
        with arrays cut to each phase's population. Where N(t) falls is static: the
        active count before iteration t is N(t - 1) (N(a) after a phase starting at a
        has cut the slots), so the history of N is the schedule itself."""
        K = int(iterations)
        plan = self.plan(K)
        state = self.init(fitness, lower, upper, key, K)
        dim, dtype = lower.shape[0], lower.dtype
        rand = iteration_randomness(self, state.key, K, dim, dtype)
        history = []
        for a, b, slots in plan.phases:
            state = shrink(state, slots)
            shape = (slots, dim)
            phase_rand = jax.tree.map(lambda r, a=a, b=b: r[a:b], rand)
            predraw = predraws(self, phase_rand, shape, dtype, b - a)
            if predraw:
                phase_rand = jax.vmap(lambda r, shape=shape: self.draw(r, shape, dtype))(
                    phase_rand)

            def body(state: SwarmState, inp: tuple[Int[Array, ""], Bool[Array, ""], Any],
                     predraw: bool = predraw, shape: tuple[int, int] = shape,
                     rerank: bool = bool(plan.drops[a:b].any())
                     ) -> tuple[SwarmState, Float[Array, ""]]:
                n_active, drop, r = inp
                if rerank:
                    state = _when(drop, lambda s: set_active(s, n_active), state)
                draws = r if predraw else self.draw(r, shape, dtype)
                state = self.update(fitness, state, draws, lower, upper)
                return state, state.best_f

            inputs = (jnp.asarray(plan.n_active[a:b], jnp.int32),
                      jnp.asarray(plan.drops[a:b]), phase_rand)
            state, fh = jax.lax.scan(body, state, inputs)
            history.append(fh)
        return self.result(state, jnp.concatenate(history), dim)


@dataclasses.dataclass(frozen=True, eq=False)
class Plan:
    """Where a run of a swarm changes its slots, per iteration (static, NumPy):
    ``phases`` the ``(first, end, slots)`` of :func:`phases`; ``n_active`` N(t);
    ``starts`` whether a phase starts at t; ``slots`` the phase's slot count; ``drops``
    whether N(t) falls below the active count before t (the worst then leave)."""

    phases: tuple
    n_active: np.ndarray
    starts: np.ndarray
    slots: np.ndarray
    drops: np.ndarray


def _plan(solver: AbstractSwarm, K: int) -> Plan:
    return _plan_of(tuple(int(n) for n in solver.schedule(K)), int(solver.n_phases))


@functools.lru_cache(maxsize=64)
def _plan_of(schedule: tuple[int, ...], n_phases: int) -> Plan:
    sched = np.asarray(schedule)
    K = len(sched)
    parts = tuple(phases(sched, n_phases))
    starts, slots, drops = np.zeros(K, bool), np.zeros(K, int), np.zeros(K, bool)
    for a, b, s in parts:
        starts[a], slots[a:b] = True, s
        before = np.concatenate([[min(sched[max(a - 1, 0)], s)], sched[a:b - 1]])
        drops[a:b] = sched[a:b] < before
    return Plan(phases=parts, n_active=sched, starts=starts, slots=slots, drops=drops)


def replace(state: SwarmState, **changes: Any) -> SwarmState:
    """``state`` with fields replaced (static ones included)."""
    return dataclasses.replace(state, **changes)


def _when(pred, fn, state):
    """``fn(state)`` where ``pred`` else ``state``: a ``lax.cond`` on the CPU, which
    skips ``fn`` when it is not needed; a select on accelerators, where a ``lax.cond``
    would read its predicate back to the host every iteration."""
    if jax.default_backend() == "cpu":
        return jax.lax.cond(pred, fn, lambda s: s, state)
    return jax.tree.map(lambda a, b: jnp.where(pred, a, b), fn(state), state)


def iteration_randomness(solver: AbstractSwarm, key: PRNGKeyArray, iterations: int, dim: int,
                         dtype: DTypeLike) -> Any:
    """Every iteration's randomness, derived before the loop: the chain
    ``key, sub = split(key)`` gives iteration t its key ``sub``, from which
    ``solver.randomness`` derives keys (or small draws), vectorised over the iterations.
    The population's draws (``solver.draw``) are then made per phase before its loop
    or inside it. The numbers are the same either way, and the same as drawing each
    inside the loop (:meth:`AbstractSwarm.step`)."""
    def chain(key: PRNGKeyArray, _: None) -> tuple[PRNGKeyArray, PRNGKeyArray]:
        key, sub = jax.random.split(key)
        return key, sub

    _, subs = jax.lax.scan(chain, key, None, length=iterations)
    return jax.vmap(lambda k: solver.randomness(k, dim, dtype))(subs)


def predraws(solver: AbstractSwarm, randomness: Any, shape: tuple[int, ...], dtype: DTypeLike,
             length: int) -> bool:
    """Whether one phase's population draws are made before its loop: when the driver
    allows it (:data:`PREDRAW`: a run compiled on its own on the CPU) and they take at
    most :data:`PREDRAW_BYTES`. Inside the loop XLA fuses the hash into each fusion that
    reads a draw, and computes it there again: with ``PREDRAW_BYTES = 0`` a float64 run
    took 56 % longer for LDWPSO (122 vs 79 ms), 32 % for BSO (184 vs 140 ms), 23 % for
    SEDSABSO (213 vs 172 ms) (2-core AMD EPYC, same process, fastest of 9 seeds). On an
    accelerator, or inside a caller's ``jit``/``vmap`` (whose batch size is unknown
    here), the draws stay in the loop, where recomputing them costs no memory."""
    if not PREDRAW.get() or jax.default_backend() != "cpu":
        return False
    one = jax.tree.map(lambda r: r[0], randomness)
    out = jax.eval_shape(lambda r: solver.draw(r, shape, dtype), one)
    size = sum(math.prod(o.shape) * o.dtype.itemsize for o in jax.tree.leaves(out))
    return size * length <= PREDRAW_BYTES


# -------------------------------------------------------------------- population state
def evaluate(fitness: Fitness | None, X: Float[Array, "k d"],
             mask: Bool[Array, " k"] | None = None, raw: Float[Array, " k"] | None = None
             ) -> tuple[Float[Array, " k"], Int[Array, " k"]]:
    """Fitness of the members ``X`` (or their ``raw`` values when already computed),
    non-finite values mapped to +Inf, and per member 1 where a value was non-finite
    (0 outside ``mask`` when given)."""
    raw = fitness.evaluate(X) if raw is None else raw  # type: ignore[union-attr]
    bad = ~jnp.isfinite(raw)
    if mask is not None:
        bad = bad & mask
    return finite_or_inf(raw), bad.astype(jnp.int32)


def antenna_difference(fl: Float[Array, " k"], fr: Float[Array, " k"]
                       ) -> tuple[Float[Array, " k"], Int[Array, " k"]]:
    """``(f(xl) - f(xr), how many of the two were NaN or Inf)`` per member from the two
    antennae's raw values; a NaN or Inf value counts as +Inf."""
    bad = (~jnp.isfinite(fl)).astype(jnp.int32) + (~jnp.isfinite(fr)).astype(jnp.int32)
    return finite_or_inf(fl) - finite_or_inf(fr), bad


def initial_positions(lower: Bounds, upper: Bounds, key: PRNGKeyArray, slots: int,
                      vmax: Float[Array, " d"]
                      ) -> tuple[Float[Array, "slots d"], Float[Array, "slots d"]]:
    """Positions uniform in the box, velocities uniform in ``+-vmax``."""
    kx, kv = jax.random.split(key)
    d = lower.shape[0]
    x = lower + (upper - lower) * jax.random.uniform(kx, (slots, d), lower.dtype)
    v = vmax * jax.random.uniform(kv, (slots, d), lower.dtype, -1.0, 1.0)
    return x, v


def initial_from(x: Float[Array, "slots d"], v: Float[Array, "slots d"],
                 raw: Float[Array, " slots"], diff: Float[Array, " slots"] | None,
                 diff_bad: Int[Array, " slots"] | None, temperature: Float[ArrayLike, ""] = 0.0
                 ) -> SwarmState:
    """The state of a population at ``x`` with velocities ``v`` and raw fitness ``raw``
    (and antenna differences, for beetles)."""
    slots = x.shape[0]
    if diff is None:
        diff, diff_bad = jnp.zeros(slots, x.dtype), jnp.zeros(slots, jnp.int32)
    f, bad = evaluate(None, x, raw=raw)
    i = jnp.argmin(f)
    return SwarmState(
        x=x, v=v, antennae=diff, antennae_bad=diff_bad,  # type: ignore[arg-type]
        pbest_x=x, pbest_f=f,
        active=jnp.ones(slots, bool), slot_nonfinite=jnp.zeros(slots, jnp.int32),
        guide_x=x[i], guide_f=f[i], best_x=x[i], best_f=f[i],
        temperature=jnp.asarray(temperature, x.dtype), sa_accepted=jnp.int32(0),
        n_evaluations=jnp.int32(slots), n_nonfinite=jnp.sum(bad, dtype=jnp.int32),
    )


def initial_state(fitness: Fitness, lower: Bounds, upper: Bounds, key: PRNGKeyArray,
                  slots: int, vmax: Float[Array, " d"], temperature: Float[ArrayLike, ""] = 0.0,
                  antenna: Float[ArrayLike, ""] | None = None) -> SwarmState:
    """Positions uniform in the box, velocities uniform in ``+-vmax``, evaluated; with
    ``antenna`` (the beetles' ``a``), also each slot's ``f(x + a v) - f(x - a v)``."""
    x, v = initial_positions(lower, upper, key, slots, vmax)
    if antenna is None:
        raw, diff, diff_bad = fitness.evaluate(x), None, None
    else:
        raw, diff, diff_bad = fitness.evaluate_with_antennae(x, v, antenna)
    return initial_from(x, v, raw, diff, diff_bad, temperature)


def update_bests(state: SwarmState, x: Float[Array, "slots d"], f: Float[Array, " slots"]
                 ) -> tuple[SwarmState, tuple[Float[Array, " d"], Float[Array, ""]]]:
    """Take the new positions; update the active slots' personal bests and the best ever.
    Returns the state and the swarm's global best ``(x, f)`` among the active slots."""
    better = state.active & (f < state.pbest_f)
    pbest_f = jnp.where(better, f, state.pbest_f)
    pbest_x = jnp.where(better[:, None], x, state.pbest_x)
    masked = jnp.where(state.active, pbest_f, jnp.inf)
    i = jnp.argmin(masked)
    improve_best = masked[i] < state.best_f
    return eqx.tree_at(
        lambda s: (s.x, s.pbest_x, s.pbest_f, s.best_x, s.best_f),
        state,
        (x, pbest_x, pbest_f,
         jnp.where(improve_best, pbest_x[i], state.best_x),
         jnp.where(improve_best, masked[i], state.best_f)),
    ), (pbest_x[i], masked[i])


def swarm_best(state: SwarmState) -> tuple[Float[Array, " d"], Float[Array, ""]]:
    """The swarm's global best ``(x, f)`` among the active slots' personal bests."""
    masked = jnp.where(state.active, state.pbest_f, jnp.inf)
    i = jnp.argmin(masked)
    return state.pbest_x[i], masked[i]


def set_active(state: SwarmState, n_active: Int[ArrayLike, ""]) -> SwarmState:
    """Keep the ``n_active`` slots with the best personal bests (worst dropped first)."""
    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))
    rank = jnp.empty_like(order).at[order].set(jnp.arange(order.shape[0]))
    return eqx.tree_at(lambda s: s.active, state, rank < n_active)


PER_SLOT = ("x", "v", "antennae", "antennae_bad", "pbest_x", "pbest_f", "active")


def _best_first(state: SwarmState, slots) -> tuple[Array, SwarmState]:
    """The slot order best first (active before inactive; stable) and the state with the
    per-slot non-finite counts moved to the total."""
    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))
    state = eqx.tree_at(lambda s: (s.n_nonfinite, s.slot_nonfinite), state,
                        (state.nonfinite_total, jnp.zeros(slots, jnp.int32)))
    return order, state


def shrink(state: SwarmState, slots: int) -> SwarmState:
    """Reorder slots best first (active before inactive) and keep the first ``slots``
    (the per-slot non-finite counts move to the total first)."""
    order, state = _best_first(state, slots)
    order = order[:slots]
    return eqx.tree_at(lambda s: [getattr(s, k) for k in PER_SLOT], state,
                       [getattr(state, k)[order] for k in PER_SLOT])


def reorder(state: SwarmState, slots: Int[ArrayLike, ""]) -> SwarmState:
    """:func:`shrink` without the cut: the slots reordered best first and those from
    ``slots`` on made inactive (the state keeps its shape)."""
    n = state.x.shape[0]
    order, state = _best_first(state, n)
    state = eqx.tree_at(lambda s: [getattr(s, k) for k in PER_SLOT], state,
                        [getattr(state, k)[order] for k in PER_SLOT])
    return eqx.tree_at(lambda s: s.active, state, state.active & (jnp.arange(n) < slots))


def phases(schedule: np.ndarray, n_phases: int) -> list[tuple[int, int, int]]:
    """Split iterations into at most ``n_phases`` runs of iterations with a static slot
    count each: the largest active count inside the phase (N(t) never grows)."""
    K = len(schedule)
    bounds = sorted({round(k * K / n_phases) for k in range(n_phases)} | {K})
    return [(a, b, int(schedule[a:b].max())) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]


def uniforms(keys: PRNGKeyArray, shape: tuple[int, ...], dtype: DTypeLike
             ) -> Float[Array, "*keys_and_shape"]:
    """``jax.random.uniform(k, shape, dtype)`` for each key of ``keys`` in one batched
    call, bit for bit (``tests/test_swarms.py`` checks it).

    For threefry keys (JAX's default, with ``jax_threefry_partitionable``, the default
    since JAX 0.5) the bits come from :func:`_threefry2x32`, the same hash written out
    round by round: XLA fuses it into one elementwise loop, where JAX's own CPU lowering
    runs it as a 5-trip loop (an iteration's r1, r2 for 50 x 21: 3.5 vs 7.1 us on the
    2-core AMD EPYC, ``python -m tools.kernels``). Other keys go through
    ``jax.random.uniform``. Element ``i`` of the flattened ``shape`` depends on ``i``
    alone, so the first rows of a larger draw are a smaller draw."""
    n = math.prod(shape)
    if not (jnp.issubdtype(keys.dtype, jax.dtypes.prng_key)
            and str(jax.random.key_impl(keys)) == "threefry2x32"
            and jax.config.jax_threefry_partitionable  # type: ignore[attr-defined]
            and n < 2**32):
        return jax.vmap(lambda k: jax.random.uniform(k, shape, dtype))(keys)
    dtype = jnp.dtype(dtype)
    kd = jax.random.key_data(keys)  # (..., 2) uint32
    lo = jax.lax.iota(np.uint32, n).reshape(shape)  # the flat index as (hi, lo) words
    k1, k2 = (kd[..., i].reshape(kd.shape[:-1] + (1,) * len(shape)) for i in (0, 1))
    b1, b2 = _threefry2x32(k1, k2, jnp.zeros_like(lo), lo)
    nbits, nmant = jnp.finfo(dtype).bits, jnp.finfo(dtype).nmant
    uint: type[np.unsignedinteger[Any]]
    if nbits == 64:
        uint = np.uint64
        bits = (b1.astype(uint) << uint(32)) | b2.astype(uint)
    else:
        uint = np.uint32
        bits = b1 ^ b2
    one = np.array(1.0, dtype).view(uint)
    float_bits = jax.lax.shift_right_logical(bits, uint(nbits - nmant)) | one
    return jax.lax.bitcast_convert_type(float_bits, dtype) - jnp.asarray(1.0, dtype)


def _threefry2x32(k1, k2, x1, x2):
    """Threefry-2x32 with 20 rounds (Salmon et al., "Parallel random numbers: as easy as
    1, 2, 3", SC 2011), as JAX computes it: key schedule ``k1, k2, k1 ^ k2 ^
    0x1BD11BDA``, rotations 13 15 26 6 / 17 29 16 24, a key injection every 4 rounds."""
    ks = (k1, k2, k1 ^ k2 ^ np.uint32(0x1BD11BDA))
    x1, x2 = x1 + ks[0], x2 + ks[1]
    for i in range(5):
        for r in ((13, 15, 26, 6), (17, 29, 16, 24))[i % 2]:
            x1 = x1 + x2
            x2 = x1 ^ ((x2 << np.uint32(r)) | jax.lax.shift_right_logical(x2, np.uint32(32 - r)))
        x1 = x1 + ks[(i + 1) % 3]
        x2 = x2 + ks[(i + 2) % 3] + np.uint32(i + 1)
    return x1, x2


def check_population(n: object, name: str) -> None:
    """A population size must be an integer >= 1."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"{name} must be an integer >= 1, got {n!r}")


def check_velocity_update(c1: float, c2: float, vmax_fraction: float) -> None:
    """The velocity update's coefficients: ``c1, c2 >= 0`` and ``vmax_fraction > 0``."""
    if vmax_fraction <= 0:
        raise ValueError(f"vmax_fraction must be > 0, got {vmax_fraction}")
    if c1 < 0 or c2 < 0:
        raise ValueError(f"c1 and c2 must be >= 0, got c1={c1}, c2={c2}")
