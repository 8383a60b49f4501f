"""The identified model judged as a simulator runs it (:class:`SimulatorCheck`): its MJCF
in MuJoCo beside the package's own model, torques and open-loop rollouts, for the
report of ``identify --mjcf-out``."""

from __future__ import annotations

import dataclasses

from .._fit._rollouts import LENGTHS, rollout_errors
from .._fit._simulator import mujoco_torques, simulated
from .._metrics import validation_metrics


@dataclasses.dataclass(frozen=True, eq=False)
class SimulatorCheck:
    """A written MJCF judged in MuJoCo beside the package's own model, on each data set
    (``rows``, one dict each: ``data``, the torque error ``own`` and ``mujoco`` (MuJoCo's
    inverse dynamics) in ``measure``, and the median end errors of open-loop rollouts,
    ``rollouts_own`` and ``rollouts_mujoco``, one per length of ``lengths`` s, in
    degrees), and what was left out (``left_out``)."""

    measure: str
    lengths: tuple[float, ...]
    rows: tuple[dict, ...]
    left_out: tuple[str, ...]
    #: the model's terms (its ``--friction`` text)
    friction: str = ""
    #: each data set's :class:`~.._fit._rollouts.RolloutErrors` (its figure), by name
    rollouts: dict = dataclasses.field(default_factory=dict)

    @classmethod
    def of(cls, ident, xml: str, recordings: dict, limits=None) -> SimulatorCheck:
        """``ident``'s MJCF ``xml`` against its own model on each recording (``{name:
        Measurements}``; new motions: their offsets' mean): the torques by the NRMS over
        the torque limits (or the relative RMS error without limits), and rollouts
        (:func:`~.._fit._rollouts.rollout_errors`)."""
        measure = ("nrms_limits_percent" if limits is not None
                   else "relative_rms_percent_overall")
        rows, rollouts = [], {}
        for name, d in recordings.items():
            own = ident.predict(d.q, d.qd, d.qdd)
            written = mujoco_torques(xml, d.q, d.qd, d.qdd)
            rollouts[name] = rollout_errors(ident, d, xml, LENGTHS)
            medians = rollouts[name].medians()
            rows.append({"data": name,
                         "own": float(validation_metrics(d.tau, own, limits)[measure]),
                         "mujoco": float(validation_metrics(d.tau, written, limits)[measure]),
                         "rollouts_own": medians["own"],
                         "rollouts_mujoco": medians["mujoco"]})
        return cls(measure, LENGTHS, tuple(rows),
                   simulated(ident.model, ident.values).left_out, ident.model.friction,
                   rollouts)

    def lines(self, title: str = "the identified model simulated, and written as MJCF "
              "for MuJoCo:") -> list[str]:
        """The report's section, under ``title``."""
        from ..._output import columns_note, markdown_table

        lengths = [f"{x:g} s" for x in self.lengths]
        table = markdown_table(
            ["data", "own [%]", "MuJoCo [%]", "MuJoCo / own",
             *(f"rollout {x} own [deg]" for x in lengths),
             *(f"rollout {x} MuJoCo [deg]" for x in lengths)],
            [[r["data"], f"{r['own']:.4f}", f"{r['mujoco']:.4f}",
              f"{r['mujoco'] / r['own']:.3f}" if r["own"] > 0 else "",
              *(f"{e:.3g}" for e in r["rollouts_own"]),
              *(f"{e:.3g}" for e in r["rollouts_mujoco"])] for r in self.rows])
        return ["", title, "", table, "", columns_note(
                    ("own [%]", f"the package's model's torque error (`{self.measure}`)"),
                    ("MuJoCo [%]", "the written MJCF's, from MuJoCo's inverse dynamics "
                     "(`mj_inverse`)"),
                    ([*(f"rollout {x} own [deg]" for x in lengths),
                      *(f"rollout {x} MuJoCo [deg]" for x in lengths)],
                     "open-loop rollouts from measured states driven by the "
                     "measured torques: the median over windows and joints of the position "
                     "error after that time (own: the package's model in JAX, linearly "
                     "implicit Euler in steps of at most 1 ms; MuJoCo: the MJCF, its "
                     "integrator; `inf`: most windows diverged)")),
                "", "left out (MuJoCo has no parameter for it): "
                + ("; ".join(self.left_out) if self.left_out else "nothing")]

    def as_dict(self) -> dict:
        return {"measure": self.measure, "friction": self.friction,
                "rollout_lengths_s": list(self.lengths), "left_out": list(self.left_out),
                "rows": list(self.rows)}
