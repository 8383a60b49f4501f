"""The command line: the RS010N table (``base-parameters``' default robot), any URDF,
errors as one line with exit status 2."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from sedsabso_jax.cli import main

ROOT = Path(__file__).resolve().parents[1]


def test_default_prints_rs010n_table(capsys):
    assert main(["base-parameters"]) == 0
    out = capsys.readouterr().out
    assert "RS010N: 21 base parameters of 36" in out
    rows = [line for line in out.splitlines() if re.match(r"\| \d+ ", line)]
    assert len(rows) == 21
    first = [c.strip() for c in rows[0].strip("|").split("|")]
    assert first[1:4] == ["ZZ1R", "ZZ1 + YY2 + 0.1225*M2 + YY3 + 1.193725*M3", "71.9201"]
    assert first[5] == "16.41"  # the paper's value, in the paper's column
    assert "paper's Table 5 value" in out


def test_base_parameters_of_the_kuka(capsys):
    assert main(["base-parameters", "--robot", "kuka_lwr4"]) == 0
    assert "kuka-lwr: 57 base parameters of 84" in capsys.readouterr().out


@pytest.mark.parametrize("argv,message", [
    (["base-parameters", "--robot", "missing.urdf"], "no such file 'missing.urdf'"),
    (["base-parameters", "--robot", "puma"], "must be one of"),
    (["base-parameters", "--robot", "rs010n", "--tip", "x"], "--tip applies to URDF files"),
])
def test_errors_are_one_line(capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


def test_malformed_urdf_is_one_line(tmp_path, capsys):
    path = tmp_path / "bad.urdf"
    path.write_text("<robot name='r'><link")
    assert main(["base-parameters", "--robot", str(path)]) == 2
    err = capsys.readouterr().err
    assert "not well-formed XML" in err and err.count("\n") == 1


def test_console_script_runs():
    """The installed entry point (python -m form, same code path)."""
    run = subprocess.run([sys.executable, "-m", "sedsabso_jax", "base-parameters", "--robot",
                          "nowhere.urdf"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and "Traceback" not in run.stderr


def test_readme_commands_match_ci():
    """.ci/run runs the README's test command verbatim."""
    readme = (ROOT / "README.md").read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    blocks = re.findall(r"```bash\n(.*?)```", readme, flags=re.S)
    assert len(blocks) >= 2, "the README opens with two bash blocks: main job, tests"
    test_command = blocks[1].strip()
    assert test_command in ci


def test_readme_examples_run():
    """The README's Python examples execute as written, in order, and print what their
    comments say: each ``print(...)  # text`` line's output matches ``text``, with ``...``
    standing for anything (a time, say)."""
    import contextlib
    import io

    readme = (ROOT / "README.md").read_text()
    namespace: dict = {}
    expected, out = [], io.StringIO()
    for example in re.findall(r"```python\n(.*?)```", readme, flags=re.S):
        expected += re.findall(r"^print\(.*\)\s+# (.*)$", example, flags=re.M)
        with contextlib.redirect_stdout(out):
            exec(compile(example, "README.md", "exec"), namespace)  # noqa: S102
    printed = out.getvalue().splitlines()
    assert len(printed) == len(expected) == 5
    for line, comment in zip(printed, expected):
        pattern = ".*".join(re.escape(part) for part in comment.split("..."))
        assert re.fullmatch(pattern, line.strip()), (line, comment)
    assert namespace["Y"].shape == (1000, 3, 36)
    # the loop the user owns found the shifted sphere's minimum at 0.3
    assert float(namespace["f_best"]) < 7e-3  # measured 6.9e-4
    assert namespace["x_best"].shape == (3,)
    assert namespace["r"].x.shape == (10, 21)
    assert float(namespace["floor"].f) <= float(namespace["r"].f.min())
    # CMA-ES with SEDSABSO's budget ends far below it (README, "Example")
    assert float(namespace["c"].f.max()) < 1e-3 * float(namespace["r"].f.min())
