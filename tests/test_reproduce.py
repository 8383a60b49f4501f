"""``sedsabso-jax reproduce`` end to end on a small budget: files, schema, honesty checks."""

from __future__ import annotations

import contextlib
import io
import json
import os
import re

import matplotlib.image
import numpy as np
import pytest

from sedsabso_jax import cli
from sedsabso_jax.reproduce import _experiment as experiment

SMALL = ["--runs", "2", "--iterations", "30", "--samples", "200", "--design-iterations", "5"]
FILES = ("table4.md", "table5.md", "fig5_population.png", "fig6_convergence.png",
         "results.json")


#: The ``progress(label, done, total)`` calls of the run below, and its stderr.
PROGRESS: list[tuple[str, float, float]] = []
STDERR = io.StringIO()


@pytest.fixture(scope="module")
def reproduced(tmp_path_factory):
    out = tmp_path_factory.mktemp("reproduce")
    run = experiment.run
    with pytest.MonkeyPatch.context() as patch, contextlib.redirect_stderr(STDERR):
        patch.setattr(experiment, "run", lambda settings, progress: run(
            settings, progress=lambda *call: (PROGRESS.append(call), progress(*call))))
        code = cli.main(["reproduce", *SMALL, "--out", str(out / "res"),
                         "--json", str(out / "copy.json")])
    assert code == 0
    return out


def test_progress_weighs_every_step_to_the_end(reproduced):
    """Before each step, the estimated seconds of the steps done (their estimates known
    from the settings: the swarms' runs weigh most), then the end."""
    from sedsabso_jax.reproduce._work import step_seconds

    settings = experiment.Settings(runs=2, iterations=30, samples=200, design_iterations=5)
    seconds = step_seconds(settings, tuple(experiment.SWARMS), experiment.BASELINES)
    total = PROGRESS[0][2]
    assert all(t == total for _, _, t in PROGRESS) and total == pytest.approx(sum(seconds))
    assert [d for _, d, _ in PROGRESS] == pytest.approx(list(np.cumsum([0.0, *seconds])))
    assert [label for label, _, _ in PROGRESS] == [
        "base parameters", "excitation design (Eq. 9)", "simulated measurements",
        "SEDSABSO: 2 runs", "BSO: 2 runs", "LDWPSO: 2 runs", "OLS", "LM", "L1-LP", "done"]
    assert PROGRESS[-1][0] == "done" and max(seconds) == seconds[3]  # SEDSABSO compiles most


def test_progress_lines_off_a_terminal(reproduced):
    """stderr is not a terminal here: a line at each step with the share of the work,
    the seconds so far and the time left, and one when all is written."""
    lines = STDERR.getvalue().splitlines()
    assert len(lines) == len(PROGRESS) + 1, lines
    elapsed, left = r"(<1|\d+) s", r"(~[\d.]+ (s|min)|<1 s)"
    assert re.fullmatch(rf"reproduce:   0%, {elapsed}: base parameters", lines[0]), lines[0]
    for line in lines[1:-1]:  # the time left once 5 % of the work has set the pace
        assert re.fullmatch(rf"reproduce: +\d+%, {elapsed}(, {left} left)?: .+", line), line
    assert all(" left: " in line for line in lines[4:-1]), lines
    assert re.fullmatch(rf"reproduce: 100%, {elapsed}: written", lines[-1]), lines[-1]


def test_writes_every_file(reproduced):
    for name in FILES:
        path = reproduced / "res" / name
        assert path.is_file() and path.stat().st_size > 500, name
    assert (reproduced / "copy.json").read_text() == (reproduced / "res" / "results.json"
                                                      ).read_text()
    assert not [p for p in os.listdir(reproduced / "res") if p.endswith(".tmp")]


def test_results_schema_and_numbers(reproduced):
    res = json.loads((reproduced / "res" / "results.json").read_text())
    assert res["schema"] == experiment.SCHEMA
    s = res["settings"]
    for key in ("runs", "iterations", "samples", "noise", "scenario", "seed", "dtype",
                "device", "search_box", "excitation"):
        assert key in s, key
    assert (s["runs"], s["iterations"], s["samples"]) == (2, 30, 200)
    names, true = res["base_parameters"]["names"], np.array(res["base_parameters"]["true"])
    assert len(names) == len(true) == 21
    lower, upper = (np.array(s["search_box"][k]) for k in ("lower", "upper"))
    assert np.all(lower < true) and np.all(true < upper)  # paper scenario: box around truth
    algos = res["algorithms"]
    assert set(algos) == {"SEDSABSO", "BSO", "LDWPSO", "OLS", "LM", "L1-LP"}
    for name in ("SEDSABSO", "BSO", "LDWPSO"):
        a = algos[name]
        for key in ("fitness_mean", "fitness_std", "time_mean_s", "batched_time_s",
                    "max_abs_error", "params_mean", "history_median"):
            assert key in a, (name, key)
        assert len(a["fitness_runs"]) == 2 and len(a["history_median"]) == 30
        hist = np.array(a["history_median"])
        assert np.all(np.diff(hist) <= 0) and hist[-1] < hist[0]  # best-so-far falls
        assert a["time_mean_s"] > 0 and a["batched_time_s"] > 0
        # the swarms cannot beat the exact L1 optimum
        assert a["fitness_mean"] >= algos["L1-LP"]["fitness_mean"] * (1 - 1e-9)
    # noise-free data: least squares and the LP recover the parameters
    for name in ("OLS", "LM", "L1-LP"):
        assert algos[name]["max_abs_error"] < 1e-6, name
    assert s["excitation"]["cond"] < 1e3


def test_seed_0_numbers_are_pinned(reproduced):
    """The small budget's seed-0 results, measured on the project's 2-core AMD EPYC VM
    (jax 0.10.2). Same machine and versions: identical; the tolerance (1e-6 relative)
    allows for floating-point reassociation elsewhere. At 30 iterations the paper's order
    is REVERSED (LDWPSO 103.6 < BSO 115.4 < SEDSABSO 249.9): the annealing and the large
    early population pay off only over a longer run (at the full 600 iterations the order
    is SEDSABSO < BSO < LDWPSO, README)."""
    res = json.loads((reproduced / "res" / "results.json").read_text())
    assert res["settings"]["excitation"]["cond"] == pytest.approx(152.93598762268036, rel=1e-6)
    pinned = {"SEDSABSO": (249.8613992955261, 1.6921719921349982),
              "BSO": (115.39486166912671, 1.3401279737349334),
              "LDWPSO": (103.63293031199616, 0.7147883000553055)}
    algos = res["algorithms"]
    for name, (fitness, error) in pinned.items():
        assert algos[name]["fitness_mean"] == pytest.approx(fitness, rel=1e-6), name
        assert algos[name]["max_abs_error"] == pytest.approx(error, rel=1e-6), name
    assert (algos["LDWPSO"]["fitness_mean"] < algos["BSO"]["fitness_mean"]
            < algos["SEDSABSO"]["fitness_mean"])


def test_tables_put_the_paper_beside_ours(reproduced):
    t4 = (reproduced / "res" / "table4.md").read_text()
    assert "paper's fitness mean" in t4 and "16.93" in t4  # SEDSABSO's published time
    t5 = (reproduced / "res" / "table5.md").read_text()
    assert "ZZ1R" in t5 and "paper's SEDSABSO" in t5 and "16.8" in t5
    assert t5.count("\n| ") == 22  # header + 21 base parameters


def test_figures_are_images(reproduced):
    for name in ("fig5_population.png", "fig6_convergence.png"):
        img = matplotlib.image.imread(reproduced / "res" / name)
        assert img.shape[0] > 300 and img.shape[1] > 500
        assert img[..., :3].std() > 0.05  # not blank


def test_same_seed_same_numbers(reproduced, tmp_path):
    assert cli.main(["reproduce", *SMALL, "--out", str(tmp_path)]) == 0
    a = json.loads((reproduced / "res" / "results.json").read_text())["algorithms"]
    b = json.loads((tmp_path / "results.json").read_text())["algorithms"]
    for name in a:
        assert a[name]["params_mean"] == b[name]["params_mean"], name
        assert a[name]["fitness_runs"] == b[name]["fitness_runs"], name


def _status(argv) -> int:
    """Exit status of the command line, whether argparse exits or main returns."""
    try:
        return cli.main(argv)
    except SystemExit as exit_:
        return exit_.code


@pytest.mark.parametrize("argv, message", [
    (["--runs", "0"], "expected an integer >= 1, got 0"),
    (["--noise", "-1"], "expected a finite number >= 0"),
    (["--noise", "nan"], "expected a finite number >= 0"),
    (["--scenario", "magic"], "invalid choice: 'magic'"),
    (["--samples", "10"], "samples must be >= 30"),
])
def test_bad_arguments_are_one_line(argv, message, tmp_path, capsys):
    status = _status(["reproduce", *argv, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_unwritable_json_fails_before_running(tmp_path, capsys):
    (tmp_path / "file").write_text("not a directory")
    status = _status(["reproduce", *SMALL, "--out", str(tmp_path / "out"),
                      "--json", str(tmp_path / "file" / "sub" / "r.json")])
    assert status == 2 and "is not a directory" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
