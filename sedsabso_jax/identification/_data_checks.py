"""Joint data checked before an identification works on them.

Data that cannot give an answer are refused with a ValueError naming the recording, the
joint, the value and what was expected: too few samples for the model's parameters
(:func:`check_samples`), no joint that moves (:func:`check_motion`), an excitation that
does not determine the robot's base parameters (:func:`check_excitation`), signals far
outside the robot's limits (:func:`check_torques`, :func:`check_limits`: degrees for
radians, torques in the wrong unit), a validation whose splits cannot be fitted
(:func:`check_splits`), the same recording given with and without a payload
(:func:`check_distinct`), drive gains that are not positive (:func:`check_gains`). Data a
fit can still use get a ``UserWarning`` naming what and where (a joint that never moves,
a poor excitation, torques beyond the effort limits). How the thresholds sit against the
shipped real recordings: docs/explanation/identification-defaults.md.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np

from .._deprecation import caller_stacklevel
from ..dynamics._robot import Robot
from ..measurements._container import Measurements
from ..optim._linear import ILL_RTOL, factorize

#: Torque equations (samples x joints) per parameter the fit needs. With ``m`` equations
#: and ``d`` parameters a least-squares residual's RMS is ``sqrt(1 - d/m)`` of the
#: noise's and a prediction's ``sqrt(1 + d/m)``: at 5 per parameter both within 11 %, so
#: the fit's and the validated errors mean what they say (whether the motion determines
#: the parameters is the condition number's to say, :data:`COND_ERROR`).
MIN_ROWS_PER_PARAMETER = 5
#: ... per parameter each validation split fits: a split's prediction RMS is then within
#: 15 % (``sqrt(1 + 1/3)``) of the noise's; phase folds fit 4/5 of the samples, speed
#: splits most of them.
MIN_SPLIT_ROWS_PER_PARAMETER = 3
#: A joint whose position spans less than this (rad, or m on a prismatic joint) over all
#: the recordings never moves: its friction and inertia are at most in the encoder's
#: noise and the backlash.
STILL_RANGE = 0.01
#: Condition number (unit-norm columns) of the base regressor above which the excitation
#: is poor (a warning): torque errors of 0.1 % may then move the least determined
#: combination of parameters by 100 %.
COND_WARN = 1e3
#: ... and above which the data do not determine the base parameters (an error): the
#: ratio the package calls poorly identifiable (``optim._linear.ILL_RTOL``).
COND_ERROR = 1.0 / ILL_RTOL
#: A joint's peak torque (or speed) beyond this many times its effort (or velocity)
#: limit is in another unit (mN m or N cm for N m, deg/s for rad/s: 100 to 1000 x):
#: no drive delivers 10 times its rated peak. Between 1 and this: a warning (torques).
LIMIT_FACTOR = 10.0
#: The quantile of ``|tau|`` (``|qd|``) called a joint's peak: one spike does not count.
PEAK_QUANTILE = 0.995
#: Positions beyond a joint's limits by more than this many times its range (``q_max -
#: q_min``) are an error: no zero offset does that (a URDF's limits are often the
#: controller's, inside the stops), while degrees for radians (57 x) do as soon as a
#: joint passes (its limit + its range) / 57 rad, and millimetres for metres (1000 x).
POSITION_RANGES = 1.0


def joint_label(robot: Robot, j: int) -> str:
    """``"joint 2 (lwr_arm_1_joint)"``: the joint's number and the robot's name for it."""
    name = robot.joint_names[j] if j < len(robot.joint_names) else ""
    return f"joint {j + 1}" + (f" ({name})" if name and name != f"J{j + 1}" else "")


def _source(d: Measurements, k: int, count: int) -> str:
    if d.source and d.source not in ("arrays", "simulated") and not d.source.startswith(
            "arrays "):
        return d.source
    return "the data" if count == 1 else f"recording {k + 1}"


def _signal(d: Measurements, field: str, j: int) -> str:
    """A joint's signal as the file names it: ``positions (column q2)`` in a CSV file,
    the array's name otherwise."""
    prefix = {"positions": "q", "velocities": "qd", "torques": "tau"}[field]
    if d.info.get("format") == "csv":
        return f"{field} (column {prefix}{j + 1})"
    return field


def _recordings(recordings: Measurements | Sequence[Measurements]) -> list[Measurements]:
    return [recordings] if isinstance(recordings, Measurements) else list(recordings)


def check_samples(robot: Robot, recordings: Sequence[Measurements], n_parameters: int,
                  what: str = "the torque model") -> None:
    """At least :data:`MIN_ROWS_PER_PARAMETER` torque equations (samples x joints) per
    parameter of ``what`` (``n_parameters``, the largest model tried)."""
    recordings = _recordings(recordings)
    samples = sum(d.n_samples for d in recordings)
    n = robot.n_joints
    need = MIN_ROWS_PER_PARAMETER * n_parameters
    if samples * n < need:
        names = ", ".join(_source(d, k, len(recordings)) for k, d in enumerate(recordings))
        raise ValueError(
            f"{names}: {samples} samples x {n} joints = {samples * n} torque equations for "
            f"the {n_parameters} parameters of {what}; at least {MIN_ROWS_PER_PARAMETER} "
            f"per parameter ({-(-need // n)} samples) are needed to fit them and judge the "
            f"fit: record a longer motion")


def still_joints(robot: Robot, recordings: Sequence[Measurements]) -> np.ndarray:
    """The joints whose positions span less than :data:`STILL_RANGE` over all the
    recordings (indices)."""
    q = np.concatenate([d.q for d in _recordings(recordings)])
    return np.flatnonzero(np.ptp(q, axis=0) < STILL_RANGE)


def check_motion(robot: Robot, recordings: Sequence[Measurements], what: str = "the data",
                 warn: bool = True) -> np.ndarray:
    """A ValueError when no joint moves in ``recordings`` (``what`` names them); a
    warning (``warn``) naming each joint that never moves (its parameters are not
    identified). Returns the still joints' indices."""
    recordings = _recordings(recordings)
    still = still_joints(robot, recordings)
    q = np.concatenate([d.q for d in recordings])
    span = np.ptp(q, axis=0)
    if still.size == robot.n_joints:
        raise ValueError(
            f"no joint moves in {what}: every joint's position spans less than "
            f"{STILL_RANGE:g} rad (the largest {span.max():.3g}); identification needs a "
            f"motion that excites the joints (an excitation trajectory)")
    if still.size and warn:
        joints = ", ".join(f"{joint_label(robot, j)} (spans {span[j]:.3g})" for j in still)
        one = still.size == 1
        warnings.warn(
            f"{joints} never {'moves' if one else 'move'} in {what} (less than "
            f"{STILL_RANGE:g} rad): {'its' if one else 'their'} friction and the inertia "
            f"only {'it excites are' if one else 'they excite are'} not identified (the "
            f"minimum-norm values), and the predicted error holds only for motions that "
            f"keep {'it' if one else 'them'} still", stacklevel=caller_stacklevel())
    return still


def check_excitation(robot: Robot, recordings: Sequence[Measurements], base, *,
                     regularized: bool = False) -> None:
    """The condition number (unit-norm columns) of ``base``'s regressor (the robot's base
    parameters, a :class:`~sedsabso_jax.BaseParameters`) at the recordings: a
    ValueError above :data:`COND_ERROR` (a warning when a prior pulls the fit,
    ``regularized``), a warning above :data:`COND_WARN`. Joints that never move are
    :func:`check_motion`'s to report (nothing here then)."""
    recordings = _recordings(recordings)
    if still_joints(robot, recordings).size:
        return
    q, qd, qdd, tau = (np.concatenate([getattr(d, f) for d in recordings])
                       for f in ("q", "qd", "qdd", "tau"))
    Y = np.asarray(base.regressor(q, qd, qdd))
    factor = factorize(Y.reshape(-1, Y.shape[-1]), tau.reshape(-1))
    cond = factor.condition_number
    if cond <= COND_WARN:
        return
    names = list(base.names)
    weakest = ", ".join(names[k] for k in factor.order[::-1][:3])
    text = (f"the data excite the robot's base parameters poorly: the regressor's condition "
            f"number is {cond:.3g} with unit-norm columns (real excitation recordings give "
            f"6 to 54); least determined: {weakest}")
    if cond > COND_ERROR and not regularized:
        raise ValueError(f"{text}; above {COND_ERROR:.0e} the data do not determine them: "
                         f"record a longer or richer motion of every joint (an excitation "
                         f"trajectory)")
    warnings.warn(f"{text}: their values carry large standard deviations and the predicted "
                  f"error holds only for motions like this one", stacklevel=caller_stacklevel())


def _peak(a: np.ndarray) -> np.ndarray:
    return np.quantile(np.abs(a), PEAK_QUANTILE, axis=0)


def check_torques(robot: Robot, recordings: Sequence[Measurements], limits,
                  warn: bool = True) -> None:
    """Each joint's peak torque against its effort limit (``limits``, ``(n,)`` or None):
    a ValueError beyond :data:`LIMIT_FACTOR` times it, a warning (``warn``: limits that
    are the drives', not weights) beyond it."""
    if limits is None:
        return
    recordings = _recordings(recordings)
    limits = np.asarray(limits, dtype=float)
    known = np.isfinite(limits) & (limits > 0)
    ratios = [np.where(known, _peak(d.tau) / np.where(known, limits, 1.0), 0.0)
              for d in recordings]

    def where(k: int, j: int) -> str:
        d = recordings[k]
        unit = "N m" if robot.joint_types[j] == "revolute" else "N"
        return (f"{_source(d, k, len(recordings))}: {joint_label(robot, j)}'s "
                f"{_signal(d, 'torques', j)} reach {ratios[k][j] * limits[j]:.4g}, "
                f"{ratios[k][j]:.3g} x its effort limit {limits[j]:.4g} {unit}")

    for k, ratio in enumerate(ratios):  # errors first: one line, no warning before it
        for j in map(int, np.flatnonzero(ratio > LIMIT_FACTOR)):
            raise ValueError(f"{where(k, j)}: torques in another unit? expected N m (N on a "
                             f"prismatic joint); currents need the drive gains "
                             f"(--drive-gains, drive_gains=)")
    for k, ratio in enumerate(ratios):
        for j in map(int, np.flatnonzero(ratio > 1) if warn else ()):
            warnings.warn(f"{where(k, j)}: beyond what the drive delivers; check the unit "
                          f"and the limit", stacklevel=caller_stacklevel())


def check_limits(robot: Robot, recordings: Sequence[Measurements], joint_limits,
                 what: str = "", torques: bool = True) -> None:
    """Positions and speeds against a :class:`~sedsabso_jax.JointLimits`:
    positions beyond a limit by more than the joint's range, or peak speeds beyond
    :data:`LIMIT_FACTOR` times the velocity limit, are a ValueError (degrees for
    radians). Then the torques (:func:`check_torques`) unless ``torques`` is False (they
    hold currents). ``what``: the source of the limits, for the messages (``" in
    lwr.urdf"``)."""
    recordings = _recordings(recordings)
    lo, hi = (np.asarray(joint_limits.q_min, float), np.asarray(joint_limits.q_max, float))
    qd_max = np.asarray(joint_limits.qd_max, float)
    span = hi - lo
    for k, d in enumerate(recordings):
        source = _source(d, k, len(recordings))
        below, above = lo - d.q.min(axis=0), d.q.max(axis=0) - hi
        excess = np.maximum(below, above)
        for j in map(int, np.flatnonzero(np.isfinite(span)
                                         & (excess > POSITION_RANGES * span))):
            unit = "rad" if robot.joint_types[j] == "revolute" else "m"
            value = d.q[:, j].min() if below[j] >= above[j] else d.q[:, j].max()
            raise ValueError(f"{source}: {joint_label(robot, j)}'s "
                             f"{_signal(d, 'positions', j)} reach {value:.4g}, beyond its "
                             f"limits{what} [{lo[j]:.4g}, {hi[j]:.4g}] {unit} by more than "
                             f"their range: positions in "
                             f"{'degrees' if unit == 'rad' else 'mm'}? expected {unit} (or "
                             f"another robot, or another joint order)")
        peak = _peak(d.qd)
        for j in map(int, np.flatnonzero(np.isfinite(qd_max)
                                         & (peak > LIMIT_FACTOR * qd_max))):
            unit = "rad/s" if robot.joint_types[j] == "revolute" else "m/s"
            raise ValueError(f"{source}: {joint_label(robot, j)}'s "
                             f"{_signal(d, 'velocities', j)} reach {peak[j]:.4g}, "
                             f"{peak[j] / qd_max[j]:.3g} x its velocity limit{what} "
                             f"{qd_max[j]:.4g} {unit}: speeds in another unit? expected {unit}")
    if torques:
        check_torques(robot, recordings, np.asarray(joint_limits.tau_max, float))


def check_splits(splits, n_joints: int, n_parameters: int) -> None:
    """That every split of a validation fits at least
    :data:`MIN_SPLIT_ROWS_PER_PARAMETER` torque equations per parameter, else a
    ValueError: its error could not be measured, and none is predicted from it."""
    need = MIN_SPLIT_ROWS_PER_PARAMETER * n_parameters
    for name, train in zip(splits.names, splits.train):
        rows = int(np.count_nonzero(train)) * n_joints
        if rows < need:
            raise ValueError(
                f"the validation cannot measure an error: its split '{name}' fits "
                f"{rows // n_joints} samples x {n_joints} joints = {rows} torque equations "
                f"for {n_parameters} parameters, fewer than {MIN_SPLIT_ROWS_PER_PARAMETER} "
                f"per parameter; record a longer motion, or choose another validation "
                f"(--validation), or none (--folds 0, validation=None: no predicted error)")


def check_distinct(unloaded: Sequence[Measurements], loaded: Sequence[Measurements],
                   flags: tuple[str, str] = ("unloaded (--data)", "loaded (--loaded)")
                   ) -> None:
    """That no recording is given both without and with the payload (the payload's
    torque would be nothing): a ValueError naming them (``flags``: what the two are
    called)."""
    for a in unloaded:
        for b in loaded:
            same = a is b or (a.q.shape == b.q.shape and np.array_equal(a.q, b.q)
                              and np.array_equal(a.tau, b.tau))
            if same:
                raise ValueError(
                    f"the {flags[0]} recording {a.source} and the {flags[1]} one {b.source} "
                    f"are the same: the payload's torque is their difference; give "
                    f"recordings made without the payload and with it")


def check_gains(gains, n: int, what: str = "drive gains") -> np.ndarray:
    """``gains`` as ``n`` positive finite numbers (torque per unit of current), else a
    ValueError naming the first that is not."""
    values = np.asarray(gains, dtype=float).reshape(-1)
    if values.shape != (n,):
        raise ValueError(f"{what}: expected {n} numbers (one per joint), got {values.size}")
    bad = np.flatnonzero(~(np.isfinite(values) & (values > 0)))
    if bad.size:
        j = int(bad[0])
        raise ValueError(f"{what}: gain {j + 1} is {values[j]:g}; expected positive finite "
                         f"numbers (torque per unit of current; a current recorded with the "
                         f"opposite sign: negate its column)")
    return values


def check_fit_data(robot: Robot, recordings: Sequence[Measurements], n_parameters: int,
                   base, limits=None, *, regularized: bool = False,
                   what: str = "the torque model") -> None:
    """What every identification checks first: enough samples
    (:func:`check_samples`), motion (:func:`check_motion`), torques within
    :data:`LIMIT_FACTOR` times ``limits`` (:func:`check_torques`; no warning below: the
    library's limits may be weights), the excitation (:func:`check_excitation`, the
    regressor of ``base``: its one evaluation, last)."""
    recordings = _recordings(recordings)
    check_samples(robot, recordings, n_parameters, what)
    check_motion(robot, recordings)
    check_torques(robot, recordings, limits, warn=False)  # the library's limits may weigh
    check_excitation(robot, recordings, base, regularized=regularized)


def pulled(estimator) -> bool:
    """Whether ``estimator`` pulls the fit toward a prior (a physically consistent one
    with ``prior_strength`` or ``prior_weight``): data that do not determine every
    parameter are then still meaningful."""
    return bool(getattr(estimator, "prior_strength", 0.0) or getattr(estimator,
                                                                       "prior_weight", 0.0))


def check_selection_data(robot: Robot, recordings: Sequence[Measurements], models: Sequence,
                         limits, validation, *, regularized: bool = False,
                         held_out: Sequence[Measurements] = ()) -> None:
    """:func:`~sedsabso_jax.select_and_identify`'s checks before its first fit: the data
    for the largest of ``models`` (:func:`check_fit_data`), every split of
    ``validation`` (None: none) fittable (:func:`check_splits`), and the torques of
    each ``held_out`` recording within reach of ``limits``."""
    n_parameters = max(m.dim for m in models)
    check_fit_data(robot, recordings, n_parameters, models[0].base, limits,
                   regularized=regularized, what="the largest torque model tried")
    if validation is not None:
        check_splits(validation.splits(recordings), robot.n_joints, n_parameters)
    if held_out:
        check_torques(robot, list(held_out), limits, warn=False)


def check_payload_data(robot: Robot, unloaded: Sequence[Measurements],
                       loaded: Sequence[Measurements], n_parameters: int) -> None:
    """What a payload's or the drive gains' identification checks first: enough samples
    for its ``n_parameters`` (:func:`check_samples`), motion in the recordings with the
    payload and in those without (:func:`check_motion`), no recording given as both
    (:func:`check_distinct`)."""
    check_samples(robot, [*unloaded, *loaded], n_parameters,
                  "the payload and the robot's model" if unloaded else "the payload")
    check_motion(robot, loaded, "the loaded recordings (--loaded, with the payload)",
                 warn=False)
    if unloaded:
        check_motion(robot, unloaded, "the unloaded recordings (--data, without the "
                     "payload)", warn=False)
    check_distinct(unloaded, loaded)
