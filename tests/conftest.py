"""Shared fixtures: random robots written as URDF or DH tables, and independent
pinocchio models built from the same descriptions (never from the package's own model)."""

from __future__ import annotations

import importlib.metadata
import json
import os
import zlib
from pathlib import Path

import jax
import numpy as np
import pytest
from hypothesis import settings

from sedsabso_jax.cli._main import _enable_compilation_cache

# The package never turns on JAX's 64-bit mode itself (tests/test_global_state.py); the
# tests, like its users, turn it on first.
jax.config.update("jax_enable_x64", True)

# Compiled XLA programs are kept between the run's processes and between runs, where the
# command keeps its own (JAX's persistent cache: $SEDSABSO_JAX_CACHE, "off" disables it):
# the xdist workers, the commands the tests start and the Python processes they start (JAX
# reads the two settings from the environment) share what one of them compiled.
CACHE_DIR = _enable_compilation_cache()
if CACHE_DIR is not None:
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.1)
    os.environ.setdefault("JAX_COMPILATION_CACHE_DIR", CACHE_DIR)
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.1")

# The xdist workers already take the cores: each fits a validation's splits in turn (the
# threads' numbers are the same, tests/test_validations.py), as do the commands they start.
os.environ.setdefault("SEDSABSO_JAX_THREADS", "1")

# Hypothesis draws the same examples on every run and keeps no example database, so a test
# passes or fails the same way on every machine and in CI. HYPOTHESIS_PROFILE=explore draws
# new random examples (with the database) to search for failures locally.
settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))

# pinocchio orders a body's parameters [m mx my mz Ixx Ixy Iyy Ixz Iyz Izz]; the project
# orders them [Ixx Iyy Izz Ixy Ixz Iyz m mx my mz].
PIN_TO_OURS = np.array([4, 6, 9, 5, 7, 8, 0, 1, 2, 3])


def random_rotation(rng) -> np.ndarray:
    Q, R = np.linalg.qr(rng.standard_normal((3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else -Q


def random_inertial(rng):
    """Physically consistent (mass, CoM, inertia about the CoM) with random principal axes."""
    mass = rng.uniform(0.5, 5.0)
    com = rng.uniform(-0.3, 0.3, 3)
    a, b = rng.uniform(0.01, 0.5, 2)
    principal = np.array([a, b, rng.uniform(abs(a - b) + 1e-3, a + b)])
    R = random_rotation(rng)
    return mass, com, R @ np.diag(principal) @ R.T


INERTIA_KEYS = {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2),
                "izz": (2, 2)}


def _fmt(v) -> str:
    return " ".join(repr(float(x)) for x in v)


def random_urdf(rng, n_movable: int, *, prismatic_prob=0.2, fixed_prob=0.3,
                friction=False, branch=False) -> tuple[str, list[str]]:
    """A serial URDF with ``n_movable`` revolute/prismatic joints at random axes and
    origins, random fixed joints in between (and after the last), random inertials.

    With ``branch``, a second movable chain of two joints hangs off the second link.
    Returns the text and the names of the links in chain order (last is the tip).
    """
    parts = ['<?xml version="1.0"?>', '<robot name="random">']
    link_names = []

    def link(name, with_inertial=True):
        if not with_inertial:
            parts.append(f'<link name="{name}"/>')
            return
        m, com, I = random_inertial(rng)
        rpy = rng.uniform(-np.pi, np.pi, 3)
        # express the inertia in a rotated inertial frame to exercise <origin rpy>; URDF's
        # rpy are extrinsic x-y-z angles: R = Rz(yaw) Ry(pitch) Rx(roll)
        from scipy.spatial.transform import Rotation

        Rin = Rotation.from_euler("xyz", rpy).as_matrix()
        Iin = Rin.T @ I @ Rin
        parts.append(
            f'<link name="{name}"><inertial><origin xyz="{_fmt(com)}" rpy="{_fmt(rpy)}"/>'
            f'<mass value="{float(m)!r}"/><inertia '
            + " ".join(f'{k}="{float(Iin[a, b])!r}"' for k, (a, b) in INERTIA_KEYS.items())
            + "/>"
            "</inertial></link>"
        )

    def joint(name, kind, parent, child):
        xyz = rng.uniform(-0.4, 0.4, 3)
        rpy = rng.uniform(-np.pi, np.pi, 3)
        text = f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
        text += f'<child link="{child}"/><origin xyz="{_fmt(xyz)}" rpy="{_fmt(rpy)}"/>'
        if kind != "fixed":
            axis = rng.standard_normal(3)
            axis /= np.linalg.norm(axis)
            text += f'<axis xyz="{_fmt(axis)}"/>'
            text += '<limit lower="-3" upper="3" effort="100" velocity="5"/>'
            if friction:
                text += (f'<dynamics friction="{float(rng.uniform(0, 2))!r}" '
                         f'damping="{float(rng.uniform(0, 2))!r}"/>')
        parts.append(text + "</joint>")

    link("base")
    parent, k = "base", 0
    for i in range(n_movable):
        if rng.uniform() < fixed_prob:
            name = f"fixed_{k}"
            link(name)
            joint(f"jf{k}", "fixed", parent, name)
            parent, k = name, k + 1
        child = f"link{i + 1}"
        link(child)
        joint(f"j{i + 1}", "prismatic" if rng.uniform() < prismatic_prob else "revolute",
              parent, child)
        link_names.append(child)
        parent = child
    # a rigid tool on the last link
    link("tool")
    joint("jtool", "fixed", parent, "tool")
    link_names.append("tool")
    if branch:
        link("side1")
        joint("side_j1", "revolute", "link1", "side1")
        link("side2")
        joint("side_j2", "revolute", "side1", "side2")
    parts.append("</robot>")
    return "\n".join(parts), link_names


def random_dh(rng, n: int, prismatic_prob=0.2):
    """A random DH table (either convention) and physically consistent link parameters."""
    table = {
        "alpha": rng.uniform(-np.pi, np.pi, n),
        "a": rng.uniform(-0.5, 0.5, n),
        "d": rng.uniform(-0.5, 0.5, n),
        "theta": rng.uniform(-np.pi, np.pi, n),
        "prismatic": rng.uniform(size=n) < prismatic_prob,
    }
    params = []
    for _ in range(n):
        m, c, I = random_inertial(rng)
        I_origin = I + m * (c @ c * np.eye(3) - np.outer(c, c))  # parallel axes
        params += [I_origin[0, 0], I_origin[1, 1], I_origin[2, 2], I_origin[0, 1],
                   I_origin[0, 2], I_origin[1, 2], m, *(m * c), *rng.uniform(0, 1, 2)]
    return table, np.array(params)


def pin_inertia(params10):
    """pinocchio Inertia from the project's 10 parameters (about the frame origin)."""
    import pinocchio as pin

    return pin.Inertia.FromDynamicParameters(np.asarray(params10)[np.argsort(PIN_TO_OURS)])


def pin_from_mdh(table, params):
    """pinocchio model of a modified-DH chain, composed with pinocchio's SE3 algebra."""
    import pinocchio as pin

    model = pin.Model()
    parent = 0
    for i in range(len(table["a"])):
        placement = (
            pin.SE3(pin.utils.rotate("x", table["alpha"][i]), np.zeros(3))
            * pin.SE3(np.eye(3), np.array([table["a"][i], 0.0, 0.0]))
            * pin.SE3(pin.utils.rotate("z", table["theta"][i]), np.zeros(3))
            * pin.SE3(np.eye(3), np.array([0.0, 0.0, table["d"][i]]))
        )
        jm = pin.JointModelPZ() if table["prismatic"][i] else pin.JointModelRZ()
        parent = model.addJoint(parent, jm, placement, f"j{i + 1}")
        body = pin_inertia(params[12 * i: 12 * i + 10])
        model.appendBodyToJoint(parent, body, pin.SE3.Identity())
    return model


def pin_from_dh(table, params):
    """pinocchio model of a standard-DH chain: joint i turns about z_{i-1}; link i's body
    (its parameters given in DH frame i) hangs at RotZ(theta) TransZ(d) TransX(a) RotX(alpha)."""
    import pinocchio as pin

    model = pin.Model()
    parent, previous = 0, pin.SE3.Identity()
    for i in range(len(table["a"])):
        jm = pin.JointModelPZ() if table["prismatic"][i] else pin.JointModelRZ()
        parent = model.addJoint(parent, jm, previous, f"j{i + 1}")
        M = (
            pin.SE3(pin.utils.rotate("z", table["theta"][i]), np.array([0, 0, table["d"][i]]))
            * pin.SE3(pin.utils.rotate("x", table["alpha"][i]), np.array([table["a"][i], 0, 0]))
        )
        model.appendBodyToJoint(parent, pin_inertia(params[12 * i: 12 * i + 10]), M)
        previous = M
    return model


def pin_regressor_in_our_order(model, q, qd, qdd):
    """pinocchio's joint-torque regressor with columns in the project's order
    (friction columns left out): (n, 10 n)."""
    import pinocchio as pin

    data = model.createData()
    n = model.nv
    Y = np.reshape(pin.computeJointTorqueRegressor(model, data, q, qd, qdd), (n, 10 * n))
    return np.concatenate([Y[:, 10 * i: 10 * i + 10][:, PIN_TO_OURS] for i in range(n)], 1)


def inertial_columns(Y, n):
    """The 10 inertial columns per link of a project regressor (..., n, 12 n)."""
    return np.concatenate([Y[..., 12 * i: 12 * i + 10] for i in range(n)], -1)


def friction_torque(params, qd):
    p = np.asarray(params).reshape(-1, 12)
    return p[:, 10] * np.sign(qd) + p[:, 11] * qd


def random_state(rng, robot, k=None):
    shape = (robot.n_joints,) if k is None else (k, robot.n_joints)
    return rng.uniform(-2, 2, shape), rng.standard_normal(shape), rng.standard_normal(shape)


@pytest.fixture
def rng(request):
    # a seed per test, stable across runs
    return np.random.default_rng(zlib.crc32(request.node.nodeid.encode()))


#: a small COCO campaign: 2 BBOB functions in 2-D, COCO's 15 instances, 2 algorithms
SMALL_CAMPAIGN = ["compare", "--suite", "bbob", "--functions", "1,21", "--dimensions", "2",
                  "--algorithms", "LDWPSO,CMA_ES", "--budget", "100d"]


def once_per_run(tmp_path_factory, name: str, make) -> Path:
    """The directory ``name`` that ``make(directory)`` filled, once in this run for all
    xdist workers: the first worker to ask makes it, the others wait for it (a file lock in
    the run's temporary directory, which the workers share)."""
    from filelock import FileLock

    base = tmp_path_factory.getbasetemp()
    worker = os.environ.get("PYTEST_XDIST_WORKER")  # set in xdist's workers only
    shared = base.parent if worker else base  # the run's, not older runs'
    out, done = shared / name, shared / f"{name}.done"
    with FileLock(str(shared / f"{name}.lock")):
        if not done.is_file():
            out.mkdir(exist_ok=True)
            make(out)
            done.touch()
    return out


#: The KUKA's default identification on its two shipped runs, as the docs quote it
#: (tests/test_docs.py) and the command's end-to-end test reads it (test_identify_cli.py).
KUKA_IDENTIFY = ("sedsabso-jax identify --robot kuka_lwr4 --data "
                 "sedsabso_jax/data/kuka_lwr4/measurements_1.npz --validate "
                 "sedsabso_jax/data/kuka_lwr4/measurements_2.npz")


@pytest.fixture(scope="session")
def kuka_identified(tmp_path_factory) -> tuple[dict, str, Path]:
    """:data:`KUKA_IDENTIFY` run by the command from the repository root, once in a run:
    ``(the JSON report, what it printed, its --out)``."""
    import contextlib
    import io
    import shlex

    from sedsabso_jax import cli

    def make(out: Path) -> None:
        argv = [*shlex.split(KUKA_IDENTIFY)[1:], "--out", str(out / "results"), "--json",
                str(out / "report.json")]
        printed = io.StringIO()
        with contextlib.chdir(Path(__file__).resolve().parents[1]), \
                contextlib.redirect_stdout(printed):
            assert cli.main(argv) == 0
        (out / "printed.txt").write_text(printed.getvalue(), encoding="utf-8")

    out = once_per_run(tmp_path_factory, "kuka-identified", make)
    return (json.loads((out / "report.json").read_text(encoding="utf-8")),
            (out / "printed.txt").read_text(encoding="utf-8"), out / "results")


@pytest.fixture(scope="session")
def small_campaign(tmp_path_factory):
    """:data:`SMALL_CAMPAIGN` run by the command, once in a run: ``(its --out, the task
    documents, summary.json)``."""
    pytest.importorskip("cocoex")
    pytest.importorskip("evosax")
    from sedsabso_jax import cli

    def make(campaign: Path) -> None:
        assert cli.main([*SMALL_CAMPAIGN, "--out", str(campaign / "serial")]) == 0

    out = once_per_run(tmp_path_factory, "campaign", make) / "serial"
    docs = [json.loads(p.read_text()) for p in sorted((out / "tasks").rglob("*.json"))]
    return out, docs, json.loads((out / "summary.json").read_text())



def _quat(R) -> np.ndarray:
    """MuJoCo's (w, x, y, z) quaternion of a rotation matrix."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(R).as_quat()
    return np.array([w, x, y, z])


def random_mjcf(rng, n_movable: int, *, prismatic_prob=0.2, fixed_prob=0.3,
                armature=False, damping=False, frictionloss=False, gravity=None,
                timestep=0.002, integrator="RK4") -> str:
    """A serial MJCF (written here, never by the package) with ``n_movable`` hinge/slide
    joints at random axes and anchors in bodies at random poses, random fixed bodies in
    between (welded: their inertia belongs to the link above), random inertials given
    either as ``quat`` + ``diaginertia`` or as ``fullinertia``; with ``armature``,
    ``damping`` or ``frictionloss`` each joint gets a random one, and each joint has a
    ``motor`` actuator (gear 1, no control range)."""
    g = rng.standard_normal(3) if gravity is None else np.asarray(gravity, float)
    g = 9.81 * g / np.linalg.norm(g) if gravity is None else g
    parts = ['<mujoco model="random">', '<compiler angle="radian" autolimits="true"/>',
             f'<option gravity="{_fmt(g)}" timestep="{timestep!r}" integrator="{integrator}"/>',
             "<worldbody>"]
    closing, joints = [], []

    def inertial(k):
        m, com, I = random_inertial(rng)
        if k % 2:
            full = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
            return (f'<inertial pos="{_fmt(com)}" mass="{float(m)!r}" '
                    f'fullinertia="{_fmt(full)}"/>')
        w, V = np.linalg.eigh(I)
        V = V * np.sign(np.linalg.det(V))
        return (f'<inertial pos="{_fmt(com)}" quat="{_fmt(_quat(V))}" mass="{float(m)!r}" '
                f'diaginertia="{_fmt(w)}"/>')

    def body(name, k):
        pos = rng.uniform(-0.4, 0.4, 3)
        parts.append(f'<body name="{name}" pos="{_fmt(pos)}" '
                     f'quat="{_fmt(_quat(random_rotation(rng)))}">')
        parts.append(inertial(k))
        closing.append("</body>")

    k = 0
    for i in range(n_movable):
        if rng.uniform() < fixed_prob:
            body(f"fixed_{k}", k)
            k += 1
        body(f"link{i + 1}", k)
        k += 1
        axis = rng.standard_normal(3)
        axis /= np.linalg.norm(axis)
        kind = "slide" if rng.uniform() < prismatic_prob else "hinge"
        extra = "".join(f' {key}="{float(rng.uniform(0.01, 0.5))!r}"'
                        for key, on in (("armature", armature), ("damping", damping),
                                        ("frictionloss", frictionloss)) if on)
        parts.append(f'<joint name="j{i + 1}" type="{kind}" axis="{_fmt(axis)}" '
                     f'pos="{_fmt(rng.uniform(-0.2, 0.2, 3))}"{extra}/>')
        joints.append(f"j{i + 1}")
    parts += closing[::-1] + ["</worldbody>", "<actuator>"]
    parts += [f'<motor name="m{j}" joint="{j}" gear="1"/>' for j in joints]
    parts += ["</actuator>", "</mujoco>"]
    return "\n".join(parts)


@pytest.fixture(scope="session")
def robots_dir() -> Path:
    """The robots of the ``example-robot-data`` package (the test extra): published URDFs."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed (the test extra)")
    return Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))


def mj_torques(m, robot, q, qd, qdd):
    """MuJoCo's ``qfrc_inverse`` (``mj_inverse`` of the compiled model ``m``) at the
    chain's joints, rows of states; every joint off the chain at rest at ``qpos = 0``."""
    import mujoco

    ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in robot.joint_names]
    qpos, dofs = m.jnt_qposadr[ids], m.jnt_dofadr[ids]
    d, out = mujoco.MjData(m), []
    for row in zip(q, qd, qdd):
        d.qpos[:], d.qvel[:], d.qacc[:] = 0.0, 0.0, 0.0
        d.qpos[qpos], d.qvel[dofs], d.qacc[dofs] = row
        mujoco.mj_inverse(m, d)
        out.append(d.qfrc_inverse[dofs].copy())
    return np.array(out)
