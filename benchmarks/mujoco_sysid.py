"""The package's identification against MuJoCo's own (``mujoco.sysid``, issue 44) on the
KUKA LWR4+: run 1 fitted, run 2 held out, the same data and filtering for both (the
package's loaded ``Measurements``).

Rows: the package's MJCF as written by ``sedsabso-jax identify ... --mjcf-out PATH
--mujoco-terms`` (read from ``--mjcf``, so that the identification is not rerun here), and
``mujoco.sysid.optimize`` (box-constrained Gauss-Newton/Levenberg-Marquardt with
finite-difference Jacobians) started from that MJCF and from the URDF's nominal model
(``to_mjcf(sj.robots.kuka_lwr4())``: CAD inertias, no friction, no armature, no offset),
with two residuals:

* ``torque``: MuJoCo's inverse dynamics (``mj_inverse``) at the measured q, qd, qdd against
  the measured torques (the actuators' ctrl), each joint over twice its torque limit;
* ``rollout``: open-loop rollouts (``mujoco.rollout``, the machinery of
  ``mujoco.sysid.sysid_rollout``) of windows of the measured motion, each started at the
  measured state and driven by the measured torques (held over each sample), compared on
  the joint positions (rad).

Parameters (``mujoco.sysid.Parameter`` with ``MjSpec`` modifiers): each joint's armature,
damping and frictionloss, each actuator's bias (the torque offset) and each body's full
inertia (``body_inertia_param(..., InertiaType.Pseudo)``: mass, CoM and rotational inertia
through the log-Cholesky pseudo-inertia, physically consistent by construction).

Columns: held-out (run 2) and identification-data (run 1) torque error, MuJoCo's
``mj_inverse`` against the measured torques, ``nrms_limits_percent``; median end error
(degrees, over windows and joints) of open-loop rollouts of 0.2 s and 0.5 s windows of run 2;
CPU seconds (``time.process_time()``) and wall seconds of each fit.

    python -m benchmarks.mujoco_sysid --mjcf /tmp/k.xml [--quick] [--json PATH]
"""

from __future__ import annotations

import argparse
import sys
import time
import xml.etree.ElementTree as ET

import jax
import mujoco
import mujoco.rollout
import mujoco.sysid as sysid
import numpy as np

import sedsabso_jax as sj
from benchmarks.output import to_json
from sedsabso_jax import validation_metrics
from sedsabso_jax.dynamics import joint_limits


class _Budget(Exception):
    """Raised from the optimizer's iteration callback when the time budget is spent."""


# --- models and parameters ---------------------------------------------------------

def _joint_dofs(m):
    """Each actuator's joint's dof and qpos address."""
    jnt = m.actuator_trnid[:, 0]
    return m.jnt_dofadr[jnt], m.jnt_qposadr[jnt]


def sysid_params(spec: mujoco.MjSpec, model: mujoco.MjModel, *, mass_bounds=(0.05, 20.0),
                 stretch_bounds=(0.01, 100.0), shear_offsets=(-1.0, 1.0),
                 com_offsets=(-0.5, 0.5), offset_bound=5.0) -> sysid.ParameterDict:
    """``mujoco.sysid`` parameters of the written MJCF: per joint armature, damping,
    frictionloss (>= 0), per actuator the bias (torque offset, +-``offset_bound`` about its
    value), per body its full inertia as a pseudo-inertia (bounds around the start)."""
    params = sysid.ParameterDict()

    def joint_attr(jname, attr, value, hi):
        def mod(s, p, jname=jname, attr=attr):
            cur = np.array(getattr(s.joint(jname), attr), dtype=float)
            if cur.ndim:  # e.g. damping: [linear, higher-order terms]
                cur.ravel()[0] = p.value[0]
                setattr(s.joint(jname), attr, cur)
            else:
                setattr(s.joint(jname), attr, float(p.value[0]))
        params.add(sysid.Parameter(f"{jname}_{attr}", value, 0.0, hi, modifier=mod))

    for a in range(model.nu):
        jid = model.actuator_trnid[a, 0]
        jname = model.joint(jid).name
        joint = spec.joint(jname)
        for attr in ("armature", "damping", "frictionloss"):
            value = float(np.ravel(getattr(joint, attr))[0])
            hi = max(10.0 * value, {"armature": 5.0, "damping": 10.0,
                                    "frictionloss": 5.0}[attr])
            joint_attr(jname, attr, value, hi)
        aname = model.actuator(a).name
        bias = float(model.actuator_biasprm[a, 0])

        def bias_mod(s, p, aname=aname):
            prm = np.array(s.actuator(aname).biasprm)
            prm[0] = p.value[0]
            s.actuator(aname).biasprm = prm
        params.add(sysid.Parameter(f"{aname}_bias", bias, bias - offset_bound,
                                   bias + offset_bound, modifier=bias_mod))
    for b in range(1, model.nbody):
        name = model.body(b).name
        params.add(sysid.body_inertia_param(
            spec, model, name, sysid.InertiaType.Pseudo,
            mass_bound_mult=np.array(mass_bounds),
            stretch_bound_mult=np.array(stretch_bounds),
            shear_bound_off=np.array(shear_offsets), ipos_bound_off=np.array(com_offsets),
            modifier=lambda s, p, name=name: _set_body_theta(s, name, p)))
    return params


def _set_body_theta(spec: mujoco.MjSpec, name: str, param) -> None:
    """Write a pseudo-inertia parameter (``theta``, ``mujoco.sysid``'s log-Cholesky
    parametrisation) into the body as mass, CoM and principal inertia with its frame.

    ``mujoco.sysid``'s own modifier (``apply_body_theta_inertia``) writes a full inertia
    with ``iquat`` NaN and a zero diagonal inertia, which MuJoCo 4.0.0's compiler rejects
    ("mass and inertia of moving bodies must be larger than mjMINVAL"), and compiles the
    spec once per body per evaluation; this writes the same inertia without compiling."""
    pi = sysid.model_modifier.pi_from_theta(np.asarray(param.value, dtype=float))
    mass = float(pi[0])
    com = pi[1:4] / mass
    skew = sysid.model_modifier.skew(com)
    inertia_com = pi[4:].reshape(3, 3) + mass * skew @ skew
    vals, vecs = np.linalg.eigh(0.5 * (inertia_com + inertia_com.T))
    if np.linalg.det(vecs) < 0:
        vecs[:, 0] = -vecs[:, 0]
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, vecs.ravel())
    body = spec.body(name)
    body.explicitinertial = True
    body.mass = mass
    body.ipos = com
    body.inertia = np.maximum(vals, 1e-12)
    body.iquat = quat
    body.fullinertia = np.full(6, np.nan)


def write_mjcf(xml_text: str, m: mujoco.MjModel) -> str:
    """``xml_text`` (an MJCF as the package writes it) with the compiled model ``m``'s
    joint armature, damping, frictionloss, actuator bias and body inertials, at full
    precision (``MjSpec.to_xml`` rounds to 6 digits, the timestep included), and the
    compiler's ``balanceinertia`` on (a thin body's A + B >= C can fail by rounding)."""
    root = ET.fromstring(xml_text)
    compiler = root.find("compiler")
    if compiler is None:
        compiler = ET.SubElement(root, "compiler")
    compiler.set("balanceinertia", "true")
    fmt = lambda a: " ".join(repr(float(v)) for v in np.ravel(a))  # noqa: E731
    for el in root.iter("joint"):
        if el.get("name") is None:
            continue
        j = m.joint(el.get("name"))
        dof = j.dofadr[0]
        el.set("armature", fmt(m.dof_armature[dof]))
        el.set("damping", fmt(m.dof_damping[dof]))
        el.set("frictionloss", fmt(m.dof_frictionloss[dof]))
    for el in root.iter("general"):
        a = m.actuator(el.get("name"))
        el.set("biasprm", fmt(m.actuator_biasprm[a.id, :3]))
    for body in root.iter("body"):
        b = m.body(body.get("name"))
        inertial = body.find("inertial")
        if inertial is None:
            inertial = ET.Element("inertial")
            body.insert(0, inertial)
        for key in ("quat", "diaginertia"):
            inertial.attrib.pop(key, None)
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, m.body_iquat[b.id])
        rot = rot.reshape(3, 3)
        full = rot @ np.diag(m.body_inertia[b.id]) @ rot.T
        inertial.set("pos", fmt(m.body_ipos[b.id]))
        inertial.set("mass", fmt(m.body_mass[b.id]))
        inertial.set("fullinertia", fmt([full[0, 0], full[1, 1], full[2, 2], full[0, 1],
                                         full[0, 2], full[1, 2]]))
    return ET.tostring(root, encoding="unicode")


def _clip_into_bounds(params):
    lo, hi = params.get_bounds()
    x = params.as_vector()
    params.update_from_vector(np.clip(x, lo, hi))


# --- residuals and errors ----------------------------------------------------------

def inverse_torques(m: mujoco.MjModel, d: mujoco.MjData, q, qd, qdd) -> np.ndarray:
    """The torques as measured (``ctrl``) that ``mj_inverse`` gives at the states, for a
    compiled model the residual modifies in place (``sj.identification.mujoco_torques``
    for an MJCF text)."""
    dof, _ = _joint_dofs(m)
    out = np.empty((len(q), m.nu))
    for k in range(len(q)):
        d.qpos[:], d.qvel[:], d.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(m, d)
        out[k] = d.qfrc_inverse[dof]
    return (out - m.actuator_biasprm[:, 0]) / m.actuator_gainprm[:, 0]


def _windows(n_samples, window, stride):
    return np.arange(0, n_samples - window, stride)


def rollout_q(models, d, data, starts, window):
    """Joint positions ``(len(models) * len(starts), window, n)`` of open-loop rollouts:
    each model from each window start (measured q, qd), ctrl = measured torque per sample
    (``mujoco.rollout``, the model's integrator and timestep)."""
    m0 = models[0]
    _, qadr = _joint_dofs(m0)
    dof, _ = _joint_dofs(m0)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS.value
    nstate = mujoco.mj_stateSize(m0, spec)
    x0 = np.empty((len(starts), nstate))
    for i, k in enumerate(starts):
        mujoco.mj_resetData(m0, d)
        d.qpos[qadr], d.qvel[dof] = data.q[k], data.qd[k]
        mujoco.mj_getState(m0, d, x0[i], spec)
    ctrl = np.stack([data.tau[k:k + window] for k in starts])
    n_models = len(models)
    state, _ = mujoco.rollout.rollout(
        [m for m in models for _ in starts], d, np.tile(x0, (n_models, 1)),
        np.tile(ctrl, (n_models, 1, 1)))
    off = mujoco.mj_stateSize(m0, mujoco.mjtState.mjSTATE_TIME.value)
    return state[:, :, off + qadr]


def mujoco_rollout_errors(xml_text: str, data, window_s: float, stride_s: float | None = None
                          ) -> np.ndarray:
    """Each window's end error per joint (degrees, ``(n_windows, n)``) of open-loop
    rollouts in MuJoCo of ``window_s`` windows every ``stride_s`` (default: the window)."""
    m = mujoco.MjModel.from_xml_string(xml_text)
    d = mujoco.MjData(m)
    dt = float(np.median(np.diff(data.times)))
    window = int(round(window_s / dt))
    stride = int(round((stride_s or window_s) / dt))
    starts = _windows(len(data.q), window, stride)
    q = rollout_q([m], d, data, starts, window)
    end = np.stack([data.q[k + window] for k in starts])
    return np.degrees(np.abs(q[:, -1] - end))


def kinematic_rollout_errors(data, windows_s=(0.2, 0.5)) -> dict:
    """References without a model: each window's end error per joint (degrees) of holding
    the start position, and of extrapolating the start state at constant velocity and at
    constant acceleration (the measured q, qd, qdd at the window start), same windows as
    :func:`mujoco_rollout_errors`."""
    dt = float(np.median(np.diff(data.times)))
    out = {"hold": {}, "constant velocity": {}, "constant acceleration": {}}
    for w_s in windows_s:
        window = int(round(w_s / dt))
        k = _windows(len(data.q), window, window)
        t = window * dt
        dq = data.q[k + window] - data.q[k]
        out["hold"][w_s] = np.degrees(np.abs(dq))
        out["constant velocity"][w_s] = np.degrees(np.abs(dq - data.qd[k] * t))
        out["constant acceleration"][w_s] = np.degrees(
            np.abs(dq - data.qd[k] * t - 0.5 * data.qdd[k] * t**2))
    return out


def torque_nrms(xml_text: str, data, limits) -> float:
    tau = sj.identification.mujoco_torques(xml_text, data.q, data.qd, data.qdd)
    return float(validation_metrics(data.tau, tau, limits).nrms_limits_percent)


def _torque_residual(spec, data, limits):
    scale = 1.0 / (2.0 * np.asarray(limits)) / np.sqrt(len(data.q))
    d_holder = {}

    def residual_fn(x, params):
        cols = x.reshape(len(x), -1)
        out = []
        for j in range(cols.shape[1]):
            params.update_from_vector(cols[:, j])
            m = sysid.apply_param_modifiers(params, spec)
            d = d_holder.setdefault("d", mujoco.MjData(m))
            tau = inverse_torques(m, d, data.q, data.qd, data.qdd)
            out.append(((tau - data.tau) * scale).ravel())
        r = np.stack(out, axis=1)
        return [r[:, 0] if x.ndim == 1 else r], None, None
    return residual_fn


def _rollout_residual(spec, data, window, stride):
    starts = _windows(len(data.q), window, stride)
    target = np.stack([data.q[k + 1:k + window + 1] for k in starts])
    scale = 1.0 / np.sqrt(target.size)
    d_holder = {}

    def residual_fn(x, params):
        cols = x.reshape(len(x), -1)
        models = []
        for j in range(cols.shape[1]):
            params.update_from_vector(cols[:, j])
            models.append(sysid.apply_param_modifiers(params, spec))
        d = d_holder.setdefault("d", mujoco.MjData(models[0]))
        q = rollout_q(models, d, data, starts, window)
        q = q.reshape(cols.shape[1], -1, *q.shape[1:])
        r = ((q - target[None]) * scale).reshape(cols.shape[1], -1).T
        r = np.nan_to_num(r, nan=1e3, posinf=1e3, neginf=-1e3)
        return [r[:, 0] if x.ndim == 1 else r], None, None
    return residual_fn


# --- the fit -----------------------------------------------------------------------

def sysid_fit(xml_text: str, data, residual: str = "torque", *, limits=None,
              windows_s: float = 0.5, max_iterations: int = 100,
              time_budget_s: float | None = None, x_scale="jac",
              joint_terms_only: bool = False):
    """``mujoco.sysid.optimize`` from the MJCF ``xml_text`` on ``data``.

    Returns ``(fitted MJCF text, CPU seconds, iterations, history)``; history: one dict per
    iteration (``cpu_s``, ``wall_s``, ``objective``). Stops after ``max_iterations`` or,
    at the end of the first iteration past ``time_budget_s`` CPU seconds, with the last
    iterate. ``joint_terms_only``: the bodies' inertias frozen at the start's (armature,
    damping, frictionloss and offsets fitted)."""
    spec = mujoco.MjSpec.from_string(xml_text)
    # the pseudo-inertia keeps every body physically consistent, but a thin body's
    # A + B >= C can fail by rounding: let MuJoCo balance it where it does
    spec.compiler.balanceinertia = True
    model = spec.compile()
    params = sysid_params(spec, model)
    if joint_terms_only:
        for name, p in params.items():
            if name.endswith("_inertia"):
                p.frozen = True
    _clip_into_bounds(params)
    if residual == "torque":
        fn = _torque_residual(spec, data, limits)
    elif residual == "rollout":
        dt = float(np.median(np.diff(data.times)))
        window = int(round(windows_s / dt))
        fn = _rollout_residual(spec, data, window, window)
    else:
        raise ValueError(f"residual must be 'torque' or 'rollout', got {residual!r}")
    history = []
    last = {"x": params.as_vector().copy()}
    c0, w0 = time.process_time(), time.perf_counter()

    def callback(trace):
        last["x"] = np.asarray(trace[-1].candidate).ravel().copy()
        history.append({"cpu_s": time.process_time() - c0,
                        "wall_s": time.perf_counter() - w0,
                        "objective": float(trace[-1].objective)})
        if time_budget_s is not None and history[-1]["cpu_s"] > time_budget_s:
            raise _Budget

    stopped = "max_iterations or converged"
    start = params.copy()
    try:
        opt, _ = sysid.optimize(start, fn, optimizer="mujoco", verbose=False,
                                max_iters=max_iterations, x_scale=x_scale,
                                iter_callback=callback)
        x = opt.as_vector()
    except _Budget:
        x, stopped = last["x"], "time budget"
    cpu = time.process_time() - c0
    params.update_from_vector(x)
    fitted = write_mjcf(xml_text, sysid.apply_param_modifiers(params, spec))
    for h in history:
        h["stopped"] = stopped
    # the optimizer logs each iteration and, on a normal end, the final point once more
    iterations = len(history) - (stopped != "time budget")
    return fitted, cpu, iterations, history


def nominal_mjcf(package_xml: str) -> str:
    """The package's MJCF (same bodies, frames, timestep, actuators) with the URDF's own
    inertials and joint damping and friction (as MuJoCo reads the URDF
    ``sj.robots.kuka_lwr4_urdf()``, meshes dropped: viscous damping 0.2-1.2 N m s/rad, no
    dry friction), no armature and no offset."""
    with sj.robots.kuka_lwr4_urdf() as path:
        urdf = ET.parse(path).getroot()
    for link in urdf.iter("link"):
        for tag in ("visual", "collision"):
            for el in link.findall(tag):
                link.remove(el)
    cad = mujoco.MjModel.from_xml_string(ET.tostring(urdf, encoding="unicode"))
    spec = mujoco.MjSpec.from_string(package_xml)
    for body in spec.bodies[1:]:
        b = cad.body(body.name)
        body.explicitinertial = True
        body.mass, body.ipos = float(b.mass[0]), b.ipos.copy()
        body.inertia, body.iquat = b.inertia.copy(), b.iquat.copy()
        body.fullinertia = np.full(6, np.nan)
    for joint in spec.joints:
        j = cad.joint(joint.name)
        joint.armature = 0.0
        joint.frictionloss = float(cad.dof_frictionloss[j.dofadr[0]])
        damping = np.zeros_like(np.array(joint.damping, dtype=float))
        damping.ravel()[0] = cad.dof_damping[j.dofadr[0]]
        joint.damping = damping
    for act in spec.actuators:
        act.biasprm = np.zeros_like(np.array(act.biasprm, dtype=float))
    return write_mjcf(package_xml, spec.compile())


def evaluate(xml_text, fit_data, held_out, limits):
    e2 = mujoco_rollout_errors(xml_text, held_out, 0.2)
    e5 = mujoco_rollout_errors(xml_text, held_out, 0.5)
    return {"held_out_nrms_percent": torque_nrms(xml_text, held_out, limits),
            "fit_nrms_percent": torque_nrms(xml_text, fit_data, limits),
            "rollout_0.2s_median_deg": float(np.median(e2)),
            "rollout_0.5s_median_deg": float(np.median(e5)),
            "rollout_0.5s_median_deg_per_joint": np.median(e5, axis=0)}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mjcf", required=True,
                    help="the package's MJCF (sedsabso-jax identify ... --mjcf-out PATH "
                         "--mujoco-terms)")
    ap.add_argument("--quick", action="store_true", help="3 iterations per fit")
    ap.add_argument("--budget", type=float, default=300.0,
                    help="CPU seconds per fit (stops at the end of that iteration)")
    ap.add_argument("--max-iterations", type=int, default=100)
    ap.add_argument("--fits", default="package:torque,package:rollout,package:rollout:joints,"
                    "nominal:torque,nominal:rollout",
                    help="start:residual[:joints] (joints: inertias frozen at the start's)")
    ap.add_argument("--json", default=None)
    ap.add_argument("--save-dir", default=None, help="write each fitted MJCF there")
    args = ap.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    fit_data, held_out = sj.load_kuka_lwr4(1), sj.load_kuka_lwr4(2)
    limits = np.asarray(joint_limits("kuka_lwr4", sj.robots.kuka_lwr4()).tau_max)
    with open(args.mjcf, encoding="utf-8") as f:
        package_xml = f.read()
    starts = {"package": package_xml, "nominal": nominal_mjcf(package_xml)}
    max_it = 3 if args.quick else args.max_iterations
    rows = []

    def add(name, xml, cpu=None, wall=None, iterations=None, history=None):
        row = {"model": name, **evaluate(xml, fit_data, held_out, limits),
               "cpu_s": cpu, "wall_s": wall, "iterations": iterations,
               "history": history}
        rows.append(row)
        print(f"{name}: held-out {row['held_out_nrms_percent']:.4f} %, fit "
              f"{row['fit_nrms_percent']:.4f} %, rollout 0.2 s "
              f"{row['rollout_0.2s_median_deg']:.3f} deg, 0.5 s "
              f"{row['rollout_0.5s_median_deg']:.3f} deg, cpu {cpu}, it {iterations}",
              flush=True)

    baselines = {f"{kind} (no model)": errs
                 for kind, errs in kinematic_rollout_errors(held_out).items()}
    for name, errs in baselines.items():
        rows.append({"model": name, "held_out_nrms_percent": None,
                     "fit_nrms_percent": None,
                     "rollout_0.2s_median_deg": float(np.median(errs[0.2])),
                     "rollout_0.5s_median_deg": float(np.median(errs[0.5])),
                     "rollout_0.5s_median_deg_per_joint": np.median(errs[0.5], axis=0),
                     "cpu_s": None, "wall_s": None, "iterations": None, "history": None})
    add("package MJCF as written", package_xml)
    seen = {"package"}
    for fit in args.fits.split(","):
        start, residual, *rest = fit.split(":")
        joints = rest == ["joints"]
        if start not in seen:
            add(f"{start} start (no fit)", starts[start])
            seen.add(start)
        w0 = time.perf_counter()
        xml, cpu, its, hist = sysid_fit(starts[start], fit_data, residual, limits=limits,
                                        max_iterations=max_it, time_budget_s=args.budget,
                                        joint_terms_only=joints)
        wall = time.perf_counter() - w0
        name = (f"mujoco.sysid {residual} residual, {start} start"
                + (", inertias frozen" if joints else ""))
        if args.save_dir:
            with open(f"{args.save_dir}/sysid_{fit.replace(':', '_')}.xml", "w",
                      encoding="utf-8") as f:
                f.write(xml)
        add(name, xml, cpu, wall, its, hist)
    print()
    print("| model | held-out NRMS [%] | fit NRMS [%] | rollout 0.2 s [deg] | "
          "rollout 0.5 s [deg] | CPU [s] | wall [s] | iterations |")
    print("|:--|--:|--:|--:|--:|--:|--:|--:|")
    for r in rows:
        cpu = "-" if r["cpu_s"] is None else f"{r['cpu_s']:.0f}"
        wall = "-" if r["wall_s"] is None else f"{r['wall_s']:.0f}"
        its = "-" if r["iterations"] is None else str(r["iterations"])
        ho = "-" if r["held_out_nrms_percent"] is None else f"{r['held_out_nrms_percent']:.4f}"
        fi = "-" if r["fit_nrms_percent"] is None else f"{r['fit_nrms_percent']:.4f}"
        print(f"| {r['model']} | {ho} | {fi} | {r['rollout_0.2s_median_deg']:.3f} | "
              f"{r['rollout_0.5s_median_deg']:.3f} | {cpu} | {wall} | {its} |")
    if args.json:
        doc = {"rows": rows, "mjcf": args.mjcf, "quick": args.quick,
               "budget_cpu_s": args.budget, "max_iterations": max_it,
               "mujoco": mujoco.__version__,
               "command": "python -m benchmarks.mujoco_sysid "
               + " ".join(sys.argv[1:] if argv is None else argv)}
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(to_json(doc))


if __name__ == "__main__":
    main()
