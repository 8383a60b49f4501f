"""The command's default as one call: choose the torque model and the estimator by
validation, then (physically consistent fits) the pull to the prior, then fit, and
judge the fit on held-out data::

    report = select_and_identify(robot, data, held_out=other_run, limits=limits)
    # or several held-out runs, each judged alone: held_out=[run2, run3] or
    # held_out={"pick and place": run2, "faster": run3}
    print(report.text())          # what `sedsabso-jax identify` prints
    report.write(settings, out_dir, json_path)

``sedsabso-jax identify`` is this function with its flags turned into objects
(:func:`~._choice.estimator_candidates` for ``--method`` and ``--weights``,
:func:`~.._model._candidates.candidate_models` for ``--friction``); the rules between its
options are stated once, in :class:`~._choice.Choice`."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable

from ...dynamics._robot import Robot
from ...measurements._container import Measurements
from .._data_checks import check_selection_data
from .._estimators._estimator import Estimator, Limits, ProgressCallback, per_joint
from .._fit._identify import identified
from .._fit._samples import recorded
from .._model._candidates import candidate_models
from .._model._checks import model_of
from .._model._torque_model import TorqueModel
from .._options import one_or_more
from .._recordings import Data, recordings_of
from .._search._methods import Held
from .._validation._progress import Fits
from .._validation._selection import choose_prior_strength, revalidated, select_model
from .._validation._splits import Validation
from .._work import evaluate_seconds, fit_seconds
from ._choice import AUTO, Choice, DefaultValidation
from ._held_out import HeldOutData, named_recordings
from ._policy import DEFAULT
from ._report import IdentificationReport
from ._signals import choose_chain


def _work_after(estimators: Iterable[Estimator], models: Iterable[TorqueModel], rows: int,
                held_rows: int, fits: int, held_fits: int = 0) -> float:
    """The estimated seconds after the model choice, for the costliest of ``estimators``
    and ``models``: ``fits`` fits of the validations after it (the prior's), ``held_fits``
    with the searched values held (the signal chains'), the fit on all ``rows`` and the
    report's evaluation (with ``held_rows``)."""
    return max(fits * fit_seconds(e, m, rows)
               + held_fits * fit_seconds(e, dataclasses.replace(m, search=Held()), rows)
               + fit_seconds(e, m, rows, final=True)
               + evaluate_seconds(m, rows + held_rows) for e in estimators for m in models)


def select_and_identify(robot: Robot, data: Data, *, held_out: HeldOutData | None = None,
                        limits: Limits = None,
                        models: TorqueModel | Iterable[TorqueModel] | None = None,
                        estimators: Estimator | Iterable[Estimator] | None = None,
                        validation: Validation | DefaultValidation | None = DefaultValidation(),
                        physical: bool | None = None, prior_strength: float | str = 0.0,
                        progress: ProgressCallback | None = None) -> IdentificationReport:
    """Identify ``robot`` from ``data`` as ``sedsabso-jax identify`` does by default
    (:data:`~._policy.DEFAULT`): choose the estimator and the torque model by validation
    (:func:`~sedsabso_jax.select_model`: the simplest within one standard error of the
    lowest validated error) and the kept terms (added and kept unless they validate
    worse) and the screened scales (searched where they validate better), then the
    signal chain (:func:`~._signals.choose_chain`: the velocities and
    accelerations recorded or derived, the cutoff that derives them, the torques' delay;
    the held-out recordings made by the same chain), then the pull to the prior, fit on
    all of ``data``, and judge the fit on it, on the validation and on each held-out
    recording alone (never used to choose or fit), and, for several, on their mean. The
    rules between the options are :class:`Choice`'s.

    Arguments:
        data: a :class:`~sedsabso_jax.Measurements`, several (one rate, fitted together;
            one torque offset per recording: ``candidate_models(robot,
            recordings=len(data))``), or ``(times, q, qd, qdd, tau)``.
        held_out: one recording (a Measurements or its arrays), a list or tuple of
            Measurements, or a mapping name -> Measurements (named by the key, else by
            its ``source``).
        limits: per-joint torque limits (the NRMS measure and the 1/limit weighting;
            candidates weighting by them are skipped without).
        models: one :class:`~sedsabso_jax.TorqueModel` or several (default
            :func:`~sedsabso_jax.identification.candidate_models` of the robot).
        estimators: one :class:`~sedsabso_jax.Estimator` or several (default
            :data:`~sedsabso_jax.identification.ESTIMATOR_CANDIDATES`;
            :func:`~sedsabso_jax.identification.estimator_candidates`).
        validation: what chooses: :class:`~._choice.DefaultValidation` (phase folds, or
            leave one recording out, pooled with :class:`~sedsabso_jax.SpeedSplits`, and
            the kept terms), a :class:`~sedsabso_jax.Validation`, or None (one candidate,
            not validated).
        physical: None: each least-squares candidate unconstrained and physically
            consistent; True: only physically consistent; False: only unconstrained.
        prior_strength: the pull of a physically consistent fit toward the a-priori
            parameters, a number or ``"cv"`` (chosen from
            :data:`~sedsabso_jax.identification.PRIOR_STRENGTHS` by the same validation,
            :func:`~sedsabso_jax.choose_prior_strength`).
        progress: ``progress(label, done, total)`` after each fit and the evaluation,
            in estimated seconds (:mod:`~sedsabso_jax.identification._work`; ``total``
            revised as choices are made, ``done == total`` at the end); None: quiet.

    Returns the :class:`~._report.IdentificationReport` the command prints (``text()``)
    and writes (``write(...)``). Raises ValueError before the first fit for data that
    cannot give an answer (:func:`~.._data_checks.check_selection_data`)."""
    held = dict(named_recordings(robot, held_out))  # checked before any work
    recordings = recordings_of(robot, data)
    models = candidate_models(robot) if models is None else tuple(
        model_of(robot, m) for m in one_or_more(models, TorqueModel))
    estimators = DEFAULT.estimators if estimators is None else one_or_more(estimators,
                                                                           Estimator)
    choice = Choice(validation, physical, prior_strength, len(models) * len(estimators),
                    len(recordings), any(m.recordings > 1 for m in models))
    return chosen_and_identified(robot, recordings, choice, models, estimators, held=held,
                                 limits=limits, progress=progress)


def chosen_and_identified(robot: Robot, recordings: list[Measurements], choice: Choice,
                          models: tuple[TorqueModel, ...], estimators: tuple[Estimator, ...],
                          *, held: dict[str, Measurements], limits: Limits = None,
                          progress: ProgressCallback | None = None) -> IdentificationReport:
    """:func:`select_and_identify` by a :class:`~._choice.Choice` built once (the
    command's, from its flags): ``recordings`` checked (:func:`~.._recordings.recordings_of`),
    ``models`` and ``estimators`` the candidates, ``held`` the held-out recordings by
    name (:func:`~._held_out.named_recordings`)."""
    estimators = choice.estimators(estimators)
    chains = (choice.validation.chains(recordings)
              if isinstance(choice.validation, DefaultValidation) else ())
    # the delay is searched with the chains the default chooses among, not given ones
    delay = bool(chains) and isinstance(choice.validation, DefaultValidation) \
        and choice.validation.signals == AUTO
    if len(chains) == 1:  # given: applied to every recording, nothing chosen
        recordings = [r.with_chain(chains[0]) for r in recordings]
        held = {k: r if r.recorded is None else r.with_chain(chains[0])
                for k, r in held.items()}
        chains = ()
    chosen_by = choice.validation_of(recordings)
    check_selection_data(robot, recordings, models, per_joint("limits", limits, robot.n_joints),
                         chosen_by, held_out=list(held.values()),
                         regularized=choice.physical is True  # "cv" may choose none
                         and not isinstance(choice.prior_strength, str)
                         and choice.prior_strength > 0)
    kept, screened = ((choice.validation.kept, choice.validation.screened)
                      if isinstance(choice.validation, DefaultValidation) and len(models) > 1
                      else (None, None))
    # the work after the model choice, for the progress: the prior's validation, the fit
    # on all the data, the evaluation; of the costliest candidate until one is chosen
    rows, held_rows = sum(r.q.size for r in recordings), sum(r.q.size for r in held.values())
    splits = (len(chosen_by.splits(recordings))
              if progress is not None and chosen_by is not None else 0)
    prior_fits = len(DEFAULT.prior_strengths) * splits if choice.prior_strength == "cv" else 0
    # an estimate, each on all the rows: the chains' validations (the searched values
    # held), and a chosen chain's own (searched)
    chain_fits, revalidation = (len(chains) + delay) * splits, splits * bool(chains)
    fits = Fits(progress, _work_after(
        estimators, models + (() if kept is None else kept.models(models[-1])), rows,
        held_rows, prior_fits + revalidation, chain_fits) if progress is not None else 0.0)
    selection = cv = signals = None
    # the samples of all the data: the final fit reuses the chain's search of the model
    samples = recorded(robot, recordings)[1]
    if chosen_by is None:
        estimator, model = estimators[0], models[0]
    else:
        selection = select_model(robot, recordings, models=models, estimators=estimators,
                                 validation=chosen_by, limits=limits, kept=kept,
                                 screened=screened, progress=fits)
        if chains:
            fits.later = _work_after((selection.estimator,), (selection.model,), rows,
                                     held_rows, prior_fits)
            signals, recordings, chosen_by = choose_chain(
                robot, recordings, chains, selection.estimator, selection.model, chosen_by,
                per_joint("limits", limits, robot.n_joints), fits,
                DEFAULT.largest_delay_s if delay else None, samples)
            if signals is not None and signals.chosen:
                samples = recorded(robot, recordings)[1]
                held = {k: r.with_chain(signals.chain, given=False)
                        if r.recorded is not None else r for k, r in held.items()}
                selection = revalidated(selection, robot, recordings, chosen_by, limits,
                                        signals.labels[signals.chosen], fits)
        estimator, model = selection.estimator, selection.model
        cv = selection.cross_validation
        fits.step(f"{'chosen' if len(selection.candidates) > 1 else 'validated'}: "
                  f"{estimator.name}, {model.friction}", 0.0,
                  _work_after((estimator,), (model,), rows, held_rows, prior_fits))
    prior_selection = None
    final = fit_seconds(estimator, model, rows, final=True)
    evaluation = evaluate_seconds(model, rows + held_rows)
    if choice.physical is True and choice.prior_strength == "cv":
        fits.later = final + evaluation
        prior_selection = choose_prior_strength(robot, recordings, estimator, model,
                                                strengths=DEFAULT.prior_strengths,
                                                validation=chosen_by,  # type: ignore[arg-type]
                                                limits=limits, progress=fits)
        estimator, cv = prior_selection.estimator, prior_selection.cross_validation
    ident = identified(robot, recordings, estimator, model, limits,  # data checked above
                       samples=samples)[0]
    fits.step("fit on all the data", final, evaluation)
    report = IdentificationReport.evaluate(ident, recordings, held or None, limits,
                                           cross_validation=cv, selection=selection,
                                           prior_selection=prior_selection)
    report = dataclasses.replace(report, chain_selection=signals)
    fits.step("evaluated" + (" on the held-out data" if held else ""), evaluation, 0.0)
    return report
