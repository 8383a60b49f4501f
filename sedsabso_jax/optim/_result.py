"""One result type for every optimiser: swarms and least-squares baselines."""

from __future__ import annotations

import equinox as eqx
import jax
import numpy as np
from jaxtyping import Array, Float, Int


class Result(eqx.Module):
    """What a run of an optimiser returns: a pytree (``jax.vmap`` over runs stacks it).

    With ``runs`` (many independent runs at once) every array gains a leading ``runs``
    axis. Non-iterative methods have empty histories.

    Attributes:
        method: name of the method (``"SEDSABSO"``, ``"BSO"``, ``"LDWPSO"``, ``"OLS"``, ...).
        x: best point ever seen (for a swarm never an SA guide that was worse).
        f: its fitness.
        history_f: best fitness after each iteration.
        history_n: active population after each iteration.
        sa_accepted: simulated-annealing moves accepted (SEDSABSO; 0 otherwise).
        n_evaluations: fitness evaluations made (a population member counts once).
        n_nonfinite: evaluations that returned NaN or Inf (never taken as best).
        compile_s: wall time spent compiling (0 when the compiled code was reused);
            None when the run was traced inside a caller's ``jit``/``vmap``, which
            compiles and times it as a whole.
        run_s: wall time of the run itself, after compilation; None as ``compile_s``.
    """

    method: str = eqx.field(static=True)
    x: Float[Array, "*runs d"]
    f: Float[Array, "*runs"]
    history_f: Float[Array, "*runs iterations"]
    history_n: Int[Array, "*runs iterations"]
    sa_accepted: Int[Array, "*runs"]
    n_evaluations: Int[Array, "*runs"]
    n_nonfinite: Int[Array, "*runs"]
    compile_s: float | None = None
    run_s: float | None = None

    def __repr__(self) -> str:
        if isinstance(self.f, jax.core.Tracer):
            return f"Result({self.method}, traced)"
        f = np.asarray(self.f)
        fs = f"{float(f):.6g}" if f.ndim == 0 else f"mean {f.mean():.6g} over {f.size} runs"
        times = ("" if self.compile_s is None or self.run_s is None else
                 f", compile {self.compile_s:.2f} s, run {self.run_s:.3f} s")
        return f"Result({self.method}, f={fs}{times})"
