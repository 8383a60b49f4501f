"""The package type-checks: mypy with the settings of pyproject.toml's [tool.mypy] (the
package, Python 3.11), no errors. About 25 s on a 2-core machine without a cache; mypy's
incremental cache is kept beside the tests' compiled programs (``mypy`` under the
directory above ``$SEDSABSO_JAX_CACHE``'s, ``off``: a new one each run), which mypy
checks against each file's contents before it reads it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_mypy_is_clean(tmp_path):
    pytest.importorskip("mypy")
    import jax

    xla = jax.config.jax_compilation_cache_dir  # set by conftest unless the cache is off
    cache = Path(xla).parent / "mypy" if xla else tmp_path / "cache"
    run = subprocess.run([sys.executable, "-m", "mypy", "--cache-dir", str(cache)],
                         cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-2000:]
    assert "Success: no issues found" in run.stdout
