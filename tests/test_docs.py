"""The documentation site (mkdocs.yml, docs/): it builds, its examples run, and every
public name is on an API page.

- ``mkdocs build --strict`` into a temporary directory succeeds: a broken link, a missing
  page, an unresolved cross-reference or a docstring griffe cannot parse fails it.
- The site's inventory (``objects.inv``, written by mkdocstrings) holds every entry of the
  ``__all__`` of ``sedsabso_jax`` and of its namespaces (tests/test_layout.py's list).
- Every ```` ```python ```` block of docs/getting-started.md and docs/how-to/*.md runs: a
  page's blocks in page order, in one namespace per page, in a temporary working directory
  standing for the repository root (``data/`` is linked into it), with JAX's 64-bit mode
  off at the start as in a fresh interpreter (a page turns it on itself), matplotlib's Agg
  backend and ``plt.show`` a no-op. A ``print(...)`` statement with a comment on its last
  line shows its output there: the printed text must match the comment, ``...`` standing
  for anything (a time, say). A block that cannot run here (one that needs a flag set
  before JAX starts, or a GPU) has the line ``<!-- skip -->`` right before it; use it
  sparingly, and never for an example that should work. Examples use small budgets
  (iterations, runs) and say what a real run would use.
- Every ``sedsabso-jax ...`` command in a ```` ```bash ```` block of those pages parses
  with the command's own parser, so a renamed flag or subcommand fails here.
- Numbers the pages quote from the package's output (:data:`QUOTED`) equal what produces
  them, to the digits the page shows: the KUKA's default ``identify`` run once for the
  module (about 40 s), or a ``print`` of the page whose output the examples' test checks.
"""

from __future__ import annotations

import ast
import contextlib
import importlib
import io
import linecache
import os
import re
import shlex
import subprocess
import sys
import textwrap
import zlib
from pathlib import Path

import pytest
from conftest import KUKA_IDENTIFY
from test_layout import NAMESPACES  # the public namespaces, each with its __all__

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: The pages whose examples run, in this order.
PAGES = [DOCS / "getting-started.md", *sorted((DOCS / "how-to").glob("*.md"))]
SKIP = "<!-- skip -->"
FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<lang>[\w-]*)[^\n]*\n(?P<body>.*?)"
                   r"^(?P=indent)```[ \t]*$", re.M | re.S)


def blocks(path: Path, lang: str) -> list[tuple[int, str, bool]]:
    """``(line, code, skipped)`` of every fenced ``lang`` block of ``path``, in order."""
    text = path.read_text(encoding="utf-8")
    found = []
    for m in FENCE.finditer(text):
        if m.group("lang") != lang:
            continue
        before = text[:m.start()].rstrip().splitlines()
        skipped = bool(before) and before[-1].strip() == SKIP
        line = text.count("\n", 0, m.start()) + 2  # the block's first code line
        found.append((line, textwrap.dedent(m.group("body")), skipped))
    return found


# ----------------------------------------------------------------------------- the build
def build(config: Path, out: Path, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    """``mkdocs build --strict`` of ``config`` into ``out``, at mkdocs' own log level: with
    ``--quiet`` mkdocs 1.6 neither shows warnings nor counts them for ``--strict``, so a
    quiet strict build passes with broken links (``test_a_broken_link_fails_the_build``)."""
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict",
                           "-f", str(config), "-d", str(out)],
                          cwd=cwd, capture_output=True, text=True, timeout=600,
                          env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    run = build(ROOT / "mkdocs.yml", out)
    assert run.returncode == 0, f"mkdocs build --strict failed:\n{run.stdout}\n{run.stderr}"
    assert "WARNING" not in run.stderr, run.stderr
    return out


def test_a_broken_link_fails_the_build(tmp_path):
    """A planted broken link fails :func:`build` (and would pass with ``--quiet``)."""
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "index.md").write_text("# Home\n\n[gone](nowhere.md)\n")
    config = tmp_path / "mkdocs.yml"
    config.write_text("site_name: planted\nvalidation:\n  unrecognized_links: warn\n")
    run = build(config, tmp_path / "site", cwd=tmp_path)
    assert run.returncode != 0 and "nowhere.md" in run.stderr, run.stderr
    quiet = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet",
                            "-f", str(config), "-d", str(tmp_path / "quiet")], cwd=tmp_path,
                           capture_output=True, text=True, timeout=600,
                           env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert quiet.returncode == 0  # why the build above must not be quiet


def inventory(path: Path) -> set[str]:
    """The object names of a Sphinx inventory (version 2: four header lines, then zlib)."""
    raw = path.read_bytes()
    header, _, body = raw.partition(b"zlib.\n")
    assert header.startswith(b"# Sphinx inventory version 2"), header[:40]
    lines = zlib.decompress(body).decode("utf-8").splitlines()
    return {line.split(" ", 1)[0] for line in lines if line.strip()}


def test_site_builds_strict(site):
    assert (site / "index.html").is_file()
    assert (site / "api" / "sedsabso_jax" / "index.html").is_file()
    # the notebooks are rendered with their stored outputs (figures inline)
    page = (site / "notebooks" / "quickstart" / "index.html").read_text(encoding="utf-8")
    assert "data:image/png;base64" in page


def test_every_public_name_on_an_api_page(site):
    names = inventory(site / "objects.inv")
    missing = []
    for namespace in NAMESPACES:
        module = importlib.import_module(namespace)
        missing += [f"{namespace}.{n}" for n in module.__all__ if f"{namespace}.{n}" not in names]
        if namespace not in names:
            missing.append(namespace)
    assert not missing, f"public names on no API page (docs/api/*.md): {missing}"


def test_inventory_reader_sees_names(site):
    names = inventory(site / "objects.inv")
    assert {"sedsabso_jax.minimise", "sedsabso_jax.robots.rs010n",
            "sedsabso_jax.SEDSABSO.paper"} <= names


# -------------------------------------------------------------------------- the examples
def test_getting_started_opens_with_the_readme_commands():
    """The install commands are the README's first two bash blocks, verbatim."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    ours = [code.strip() for _, code, _ in blocks(DOCS / "getting-started.md", "bash")[:2]]
    theirs = [b.strip() for b in re.findall(r"```bash\n(.*?)```", readme, flags=re.S)[:2]]
    assert ours == theirs


def _commands(code: str) -> list[list[str]]:
    """The ``sedsabso-jax`` invocations of a bash block: arguments after the program."""
    found = []
    for line in code.replace("\\\n", " ").splitlines():
        tokens = shlex.split(line, comments=True)
        command: list[str] = []
        for token in tokens + ["&&"]:
            if token in ("&&", "||", ";", "|"):
                programs = [i for i, t in enumerate(command) if t.endswith("sedsabso-jax")]
                if programs:
                    found.append(command[programs[0] + 1:])
                command = []
            else:
                command.append(token)
    return found


@pytest.mark.parametrize("path", PAGES, ids=lambda p: p.stem)
def test_commands_parse(path, tmp_path):
    """Each command parses; its ``--config FILE`` is the page's TOML block (the file shown)."""
    from sedsabso_jax.cli import _config as config
    from sedsabso_jax.cli import build_parser

    toml = [code for _, code, skipped in blocks(path, "toml") if not skipped]
    for line, code, skipped in blocks(path, "bash"):
        for argv in _commands(code):
            if skipped or {"--help", "-h", "--version"} & set(argv):
                continue
            if "--config" in argv:
                assert toml, f"{path.name}:{line}: --config without a TOML block on the page"
                file = tmp_path / Path(argv[argv.index("--config") + 1]).name
                file.write_text(toml[0], encoding="utf-8")
                argv = [str(file) if a == argv[argv.index("--config") + 1] else a
                        for a in argv]
            err = io.StringIO()
            try:
                with contextlib.redirect_stderr(err):
                    config.parse_args(build_parser(), argv)
            except SystemExit:
                pytest.fail(f"{path.name}:{line}: sedsabso-jax {shlex.join(argv)} does not "
                            f"parse: {err.getvalue().strip()}")


@pytest.mark.parametrize("path", PAGES, ids=lambda p: p.stem)
def test_config_examples_read(path, tmp_path, capsys):
    """Every TOML block of a page is a valid ``identify --config`` file: its keys are
    flags and its values parse with the flags' own types."""
    from sedsabso_jax.cli import _config as config
    from sedsabso_jax.cli import build_parser

    for line, code, skipped in blocks(path, "toml"):
        if skipped:
            continue
        file = tmp_path / f"line{line}.toml"
        file.write_text(code, encoding="utf-8")
        try:
            args = config.parse_args(build_parser(), ["identify", "--config", str(file),
                                                      "--data", "run.npz"])
        except SystemExit:
            pytest.fail(f"{path.name}:{line}: not a valid identify --config file: "
                        f"{capsys.readouterr().err.strip()}")
        assert args.robot is not None


def test_pages_found():
    names = {p.name for p in PAGES}
    assert {"getting-started.md", "motor-side.md", "excitation.md", "compare-optimisers.md",
            "gpu-and-devices.md", "jax-composition.md", "reproduce.md",
            "command-line.md"} <= names
    assert all(blocks(p, "python") or blocks(p, "bash") for p in PAGES)


def _expected(statement: ast.stmt, source_lines: list[str]) -> str | None:
    """The comment after a top-level ``print(...)`` statement, if it has one."""
    if not (isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Call)
            and isinstance(statement.value.func, ast.Name)
            and statement.value.func.id == "print"):
        return None
    last = source_lines[statement.end_lineno - 1]
    tail = last[statement.end_col_offset:]
    m = re.match(r"\s*#\s?(.*)$", tail)
    return m.group(1).rstrip() if m else None


def run_page(path: Path, namespace: dict) -> None:
    """Execute the page's python blocks in order in ``namespace``, statement by statement,
    checking each commented ``print``'s output."""
    for line, code, skipped in blocks(path, "python"):
        if skipped:
            continue
        name = f"{path.relative_to(ROOT)}:{line}"
        source_lines = code.splitlines()
        linecache.cache[name] = (len(code), None, code.splitlines(True), name)
        tree = ast.parse(code, filename=name)
        for statement in tree.body:
            module = ast.Module(body=[statement], type_ignores=[])
            expected = _expected(statement, source_lines)
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                exec(compile(module, name, "exec"), namespace)  # noqa: S102
            printed = out.getvalue()
            sys.stdout.write(printed)
            if expected is not None:
                pattern = ".*".join(re.escape(part) for part in expected.split("..."))
                assert re.fullmatch(pattern, printed.strip(), flags=re.S), (
                    f"{name}, line {statement.lineno}: printed {printed.strip()!r}, the "
                    f"page shows {expected!r}")


@pytest.mark.parametrize("path", PAGES, ids=lambda p: p.stem)
def test_examples_run(path, tmp_path, monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    import jax
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.setattr(plt, "show", lambda *args, **kwargs: None)
    (tmp_path / "data").symlink_to(ROOT / "data", target_is_directory=True)
    monkeypatch.chdir(tmp_path)  # files a page writes land here
    jax.config.update("jax_enable_x64", False)  # as in a fresh interpreter
    try:
        run_page(path, {"__name__": "__main__"})
    finally:
        plt.close("all")
        jax.config.update("jax_enable_x64", True)


# ----------------------------------------------------------- the numbers the pages quote
NUMBER = r"(\d+\.\d+)"
#: Numbers quoted in the pages: (page under docs/, a pattern of the page's text with its
#: line breaks read as spaces, its group the number, where the number comes from). From
#: ``("kuka", key)``: the JSON report of :data:`KUKA_IDENTIFY` (``validation``: the held-out
#: NRMS over the limits; ``score``: the error predicted for new motions); from
#: ``("printed", text)``: the page's own ``print`` whose shown output starts with ``text``.
QUOTED = [
    ("explanation/identification-defaults.md",
     rf"the default scores {NUMBER} % \(`{re.escape(KUKA_IDENTIFY)}`", ("kuka", "validation")),
    ("results/real-robots.md", rf"the default scores \*\*{NUMBER} %\*\* "
     rf"\(`{re.escape(KUKA_IDENTIFY)}`", ("kuka", "validation")),
    ("results/real-robots.md", rf"The choices on all the data: the KUKA .{{0,100}}\(predicted "
     rf"{NUMBER} %", ("kuka", "score")),
    ("results/real-robots.md", rf"\(predicted \S+ %; its second run {NUMBER} %\)",
     ("kuka", "validation")),
    ("getting-started.md", rf"The same runs as shipped \(`--data` the `\.npz` files, with the "
     rf"logger's accelerations instead of derived ones\) give {NUMBER} %", ("kuka", "validation")),
    ("getting-started.md", rf"The held-out \*\*validation\*\* \({NUMBER} %\) is the check on "
     r"`run2\.csv`", ("printed", "held-out NRMS over the limits")),
    ("getting-started.md", rf"It chose the same model as step 3 \(held out {NUMBER} % over the "
     r"limits\)", ("printed", "held-out NRMS over the limits")),
    ("getting-started.md", rf"\*\*The predicted error on new motions\*\* \({NUMBER} % of the "
     r"limits", ("printed", "predicted for new motions")),
    ("getting-started.md", rf"validated error \(nrms_limits_percent\): {NUMBER} \+-",
     ("printed", "predicted for new motions")),
]


@pytest.fixture(scope="module")
def kuka_report(kuka_identified) -> dict:
    """The JSON report of :data:`KUKA_IDENTIFY`, run from the repository root."""
    return kuka_identified[0]


def _printed(page: Path, text: str) -> str:
    """The number after ``text`` in the output a ``print`` of ``page`` shows."""
    shown = [expected for _, code, skipped in blocks(page, "python") if not skipped
             for statement in ast.parse(code).body
             if (expected := _expected(statement, code.splitlines())) is not None]
    found = [m.group(1) for e in shown if (m := re.match(rf"{re.escape(text)} {NUMBER}", e))]
    assert len(found) == 1, f"{page.name}: {len(found)} prints show {text!r}, expected one"
    return found[0]


@pytest.mark.parametrize("page, pattern, source", QUOTED,
                         ids=[f"{p}:{s[1]}" for p, _, s in QUOTED])
def test_quoted_numbers_are_what_produces_them(page, pattern, source, request):
    text = " ".join((DOCS / page).read_text(encoding="utf-8").split())
    quoted = re.findall(pattern, text)
    assert len(quoted) == 1, f"{page}: {len(quoted)} places match {pattern!r}, expected one"
    kind, key = source
    if kind == "kuka":
        report = request.getfixturevalue("kuka_report")
        value = {"validation": report["validation"]["nrms_limits_percent"],
                 "score": report["cross_validation"]["score"]}[key]
    else:
        value = float(_printed(DOCS / page, key))
    digits = len(quoted[0].split(".")[1])
    assert quoted[0] == f"{value:.{digits}f}", (
        f"{page} quotes {quoted[0]} % where {key} is {value:.{digits}f} %")


def test_the_compare_log_line_is_what_compare_writes():
    """command-line.md's example of ``compare``'s line per task off a terminal."""
    from sedsabso_jax.cli._compare import CompareProgress

    page = DOCS / "how-to" / "command-line.md"
    shown = [line for _, code, _ in blocks(page, "text") for line in code.splitlines()
             if line.startswith("compare: ")]
    assert len(shown) == 1, f"{page.name}: expected one example line of compare's log"
    m = re.fullmatch(r"compare: (\d+)/(\d+) +(\d+) s (.+?)( ~\d+ min left)?", shown[0])
    assert m, f"{page.name}: {shown[0]!r} is not a line of compare's log"
    log = io.StringIO()
    CompareProgress(log)(m.group(4), int(m.group(1)), int(m.group(2)), float(m.group(3)))
    assert log.getvalue().rstrip("\n") == shown[0]


def test_the_progress_lines_are_what_the_commands_write():
    """command-line.md's example lines of ``identify`` and ``reproduce`` off a terminal."""
    from sedsabso_jax.cli._common import LineProgress

    page = DOCS / "how-to" / "command-line.md"
    shown = [line for _, code, _ in blocks(page, "text") for line in code.splitlines()
             if line.startswith(("identify: ", "reproduce: "))]
    assert {line.split(":")[0] for line in shown} == {"identify", "reproduce"}, shown
    for line in shown:
        m = re.fullmatch(r"(\w+): +(\d+)%, (\d+) s(?:, ~(\d+) s left)?: (.+)", line)
        assert m, f"{page.name}: {line!r} is not a progress line"
        left = None if m.group(4) is None else float(m.group(4))
        made = LineProgress(m.group(1)).line(int(m.group(2)) / 100, float(m.group(3)), left,
                                             m.group(5))
        assert made == line

