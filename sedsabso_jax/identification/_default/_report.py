"""What ``sedsabso-jax identify`` reports: the identified parameters, fit and validation
metrics as text, a JSON document, and measured-against-predicted torque plots."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from jaxtyping import ArrayLike, Float

from ..._output import (
    PathLike,
    columns_note,
    jsonable,
    markdown_table,
    pyplot,
    save_figure,
    to_its_std,
    write_json,
    write_text,
)
from ...measurements._container import Measurements
from ...measurements._signal import describe_signals
from .._estimators._estimator import Limits
from .._fit._identify import Identification
from .._fit._rollouts import figure_rollouts
from .._fit._uncertainty import relative_std_percent
from .._metrics import (
    METRICS_NOTE,
    SAME_COLUMNS,
    Metrics,
    mean_metrics,
    metrics_table,
    validation_metrics,
)
from .._model._torque_model import TorqueModel
from .._recordings import joined, stacked
from .._validation._extrapolation import Extrapolation
from .._validation._rests import Rests
from .._validation._selection import CrossValidation, PriorSelection, Selection
from ._held_out import (
    HeldOut,
    HeldOutData,
    held_out_document,
    held_out_lines,
    judge,
    named_recordings,
)
from ._signals import ChainSelection
from ._simulator_check import SimulatorCheck
from ._stages import stage_lines

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def figure_torques(times: Float[ArrayLike, " T"], tau_measured: Float[ArrayLike, "T n"],
                   tau_predicted: Float[ArrayLike, "T n"], joint_names: Sequence[str],
                   title: str) -> Figure:
    """Measured against predicted torque per joint (one panel each), error in the legend."""
    plt = pyplot()
    tau_measured, tau_predicted = np.asarray(tau_measured), np.asarray(tau_predicted)
    n = tau_measured.shape[1]
    t = np.asarray(times) - float(np.asarray(times)[0])
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.6 * n + 0.8), sharex=True,
                             constrained_layout=True, squeeze=False)
    for j, ax in enumerate(axes[:, 0]):
        rms = float(np.sqrt(np.mean((tau_predicted[:, j] - tau_measured[:, j]) ** 2)))
        ax.plot(t, tau_measured[:, j], color="0.3", lw=1.2, label="measured")
        ax.plot(t, tau_predicted[:, j], color="tab:red", lw=1, ls="--",
                label=f"predicted (RMS error {rms:.3g} N m)")
        ax.set_ylabel(f"{joint_names[j]}\n[N m]")
        ax.legend(loc="best", fontsize="small")
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title)
    return fig


#: The unit of a base parameter, by the letters of its name.
PARAMETER_UNITS = ("in SI units by name (kg m^2 for inertia XX..ZZ, kg m for first moments "
                   "MX..MZ, kg for M, N m for Coulomb friction FC, N m s/rad for viscous "
                   "friction FV, N and N s/m on a prismatic joint, a regrouped `...R` "
                   "parameter in its first term's unit)")


def model_units(model: TorqueModel) -> str:
    """The units of ``model``'s extra terms, each term's own
    (:attr:`~.._model._term.AbstractTerm.unit`), in the model's order."""
    units = [t.unit for t in model.terms if t.unit]
    return ", extra terms in " + "; ".join(units) if units else ""


def _cv_error(cv: CrossValidation) -> str:
    measure = cv.measure
    what = ("NRMS over the torque limits" if measure == "nrms_limits_percent"
            else "relative RMS error")
    return (f"mean +- standard error over the splits of each split's predicted samples' "
            f"{what} (`{measure}`)")


#: What each kind of split predicts the error of.
PART_MEANING = {"phase folds": "motions like the fitted one", "speed splits": "faster ones",
                "recording folds": "another recording", "given folds": "the given folds"}


def _described(cv: CrossValidation) -> str:
    """What a validation did, for the report."""
    text = cv.validation.get("description", cv.validation["kind"])
    if cv.period_s is not None:
        text += f"; period {cv.period_s:.4g} s"
    elif cv.validation["kind"] == "phase folds":
        text += "; contiguous folds, the motion does not repeat"
    return text


#: How the report words the kept terms' stage (:class:`~sedsabso_jax.identification.KeptTerms`).
KEPT_RULE = ("; then the last rows: terms real drives have, friction at rest, added to "
             "that choice and kept unless their excess over it is above one standard error")


@dataclasses.dataclass(frozen=True, eq=False)
class IdentificationReport:
    """An identification judged on its own data and, when given, on held-out data.

    ``data`` and ``held_out`` are :class:`~sedsabso_jax.Measurements`; ``fit`` and
    ``validation`` their :class:`~sedsabso_jax.Metrics` (``validation`` None without
    held-out data); ``predicted`` the predicted torques of each; ``validations`` each
    held-out recording judged alone (:class:`~sedsabso_jax.identification.HeldOut`, in
    the order given).
    With several held-out recordings, ``held_out``, ``extrapolation``, ``rests`` and
    ``predicted[1]`` are None (each recording's are in ``validations``) and
    ``validation`` is their mean (:func:`~sedsabso_jax.identification.mean_metrics`:
    each figure averaged, each recording weighed alike); ``cross_validation`` the
    chosen setting's :class:`~sedsabso_jax.identification.CrossValidation` on ``data``
    and ``selection`` the :class:`~sedsabso_jax.identification.Selection` it came from,
    ``prior_selection`` the :class:`~sedsabso_jax.identification.PriorSelection` of a
    physical fit's pull to the prior (each None when not run).
    """

    ident: Identification
    data: Measurements
    held_out: Measurements | None
    limits: Limits
    fit: Metrics
    validation: Metrics | None
    predicted: tuple[np.ndarray, np.ndarray | None]
    cross_validation: CrossValidation | None = None
    selection: Selection | None = None
    prior_selection: PriorSelection | None = None
    #: how far ``held_out`` goes beyond ``data``
    #: (:func:`~.._validation._extrapolation.extrapolation`)
    extrapolation: Extrapolation | None = None
    #: how much more ``held_out`` rests than ``data``, and the validated error weighed
    #: to its speeds (:func:`~.._validation._rests.rests`)
    rests: Rests | None = None
    #: each held-out recording judged alone, in the order given
    validations: tuple[HeldOut, ...] = ()
    #: the identified model written as MJCF and judged in MuJoCo, with its text
    #: (:meth:`with_mjcf`), or None
    simulator: SimulatorCheck | None = None
    mjcf: str | None = None
    #: the same judgement of the choice made for MuJoCo (only the terms it holds), beside
    #: a choice that has others (:meth:`beside_made_for_mujoco`), or None
    made_for_mujoco: SimulatorCheck | None = None
    #: the signal chain's choice (:func:`~._signals.choose_chain`), or None
    chain_selection: ChainSelection | None = None

    def beside_made_for_mujoco(self, other: IdentificationReport) -> IdentificationReport:
        """This report with ``other``'s MuJoCo judgement (the choice among the terms MuJoCo
        holds, made :meth:`with_mjcf`) shown beside its own."""
        if other.simulator is None:
            raise ValueError("the report made for MuJoCo has no MJCF: make it with_mjcf()")
        return dataclasses.replace(self, made_for_mujoco=other.simulator)

    def with_mjcf(self, **options) -> IdentificationReport:
        """This report with the identification written as MJCF
        (:meth:`~.._fit._identify.Identification.mjcf`, ``options`` its) and judged in
        MuJoCo on the identification data and each held-out recording."""
        xml = self.ident.mjcf(**options)
        recordings = {"identification data": self.data,
                      **{h.name: h.data for h in self.validations}}
        check = SimulatorCheck.of(self.ident, xml, recordings, self.limits)
        return dataclasses.replace(self, simulator=check, mjcf=xml)

    @classmethod
    def evaluate(cls, ident: Identification, data: Measurements | Sequence[Measurements],
                 held_out: HeldOutData | None = None, limits: Limits = None, *,
                 cross_validation: CrossValidation | None = None,
                 selection: Selection | None = None,
                 prior_selection: PriorSelection | None = None) -> IdentificationReport:
        """Predict the torques of ``data`` (one recording or several; their own torque
        offsets where the model has one per recording) and of each held-out recording
        (``held_out``: one, a list or tuple, or a mapping name -> recording), and
        compare; for each, measure how far it goes beyond ``data``
        (:func:`~sedsabso_jax.identification.extrapolation`) and warn when a joint is
        beyond the thresholds, and how much more it rests
        (:func:`~sedsabso_jax.identification.rests`: the validated error weighed to its
        speeds, a warning where it rests more)."""
        recordings = [data] if isinstance(data, Measurements) else list(data)
        data = joined(recordings)
        judged = judge(ident, data, named_recordings(ident.model.robot, held_out), limits,
                       cross_validation)
        index = stacked(recordings)[-1] if len(recordings) > 1 else None
        fit_pred = ident.model.predict(ident.values, data.q, data.qd, data.qdd, index)
        fit = validation_metrics(data.tau, fit_pred, limits)
        if len(judged) != 1:  # none, or several: each in judged, their mean the validation
            mean = mean_metrics([h.metrics for h in judged]) if judged else None
            return cls(ident, data, None, limits, fit, mean, (fit_pred, None),
                       cross_validation, selection, prior_selection, validations=judged)
        one, = judged
        return cls(ident, data, one.data, limits, fit, one.metrics, (fit_pred, one.predicted),
                   cross_validation, selection, prior_selection, one.extrapolation, one.rests,
                   judged)

    def text(self) -> str:
        """The parameters and per-joint metrics as markdown tables, each with a note that
        defines its columns."""
        ident, robot = self.ident, self.ident.model.robot
        joints = robot.joint_names
        std = ident.std if ident.std is not None else np.full(len(ident.values), np.nan)
        relative = relative_std_percent(std, ident.values)
        rows = [[str(i), name, to_its_std(value, sd), to_its_std(sd, sd), f"{rel:.3g}"]
                for i, (name, value, sd, rel)
                in enumerate(zip(ident.names, ident.values, std, relative), 1)]
        lines = [f"{robot.name}: {len(ident.names)} parameters identified by {ident.method} "
                 f"(friction {ident.model.friction}) from {self.data.n_samples} samples of "
                 f"{self.data.source}", "", f"signals: {self.signals}", "",
                 *([] if self.chain_selection is None else self.chain_selection.lines()),
                 markdown_table(["#", "parameter", "value", "std", "relative std [%]"], rows),
                 "", columns_note(
                     ("#", "row number"),
                     ("parameter", "a base parameter (Eq. 3-4, `R` where others are "
                      "regrouped onto it) or an extra term of the friction model"),
                     ("value", f"the identified value to its std's second significant "
                      f"digit (every digit in the JSON) {PARAMETER_UNITS}"
                      f"{model_units(ident.model)}"),
                     ("std", "its standard deviation in the value's unit (2 significant "
                      "digits), from the residual covariance s^2 (W^T W)^-1 of the weighted "
                      "rows W (exact for OLS and WLS with independent errors and the model "
                      "right; a linearisation that ignores the constraints and the prior of a "
                      "physical fit; `inf`: not determined by the data)"),
                     ("relative std [%]", "100 std / |value|")),
                 *stage_lines(ident.settings, ident.model.terms),
                 "", "fit (identification data):", "", metrics_table(self.fit, joints), "",
                 METRICS_NOTE]
        if self.cross_validation is not None:
            cv = self.cross_validation
            lines += ["", f"predicted error on new motions ({_described(cv)}):", "",
                      metrics_table(cv.metrics, joints), "", SAME_COLUMNS, "",
                      f"validated error ({cv.measure}): {cv.score:.4f} +- "
                      f"{cv.standard_error:.4f} (mean and standard error over "
                      f"{len(cv.fold_scores)} splits): the error to expect on new motions"]
            if len(cv.part_scores) > 1:
                lines += ["", "by kind of split: " + "; ".join(
                    f"{k} {v:.4f} ({PART_MEANING.get(k, k)})"
                    for k, v in cv.part_scores.items())]
        if self.selection is not None:
            sel = self.selection
            parts = sel.parts if len(sel.parts) > 1 else ()
            kept = any(st.get("kept_terms") for st, _ in sel.candidates)
            lines += ["", f"chosen by {' and '.join(sel.parts)} (the simplest whose "
                          f"split-by-split excess over the lowest is within one standard "
                          f"error{KEPT_RULE if kept else ''}):", "",
                      markdown_table(["method", "sigma", "physical", "friction", "parameters",
                                      "error [%]", *(f"{k} [%]" for k in parts), "choice"],
                                     sel.table()),
                      "", columns_note(
                          ("method", "the estimator (`identify --method`)"),
                          ("sigma", "what each joint's rows are divided by (`equal`: "
                           "nothing, `residual`: the RMS of its OLS residual, Gautier's "
                           "two-step WLS, `limits`: its torque limit)"),
                          ("physical", "`yes`: physically consistent parameters "
                           "(`identify --physical`), friction coefficients >= 0"),
                          ("friction", "the torque model's terms (`identify --friction`)"),
                          ("parameters", "the number of parameters the model identifies"),
                          ("error [%]", _cv_error(sel.cross_validation)),
                          *((f"{k} [%]", f"the mean over the {k} alone") for k in parts),
                          ("choice", "`chosen` (the simplest, fewest parameters then "
                           "physically consistent, whose split-by-split excess over the "
                           "lowest is within one standard error) or `lowest` (the lowest "
                           "error)")), *(["", sel.screen.line()] if sel.screen else [])]
        if self.prior_selection is not None:
            lines += ["", "pull toward the a-priori parameters chosen by validation (the "
                          "strongest within one standard error of the lowest):", "",
                      markdown_table(["prior strength", "CV error [%]", "choice"],
                                     self.prior_selection.table()),
                      "", columns_note(
                          ("prior strength", "weight of the pull toward the a-priori "
                           "parameters, in multiples of the data term's mean curvature"),
                          ("CV error [%]", _cv_error(self.prior_selection.cross_validation)),
                          ("choice", "`chosen` (the strongest pull within one standard error "
                           "of the lowest) or `lowest` (the lowest CV error)"))]
        lines += held_out_lines(self.validations, joints)
        if self.simulator is not None:
            lines += self.simulator.lines()
        if self.made_for_mujoco is not None:
            lines += self.made_for_mujoco.lines(
                "beside it, the choice among the terms MuJoCo holds (`--mujoco-terms`, "
                f"friction {self.made_for_mujoco.friction}), not written:")
        if self.limits is None:
            lines += ["", "NRMS over torque limits: no limits known for this robot"]
        return "\n".join(lines)

    @property
    def signals(self) -> str:
        """How the identification data's signals were obtained, in words
        (:func:`~sedsabso_jax.measurements.describe_signals`), and that the written model
        carries none of it."""
        return (f"{describe_signals(self.data.info)}. This is the measurement's, not the "
                f"robot's: the identified model, URDF and MJCF carry none of it")

    def document(self, settings: dict) -> dict:
        """The JSON document: parameters, fit and validation metrics, ``settings`` merged
        with the identification's own."""
        ident = self.ident
        return jsonable({
            "base_parameters": {"names": ident.names, "values": ident.values,
                                "std": ident.std,
                                "relative_std_percent": ident.relative_std_percent},
            "fit": {**self.fit.as_dict(), "residual": ident.fit},
            "validation": None if self.validation is None else self.validation.as_dict(),
            "cross_validation": None if self.cross_validation is None else {
                **self.cross_validation.as_dict(),
                "selection": None if self.selection is None else self.selection.as_dict(),
                "prior_strength": None if self.prior_selection is None
                else self.prior_selection.as_dict()},
            "settings": {**settings, **ident.settings},
            "signals": {"description": self.signals, "info": self.data.info,
                        "choice": None if self.chain_selection is None
                        else self.chain_selection.as_dict()},
            "extrapolation": None if self.extrapolation is None
            else self.extrapolation.as_dict(),
            "rests": None if self.rests is None else self.rests.as_dict(),
            "validations": held_out_document(self.validations),
            "mujoco": None if self.simulator is None else {
                **self.simulator.as_dict(), "made_for_mujoco": None
                if self.made_for_mujoco is None else self.made_for_mujoco.as_dict()},
        })

    def figures(self) -> dict:
        """``{file name: figure}``: measured against predicted torques per data set
        (``torques_validation.png`` for one held-out recording, ``torques_validation_K.png``
        for the K-th of several), and with :attr:`simulator` their rollouts
        (``rollouts_fit.png``, ...)."""
        ident, robot = self.ident, self.ident.model.robot
        sets: list[tuple[str, Measurements, np.ndarray | None, str]] = [
            ("torques_fit.png", self.data, self.predicted[0], "identification data")]
        several = len(self.validations) > 1
        sets += [(f"torques_validation{f'_{k}' * several}.png", h.data, h.predicted,
                  f"held-out data{f': {h.name}' * several}")
                 for k, h in enumerate(self.validations, 1)]
        method = ident.method + (", physically consistent" if ident.full_params is not None
                                 else "")
        figures = {name: figure_torques(d.times, d.tau, pred,  # type: ignore[arg-type]
                                        robot.joint_names, f"{robot.name}, {method}: {label}")
                   for name, d, pred, label in sets}
        if self.simulator is not None:  # the rollouts, named as the torque figures
            for (name, _, _, label), r in zip(sets, self.simulator.rollouts.values()):
                figures[name.replace("torques", "rollouts")] = figure_rollouts(
                    r, robot, f"{robot.name}: open-loop rollouts, {label}")
        return figures

    def write(self, settings: dict, out_dir: PathLike | None = None,
              json_path: PathLike | None = None, urdf_path: PathLike | None = None,
              urdf_source: PathLike | None = None, mjcf_path: PathLike | None = None
              ) -> list[str]:
        """Write the figures and ``identification.json`` into ``out_dir`` (created if
        missing), the JSON also to ``json_path`` and the identified robot's URDF to
        ``urdf_path`` (``urdf_source`` updated, if given: :meth:`Identification.urdf`),
        its MJCF (:meth:`with_mjcf`) to ``mjcf_path`` (their directories created);
        everything is rendered before the first file is
        written. Returns the paths written."""
        document = self.document(settings)
        urdf = self.ident.urdf(urdf_source) if urdf_path is not None else None
        if mjcf_path is not None and self.mjcf is None:
            raise ValueError("write the MJCF of a report made with_mjcf()")
        figures = self.figures() if out_dir is not None else {}
        written = []
        if out_dir is not None:
            os.makedirs(out_dir, exist_ok=True)
            for name, fig in figures.items():
                save_figure(fig, os.path.join(out_dir, name))
                written.append(os.path.join(out_dir, name))
            write_json(os.path.join(out_dir, "identification.json"), document)
            written.append(os.path.join(out_dir, "identification.json"))
        outputs = ((json_path, write_json, document), (urdf_path, write_text, urdf),
                   (mjcf_path, write_text, self.mjcf))
        for path, write, body in outputs:
            if path is not None and body is not None:
                os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
                write(path, body)  # type: ignore[arg-type]
                written.append(os.fspath(path))
        return written
