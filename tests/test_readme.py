"""The README stays a short front page: at most 150 lines, and every relative link in it
points to a file of the repository (the measured results and explanations live in docs/,
where ``mkdocs build --strict`` checks their links; tests/test_cli.py runs the README's
commands and examples)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
MAX_LINES = 150
#: ``[text](target)`` and ``![alt](target)``, the target up to a space or ``)``.
LINK = re.compile(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")


def _relative_links(text: str) -> list[str]:
    text = re.sub(r"```.*?```", "", text, flags=re.S)  # code blocks hold no links
    targets = LINK.findall(text)
    return [t for t in targets if not re.match(r"^[a-z][a-z0-9+.-]*:", t, flags=re.I)
            and not t.startswith("#")]


def test_readme_is_short():
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= MAX_LINES, (
        f"README.md has {len(lines)} lines (at most {MAX_LINES}): move details to docs/")


def test_readme_relative_links_resolve():
    links = _relative_links(README.read_text(encoding="utf-8"))
    assert links, "the README links to its documentation pages"
    missing = [t for t in links if not (ROOT / t.split("#", 1)[0]).exists()]
    assert not missing, f"README.md links to files that do not exist: {missing}"


def test_link_pattern():
    text = ("[a](docs/x.md) [b](https://e.org) ![c](img.png) [d](#top) "
            "[e](docs/y.md#part)\n```\n[f](not/a/link.md)\n```")
    assert _relative_links(text) == ["docs/x.md", "img.png", "docs/y.md#part"]
