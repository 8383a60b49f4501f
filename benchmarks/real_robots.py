"""How `sedsabso-jax identify`'s default generalises on three real robots: the KUKA LWR4+
(joint torque sensors; two runs of one trajectory), the Franka Emika Panda (link-side
torque sensors) and the Staubli TX40 (motor side, coupled wrist).

The default (``sj.select_and_identify``) chooses method, weighting, torque model and
physical consistency by the phase folds and the speed splits pooled (``sj.Pooled``:
folds of the motion's phase, and each joint's fast samples predicted by a fit to its slow
ones), then the signal chain (velocities and accelerations recorded or derived, the
cutoff and the torques' delay; ``--signals as-loaded``: the signals as loaded), and the
part it is judged on is made by the chain it chose. Its generalisation is
measured on each recording by NESTED validation, the whole choice and fit made on one
part and judged on another that no choice or fit saw, in two ways:

- ``phase``: the recording's phase cut into 5 folds; each is predicted by the default
  chosen and fitted on the other 4 (motions like the fitted one: interpolation);
- ``speed``: for each joint, the samples where it moves faster than 0.8 of its peak speed
  are predicted by the default chosen and fitted on those where it moves slower than 0.7:
  a faster motion.

Beside it, on the same outer splits: the same 24 candidates chosen by the speed splits
alone and by the phase folds alone (what each part of the validation does), 0.4's
default (the choice by phase folds among the 12 unconstrained fits only) and plain OLS
(Coulomb + viscous friction). The KUKA's second run repeats the first's trajectory: its
figure measures repeatability, not generalisation.

    python -m benchmarks.real_robots [--json benchmarks/results/real_robots.json]

``--kept bound`` or ``--kept smooth`` gives the default alternatives to its friction at rest
(searched up to 20 mrad) for the validation to choose among: the same searched up to 0.5
rad, or with the smooth Coulomb's velocity scales searched too (issue 45).

Figures: NRMS over the joint torque limits [%] (RMS error / (2 limit), mean over joints).
"""

from __future__ import annotations

import argparse
import platform
import time
import warnings
from pathlib import Path

import jax
import numpy as np

import sedsabso_jax as sj
from benchmarks.output import to_json
from data import real_robots
from sedsabso_jax import Presliding
from sedsabso_jax.dynamics import joint_limits
from sedsabso_jax.identification import KEPT_TERMS, KeptTerms, candidate_models

DEFAULT = "default"
BY_SPEED = "the same candidates chosen by speed splits alone"
BY_PHASE = "the same candidates chosen by phase folds alone"
PREVIOUS = "0.4's default: phase folds, unconstrained"
PLAIN = "OLS, Coulomb + viscous"
SETTINGS = (DEFAULT, BY_SPEED, BY_PHASE, PREVIOUS, PLAIN)
#: ``--settings``' words for them.
WORDS = dict(zip(("default", "speed", "phase", "previous", "plain"), SETTINGS))


#: ``--kept``'s words: the default's kept terms, or alternatives the validation chooses
#: among (friction at rest searched up to 20 mrad, or up to 0.5 rad; or up to 20 mrad,
#: alone or with the smooth Coulomb's velocity scales searched).
_AT_REST = Presliding(fitted=True, largest=0.02)
KEPT = {"default": None,
        "bound": KeptTerms([(_AT_REST,), (Presliding(fitted=True, largest=0.5),)]),
        "smooth": KeptTerms([(_AT_REST,), (_AT_REST, sj.SmoothCoulomb(fitted=True))])}

#: ``--robots``' words.
ROBOTS = ("kuka", "panda", "tx40")


def datasets(tmp: Path, robots=ROBOTS):
    """(name, robot, measurements (joint side), limits, transmission, held-out runs)."""
    if "kuka" in robots:
        kuka = sj.robots.kuka_lwr4()
        yield ("KUKA LWR4+", kuka, sj.load_kuka_lwr4(1), joint_limits("kuka_lwr4", kuka),
               None, {"run 2 (repeats run 1: repeatability)": sj.load_kuka_lwr4(2)})
    if "panda" in robots:
        panda = sj.robots.franka_panda()
        data = sj.load_measurements(real_robots.panda_npz(tmp / "panda.npz"), n_joints=7,
                                    resample_hz=1000.0)
        yield "Franka Panda", panda, data, joint_limits("franka_panda", panda), None, {}
    if "tx40" in robots:
        tx40 = sj.robots.staubli_tx40()
        data, tr = real_robots.tx40_joint_side(tmp)
        yield ("Staubli TX40 (motor side, 1 kHz)", tx40, data,
               joint_limits("staubli_tx40", tx40), tr, {})



def nrms(ident, data, limits) -> float:
    pred = ident.predict(data.q, data.qd, data.qdd)
    return sj.validation_metrics(data.tau, pred, limits.torque_limits).nrms_limits_percent


def judged_on(fit, data: sj.Measurements) -> sj.Measurements:
    """``data`` made by the signal chain the default chose for ``fit`` (as loaded where it
    kept the loaded one, or for a plain fit)."""
    chosen = getattr(fit, "chain_selection", None)
    return data if chosen is None or chosen.chosen == 0 else data.with_chain(chosen.chain,
                                                                              given=False)


def fits(robot, train: sj.Measurements, limits, transmission, base, inner,
         settings=SETTINGS, signals=None, kept=None) -> dict:
    """The ``settings`` on ``train``: the reports of the choices, plain OLS's
    identification; ``inner``: the phase folds (a count, or labels) of the choices by
    phase folds and of the default's second validation; ``signals``: the default's
    (``DefaultValidation(signals=...)``: None, as loaded, or ``"auto"``, chosen);
    ``kept``: the default's kept terms (None: its own, ``KEPT_TERMS``)."""
    models = candidate_models(robot, transmission=transmission, base=base)
    common = dict(limits=limits.torque_limits, models=models)
    phase = sj.GivenFolds(inner) if np.ndim(inner) == 1 else sj.PhaseFolds(inner)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # the default: its candidates, then friction at rest kept unless worse
        made = {DEFAULT: lambda: sj.select_and_identify(
                    robot, train, validation=sj.identification.DefaultValidation(
                        interpolation=phase, signals=signals,
                        kept=KEPT_TERMS if kept is None else kept), **common),
                BY_SPEED: lambda: sj.select_and_identify(
                    robot, train, validation=sj.SpeedSplits(), **common),
                BY_PHASE: lambda: sj.select_and_identify(robot, train, validation=phase,
                                                         **common),
                PREVIOUS: lambda: sj.select_and_identify(
                    robot, train, physical=False, validation=phase, **common),
                PLAIN: lambda: sj.identify(robot, train, sj.OLS(), sj.TorqueModel.of(
                    robot, transmission=transmission, base=base),
                    limits=limits.torque_limits)}
        return {k: made[k]() for k in settings}


def _ident(fit):
    return fit if isinstance(fit, sj.Identification) else fit.ident


def _release_compiled() -> None:
    """Clear JAX's compiled programs once the process holds more than half the memory
    maps the kernel allows: each outer split's recording has its own length, every
    program compiled for it stays (about 50 per split, 4-5 maps each), and a longer
    nested run ran out of maps. Clearing at every split instead took 454 s against 348 s
    (the KUKA's default: what the splits share compiled again)."""
    try:
        with open("/proc/self/maps") as held, open("/proc/sys/vm/max_map_count") as most:
            crowded = sum(1 for _ in held) > int(most.read()) // 2
    except OSError:  # not Linux: no such limit read
        return
    if crowded:
        jax.clear_caches()


def evaluate(name, robot, data, limits, transmission, runs, folds=5,
             settings=SETTINGS, signals=None, kept=None) -> dict:
    base = sj.base_parameters(robot)
    t0 = time.perf_counter()
    phase = sj.PhaseFolds(folds).splits([data])
    speed = sj.SpeedSplits().splits([data])
    held: dict = {"phase": {k: [] for k in settings}, "speed": {k: [] for k in settings}}
    chosen: dict = {"phase": [], "speed": []}
    predicted: dict = {"phase": [], "speed": []}
    for kind, splits in (("phase", phase), ("speed", speed)):
        for train, test in zip(splits.train, splits.test):
            # phase: the inner folds are the outer ones left; speed: the slow part's own
            inner = (np.searchsorted(np.unique(phase.labels[train]), phase.labels[train])
                     if kind == "phase" else folds)
            found = fits(robot, data.subset(train), limits, transmission, base, inner,
                         settings, signals, kept)
            for label, fit in found.items():
                held[kind][label].append(nrms(_ident(fit), judged_on(fit, data.subset(test)),
                                              limits))
            chain = found[DEFAULT].chain_selection
            chosen[kind].append({**found[DEFAULT].selection.chosen, "signals": None if chain
                                 is None else chain.labels[chain.chosen]})
            predicted[kind].append(found[DEFAULT].cross_validation.score)
            _release_compiled()
    nested_s = time.perf_counter() - t0
    _release_compiled()
    full = fits(robot, data, limits, transmission, base, folds, settings, signals, kept)
    other_runs = {run: {label: nrms(_ident(f), judged_on(f, d), limits)
                        for label, f in full.items()} for run, d in runs.items()}
    report = full[DEFAULT]
    return {
        "robot": name, "samples": data.n_samples, "period_s": phase.period_s,
        "nested_held_out_percent": {kind: {k: {"mean": float(np.mean(v)), "splits": v}
                                           for k, v in rows.items()}
                                    for kind, rows in held.items()},
        "default_chosen_per_outer_split": chosen,
        "default_predicted_per_outer_split": predicted,
        "chosen_on_all_data": report.selection.chosen,
        "signals_on_all_data": None if report.chain_selection is None
        else report.chain_selection.as_dict(),
        "predicted_percent": report.cross_validation.score,
        "predicted_standard_error": report.cross_validation.standard_error,
        "part_scores": report.cross_validation.part_scores,
        **{key: full[k].selection.chosen for key, k in (
            ("by_speed_choice_on_all_data", BY_SPEED), ("by_phase_choice_on_all_data", BY_PHASE),
            ("previous_choice_on_all_data", PREVIOUS)) if k in full},
        "fit_percent": report.ident.fit["nrms_limits_percent"], "other_runs": other_runs,
        "candidates": [{"settings": s, "score": cv.score, "se": cv.standard_error,
                        **cv.part_scores, "n_parameters": cv.n_parameters}
                       for s, cv in report.selection.candidates],
        "nested_seconds": nested_s,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default="benchmarks/results/real_robots.json")
    ap.add_argument("--settings", default=",".join(WORDS),
                    help="the settings compared, comma-separated words of "
                         f"{', '.join(WORDS)} (default: all; 'default' must be one)")
    ap.add_argument("--signals", choices=("auto", "as-loaded"), default="auto",
                    help="the default's signal chain: chosen by validation (auto), or as "
                         "loaded")
    ap.add_argument("--kept", choices=tuple(KEPT), default="default",
                    help="the default's terms kept unless worse: its own (default), or "
                         "alternatives the validation chooses among (module docstring)")
    ap.add_argument("--robots", default=",".join(ROBOTS),
                    help=f"the robots, comma-separated words of {', '.join(ROBOTS)}")
    args = ap.parse_args(argv)
    robots = args.robots.split(",")
    if not set(robots) <= set(ROBOTS):
        ap.error(f"--robots: {sorted(set(robots) - set(ROBOTS))}; known: {', '.join(ROBOTS)}")
    words = args.settings.split(",")
    unknown = [w for w in words if w not in WORDS]
    if unknown or "default" not in words:
        ap.error(f"--settings: {unknown or 'default is needed'}; known: {', '.join(WORDS)}")
    settings = tuple(WORDS[w] for w in words)
    jax.config.update("jax_enable_x64", True)
    import tempfile

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, robot, data, limits, tr, runs in datasets(Path(tmp), robots):
            rows.append(evaluate(name, robot, data, limits, tr, runs, settings=settings,
                                 signals="auto" if args.signals == "auto" else None,
                                 kept=KEPT[args.kept]))
            r = rows[-1]
            print(f"{name}: chosen {r['chosen_on_all_data']}, predicted "
                  f"{r['predicted_percent']:.4f} %, nested {r['nested_seconds']:.0f} s",
                  flush=True)
    print("\n| robot | outer splits | " + " | ".join(settings) + " |")
    print("|---|---|" + "---|" * len(settings))
    for r in rows:
        for kind, h in r["nested_held_out_percent"].items():
            print(f"| {r['robot']} | {kind} | "
                  + " | ".join(f"{h[k]['mean']:.4f}" for k in settings) + " |")
    doc = {"machine": platform.processor() or platform.machine(), "rows": rows,
           "versions": {"sedsabso_jax": sj.__version__},
           "command": "python -m benchmarks.real_robots" + (
               "" if settings == SETTINGS else f" --settings {args.settings}") + (
               "" if args.signals == "auto" else f" --signals {args.signals}") + (
               "" if args.kept == "default" else f" --kept {args.kept}") + (
               "" if robots == list(ROBOTS) else f" --robots {args.robots}")}
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(to_json(doc))
    print(f"written: {args.json}")


if __name__ == "__main__":
    main()
