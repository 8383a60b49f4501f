"""Execute every notebook in notebooks/ with the small budget, and check it is stored
executed: every code cell run once, in order (execution counts 1..n), none with an error
output (the documentation site shows the stored outputs; notebooks/README.md says how to
re-execute them).

No Jupyter is needed: the code cells are run in order with ``exec`` in one fresh
namespace (tracebacks name the cell), in a temporary working directory (files a notebook
writes land there), with ``SEDSABSO_NOTEBOOK_SMALL=1`` (each notebook's budget switch),
matplotlib's Agg backend and ``plt.show`` replaced by a no-op. Notebooks run in this one
process, so compiled JAX code (swarms, excitation design) is shared between them, as in
one kernel session.
"""

from __future__ import annotations

import json
import linecache
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))


def _load(path: Path) -> dict:
    with open(path, encoding="utf-8") as fh:
        return json.load(fh)


def _source(cell: dict) -> str:
    source = cell.get("source", "")
    return "".join(source) if isinstance(source, list) else source


def test_notebooks_found():
    names = {p.name for p in NOTEBOOKS}
    assert {"quickstart.ipynb", "excitation_design.ipynb", "noise_robustness.ipynb"} <= names


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_executed(path):
    """Stored with its outputs, from one fresh run top to bottom: the code cells' execution
    counts are 1..n in order, and no output is an error."""
    nb = _load(path)
    assert nb.get("nbformat") == 4, f"{path.name}: expected nbformat 4"
    assert nb["metadata"].get("kernelspec", {}).get("name") == "python3", path.name
    counts = []
    for i, cell in enumerate(nb["cells"]):
        assert cell["cell_type"] in ("code", "markdown", "raw"), f"{path.name} cell {i}"
        assert "attachments" not in cell or not cell["attachments"], f"{path.name} cell {i}"
        if cell["cell_type"] != "code":
            continue
        counts.append(cell.get("execution_count"))
        for output in cell.get("outputs", []):
            assert output.get("output_type") != "error", (
                f"{path.name} cell {i}: stored with an error output "
                f"({output.get('ename')}: {output.get('evalue')})")
    assert counts == list(range(1, len(counts) + 1)), (
        f"{path.name}: execution counts {counts}, expected 1..{len(counts)} (re-execute "
        f"it top to bottom: notebooks/README.md)")
    assert any(cell.get("outputs") for cell in nb["cells"] if cell["cell_type"] == "code"), (
        f"{path.name}: stored without outputs")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs(path, tmp_path, monkeypatch):
    monkeypatch.setenv("SEDSABSO_NOTEBOOK_SMALL", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    import matplotlib

    matplotlib.use("Agg")  # also when another test imported matplotlib first
    import matplotlib.pyplot as plt

    monkeypatch.setattr(plt, "show", lambda *args, **kwargs: None)
    monkeypatch.chdir(tmp_path)
    nb = _load(path)
    cells = [_source(c) for c in nb["cells"] if c["cell_type"] == "code"]
    assert cells, f"{path.name} has no code cells"
    for i, src in enumerate(cells):
        assert not any(line.lstrip().startswith(("%", "!")) for line in src.splitlines()), (
            f"{path.name} code cell {i}: IPython magics or shell escapes cannot run here")
    namespace = {"__name__": "__main__"}
    import jax

    # as in a fresh kernel: 64-bit mode off until the notebook turns it on itself
    jax.config.update("jax_enable_x64", False)
    try:
        for i, src in enumerate(cells):  # in order, one namespace: like a kernel
            name = f"{path.name} code cell {i}"
            linecache.cache[name] = (len(src), None, src.splitlines(True), name)  # tracebacks
            exec(compile(src, name, "exec"), namespace)
    finally:
        plt.close("all")
        jax.config.update("jax_enable_x64", True)
    assert namespace.get("SMALL") is True, f"{path.name}: the budget switch SMALL is not set"
