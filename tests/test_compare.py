"""``sedsabso-jax compare`` and its problems: the exact L1 optimum in a box against cvxpy,
COCO's instance numbers and ranges, and the command (outputs, resume, settings mismatch,
bad input: exit 2 with nothing written). COCO's format and cocopp's reading of it:
tests/test_compare_coco.py; Dask: tests/test_compare_campaigns.py."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from conftest import SMALL_CAMPAIGN

from sedsabso_jax import cli
from sedsabso_jax.compare import _bbob as B
from sedsabso_jax.compare import _run as R
from sedsabso_jax.optim._linear import l1_solve, l1_solve_box

pytest.importorskip("evosax")


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
    assert R.Settings(algorithms=("evosax:PSO", "LDWPSO")).algorithms == ("PSO", "LDWPSO")


def test_coco_numbers():
    assert B.parse_numbers("1-5,101-110", "instances") == B.DEFAULT_INSTANCES
    assert B.parse_numbers("3, 1-2", "functions") == (3, 1, 2)
    assert R.Settings(instances="1-3,1-3").instances == (1, 2, 3, 1, 2, 3)
    assert len(B.DEFAULT_INSTANCES) == 15 and B.DIMENSIONS == (2, 3, 5, 10, 20, 40)
    for bad in ("1-", "a", "5-1", "1,,2"):
        with pytest.raises(ValueError, match="--instances: expected comma-separated"):
            B.parse_numbers(bad, "instances")
    assert B.parse_name(B.problem_name(21, 40)) == (21, 40) and B.parse_name("kuka-real") is None


def _run(args, capsys):
    try:
        code = cli.main(["compare", *args])
    except SystemExit as exit_:  # argparse's usage errors
        code = int(exit_.code or 0)
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("args, message", [
    (["--algorithms", "SEDSABSO,NoSuchES"], "unknown algorithm 'NoSuchES'"),
    (["--suite", "cec"], "unknown suite 'cec'"),
    (["--budget", "10"], "below one generation of LDWPSO"),
    (["--dimensions", "4"], "unknown BBOB dimension 4; expected one of COCO's 2, 3, 5"),
    (["--dimensions", "5,x"], "--dimensions: expected comma-separated numbers"),
    (["--functions", "25"], "unknown BBOB function 25; expected 1 to 24"),
    (["--functions", "0-2"], "unknown BBOB function 0"),
    (["--instances", "0"], "unknown BBOB instance 0; expected COCO's instance numbers"),
    (["--instances", "1,1,2"], "every BBOB instance must be named equally often"),
    (["--algorithms", "LDWPSO,LDWPSO"], "named twice"),
    (["--algorithms", "PSO,evosax:PSO"], "named twice"),
    (["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "not allowed with argument"),
    (["--runs", "5"], "--runs 5 has no effect with --suite bbob, which runs once per instance"),
])
def test_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, args, message):
    out = tmp_path / "out"
    base = ["--suite", "bbob", "--dimensions", "2", "--algorithms", "LDWPSO", "--functions",
            "1", "--instances", "1", "--out", str(out)]
    code, _, err = _run(base + args, capsys)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_runs_from_a_config_file_are_refused_with_bbob_too(tmp_path, capsys):
    config, out = tmp_path / "cmp.toml", tmp_path / "out"
    config.write_text("runs = 20\n")
    code, _, err = _run(["--suite", "bbob", "--dimensions", "2", "--algorithms", "LDWPSO",
                         "--functions", "1", "--instances", "1", "--config", str(config),
                         "--out", str(out)], capsys)
    assert code == 2 and "--runs 20 has no effect with --suite bbob" in err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


def test_compare_writes_resumes_and_refuses_other_settings(small_campaign, tmp_path, capsys):
    """The small campaign's files (tests/conftest.py), then the command again on a copy:
    nothing runs again and the same report comes back; other settings are refused."""
    serial, _, _ = small_campaign
    files = sorted(str(p.relative_to(serial)) for p in (serial / "tasks").rglob("*.json"))
    assert files == [f"tasks/{B.problem_name(f, 2)}/{a}.json" for f in (1, 21)
                     for a in ("CMA_ES", "LDWPSO")]
    doc = json.loads((serial / files[1]).read_text())
    a = doc["algorithms"]["LDWPSO"]
    instances = [1, 2, 3, 4, 5, *range(101, 111)]
    assert a["evaluations"] <= 200 and len(a["final"]) == 15
    assert a["instance_of_run"] == instances and doc["problem"]["instances"] == instances
    assert np.asarray(a["history"]["precision"]).shape == (15, len(a["history"]["evaluations"]))
    # precision is f - f_opt of the run's instance, COCO's f_opt
    assert doc["problem"]["f_opt"][:2] == [79.48, 394.48]
    np.testing.assert_allclose(a["precision"], np.asarray(a["final"]) - doc["problem"]["f_opt"],
                               atol=1e-9)
    for name in ("report.md", "summary.json", "ecdf_bbob_d02.png",
                 "coco/LDWPSO/bbobexp_f21.info", "coco/CMA_ES/data_f1/bbobexp_f1_DIM2.tdat"):
        assert (serial / name).stat().st_size > 0
    # resume: nothing runs again, the same report comes back
    out = tmp_path / "cmp"
    shutil.copytree(serial, out)
    args = [*SMALL_CAMPAIGN[1:], "--out", str(out)]
    stamps = {f: (out / f).stat().st_mtime_ns for f in files}
    code, text, _ = _run(args, capsys)
    assert code == 0 and "Best algorithm" in text
    def body(path):  # between the wall time and the commands, which name --out
        return path.read_text().split("Wall time")[1].split("\n", 1)[1].split("## Repro")[0]

    assert body(out / "report.md") == body(serial / "report.md")
    assert stamps == {f: (out / f).stat().st_mtime_ns for f in files}
    # other settings in the same directory: refused, nothing touched
    code, _, err = _run([*args[:-2], "--seed", "1", "--out", str(out)], capsys)
    assert code == 2 and "holds results of other settings (seed)" in err
    assert stamps == {f: (out / f).stat().st_mtime_ns for f in files}
