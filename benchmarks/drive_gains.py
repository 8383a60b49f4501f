"""Drive gains from a known payload, and payloads from calibrated currents: a simulation
study on the four shipped robots (issue 37).

Each robot records currents, not torques: ``c = tau / g`` with true drive gains ``g``
drawn per joint in [0.05, 2] (torque per unit), and a published set off by up to 20 %
per joint. The plant (``Plant``): the robot's rigid-body parameters (the Panda's from a
physically consistent fit of its real run), viscous and Coulomb friction (each 3 % of
the joint's RMS torque), Coulomb friction growing with the load (3 % of the joint's
rigid-body torque, the payload's included), friction at rest (Dahl's presliding state,
``q_c`` in 5-20 mrad per joint, 3 % of the RMS torque), a torque offset (2 %), and 2 %
Gaussian noise of each joint's RMS torque; motions as ``benchmarks.payload``'s (the
RS010N's designed excitation, the KUKA's, the Panda's and the TX40's real trajectories).

``gains`` (every robot, each seed): recordings without and with a weighed calibration
payload (RS010N 10 kg, KUKA 3 kg, Panda 2 kg, TX40 2 kg on ``tool0``; its centre of mass
unknown to the fit), ``sj.identify_drive_gains`` by each method with the torque model
offset + load + presliding (``q_c`` 10 mrad, not the plant's); then another payload
(``benchmarks.payload``'s) picked up and identified by ``sj.identify_payload`` (same
torque model) from the currents turned into torques by the true, the identified
(likelihood) and the published gains. Figures: each joint's gain error (%), its
predicted relative standard deviation, whether it is calibrated (relative std at most
``sj.identification.CALIBRATED_STD``); the payload's mass error (%) and CoM error (mm).

``causes`` (the KUKA, true gains unless said): what moves a payload's mass, one cause at
a time, each against the plant above fitted with the full model (``baseline``):
gains 5 % off (all, or alternating), the published ones (up to 20 % off) or the
identified ones; the model without the load term (``no load friction``) or without
friction at rest; the payload's link barely turning (joints 2-7 at 10 % of their
excursion, only the vertical first axis moving fully: ``unexcited CoM``); velocities and
accelerations derived from filtered positions (10 Hz, the loader's default), the torques
unfiltered or filtered alike (``filtering``).

    python -m benchmarks.drive_gains [--seeds 3] [--part gains|causes|all] [--json PATH]

Typical output (2-core CPU VM, 2026-11-27, 3 seeds, 7 minutes; all the rows in
``benchmarks/results/drive_gains.json``): per joint the largest |gain error| (%, ``*``:
not calibrated) and the median predicted relative std (%); a payload's mass error (mean
/ largest, %) and CoM error (mm)::

    | robot | method or cause | gain error % | rel. std % | mass % | CoM mm |
    |---|---|---|---|---|---|
    | RS010N | ordinary | 24.51* 4.55 55.36* | 0.92 0.27 2.29 | | |
    | RS010N | total | 3.90* 0.22 7.11* | 0.90 0.33 1.25 | | |
    | RS010N | likelihood | 1.15* 0.38 0.45* | 0.91 0.26 1.56 | | |
    | RS010N | payload, identified gains | | | 0.13 / 0.20 | 21.56 |
    | KUKA LWR4+ | ordinary | 1.80 1.71 1.31 0.70 8.32 5.23 9.54 | ... | | |
    | KUKA LWR4+ | total | 0.13 0.11 0.23 0.22 1.24 0.21 0.37 | ... | | |
    | KUKA LWR4+ | likelihood | 0.07 0.10 0.12 0.12 0.68 0.08 0.23 | ... | | |
    | KUKA LWR4+ | payload, identified gains | | | 0.08 / 0.12 | 0.17 |
    | KUKA LWR4+ | payload, published gains | | | 11.92 / 13.67 | 26.07 |
    | Franka Panda | likelihood | 0.14 0.07 0.15 0.22 0.05 0.09 0.57 | ... | | |
    | Franka Panda | payload, identified gains | | | 0.04 / 0.08 | 0.08 |
    | Staubli TX40 | likelihood | 0.29 0.24 0.22 0.67 0.62 0.75 | ... | | |
    | Staubli TX40 | payload, identified gains | | | 0.20 / 0.44 | 0.12 |
    | KUKA LWR4+ | baseline | | | 0.09 / 0.14 | 0.16 |
    | KUKA LWR4+ | gains all 5 % high | | | 4.98 / 5.12 | 0.16 |
    | KUKA LWR4+ | no load friction in the model | | | 0.85 / 1.01 | 1.34 |
    | KUKA LWR4+ | unexcited CoM (joints 2-7 at 10 %) | | | 0.31 / 0.40 | 4.42 |
    | KUKA LWR4+ | filtering: torques unfiltered | | | 0.21 / 0.39 | 0.20 |
"""

from __future__ import annotations

import argparse
import tempfile
import time
import warnings
from pathlib import Path

import jax
import numpy as np

import sedsabso_jax as sj
from benchmarks.device import device_info
from benchmarks.output import to_json
from benchmarks.payload import box, motions, plant_params
from sedsabso_jax.dynamics import fixed_link_pose, params_from_com

NOISE, FRICTION, LOAD, REST, OFFSET, GAIN_ERROR = 0.02, 0.03, 0.03, 0.03, 0.02, 0.20
DISPLACEMENT = 0.01  # the model's presliding q_c (rad); the plant's are 5-20 mrad
METHODS = (sj.identification.OrdinaryGains(), sj.identification.TotalGains(),
           sj.identification.LikelihoodGains())
CALIBRATION = {"RS010N": (10.0, [0.05, 0.02, 0.1], (0.25, 0.2, 0.2)),
               "KUKA LWR4+": (3.0, [0.0, 0.01, 0.06], (0.1, 0.1, 0.12)),
               "Franka Panda": (2.0, [0.0, 0.01, 0.08], (0.08, 0.08, 0.1)),
               "Staubli TX40": (2.0, [0.01, 0.0, 0.04], (0.08, 0.06, 0.06))}


def dahl_loop(q, q_c):
    """Dahl's state along ``q`` by a plain loop (``benchmarks.friction_state``'s)."""
    z = np.zeros_like(q)
    for k in range(1, len(q)):
        s = np.sign(q[k] - q[k - 1])
        z[k] = s + (z[k - 1] - s) * np.exp(-np.abs(q[k] - q[k - 1]) / q_c)
    return z


def terms(load: bool = True, rest: bool = True) -> tuple:
    return (sj.Offset(), *([sj.LoadFriction()] if load else []),
            *([sj.Presliding(DISPLACEMENT)] if rest else []))


class Plant:
    """One robot, motion and plant (module docstring); :meth:`currents` records a run."""

    def __init__(self, name, robot, motion, link, urdf, tmp, seed):
        self.name, self.robot, self.motion, self.link, self.urdf = name, robot, motion, link, urdf
        moving, self.T = (fixed_link_pose(urdf, link, robot.link_names) if urdf
                          else (link, np.eye(4)))
        self.k = robot.link_names.index(moving)
        rigid = plant_params(name, robot, tmp).reshape(-1, 12)
        rigid[:, 10:] = 0.0
        t, q, qd, qdd = motion
        rms = np.sqrt(np.mean(np.asarray(sj.inverse_dynamics(
            robot, rigid.ravel(), q, qd, qdd)) ** 2, axis=0))
        rigid[:, 10] = FRICTION * rms
        rigid[:, 11] = FRICTION * rms / np.sqrt(np.mean(qd ** 2, axis=0))
        self.params = rigid.ravel()
        n = robot.n_joints
        rng = np.random.default_rng(1000 + seed)
        self.gains = rng.uniform(0.05, 2.0, n)
        self.published = self.gains * (1 + rng.uniform(-GAIN_ERROR, GAIN_ERROR, n))
        self.q_c, self.rest = rng.uniform(0.005, 0.02, n), REST * rms
        self.offset = OFFSET * rms * np.where(np.arange(n) % 2, 1.0, -1.0)

    def carrying(self, mass, com, inertia_com) -> np.ndarray:
        """The plant's parameters with a payload (given in the named link's frame)."""
        R, p = self.T[:3, :3], self.T[:3, 3]
        out = self.params.copy()
        out[12 * self.k: 12 * self.k + 10] += params_from_com(mass, R @ np.asarray(com) + p,
                                                              R @ inertia_com @ R.T)
        return out

    def torques(self, params, seed, motion=None, load=LOAD) -> np.ndarray:
        t, q, qd, qdd = self.motion if motion is None else motion
        tau = np.asarray(sj.inverse_dynamics(self.robot, params, q, qd, qdd))
        rigid = params.reshape(-1, 12).copy()
        rigid[:, 10:] = 0.0
        tau_rigid = np.asarray(sj.inverse_dynamics(self.robot, rigid.ravel(), q, qd, qdd))
        tau = (tau + load * np.abs(tau_rigid) * np.sign(qd) + self.rest * dahl_loop(q, self.q_c)
               + self.offset)
        noise = np.random.default_rng(seed).standard_normal(tau.shape)
        return tau + NOISE * np.sqrt(np.mean(tau ** 2, axis=0)) * noise

    def currents(self, params, seed, motion=None, load=LOAD) -> sj.Measurements:
        t, q, qd, qdd = self.motion if motion is None else motion
        return sj.Measurements(t, q, qd, qdd, self.torques(params, seed, motion, load)
                               / self.gains)


def as_torques(data: sj.Measurements, gains) -> sj.Measurements:
    return sj.Measurements(data.times, data.q, data.qd, data.qdd, data.tau * gains)


def payload_errors(plant: Plant, found: sj.Payload, truth) -> dict:
    mass, com, _ = truth
    return {"mass_percent": 100 * (found.mass - mass) / mass,
            "com_mm": 1000 * float(np.linalg.norm(found.com - np.asarray(com))),
            "mass_std_percent": 100 * found.std["mass"] / found.mass}


def gains_case(plant: Plant, picked, seed: int) -> list[dict]:
    """Each method's gains on one seed, then the picked payload with each set of gains."""
    M, com, sides = CALIBRATION[plant.name]
    calibration = (M, com, box(M, sides, 0.3))
    unloaded = plant.currents(plant.params, 3 * seed)
    loaded = plant.currents(plant.carrying(*calibration), 3 * seed + 1)
    model = sj.TorqueModel.of(plant.robot, terms())
    rows, found = [], {}
    for method in METHODS:
        t0 = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            gains = sj.identify_drive_gains(plant.robot, unloaded, loaded, plant.link, M,
                                            model=model, method=method, urdf=plant.urdf)
        found[method.name] = gains
        rows.append({"robot": plant.name, "seed": seed, "method": method.name,
                     "seconds": time.perf_counter() - t0,
                     "gain_error_percent": 100 * (gains.gains / plant.gains - 1),
                     "relative_std_percent": 100 * gains.relative_std,
                     "calibrated": gains.calibrated,
                     "warned": [str(w.message) for w in caught]})
    picked_loaded = plant.currents(plant.carrying(*picked), 3 * seed + 2)
    for label, g in (("true gains", plant.gains), ("identified gains", found["likelihood"].gains),
                     ("published gains", plant.published)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            payload = sj.identify_payload(plant.robot, as_torques(picked_loaded, g), plant.link,
                                          unloaded=as_torques(unloaded, g), model=model,
                                          urdf=plant.urdf)
        rows.append({"robot": plant.name, "seed": seed, "method": f"payload, {label}",
                     **payload_errors(plant, payload, picked)})
    return rows


def barely_moving(motion, joints=slice(1, None), share=0.1):
    """``motion`` with ``joints`` at ``share`` of their excursion about their mean."""
    t, q, qd, qdd = (np.array(a, dtype=float) for a in motion)
    mean = q[:, joints].mean(axis=0)
    q[:, joints] = mean + share * (q[:, joints] - mean)
    qd[:, joints] *= share
    qdd[:, joints] *= share
    return t, q, qd, qdd


def filtered(data: sj.Measurements, tmp: Path, filter_torques: bool) -> sj.Measurements:
    """``data`` as a logger gives it (positions and torques), loaded with velocities and
    accelerations derived through the loader's 10 Hz zero-phase filter."""
    path = tmp / "log.npz"
    np.savez(path, times=data.times, positions=data.q, torques=data.tau)
    return sj.load_measurements(path, filter_torques=filter_torques)


def causes(plant: Plant, picked, seed: int, tmp: Path) -> list[dict]:
    """What moves the picked payload's mass, one cause at a time (module docstring)."""
    model = sj.TorqueModel.of(plant.robot, terms())
    unloaded = plant.currents(plant.params, 3 * seed)
    loaded = plant.currents(plant.carrying(*picked), 3 * seed + 2)
    M, com, sides = CALIBRATION[plant.name]
    calibration = plant.currents(plant.carrying(M, com, box(M, sides, 0.3)), 3 * seed + 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        identified = sj.identify_drive_gains(plant.robot, unloaded, calibration, plant.link, M,
                                             model=model, urdf=plant.urdf).gains
    n = plant.robot.n_joints
    alternating = plant.gains * (1 + 0.05 * np.where(np.arange(n) % 2, 1.0, -1.0))
    cases = [("baseline", plant.gains, model, None),
             ("gains all 5 % high", 1.05 * plant.gains, model, None),
             ("gains 5 % off, alternating", alternating, model, None),
             ("gains published (up to 20 % off)", plant.published, model, None),
             ("gains identified", identified, model, None),
             ("no load friction in the model", plant.gains,
              sj.TorqueModel.of(plant.robot, terms(load=False), base=model.base), None),
             ("no friction at rest in the model", plant.gains,
              sj.TorqueModel.of(plant.robot, terms(rest=False), base=model.base), None),
             ("unexcited CoM (joints 2-7 at 10 %)", plant.gains, model,
              barely_moving(plant.motion)),
             ("filtering: torques unfiltered", plant.gains, model, False),
             ("filtering: torques filtered alike", plant.gains, model, True)]
    rows = []
    for label, gains, with_model, how in cases:
        u, l = as_torques(unloaded, gains), as_torques(loaded, gains)
        if isinstance(how, tuple):  # another motion
            u = as_torques(plant.currents(plant.params, 3 * seed, motion=how), gains)
            l = as_torques(plant.currents(plant.carrying(*picked), 3 * seed + 2, motion=how),
                           gains)
        elif how is not None:
            u, l = filtered(u, tmp, how), filtered(l, tmp, how)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found = sj.identify_payload(plant.robot, l, plant.link, unloaded=u,
                                        model=with_model, urdf=plant.urdf)
        rows.append({"robot": plant.name, "seed": seed, "cause": label,
                     **payload_errors(plant, found, picked)})
    return rows


def summary(rows: list[dict]) -> list[dict]:
    """Per robot and method (or cause), over the seeds: the largest |gain error| per
    joint, the median relative std, whether every seed calibrated the joint; the mean
    and largest |mass error| and the median CoM error."""
    out = []
    keys = sorted({(r["robot"], r.get("method") or r["cause"]) for r in rows},
                  key=lambda k: [(r["robot"], r.get("method") or r["cause"]) for r in rows]
                  .index(k))
    for robot, what in keys:
        found = [r for r in rows if r["robot"] == robot and (r.get("method") or r["cause"])
                 == what]
        s: dict = {"robot": robot, "what": what, "seeds": len(found)}
        if "gain_error_percent" in found[0]:
            err = np.array([r["gain_error_percent"] for r in found])
            s.update(gain_error_max_abs_percent=np.nanmax(np.abs(err), axis=0),
                     relative_std_median_percent=np.median(
                         [r["relative_std_percent"] for r in found], axis=0),
                     calibrated=np.all([r["calibrated"] for r in found], axis=0),
                     seconds_median=float(np.median([r["seconds"] for r in found])))
        else:
            mass = np.abs([r["mass_percent"] for r in found])
            s.update(mass_mean_abs_percent=float(mass.mean()),
                     mass_max_abs_percent=float(mass.max()),
                     com_mm_median=float(np.median([r["com_mm"] for r in found])),
                     mass_std_median_percent=float(np.median(
                         [r["mass_std_percent"] for r in found])))
        out.append(s)
    return out


def table(summaries: list[dict]) -> str:
    lines = ["| robot | method or cause | gain error % | rel. std % | mass % | CoM mm |",
             "|---|---|---|---|---|---|"]
    for s in summaries:
        if "gain_error_max_abs_percent" in s:
            err = " ".join(f"{e:.2f}" + ("" if ok else "*") for e, ok in
                           zip(s["gain_error_max_abs_percent"], s["calibrated"]))
            std = " ".join(f"{v:.2f}" for v in s["relative_std_median_percent"])
            lines.append(f"| {s['robot']} | {s['what']} | {err} | {std} | | |")
        else:
            lines.append(f"| {s['robot']} | {s['what']} | | | {s['mass_mean_abs_percent']:.2f}"
                         f" / {s['mass_max_abs_percent']:.2f} | {s['com_mm_median']:.2f} |")
    return "\n".join(lines) + "\n(* not calibrated: relative std above CALIBRATED_STD)"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--part", choices=("gains", "causes", "all"), default="all")
    parser.add_argument("--only", default=None, help="one robot's name, e.g. 'KUKA LWR4+'")
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    rows: dict[str, list] = {"gains": [], "causes": []}
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the URDFs' notes, rank warnings
        for name, robot, motion, link, urdf, picked, _ in motions(Path(tmp)):
            if args.only and name != args.only:
                continue
            t0 = time.perf_counter()
            for seed in range(args.seeds):
                plant = Plant(name, robot, motion, link, urdf, Path(tmp), seed)
                payload = (picked[0], picked[1], picked[2])
                if args.part in ("gains", "all"):
                    rows["gains"] += gains_case(plant, payload, seed)
                if args.part in ("causes", "all") and name == "KUKA LWR4+":
                    rows["causes"] += causes(plant, payload, seed, Path(tmp))
            print(f"{name}: {time.perf_counter() - t0:.0f} s", flush=True)
    summaries = summary(rows["gains"]) + summary(rows["causes"])
    print(table(summaries))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json({"noise": NOISE, "friction": FRICTION, "load": LOAD, "rest": REST,
                             "offset": OFFSET, "gain_error": GAIN_ERROR,
                             "displacement": DISPLACEMENT, "summary": summaries,
                             "rows": rows, "device": device_info()}))


if __name__ == "__main__":
    main()
