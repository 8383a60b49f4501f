"""Where a new motion rests, against the recording a model was fitted to, and the
validated error weighed to the new motion's speeds.

An excitation recording barely rests: its joints pass through zero speed only at their
reversals. Point-to-point moves, pick and place and dwells spend much of their time at
rest or slow, where friction at rest, Stribeck friction and the velocity's noise make
most of the error, and a validation on the excitation recording weighs those samples by
their share in it. :func:`rests` measures, per joint, the share of samples

- at rest: ``|qd| < REST_SPEED`` of the joint's fitted peak speed;
- slow: ``|qd| < SLOW_SPEED`` of it (rests, starts, stops and reversals);

in both recordings, flags the joints where the new motion has more (by more than
:data:`SHARE_MARGIN`), and, given the chosen model's validation, weighs its
out-of-sample errors to the new motion's speeds: per joint, the mean squared error of
the validation's predicted samples in each band of ``|qd|`` over the fitted peak
(:data:`SPEED_BANDS`), weighed by the share of the new motion's samples in the band,
over the same weighed by the fitted recording's shares. The validated error times that
ratio (:attr:`Rests.factor`) is the error predicted for the new motion: equal to the
validated error for a motion with the fitted recording's mix of speeds, larger for one
that rests more (docs/results/extrapolation.md measures it against the error met).
Peaks are the 99.5 % quantiles of ``|qd|`` (:func:`~._splits.peak_speed`), as the
speed splits take them."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Sequence

import numpy as np

from ... import _deprecation
from ..._output import columns_note, markdown_table
from ...measurements._container import Measurements
from ._cross_validation import CrossValidation
from ._extrapolation import joint_names_of
from ._splits import peak_speed

#: |qd| below this fraction of the fitted peak speed: at rest.
REST_SPEED = 0.02
#: |qd| below this fraction of the fitted peak speed: slow (rests, starts, reversals).
SLOW_SPEED = 0.1
#: A joint is flagged where the new motion's share at rest or slow exceeds the fitted
#: recording's by more than this (a fraction of the samples).
SHARE_MARGIN = 0.05
#: Edges of the bands of |qd| / fitted peak speed the validated error is weighed over
#: (how they were chosen: docs/explanation/identification-defaults.md).
SPEED_BANDS = (REST_SPEED, SLOW_SPEED, 0.3)
#: The fewest predicted samples of a joint in a band for its own error; a band with
#: fewer takes the next faster band's.
MIN_SAMPLES = 20


def _bands(speed: np.ndarray, peak: np.ndarray) -> np.ndarray:
    """The band (0..len(SPEED_BANDS)) of each sample and joint."""
    with np.errstate(divide="ignore", invalid="ignore"):
        relative = np.where(peak > 0, np.abs(speed) / peak, np.inf)
    return np.searchsorted(np.asarray(SPEED_BANDS), relative, side="right")


def _shares(bands: np.ndarray, count: int) -> np.ndarray:
    """``(count, n)``: the share of each joint's samples in each band."""
    return np.stack([np.mean(bands == b, axis=0) for b in range(count)])


@dataclasses.dataclass(frozen=True)
class Rests:
    """Per joint, the share of samples at rest and slow in the fitted recording and in
    the new motion (see :func:`rests`); ``factor`` the validated error's weighing to the
    new motion's speeds and ``predicted`` the validated error times it (None without a
    validation)."""

    joint_names: tuple[str, ...]
    rest_share: np.ndarray
    new_rest_share: np.ndarray
    slow_share: np.ndarray
    new_slow_share: np.ndarray
    factor: float | None = None
    predicted: float | None = None
    joint_factors: np.ndarray | None = None

    def flagged(self) -> list[int]:
        """The joints whose new motion rests or moves slowly more than the fitted one."""
        return [j for j in range(len(self.joint_names))
                if self.new_rest_share[j] > self.rest_share[j] + SHARE_MARGIN
                or self.new_slow_share[j] > self.slow_share[j] + SHARE_MARGIN]

    def message(self) -> str | None:
        """One line naming the joints that rest more, with the prediction, or None."""
        parts = [f"{self.joint_names[j]} at rest {100 * self.new_rest_share[j]:.0f} % "
                 f"(fitted {100 * self.rest_share[j]:.0f} %), slow "
                 f"{100 * self.new_slow_share[j]:.0f} % ({100 * self.slow_share[j]:.0f} %)"
                 for j in self.flagged()]
        if not parts:
            return None
        text = ("the new motion rests or moves slowly more than the identification data, "
                "where friction at rest and the velocity's noise make most of the error: "
                + "; ".join(parts))
        if self.factor is not None:
            text += (f". Weighed to its speeds, the validated error becomes "
                     f"{self.predicted:.4f} % ({self.factor:.2f}x)")
        return text

    def warn(self) -> None:
        """A ``UserWarning`` with :meth:`message`, if any joint rests more."""
        text = self.message()
        if text is not None:
            warnings.warn(text, UserWarning, stacklevel=_deprecation.caller_stacklevel())

    def table(self) -> str:
        """Markdown table, one row per joint (columns in :meth:`note`)."""
        flagged = set(self.flagged())
        factors = (self.joint_factors if self.joint_factors is not None
                   else np.full(len(self.joint_names), np.nan))
        rows = [[name, f"{100 * self.rest_share[j]:.1f}", f"{100 * self.new_rest_share[j]:.1f}",
                 f"{100 * self.slow_share[j]:.1f}", f"{100 * self.new_slow_share[j]:.1f}",
                 f"{factors[j]:.2f}", "yes" if j in flagged else "no"]
                for j, name in enumerate(self.joint_names)]
        return markdown_table(["joint", "fitted at rest [%]", "new at rest [%]",
                               "fitted slow [%]", "new slow [%]", "error factor", "rests more"],
                              rows, align=["left"] + ["right"] * 5 + ["left"])

    def note(self) -> str:
        """The note under :meth:`table` that defines its columns."""
        return columns_note(
            ("joint", "one row per joint"),
            (("fitted at rest [%]", "new at rest [%]"), "the share of the identification "
             f"data's (the new motion's) samples where |qd| is below {REST_SPEED:g} of the "
             "joint's peak speed in the identification data (its 99.5 % quantile of |qd|)"),
            (("fitted slow [%]", "new slow [%]"), f"the same below {SLOW_SPEED:g} of it "
             "(rests, starts, stops and reversals)"),
            ("error factor", "the joint's validated RMS error weighed to the new motion's "
             "speeds over the same weighed to the identification data's (bands of |qd| / "
             f"peak with edges {', '.join(f'{b:g}' for b in SPEED_BANDS)}; `nan`: no "
             "validation)"),
            ("rests more", f"`yes` where the new motion's share at rest or slow exceeds the "
             f"identification data's by more than {100 * SHARE_MARGIN:g} % of the samples "
             "(the joints the warning names)"))

    def as_dict(self) -> dict:
        return {"joint_names": list(self.joint_names),
                "rest_share": self.rest_share.tolist(),
                "new_rest_share": self.new_rest_share.tolist(),
                "slow_share": self.slow_share.tolist(),
                "new_slow_share": self.new_slow_share.tolist(),
                "rests_more": [self.joint_names[j] for j in self.flagged()],
                "error_factor": self.factor, "predicted_percent": self.predicted,
                "joint_error_factors": None if self.joint_factors is None
                else self.joint_factors.tolist(),
                "thresholds": {"rest_speed": REST_SPEED, "slow_speed": SLOW_SPEED,
                               "share_margin": SHARE_MARGIN, "speed_bands": list(SPEED_BANDS)}}


def _band_errors(cv: CrossValidation, bands: np.ndarray, count: int) -> np.ndarray:
    """``(count, n)``: the mean squared error of ``cv``'s predicted samples per band of
    each joint, a band with fewer than :data:`MIN_SAMPLES` taking the next faster's (the
    fastest populated band's where none is faster)."""
    if cv.residuals is None or cv.tested is None:
        raise ValueError("the validation kept no residuals (a CrossValidation of this "
                         "version's cross_validate or select_model is needed)")
    tested_bands = bands[cv.tested]
    out = np.full((count, bands.shape[1]), np.nan)
    for j in range(bands.shape[1]):
        found = np.nan
        for b in reversed(range(count)):  # fastest first: a sparse band takes the faster's
            inside = tested_bands[:, j] == b
            if inside.sum() >= MIN_SAMPLES:
                found = float(np.mean(cv.residuals[inside, j] ** 2))
            out[b, j] = found
        populated = np.flatnonzero(~np.isnan(out[:, j]))
        if len(populated):  # bands faster than any populated one: the fastest's
            out[populated[-1]:, j] = out[populated[-1], j]
        else:
            out[:, j] = float(np.mean(cv.residuals[:, j] ** 2))
    return out


def rests(data: Measurements, held_out: Measurements, *,
          cross_validation: CrossValidation | None = None,
          limits: Sequence[float] | np.ndarray | None = None,
          joint_names: Sequence[str] | None = None, warn: bool = False) -> Rests:
    """How much more ``held_out`` (a new motion; its torques are not read) rests than
    ``data`` (the joint-side :class:`~sedsabso_jax.Measurements` the model was fitted to,
    the recordings joined), per joint (module docstring); with ``cross_validation`` (the
    chosen model's, on ``data``'s samples in order), the validated error weighed to
    ``held_out``'s speeds: ``predicted = score x factor``, ``factor`` the mean over joints
    of each joint's weighed RMS error over the limits (``limits``; without, over the RMS
    of its measured torque) divided by the same at ``data``'s own speeds. ``warn``: a
    ``UserWarning`` naming the joints that rest more (:meth:`Rests.warn`)."""
    names = joint_names_of(data, held_out, joint_names)
    qd, qd_new = np.asarray(data.qd, float), np.asarray(held_out.qd, float)
    peak = peak_speed(qd)
    count = len(SPEED_BANDS) + 1
    bands, bands_new = _bands(qd, peak), _bands(qd_new, peak)
    shares, shares_new = _shares(bands, count), _shares(bands_new, count)
    factor = predicted = joint_factors = None
    if cross_validation is not None:
        if cross_validation.tested is not None and len(qd) <= int(cross_validation.tested.max()):
            raise ValueError(f"cross_validation predicted sample {cross_validation.tested.max()}"
                             f" of data's {len(qd)}: it is not a validation on data")
        errors = _band_errors(cross_validation, bands, count)
        rms = np.sqrt(np.sum(shares * errors, axis=0))
        rms_new = np.sqrt(np.sum(shares_new * errors, axis=0))
        scale = (np.asarray(limits, float) if limits is not None
                 else np.sqrt(np.mean(np.asarray(data.tau, float) ** 2, axis=0)))
        with np.errstate(divide="ignore", invalid="ignore"):
            joint_factors = np.where(rms > 0, rms_new / rms, 1.0)
        factor = float(np.sum(rms_new / scale) / np.sum(rms / scale))
        predicted = cross_validation.score * factor
    slow = len([b for b in SPEED_BANDS if b <= SLOW_SPEED])
    result = Rests(names, shares[0], shares_new[0], shares[:slow].sum(0),
                   shares_new[:slow].sum(0), factor, predicted, joint_factors)
    if warn:
        result.warn()
    return result
