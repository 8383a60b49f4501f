"""How accurately is a payload identified? A simulation study on the four shipped robots
(issue 30, part 5).

Each robot carries a known payload (a box: mass, centre of mass off the frame's origin,
inertia about its CoM turned off the axes) on its last link, the Staubli TX40's on its
URDF's ``tool0`` frame (fixed to ``link_6``, to exercise the frame's change). It moves along
an exciting motion: the RS010N along the package's excitation design (Eq. 9, 100 Hz,
10 s), the KUKA LWR4+, the Franka Panda and the TX40 along their real recordings'
trajectories (200 Hz: the KUKA's 25 s, the Panda's 21 s and the TX40's 8.6 s, every 5th
sample of the latter two). The plant is the robot's own rigid-body parameters (the Panda,
which ships none: a physically consistent fit of its real recording), plus viscous and
Coulomb friction (each 3 % of the joint's RMS torque at its RMS speed), a torque offset
(2 % of it) and Gaussian torque noise (2 % of each joint's RMS torque), drawn anew per
seed for the run without the payload and the run with it, along the same motion.

Methods (each seed):

- ``joint``: ``sj.identify_payload(robot, loaded, link, unloaded=...)``, the default: the
  robot's torque model (viscous + Coulomb + offset) and the payload fitted together;
- ``difference``: the sample-by-sample difference of the two runs, ``tau_loaded -
  tau_unloaded = Y_k p`` (Khalil & Dombre's classical scheme; needs the same motion,
  aligned), least squares with Gautier's per-joint weights, unconstrained;
- ``identified``: ``sj.identify`` on the unloaded run (WLS, the same torque model), then
  the payload against that fit taken as given;
- ``own parameters``: the payload against the robot's own parameters (a URDF's, the
  paper's), friction and offsets unknown to them (not for the Panda, which has none).

and what breaks them (the KUKA): a friction that grows with the load (Coulomb friction 3 %
of each joint's rigid-body torque, in no candidate model), a payload that barely moves
the torques (0.1 kg), torque offsets that moved between the runs (by half, up on joints
1-4, down on 5-7; ``joint, offset per run``: the joint fit with one offset per run), and
(the RS010N) the loaded run along ANOTHER designed motion, which the difference cannot
use.

Figures per method and scenario (``noise``: the plant above; ``other motion``,
``offsets moved``, ``load friction``, ``0.1 kg payload``: the cases above), over the
seeds: ``mass %`` the mass error (mean of |error|), ``max %`` its largest, ``CoM mm`` the
CoM error (median of the distance), ``I_c %`` and ``I_o %`` the inertia errors about the
CoM and about the frame's origin (median of the Frobenius norm of the error over the true
one's), ``std %`` the predicted standard deviation of the mass (median), ``cond`` the
payload columns' condition number after the robot's (median).

    python -m benchmarks.payload [--seeds 5] [--json benchmarks/results/payload.json]

Typical output (2-core CPU VM, 2026-11-26, 5 seeds, 2-3 minutes; the rows that fit
here, all of them in ``benchmarks/results/payload.json``)::

    | robot | scenario | method | mass % | max % | CoM mm | I_c % | I_o % | std % | cond |
    |---|---|---|---|---|---|---|---|---|---|
    | RS010N | noise | joint | 0.384 | 0.755 | 16.8 | 92.7 | 46.5 | 0.465 | 3.03 |
    | RS010N | noise | difference | 0.438 | 0.813 | 24.4 | 212 | 90.4 | - | - |
    | RS010N | noise | identified | 0.38 | 0.76 | 17.2 | 94.5 | 47.3 | 0.361 | 3.06 |
    | RS010N | noise | own parameters | 8.15 | 8.48 | 401 | 348 | 835 | 0.995 | 3.05 |
    | RS010N | other motion | joint | 0.479 | 0.797 | 23.1 | 133 | 61.2 | 0.474 | 2.69 |
    | KUKA LWR4+ | noise | joint | 0.0309 | 0.0475 | 0.0539 | 15.1 | 3.7 | 0.0538 | 17.6 |
    | KUKA LWR4+ | noise | difference | 0.0307 | 0.0484 | 0.0479 | 15.9 | 3.73 | - | - |
    | KUKA LWR4+ | noise | identified | 0.0306 | 0.0459 | 0.0526 | 15 | 3.61 | 0.0449 | 17.6 |
    | KUKA LWR4+ | noise | own parameters | 2.54 | 2.63 | 21.6 | 1.89e+03 | 429 | 0.0851 | 16.7 |
    | KUKA LWR4+ | offsets moved | joint | 0.0341 | 0.0628 | 0.0384 | 32.4 | 7.78 | 0.0547 | 17.6 |
    | KUKA LWR4+ | offsets moved | difference | 0.0348 | 0.0573 | 0.221 | 51 | 12.2 | - | - |
    | KUKA LWR4+ | load friction | joint | 1.25 | 1.28 | 0.675 | 136 | 31.5 | 0.056 | 17.4 |
    | KUKA LWR4+ | load friction | difference | 1.05 | 1.11 | 0.745 | 491 | 117 | - | - |
    | KUKA LWR4+ | 0.1 kg payload | joint | 0.6 | 0.914 | 0.977 | 40.2 | 9.64 | 0.842 | 17.9 |
    | Franka Panda | noise | joint | 0.046 | 0.0877 | 0.0591 | 5.24 | 0.462 | 0.0568 | 10.2 |
    | Franka Panda | noise | difference | 0.047 | 0.0873 | 0.0606 | 5.64 | 0.503 | - | - |
    | Franka Panda | noise | identified | 0.0443 | 0.0841 | 0.0598 | 5.55 | 0.515 | 0.048 | 8.88 |
    | Staubli TX40 | noise | joint | 0.19 | 0.358 | 0.0909 | 1.92 | 0.2 | 0.21 | 3.37 |
    | Staubli TX40 | noise | difference | 0.193 | 0.363 | 0.0924 | 2.1 | 0.25 | - | - |
    | Staubli TX40 | noise | identified | 0.184 | 0.364 | 0.0904 | 2.15 | 0.204 | 0.168 | 3.28 |
    | Staubli TX40 | noise | own parameters | 1.53 | 1.68 | 0.962 | 9.08 | 0.415 | 0.412 | 3.85 |
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
from data import real_robots
from sedsabso_jax.dynamics import fixed_link_pose, params_from_com
from sedsabso_jax.excitation import DesignSearch

NOISE, FRICTION, OFFSET = 0.02, 0.03, 0.02
TERMS = (sj.Offset(),)


def box(mass: float, sides, angle: float) -> np.ndarray:
    """A box's inertia about its CoM, turned by ``angle`` about z then x."""
    a, b, c = sides
    inertia = mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    cz, sz, cx, sx = np.cos(angle), np.sin(angle), np.cos(angle / 2), np.sin(angle / 2)
    R = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1.0]]) @ np.array(
        [[1.0, 0, 0], [0, cx, -sx], [0, sx, cx]])
    return R @ inertia @ R.T


def motions(tmp: Path):
    """(name, robot, motion (times, q, qd, qdd), link, urdf or None, payload, second
    motion or None)."""
    rs = sj.robots.rs010n()
    designs = [sj.design_excitation(rs, sj.JointLimits.rs010n(), search=DesignSearch(),
                                    key=key) for key in (0, 1)]
    times = np.arange(1000) / 100.0
    rs_motions = [(times, *d.trajectory.sample(times)) for d in designs]
    yield ("RS010N", rs, rs_motions[0], "link3", None,
           (5.0, [0.10, 0.05, -0.03], box(5.0, (0.3, 0.2, 0.15), 0.5)), rs_motions[1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the vendored KUKA URDF's duplicate <origin>
        kuka = sj.robots.kuka_lwr4()
    m = sj.load_kuka_lwr4(1)
    yield ("KUKA LWR4+", kuka, (m.times, m.q, m.qd, m.qdd), "lwr_7_link", None,
           (2.0, [0.01, -0.02, 0.08], box(2.0, (0.10, 0.08, 0.12), 0.4)), None)
    panda = sj.robots.franka_panda()
    m = sj.load_measurements(real_robots.panda_npz(tmp / "panda.npz"), n_joints=7,
                             resample_hz=1000.0).downsample(5)
    yield ("Franka Panda", panda, (m.times, m.q, m.qd, m.qdd), "link7", None,
           (1.5, [0.02, 0.0, 0.12], box(1.5, (0.08, 0.08, 0.10), 0.3)), None)
    tx40 = sj.robots.staubli_tx40()
    m = real_robots.tx40_joint_side(tmp)[0].downsample(5)
    with sj.robots.staubli_tx40_urdf() as urdf:
        yield ("Staubli TX40", tx40, (m.times, m.q, m.qd, m.qdd), "tool0", str(urdf),
               (1.0, [0.0, 0.02, 0.05], box(1.0, (0.06, 0.05, 0.04), 0.6)), None)


def plant_params(name: str, robot: sj.Robot, tmp: Path) -> np.ndarray:
    """The plant's rigid-body parameters: the robot's own, the Panda's fitted."""
    if name != "Franka Panda":
        return np.asarray(robot.params, dtype=float).copy()
    data = sj.load_measurements(real_robots.panda_npz(tmp / "panda.npz"), n_joints=7,
                                resample_hz=1000.0).downsample(5)
    fit = sj.identify(robot, data, sj.PhysicallyConsistent(sj.OLS()))
    return np.asarray(fit.full_params, dtype=float)


class Case:
    """One robot, motion, plant and payload; :meth:`runs` draws a seed's recordings."""

    def __init__(self, name, robot, motion, link, urdf, payload, tmp):
        self.name, self.robot, self.motion, self.link, self.urdf = (name, robot, motion,
                                                                    link, urdf)
        moving, T = (fixed_link_pose(urdf, link, robot.link_names) if urdf
                     else (link, np.eye(4)))
        self.k, self.T = robot.link_names.index(moving), T
        self.mass, self.com, self.inertia_com = payload[0], np.asarray(payload[1]), payload[2]
        R, p = T[:3, :3], T[:3, 3]
        in_link = params_from_com(self.mass, R @ self.com + p, R @ self.inertia_com @ R.T)
        rigid = plant_params(name, robot, tmp).reshape(-1, 12)
        rigid[:, 10:] = 0.0
        t, q, qd, qdd = motion
        rms = np.sqrt(np.mean(np.asarray(sj.inverse_dynamics(
            robot, rigid.ravel(), q, qd, qdd)) ** 2, axis=0))
        rigid[:, 10] = FRICTION * rms  # Coulomb
        rigid[:, 11] = FRICTION * rms / np.sqrt(np.mean(qd ** 2, axis=0))  # viscous
        self.plant, self.loaded_plant = rigid.ravel(), rigid.ravel().copy()
        self.loaded_plant[12 * self.k: 12 * self.k + 10] += in_link
        self.offset = OFFSET * rms * np.where(np.arange(robot.n_joints) % 2, 1.0, -1.0)

    def record(self, params, seed, motion=None, load_friction=0.0, offset=None
               ) -> sj.Measurements:
        t, q, qd, qdd = self.motion if motion is None else motion
        plant = self.robot.with_params(params)
        m = sj.simulate_measurements(plant, q, qd, qdd, t, torque_noise=NOISE, seed=seed)
        tau = m.tau + (self.offset if offset is None else offset)
        if load_friction:  # Coulomb friction growing with the rigid-body torque
            rigid = np.asarray(params).reshape(-1, 12).copy()
            rigid[:, 10:] = 0.0
            tau_rigid = np.asarray(sj.inverse_dynamics(self.robot, rigid.ravel(), q, qd, qdd))
            tau = tau + load_friction * np.abs(tau_rigid) * np.sign(qd)
        return sj.Measurements(t, q, qd, qdd, tau)

    def errors(self, mass, com, inertia_com) -> dict:
        """Errors of an estimate given in the named frame."""
        I_o = lambda m, c, Ic: Ic + m * (c @ c * np.eye(3) - np.outer(c, c))  # noqa: E731
        true_o = I_o(self.mass, self.com, self.inertia_com)
        found_o = I_o(mass, com, inertia_com)
        return {"mass_percent": 100 * (mass - self.mass) / self.mass,
                "com_mm": 1000 * float(np.linalg.norm(com - self.com)),
                "inertia_com_percent": 100 * float(np.linalg.norm(inertia_com
                                                                   - self.inertia_com)
                                                    / np.linalg.norm(self.inertia_com)),
                "inertia_percent": 100 * float(np.linalg.norm(found_o - true_o)
                                               / np.linalg.norm(true_o))}


def difference(case: Case, unloaded: sj.Measurements, loaded: sj.Measurements) -> dict:
    """The aligned runs' torque difference fitted by Gautier's weighted least squares, in
    the moving link's frame, then moved to the named frame."""
    t, q, qd, qdd = case.motion
    Y = np.asarray(sj.regressor(case.robot, q, qd, qdd))[..., 12 * case.k: 12 * case.k + 10]
    dtau = loaded.tau - unloaded.tau
    sigma = np.ones(case.robot.n_joints)
    for _ in range(2):
        W, b = (Y / sigma[:, None]).reshape(-1, 10), (dtau / sigma).reshape(-1)
        p = np.linalg.lstsq(W, b, rcond=None)[0]
        sigma = np.sqrt(np.mean((Y @ p - dtau) ** 2, axis=0)) + 1e-12
    m, h = p[6], p[7:]
    c_link = h / m
    I_link = np.array([[p[0], p[3], p[4]], [p[3], p[1], p[5]], [p[4], p[5], p[2]]])
    Ic_link = I_link - m * (c_link @ c_link * np.eye(3) - np.outer(c_link, c_link))
    R, pos = case.T[:3, :3], case.T[:3, 3]
    return case.errors(m, R.T @ (c_link - pos), R.T @ Ic_link @ R)


def ours(case: Case, payload: sj.Payload) -> dict:
    return {**case.errors(payload.mass, payload.com, payload.inertia_com),
            "mass_std_percent": 100 * payload.std["mass"] / payload.mass,
            "condition_number": payload.fit["condition_number"]}


def methods(case: Case, model: sj.TorqueModel, unloaded, loaded, robot_fixed: bool) -> dict:
    """Each method's errors on one seed's runs."""
    out = {"joint": ours(case, sj.identify_payload(case.robot, loaded, case.link,
                                                   unloaded=unloaded, model=model,
                                                   urdf=case.urdf)),
           "difference": difference(case, unloaded, loaded)}
    fit = sj.identify(case.robot, unloaded, sj.WLS(), model)
    out["identified"] = ours(case, sj.identify_payload(fit, loaded, case.link,
                                                       urdf=case.urdf))
    if robot_fixed:
        out["own parameters"] = ours(case, sj.identify_payload(case.robot, loaded, case.link,
                                                               urdf=case.urdf))
    return out


def summary(found: list[dict]) -> dict:
    """Mean and largest |mass error|, median of the other figures, over the seeds."""
    mass = np.abs([f["mass_percent"] for f in found])
    out = {"mass_mean_abs_percent": float(mass.mean()), "mass_max_abs_percent": float(
        mass.max()), "seeds": len(found)}
    for key in ("com_mm", "inertia_com_percent", "inertia_percent", "mass_std_percent",
                "condition_number"):
        if key in found[0]:
            out[f"{key}_median"] = float(np.median([f[key] for f in found]))
    return out


def study(seeds: int) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, robot, motion, link, urdf, payload, other in motions(Path(tmp)):
            t0 = time.perf_counter()
            case = Case(name, robot, motion, link, urdf, payload, Path(tmp))
            model = sj.TorqueModel.of(robot, TERMS)
            runs: dict[tuple[str, str], list[dict]] = {}
            for seed in range(seeds):
                unloaded = case.record(case.plant, 2 * seed)
                loaded = case.record(case.loaded_plant, 2 * seed + 1)
                for method, err in methods(case, model, unloaded, loaded,
                                           name != "Franka Panda").items():
                    runs.setdefault(("noise", method), []).append(err)
                if name == "KUKA LWR4+":
                    scenarios(case, model, seed, runs)
                if other is not None:
                    moved = case.record(case.loaded_plant, 2 * seed + 1, motion=other)
                    runs.setdefault(("other motion", "joint"), []).append(
                        ours(case, sj.identify_payload(robot, moved, link, unloaded=unloaded,
                                                       model=model, urdf=urdf)))
            for (scenario, method), found in runs.items():
                rows.append({"robot": name, "link": link, "scenario": scenario,
                             "method": method, **summary(found)})
            print(f"{name}: {time.perf_counter() - t0:.0f} s", flush=True)
    return rows


def scenarios(case: Case, model: sj.TorqueModel, seed: int, runs: dict) -> None:
    """What breaks it: load-dependent friction; a payload that barely moves the torques;
    and what does not break the joint fit: torque offsets that moved between the runs."""
    moved = case.offset * (1 + np.where(np.arange(case.robot.n_joints) < 4, 0.5, -0.5))
    unloaded = case.record(case.plant, 2 * seed)
    loaded = case.record(case.loaded_plant, 2 * seed + 1, offset=moved)
    key = "offsets moved"
    per_run = sj.TorqueModel.of(case.robot, TERMS, base=model.base, recordings=2)
    runs.setdefault((key, "joint, offset per run"), []).append(ours(case, sj.identify_payload(
        case.robot, loaded, case.link, unloaded=unloaded, model=per_run)))
    runs.setdefault((key, "joint"), []).append(ours(case, sj.identify_payload(
        case.robot, loaded, case.link, unloaded=unloaded, model=model)))
    runs.setdefault((key, "difference"), []).append(difference(case, unloaded, loaded))
    unloaded = case.record(case.plant, 2 * seed, load_friction=FRICTION)
    loaded = case.record(case.loaded_plant, 2 * seed + 1, load_friction=FRICTION)
    key = "load friction"
    runs.setdefault((key, "joint"), []).append(ours(case, sj.identify_payload(
        case.robot, loaded, case.link, unloaded=unloaded, model=model)))
    runs.setdefault((key, "difference"), []).append(difference(case, unloaded, loaded))
    light = Case(case.name, case.robot, case.motion, case.link, case.urdf,
                 (0.1, case.com, case.inertia_com / 20), Path("."))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the poorly determined mass is warned of
        found = sj.identify_payload(case.robot, light.record(light.loaded_plant, 2 * seed + 1),
                                    case.link, unloaded=light.record(light.plant, 2 * seed),
                                    model=model)
    runs.setdefault(("0.1 kg payload", "joint"), []).append(ours(light, found))


def table(rows: list[dict]) -> str:
    head = ("robot", "scenario", "method", "mass %", "max %", "CoM mm", "I_c %", "I_o %",
            "std %", "cond")
    keys = ("mass_mean_abs_percent", "mass_max_abs_percent", "com_mm_median",
            "inertia_com_percent_median", "inertia_percent_median",
            "mass_std_percent_median", "condition_number_median")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [r["robot"], r["scenario"], r["method"]] + [
            f"{r[k]:.3g}" if k in r else "-" for k in keys]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the URDFs' notes, rank warnings
        rows = study(args.seeds)
    print(table(rows))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json({"noise": NOISE, "friction": FRICTION, "offset": OFFSET,
                             "rows": rows, "device": device_info()}))


if __name__ == "__main__":
    main()
