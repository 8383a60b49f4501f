"""The command line as its peers': --version, help without a command, help in groups with
examples, exit statuses (2 bad input, 1 a failure while running), ``base-parameters
--json``, ``--config FILE`` under the command line, and progress bars only on a terminal
(the library reports to a callback, quietly by default)."""

from __future__ import annotations

import dataclasses
import io
import json
import re

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax import cli
from sedsabso_jax.cli._config import parse_args

COMMANDS = ("base-parameters", "reproduce", "compare", "identify", "identify-payload",
            "identify-gains")


def _status(argv) -> int:
    try:
        return cli.main(argv)
    except SystemExit as exit_:
        return int(exit_.code or 0)


@pytest.fixture(scope="module")
def data_file(tmp_path_factory):
    """Noise-free RS010N measurements along a random smooth motion (10 s at 40 Hz)."""
    robot = sj.robots.rs010n()
    rng = np.random.default_rng(1)
    traj = sj.FourierTrajectory(rng.uniform(-0.3, 0.3, (3, 3)),
                                rng.uniform(-0.3, 0.3, (3, 3)), np.zeros(3), wf=0.6)
    data = sj.simulate_measurements_along(robot, traj, np.arange(400) / 40.0)
    return str(data.save(tmp_path_factory.mktemp("data") / "run.npz"))


# ------------------------------------------------------------------------------ help
def test_version(capsys):
    assert _status(["--version"]) == 0
    assert capsys.readouterr().out == f"sedsabso-jax {sj.__version__}\n"


def test_no_command_prints_the_help(capsys):
    assert cli.main([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: sedsabso-jax")
    assert all(c in out for c in COMMANDS) and "exit status:" in out


def _help(argv, monkeypatch, capsys, columns=80) -> str:
    monkeypatch.setenv("COLUMNS", str(columns))
    assert _status([*argv, "--help"]) == 0
    return capsys.readouterr().out


def _groups(text: str) -> dict[str, list[str]]:
    """The help's sections (``title:`` lines at the margin) and their lines."""
    groups: dict[str, list[str]] = {}
    title = None
    for line in text.rstrip().splitlines():
        if re.fullmatch(r"[a-z][a-z ]*:", line):
            title = line[:-1]
            groups[title] = []
        if title is not None:
            groups[title].append(line)
    return groups


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_has_groups_examples_and_exit_statuses(command, monkeypatch, capsys):
    text = _help([command], monkeypatch, capsys)
    groups = _groups(text)
    assert "run" in groups and "outputs" in groups and "options" not in groups, list(groups)
    examples = [line.strip() for line in groups["examples"] if line.startswith("  ")]
    assert examples and all(e.startswith(f"sedsabso-jax {command}") for e in examples)
    assert "exit status: 0 done; 1 a failure while running" in " ".join(text.split())


def test_identify_help_fits_a_screen_per_group(monkeypatch, capsys):
    groups = _groups(_help(["identify"], monkeypatch, capsys, columns=80))
    assert {"input", "motors", "torque model", "estimator", "validation", "outputs",
            "run"} <= set(groups)
    for title, lines in groups.items():
        assert len(lines) <= 24, f"{title}: {len(lines)} lines at 80 columns"
        assert max(map(len, lines)) <= 80, title


# --------------------------------------------------------------------- exit statuses
def test_bad_flag_value_is_status_2(capsys):
    assert _status(["identify", "--robot", "rs010n", "--data", "x.npz", "--folds", "x"]) == 2
    err = capsys.readouterr().err
    assert "--folds" in err and err.count("\n") == 1


def test_missing_data_file_is_status_2(tmp_path, capsys):
    missing = str(tmp_path / "none.npz")
    assert cli.main(["identify", "--robot", "rs010n", "--data", missing]) == 2
    err = capsys.readouterr().err
    assert err.startswith("sedsabso-jax: error:") and missing in err and err.count("\n") == 1


def _failing(error: BaseException):
    def select_and_identify(*args, **kwargs):
        raise error
    return select_and_identify


@pytest.mark.parametrize("error, status, message", [
    (RuntimeError("RESOURCE_EXHAUSTED: Out of memory allocating 9 GB\nBufferAssignment: ..."),
     1, "sedsabso-jax: error: RESOURCE_EXHAUSTED: Out of memory allocating 9 GB\n"),
    (MemoryError(), 1, "sedsabso-jax: error: MemoryError\n"),
    (KeyError("q"), 1, "sedsabso-jax: error: KeyError: 'q' (--debug shows the traceback)\n"),
    (KeyboardInterrupt(), 130, "sedsabso-jax: interrupted\n"),
    (ValueError("bad value"), 2, "sedsabso-jax: error: bad value\n"),
], ids=["runtime", "memory", "unexpected", "interrupt", "value"])
def test_failures_while_running_are_status_1(error, status, message, data_file, monkeypatch,
                                              capsys):
    from sedsabso_jax.identification._default import _select_and_identify as _auto

    monkeypatch.setattr(_auto, "chosen_and_identified", _failing(error))
    assert cli.main(["identify", "--robot", "rs010n", "--data", data_file]) == status
    assert capsys.readouterr().err == message


def test_solver_failure_is_status_1(data_file, monkeypatch, capsys):
    cvxpy = pytest.importorskip("cvxpy")
    from sedsabso_jax.identification._default import _select_and_identify as _auto

    monkeypatch.setattr(_auto, "chosen_and_identified", _failing(cvxpy.error.SolverError("x")))
    assert cli.main(["identify", "--robot", "rs010n", "--data", data_file]) == 1
    assert capsys.readouterr().err.count("\n") == 1


def test_each_warning_once(data_file, monkeypatch, capsys):
    """A warning given twice (a URDF read by the robot and by its limits) is one line;
    another message is another line."""
    import warnings

    from sedsabso_jax.identification._default import _select_and_identify as _auto

    def warns(*args, **kwargs):  # from two places, as the robot and its limits read a URDF
        warnings.warn("URDF 'a.urdf': origin twice", stacklevel=1)
        warnings.warn("URDF 'a.urdf': origin twice", stacklevel=1)
        warnings.warn("other", stacklevel=1)
        raise ValueError("stop")

    monkeypatch.setattr(_auto, "chosen_and_identified", warns)
    assert cli.main(["identify", "--robot", "rs010n", "--data", data_file]) == 2
    assert capsys.readouterr().err.splitlines() == [
        "sedsabso-jax: warning: URDF 'a.urdf': origin twice", "sedsabso-jax: warning: other",
        "sedsabso-jax: error: stop"]


# --------------------------------------------------------------- base-parameters --json
def test_base_parameters_json_matches_the_table(tmp_path, capsys):
    path = tmp_path / "new" / "base.json"
    assert cli.main(["base-parameters", "--json", str(path)]) == 0
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if re.match(r"\| \d+ ", line)]
    doc = json.loads(path.read_text())
    assert doc["robot"] == "RS010N" and doc["n_joints"] == 3
    assert doc["n_base_parameters"] == len(rows) == len(doc["base_parameters"]) == 21
    assert len(doc["standard_parameters"]) == doc["n_standard_parameters"] == 36
    first = doc["base_parameters"][0]
    assert first["name"] == "ZZ1R" and first["expression"] in rows[0]
    assert f"{first['value']:.4f}" in rows[0] and first["paper_table5"]["value"] == 16.41
    assert np.shape(doc["matrix"]) == (21, 36)
    assert out.endswith(f"written: {path}\n")
    assert sorted(p.name for p in path.parent.iterdir()) == ["base.json"]  # no temporary


def test_base_parameters_json_to_stdout(capsys):
    assert cli.main(["base-parameters", "--robot", "kuka_lwr4", "--json", "-"]) == 0
    doc = json.loads(capsys.readouterr().out)  # only the JSON on stdout
    assert doc["n_base_parameters"] == 57 and "paper_table5" not in doc["base_parameters"][0]


# ----------------------------------------------------------------------------- --config
FLAGS = ["--robot", "rs010n", "--data", "d.npz", "--method", "OLS", "--physical",
         "--prior-strength", "1e-3", "--folds", "3", "--cutoff-hz", "5", "--coupling", "2:1=3",
         "--coupling", "3:2=4", "--json", "r.json"]
TOML = """robot = "rs010n"
data = "d.npz"
method = "OLS"
physical = true
prior_strength = 1e-3
folds = 3
cutoff-hz = 5
coupling = ["2:1=3", "3:2=4"]
json = "r.json"
"""


def _without_config(args) -> dict:
    return {k: v for k, v in vars(args).items() if k not in ("config", "func")}


@pytest.mark.parametrize("name, text", [
    ("run.toml", TOML),
    ("run.yaml", TOML.replace(" = ", ": ").replace("true", "yes")),
])
def test_config_gives_the_flags_arguments(name, text, tmp_path):
    if name.endswith(".yaml"):
        pytest.importorskip("yaml")
    path = tmp_path / name
    path.write_text(text)
    flags = parse_args(cli.build_parser(), ["identify", *FLAGS])
    config = parse_args(cli.build_parser(), ["identify", "--config", str(path)])
    assert _without_config(config) == _without_config(flags)
    assert config.prior_strength == 1e-3 and config.folds == 3 and config.physical is True


def test_command_line_wins_over_the_config(tmp_path, capsys):
    path = tmp_path / "run.toml"
    path.write_text(TOML)
    args = parse_args(cli.build_parser(), ["identify", "--folds", "4", "--config", str(path),
                                           "--coupling", "1:2=5"])
    assert args.folds == 4 and args.coupling == ["1:2=5"] and args.method == "OLS"
    assert sorted(capsys.readouterr().err.splitlines()) == [
        f"sedsabso-jax: note: --coupling from the command line overrides {path}'s value",
        f"sedsabso-jax: note: --folds from the command line overrides {path}'s value"]


@pytest.mark.parametrize("text, message", [
    ('prior_strenght = 1e-3', "unknown key 'prior_strenght'; did you mean 'prior-strength'?"),
    ('folds = "many"', "key 'folds' (--folds): expected an integer >= 0, got 'many'"),
    ('folds = 2.5', "key 'folds' (--folds): expected an integer >= 0, got '2.5'"),
    ('physical = "yes"', "key 'physical' (--physical): expected true or false, got 'yes'"),
    ('method = "magic"', "key 'method' (--method): expected one of auto, OLS"),
    ('robot = ["rs010n"]', "key 'robot' (--robot): expected a string or a number"),
    ('folds = ', "not a valid .toml file"),
])
def test_bad_config_is_one_line_and_status_2(text, message, tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(f'robot = "rs010n"\n{text}\n' if "robot" not in text else text + "\n")
    out = tmp_path / "out"
    status = _status(["identify", "--config", str(path), "--data", "d.npz", "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2 and message in err and err.count("\n") == 1, err
    assert str(path) in err and not out.exists()


def test_yaml_config_without_pyyaml_says_what_to_do(tmp_path, monkeypatch, capsys):
    import sys

    monkeypatch.setitem(sys.modules, "yaml", None)  # import yaml fails
    path = tmp_path / "run.yml"
    path.write_text("robot: rs010n\n")
    assert _status(["identify", "--config", str(path), "--data", "d.npz"]) == 2
    err = capsys.readouterr().err
    assert "pip install pyyaml, or write the file as TOML" in err and err.count("\n") == 1


# ----------------------------------------------------------------------------- progress
def test_select_and_identify_reports_its_work(data_file):
    """``progress`` reports work in estimated seconds, each fit's known before it runs:
    the splits' conic fits (the first sets the conic solver up), the fit on all the data,
    the evaluation; ``done`` grows to ``total``. The signals as loaded: the chain's
    choice reports its own work (tests/test_signal_chain.py)."""
    from sedsabso_jax.identification import _work

    calls: list[tuple[str, float, float]] = []
    data = sj.load_measurements(data_file, n_joints=3)
    robot = sj.robots.rs010n()
    plain = sj.TorqueModel.of(robot)
    loaded = sj.identification.DefaultValidation(signals=None)
    quiet = sj.select_and_identify(robot, data, estimators=sj.OLS(), models=plain,
                                   physical=True, prior_strength=1e-3, validation=loaded)
    report = sj.select_and_identify(robot, data, estimators=sj.OLS(), models=plain,
                                    physical=True, prior_strength=1e-3, validation=loaded,
                                    progress=lambda *call: calls.append(call))
    # 3 speed splits' and 5 phase folds' conic fits, the candidate validated (the work
    # after it revised), the fit on all the data, the evaluation
    assert [c[0] for c in calls] == (["OLS physical, viscous-coulomb"] * 8 + [
        "validated: OLS, viscous-coulomb", "fit on all the data", "evaluated"])
    done, total = [c[1] for c in calls], calls[-1][2]
    assert all(c[2] == pytest.approx(total) for c in calls) and done[-1] == total
    steps = np.diff([0.0, *done])
    assert (np.delete(steps, 8) > 0).all() and steps[8] == 0
    estimator = sj.PhysicallyConsistent(sj.OLS(), prior_strength=1e-3)
    assert steps[0] - max(steps[1:8]) > 0.9 * _work.SETUP["conic"]
    assert steps[-2] == pytest.approx(_work.fit_seconds(estimator, plain, data.q.size,
                                                        final=True))
    assert steps[-1] == pytest.approx(_work.evaluate_seconds(plain, data.q.size))
    assert report.text() == quiet.text()  # the callback changes nothing


def test_model_choice_and_prior_report_their_work(data_file):
    """The fits that search (friction at rest, kept unless worse) weigh more than the
    grid's least squares, the fit on all the data more than any split; the total is
    revised when the choice is made and ends where the work does."""
    calls: list[tuple[str, float, float]] = []
    data = sj.load_measurements(data_file, n_joints=3)
    robot = sj.robots.rs010n()
    sj.select_and_identify(robot, data, estimators=(sj.OLS(), sj.WLS()),
                           models=sj.identification.candidate_models(robot, [(), [sj.Offset()]]),
                           validation=sj.identification.DefaultValidation(3, signals=None),
                           physical=True, prior_strength=1e-3,
                           progress=lambda *call: calls.append(call))
    labels = [c[0] for c in calls]
    # candidates (with the pull to the prior), then friction at rest kept unless worse, x
    # (3 speed splits + 3 phase folds), the choice, the fit, the evaluation
    assert len(calls) == (2 * 2 + 1) * (3 + 3) + 3
    assert labels[0] == "OLS physical, viscous-coulomb" and labels[-1] == "evaluated"
    assert labels[-3].startswith("chosen: ") and labels[-2] == "fit on all the data"
    done = [c[1] for c in calls]
    steps = np.diff([0.0, *done])
    grid, kept = steps[1:24], steps[24:30]  # the first sets the conic solver up
    assert all("kept unless worse" in label for label in labels[24:30])
    assert kept.min() > 3 * grid.max() and steps[-2] > kept.max()
    assert done == sorted(done) and done[-1] == calls[-1][2]


def test_a_fit_with_its_searched_values_held_weighs_no_search():
    """A signal chain's validation holds the model's searched values where a fit to all
    the data put them: its fits are estimated as least squares, not as searches (they
    were, and the KUKA's progress said ~15 s left for 6 s)."""
    from sedsabso_jax.identification import _work
    from sedsabso_jax.identification._search._methods import Held

    robot = sj.robots.rs010n()
    searched = sj.TorqueModel.of(robot, (sj.Presliding(fitted=True),))
    held = dataclasses.replace(searched, search=Held())
    plain = sj.TorqueModel.of(robot, (sj.Presliding(),))
    rows = 3 * 3000
    assert _work.fit_seconds(sj.OLS(), held, rows) == _work.fit_seconds(sj.OLS(), plain, rows)
    assert _work.fit_seconds(sj.OLS(), searched, rows) > 5 * _work.fit_seconds(
        sj.OLS(), held, rows)
    assert _work.parts(sj.OLS(), held) == frozenset() != _work.parts(sj.OLS(), searched)


def test_config_of_reproduce_and_compare(tmp_path):
    path = tmp_path / "run.toml"
    path.write_text("design_iterations = 50\nruns = 3\n")
    args = parse_args(cli.build_parser(), ["reproduce", "--config", str(path)])
    assert (args.design_iterations, args.runs, args.iterations) == (50, 3, 600)
    path.write_text("runs = 20\nalgorithms = \"SEDSABSO,CMA_ES\"\n")
    args = parse_args(cli.build_parser(), ["compare", "--config", str(path)])
    assert (args.runs, args.algorithms) == (20, "SEDSABSO,CMA_ES")


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_bars_only_on_a_terminal():
    from sedsabso_jax.cli._common import Progress
    from sedsabso_jax.cli._compare import CompareProgress

    log, tty = io.StringIO(), _Terminal()
    for stream in (log, tty):
        with Progress("identify", stream) as progress:
            for k in range(1, 4):
                progress("OLS, viscous-coulomb", k, 3)
    assert log.getvalue() == ""
    assert tty.getvalue().startswith("\ridentify:") and "/3 [" in tty.getvalue()
    with CompareProgress(log) as progress:
        progress("f1_d5", 0, 2, 0.0)
        progress("f2_d5", 1, 2, 60.0)
    assert log.getvalue().splitlines() == ["compare: 0/2      0 s f1_d5",
                                           "compare: 1/2     60 s f2_d5 ~1 min left"]


def test_identify_draws_no_bar_off_a_terminal(data_file, capsys):
    """Off a terminal, lines: the share of the work, the seconds so far and the time
    left, the last when the report is written."""
    assert cli.main(["identify", "--robot", "rs010n", "--data", data_file, "--method", "OLS",
                     "--weights", "equal", "--friction", "viscous-coulomb"]) == 0
    err = capsys.readouterr().err
    assert not re.search(r"[\r█|]|fit/s", err), err
    lines = err.splitlines()
    elapsed, left = r"(<1|\d+) s", r"(~[\d.]+ (s|min)|<1 s)"
    assert all(re.fullmatch(rf"identify: +\d+%, {elapsed}(, {left} left)?: .+", line)
               for line in lines), err
    assert lines[-1].startswith("identify: 100%") and lines[-1].endswith(": done")


def test_progress_lines_weigh_the_work_and_pace_from_the_first_call():
    """A line at each tenth of the work (not of the calls) and at the end; the time left
    is the pace since the first call (what came before it sets none) applied to the work
    left, the command's own after the library's (``then``) included; a revised total."""
    from sedsabso_jax.cli._common import LineProgress

    now = [0.0]
    log = io.StringIO()
    progress = LineProgress("identify", log, then=10.0, clock=lambda: now[0])
    for t, label, done, total in [(30, "first fit", 1, 90), (31, "small", 2, 90),
                                  (40, "tenth", 11, 90), (41, "no line", 12, 90),
                                  (70, "revised", 41, 70), (100, "last", 70, 70)]:
        now[0] = t
        progress(label, done, total)
    now[0] = 102
    progress.finish("written")
    assert log.getvalue().splitlines() == [
        "identify:   1%, 30 s: first fit",
        "identify:  11%, 40 s, ~89 s left: tenth",   # (40-30)/(11-1) s per estimated s x 89
        "identify:  51%, 70 s, ~39 s left: revised",  # 40 s for 40, total now 70 + 10
        "identify:  87%, 100 s, ~10 s left: last",
        "identify: 100%, 102 s: written"]
    # fits four times faster than estimated (a warm compilation cache): the writing after
    # them is still its own seconds, not a quarter of them
    log, now[0] = io.StringIO(), 0.0
    progress = LineProgress("identify", log, then=5.0, every=0, clock=lambda: now[0])
    for t, label, done in [(10, "first fit", 0), (15, "half", 20)]:
        now[0] = t
        progress(label, done, 40)
    assert log.getvalue().splitlines()[-1] == "identify:  44%, 15 s, ~10 s left: half"
