"""The command answers at once where it needs no computation: ``import sedsabso_jax``
imports no JAX (its names are imported when first used), and the help of every command,
usage errors and files that cannot be read or written are answered without importing
JAX, NumPy or SciPy (checked in a fresh interpreter's ``sys.modules``, which a loaded
machine cannot make flaky as a timing would). The words the flags take, written out in
the command (``cli/_vocabulary.py``), are the library's own."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import sedsabso_jax as sj
from sedsabso_jax import _lazy
from sedsabso_jax.cli import _vocabulary as words

ROOT = Path(__file__).resolve().parents[1]
#: What the command must not import before it computes something.
HEAVY = ("jax", "jaxlib", "numpy", "scipy", "equinox", "matplotlib", "cvxpy", "dask")


def _fresh(code: str) -> dict:
    """Run ``code`` in a fresh interpreter (this repository first on the path); the JSON
    it prints last."""
    run = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                         text=True, timeout=120, cwd=ROOT,
                         env={"PATH": "/usr/bin:/bin", "PYTHONPATH": str(ROOT)})
    assert run.returncode == 0, run.stderr[-3000:]
    return json.loads(run.stdout.strip().splitlines()[-1])


def test_import_imports_no_jax_and_the_names_come_when_used():
    found = _fresh("""
        import json, sys
        import sedsabso_jax as sj
        heavy = sorted(m for m in sys.modules if m.split(".")[0] in %r)
        from sedsabso_jax import Robot, select_and_identify
        names = dir(sj)
        try:
            sj.no_such_name
            missing = "no error"
        except AttributeError as err:
            missing = str(err)
        print(json.dumps({"heavy": heavy, "robot": Robot.__module__,
                          "all": sorted(set(sj.__all__) - set(names)), "missing": missing,
                          "jax": "jax" in sys.modules}))
    """ % (HEAVY,))
    assert found["heavy"] == [], found["heavy"]
    assert found["robot"] == "sedsabso_jax.dynamics._robot" and found["jax"]
    assert found["all"] == [], "dir(sedsabso_jax) lacks names of __all__"
    assert found["missing"] == "module 'sedsabso_jax' has no attribute 'no_such_name'"


def test_reading_a_urdf_imports_no_torch():
    """pytorch-kinematics' URDF parser without its package, which imports torch (seconds
    to import, and to exit)."""
    found = _fresh("""
        import json, sys
        import jax
        jax.config.update("jax_enable_x64", True)
        import sedsabso_jax as sj
        robot = sj.robots.kuka_lwr4()
        print(json.dumps({"joints": robot.n_joints, "torch": "torch" in sys.modules,
                          "pk": "pytorch_kinematics" in sys.modules}))
    """)
    assert found == {"joints": 7, "torch": False, "pk": False}


def test_the_lazy_table_is_the_root_all():
    """Every name of ``__all__`` is imported lazily from where the root's ``if
    TYPE_CHECKING:`` block says (what mypy and the documentation read), or defined."""
    table = _lazy.imports((ROOT / "sedsabso_jax" / "__init__.py").read_text())
    assert set(sj.__all__) - set(table) == {"__version__"}
    assert set(table) <= set(sj.__all__)
    assert table["Robot"] == (".dynamics._robot", "Robot")
    assert table["robots"] == (".robots", None)
    with pytest.raises(ImportError, match="only 'from ... import ...'"):
        _lazy.imports("if TYPE_CHECKING:\n    import numpy\n")


#: (argv, exit status, what stderr says); run one after another in one interpreter.
CASES = [
    (["--help"], 0, ""),
    *[([command, "--help"], 0, "") for command in (
        "base-parameters", "reproduce", "compare", "identify", "identify-payload",
        "identify-gains")],
    (["identify", "--robot", "kuka_lwr4"], 2, "the following arguments are required: --data"),
    (["identify", "--robot", "kuka_lwr4", "--data", "x.npz", "--folds", "x"], 2, "--folds"),
    (["identify", "--robot", "kuka_lwr4", "--data", "missing.npz"], 2,
     "--data missing.npz: no such file"),
    (["identify", "--robot", "kuka_lwr4", "--data", "{data}", "--validate", "gone.csv"], 2,
     "--validate gone.csv: no such file"),
    (["identify", "--robot", "kuka_lwr4", "--data", "{tmp}"], 2, "a directory"),
    (["identify", "--robot", "arm.urdf", "--data", "{data}"], 2,
     "--robot: no such file 'arm.urdf'"),
    (["identify", "--config", "none.toml", "--robot", "kuka_lwr4", "--data", "{data}"], 2,
     "--config none.toml"),
    (["identify", "--robot", "kuka_lwr4", "--data", "{data}", "--json", "{data}/r.json"], 2,
     "is not a directory"),
    (["identify", "--robot", "kuka_lwr4", "--data", "{data}", "--json", "/proc/r.json"], 2,
     "cannot write in directory"),
    (["identify-payload", "--robot", "kuka_lwr4", "--loaded", "none.npz", "--link", "x"], 2,
     "--loaded none.npz: no such file"),
    (["identify", "--robot", "kuka_lwr4", "--data", "{data}", "--drive-gains", "g.json"], 2,
     "--drive-gains g.json: no such file"),
    (["reproduce", "--out", "{data}"], 2, "exists and is not a directory"),
]


def test_help_usage_and_file_errors_import_nothing_heavy(tmp_path):
    """Each case's exit status and message, and no heavy module imported after it: the
    first case that imports one is named."""
    data = tmp_path / "run.npz"
    data.write_bytes(b"not read")
    cases = [([a.format(data=data, tmp=tmp_path) for a in argv], status, message)
             for argv, status, message in CASES]
    found = _fresh("""
        import contextlib, io, json, sys
        from sedsabso_jax.cli import main
        out = []
        for argv in %r:
            err = io.StringIO()
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                try:
                    status = main(argv)
                except SystemExit as exit_:
                    status = exit_.code
            heavy = sorted(m for m in sys.modules if m.split(".")[0] in %r)
            out.append([status, err.getvalue(), heavy])
        print(json.dumps(out))
    """ % ([argv for argv, _, _ in cases], HEAVY))
    for (argv, status, message), (got, err, heavy) in zip(cases, found):
        assert heavy == [], f"{argv} imported {heavy}"
        assert got == status, (argv, got, err)
        assert message in err and err.count("\n") <= 1, (argv, err)


def test_the_flags_words_are_the_librarys():
    from sedsabso_jax.compare._bbob import DEFAULT_INSTANCES, DIMENSIONS, FUNCTIONS, ranges
    from sedsabso_jax.compare._run import DEFAULT_ALGORITHMS, DEFAULT_BUDGET
    from sedsabso_jax.identification._gains._identify_gains import DEFAULT_METHOD
    from sedsabso_jax.identification._model._order import friction_text

    ident = sj.identification
    assert words.ESTIMATORS == sj.Estimator.registered()
    assert words.FRICTION_TERMS == ident.FRICTION_TERMS
    assert words.FRICTION_CANDIDATES == tuple(friction_text(t)
                                              for t in ident.FRICTION_CANDIDATES)
    assert words.PRIOR_STRENGTHS == ident.PRIOR_STRENGTHS
    assert words.AUTO == ident.Default.auto
    assert (words.FOLDS, words.FIT_BELOW, words.PREDICT_ABOVE) == (
        ident.DEFAULT.folds, ident.DEFAULT.fit_below, ident.DEFAULT.predict_above)
    assert words.GAIN_METHODS == tuple(ident.GAIN_METHODS)
    assert words.DEFAULT_GAIN_METHOD == DEFAULT_METHOD.name
    assert words.COMPARE_ALGORITHMS == DEFAULT_ALGORITHMS
    assert words.COMPARE_BUDGET == DEFAULT_BUDGET
    assert words.BBOB_FUNCTIONS == ranges(range(1, len(FUNCTIONS) + 1))
    assert words.BBOB_DIMENSIONS == DIMENSIONS
    assert words.BBOB_INSTANCES == ranges(DEFAULT_INSTANCES)
