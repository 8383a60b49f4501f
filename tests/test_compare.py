"""``sedsabso-jax compare`` and its problems: BBOB wired to evosax's functions (closed form
of the sphere, evosax's own evaluation as the reference for the rest), the exact L1
optimum in a box against cvxpy, and the command (outputs, resume, settings mismatch, bad
input: exit 2 with nothing written)."""

from __future__ import annotations

import json
import os

import jax
import numpy as np
import pytest

from sedsabso_jax import cli
from sedsabso_jax.compare import _problems as P
from sedsabso_jax.compare import _run as R
from sedsabso_jax.optim._linear import l1_solve, l1_solve_box

pytest.importorskip("evosax")


def test_sphere_closed_form():
    p = P.bbob_problem(0, 4, instances=2)
    rng = np.random.default_rng(0)
    for inst in p.instances:
        x_opt = np.asarray(inst.fitness.args[1])
        for x in rng.uniform(-5, 5, (5, 4)):
            assert float(inst.fitness(x)) == pytest.approx(np.sum((x - x_opt) ** 2) + inst.f_opt)
    assert p.instances[0].f_opt != p.instances[1].f_opt  # instances differ


def test_every_function_matches_evosax():
    """Our switch over the 24 functions, with f_opt added, against evosax's own
    meta-problem evaluation with the same parameters."""
    from evosax.problems.bbob.meta_bbob import MetaBBOBProblem

    dim = 6
    names = P.bbob_functions()
    assert len(names) == 24 and names[0] == "sphere" and names[-1] == "lunacek"
    x = np.random.default_rng(dim).uniform(-5, 5, (6, dim))
    ref = MetaBBOBProblem(fn_names=list(names), min_num_dims=dim, max_num_dims=dim)
    ours = jax.jit(jax.vmap(P.bbob_value, in_axes=(0, None)))  # one compiled switch
    for i, name in enumerate(names):
        inst = P.bbob_problem(i, dim, instances=1).instances[0]
        x_opt = inst.fitness.args[1]
        params = ref.sample_params(jax.random.key(1))
        assert np.array_equal(params.x_opt, x_opt) and float(params.f_opt) == inst.f_opt
        params = params.replace(fn_id=jax.numpy.int32(i))
        want, _, _ = ref.eval(jax.random.key(0), x, ref.init(jax.random.key(0), params),
                              params)
        np.testing.assert_allclose(np.asarray(ours(x, inst.fitness.args)), np.asarray(want),
                                   rtol=1e-9, err_msg=name)


@pytest.mark.parametrize("dim", [2, 40])
def test_gallagher_peaks_drawn_once_match_evosax(dim):
    """f21 and f22 from peaks drawn once per instance against evosax's function, which
    draws them at every evaluation, on several instances (a wrong draw, a peak's
    alpha or range, or a transposed rotation changes the values by far more than 1e-9)."""
    from evosax.problems.bbob.bbob_fns import bbob_fns

    x = np.random.default_rng(dim).uniform(-6, 6, (16, dim))  # some outside the box
    for index in sorted(P.GALLAGHER):
        name = P.bbob_functions()[index]
        for inst in P.bbob_problem(index, dim, instances=3).instances:
            _, x_opt, f_opt, R, Q, _ = inst.fitness.args
            value, pen = jax.vmap(bbob_fns[name], in_axes=(0, None, None, None, None))(
                x, x_opt, R, Q, dim)
            want = np.asarray(value + pen) + float(f_opt)
            np.testing.assert_allclose(np.asarray(inst.fitness.evaluate(x)), want,
                                       rtol=1e-9, err_msg=name)
            # at the optimum the value is f_opt
            assert float(inst.fitness(x_opt * P.GALLAGHER[index][3])) == pytest.approx(
                inst.f_opt, abs=1e-9)


def test_l1_optimum_in_a_box_matches_cvxpy():
    import cvxpy as cp

    rng = np.random.default_rng(2)
    W = rng.standard_normal((60, 4)) * [1, 10, 100, 0.1]
    b = W @ np.array([1.0, -2.0, 0.5, 3.0]) + 0.1 * rng.standard_normal(60)
    lower, upper = np.array([-1, -1, -1, -1.0]), np.array([0.5, 1, 1, 1.0])  # cuts 3 of 4
    x, _ = l1_solve_box(W, b, lower, upper)
    v = cp.Variable(4)
    prob = cp.Problem(cp.Minimize(cp.norm1(W @ v - b)), [v >= lower, v <= upper])
    prob.solve(solver=cp.CLARABEL)
    assert np.all((x >= lower) & (x <= upper))
    assert np.abs(W @ x - b).sum() == pytest.approx(prob.value, rel=1e-7)
    # an optimum inside the box is the unconstrained one
    x_in, _ = l1_solve_box(W, b, -10 * np.ones(4), 10 * np.ones(4))
    np.testing.assert_array_equal(x_in, l1_solve(W, b)[0])


def test_budget_parsing_and_names():
    assert R.parse_budget("1000d") == (1000, True) and R.parse_budget("20000") == (20000, False)
    assert R.Settings(budget="300d").evaluations(7) == 2100
    for bad in ("0", "d", "10x", "-5d", ""):
        with pytest.raises(ValueError, match="budget: expected"):
            R.parse_budget(bad)
    assert R.label("CMA_ES") == "evosax CMA_ES" and R.label("BSO") == "BSO"
    assert R.solver_for("evosax:PSO").name == "PSO"
    assert R.DEFAULT_BUDGET == R.Settings().budget


def _run(args, capsys):
    code = cli.main(["compare", *args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("args, message", [
    (["--algorithms", "SEDSABSO,NoSuchES"], "unknown algorithm 'NoSuchES'"),
    (["--suite", "cec"], "unknown suite 'cec'"),
    (["--budget", "10"], "below one generation of LDWPSO"),
    (["--dimensions", "1"], "dimensions must be integers from 2"),
    (["--dimensions", "5,x"], "--dimensions: expected comma-separated integers"),
    (["--algorithms", "LDWPSO,LDWPSO"], "named twice"),
    (["--runs", "2", "--instances", "3"], "runs (2) must be at least"),
])
def test_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, args, message):
    out = tmp_path / "out"
    base = ["--suite", "bbob", "--dimensions", "2", "--algorithms", "LDWPSO", "--runs", "2",
            "--instances", "1", "--out", str(out)]
    code, _, err = _run(base + args, capsys)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_compare_runs_resumes_and_refuses_other_settings(tmp_path, capsys):
    out = tmp_path / "cmp"
    args = ["--suite", "bbob", "--dimensions", "2", "--algorithms", "LDWPSO,PSO", "--runs",
            "4", "--instances", "2", "--budget", "100d", "--out", str(out)]
    code, text, _ = _run(args, capsys)
    assert code == 0 and "Best algorithm" in text
    files = sorted(os.listdir(out / "problems"))
    assert len(files) == 24
    doc = json.loads((out / "problems" / files[0]).read_text())
    a = doc["algorithms"]["LDWPSO"]
    assert a["evaluations"] <= 200 and len(a["final"]) == 4
    assert a["instance_of_run"] == [0, 0, 1, 1]
    assert np.asarray(a["history"]["precision"]).shape == (4, len(a["history"]["evaluations"]))
    # precision is f - f_opt of the run's instance
    f_opt = np.asarray(doc["problem"]["f_opt"])[a["instance_of_run"]]
    np.testing.assert_allclose(a["precision"], np.asarray(a["final"]) - f_opt, atol=1e-9)
    for name in ("report.md", "summary.json", "ecdf_bbob_d02.png"):
        assert (out / name).stat().st_size > 0
    # resume: nothing runs again, the same numbers come back
    stamps = {f: (out / "problems" / f).stat().st_mtime_ns for f in files}
    code, text2, _ = _run(args, capsys)
    assert code == 0 and text2.split("Wall time")[1].split("\n", 1)[1] == \
        text.split("Wall time")[1].split("\n", 1)[1]
    assert stamps == {f: (out / "problems" / f).stat().st_mtime_ns for f in files}
    # other settings in the same directory: refused, nothing touched
    code, _, err = _run([*args[:-2], "--seed", "1", "--out", str(out)], capsys)
    assert code == 2 and "holds results of other settings (seed)" in err
    assert stamps == {f: (out / "problems" / f).stat().st_mtime_ns for f in files}
