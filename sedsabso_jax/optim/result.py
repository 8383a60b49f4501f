"""One result type for every optimiser: swarms and least-squares baselines."""

from __future__ import annotations

import equinox as eqx
import numpy as np
from jaxtyping import Array, Float, Int


class Result(eqx.Module):
    """What an identification run returns.

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
        compile_s: wall time spent compiling (0 when the compiled code was reused).
        run_s: wall time of the run itself, after compilation.
    """

    method: str = eqx.field(static=True)
    x: Float[Array, "*runs d"]
    f: Float[Array, "*runs"]
    history_f: Float[Array, "*runs iterations"]
    history_n: Int[Array, "*runs iterations"]
    sa_accepted: Int[Array, "*runs"]
    n_evaluations: Int[Array, "*runs"]
    n_nonfinite: Int[Array, "*runs"]
    compile_s: float = 0.0
    run_s: float = 0.0

    def __repr__(self) -> str:
        f = np.asarray(self.f)
        fs = f"{float(f):.6g}" if f.ndim == 0 else f"mean {f.mean():.6g} over {f.size} runs"
        return (f"Result({self.method}, f={fs}, compile {self.compile_s:.2f} s, "
                f"run {self.run_s:.3f} s)")
