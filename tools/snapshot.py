"""Snapshot the command's outputs, to check that a change of structure changes no result.

    python tools/snapshot.py run OUT [--only identify|reproduce|compare] [--names a,b]
    python tools/snapshot.py diff OLD NEW

``run`` writes what ``identify`` (three shipped robots, several estimators and models),
``reproduce`` and ``compare --runs 5`` write into OUT; ``diff`` compares two snapshots
file by file, byte for byte, except the timings: JSON keys that hold seconds
(``seconds``, ``*_s``, ``time*``) are dropped, lines of text that print seconds are
masked, and progress lines (``identify: 37/372 fits, ...``) are left out.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
KUKA = ROOT / "sedsabso_jax" / "data" / "kuka_lwr4"


def identify_runs(tmp: Path) -> dict[str, list[str]]:
    sys.path.insert(0, str(ROOT))
    from data import real_robots

    m1, m2 = str(KUKA / "measurements_1.npz"), str(KUKA / "measurements_2.npz")
    panda = str(real_robots.panda_npz(tmp / "panda.npz"))
    tx40 = str(real_robots.tx40_npz(tmp / "tx40.npz"))
    kuka = ["--robot", "kuka_lwr4", "--data", m1, "--validate", m2]
    return {
        "kuka-default": kuka,
        "kuka-physical-cv": [*kuka, "--physical", "--prior-strength", "cv"],
        "kuka-wls-smooth": [*kuka, "--method", "WLS", "--friction",
                            "viscous-coulomb+offset+quadratic+smooth", "--no-physical"],
        "kuka-l1": [*kuka, "--method", "L1", "--weights", "equal",
                    "--friction", "viscous-coulomb+offset"],
        "kuka-sedsabso": [*kuka, "--method", "SEDSABSO", "--runs", "2", "--iterations", "60",
                          "--friction", "viscous-coulomb"],
        "kuka-two-runs": ["--robot", "kuka_lwr4", "--data", m1, m2, "--offset-per-recording"],
        "panda-default": ["--robot", "franka_panda", "--data", panda, "--resample-hz", "1000"],
        "tx40-default": [*real_robots.TX40_FLAGS, "--data", tx40, "--downsample", "5"],
    }


def run(out: Path, only: str | None, names: set[str] | None = None) -> None:
    out.mkdir(parents=True, exist_ok=True)
    exe = str(Path(sys.executable).parent / "sedsabso-jax")
    data = out / "_data"  # converted recordings, under OUT so that paths compare
    data.mkdir(exist_ok=True)
    (out / "_root.txt").write_text(str(ROOT))  # the checkout, masked by diff
    jobs: list[tuple[str, list[str]]] = []
    if only in (None, "identify"):
        for name, argv in identify_runs(data).items():
            if names is not None and name not in names:
                continue
            jobs.append((name, ["identify", *argv, "--out", str(out / name),
                                "--json", str(out / f"{name}.json")]))
    if only in (None, "reproduce"):
        jobs.append(("reproduce", ["reproduce", "--out", str(out / "reproduce"),
                                   "--json", str(out / "reproduce.json")]))
    if only in (None, "compare"):
        jobs.append(("compare", ["compare", "--runs", "5", "--dimensions", "5,10",
                                 "--out", str(out / "compare")]))
    for name, argv in jobs:
        p = subprocess.run([exe, *argv], capture_output=True, text=True)
        (out / f"{name}.stdout").write_text(p.stdout)
        (out / f"{name}.stderr").write_text(p.stderr)
        print(f"{name}: exit {p.returncode}", flush=True)


TIMING_KEY = re.compile(r"(seconds|_s|^time.*|^elapsed.*|^version)$")
PROGRESS = re.compile(r"^(identify|compare): \d+/\d+ ")
TIMING_TEXT = re.compile(r"\d+(\.\d+)?\s*(s|ms|min)\b|\d+(\.\d+)?s\b|sedsabso-jax \d+\.\d+")


def _strip(obj):
    if isinstance(obj, dict):
        return {k: _strip(v) for k, v in obj.items() if not TIMING_KEY.search(k)}
    if isinstance(obj, list):
        return [_strip(v) for v in obj]
    return obj


def _unrooted(text: str, out: Path) -> str:
    """``text`` with the snapshot's folder and the checkout it was run from masked."""
    text = text.replace(str(out), "OUT")
    root = out / "_root.txt"
    return text.replace(root.read_text(), "ROOT") if root.exists() else text


def _masked(text: str) -> list[str]:
    """The lines of ``text`` with times masked: numbers with a unit of time, and the cells
    of table columns whose header says seconds (``[s]``)."""
    out, timed = [], set()
    for line in text.splitlines():
        if PROGRESS.match(line):
            continue
        cells = line.split("|")
        if line.startswith("|") and not set(line) <= set("|:- "):
            if any("[s]" in c for c in cells):  # a header row
                timed = {i for i, c in enumerate(cells) if "[s]" in c}
            else:
                cells = ["#" if i in timed else c for i, c in enumerate(cells)]
        elif not line.startswith("|"):
            timed = set()
        out.append(TIMING_TEXT.sub("#", "|".join(cells)))
    return out


def diff(old: Path, new: Path, subset: bool = False) -> int:
    """Files that differ between snapshots ``old`` and ``new`` (``subset``: ``new`` was a
    part of the runs, and what only ``old`` has is not counted)."""
    bad = 0
    files = sorted({p.relative_to(old) for p in old.rglob("*") if p.is_file()}
                   | {p.relative_to(new) for p in new.rglob("*") if p.is_file()})
    for rel in files:
        a, b = old / rel, new / rel
        if subset and not b.exists():
            continue
        if not (a.exists() and b.exists()):
            print(f"only in {'old' if a.exists() else 'new'}: {rel}")
            bad += 1
            continue
        if rel.suffix in (".png", ".npz") or rel.name == "_root.txt" \
                or a.read_bytes() == b.read_bytes():
            continue
        text_a, text_b = (_unrooted(p.read_text(), root) for p, root in ((a, old), (b, new)))
        if rel.suffix == ".json":
            same = _strip(json.loads(text_a)) == _strip(json.loads(text_b))
        else:
            same = _masked(text_a) == _masked(text_b)
        if not same:
            print(f"differs: {rel}")
            bad += 1
    print(f"{len(files)} files, {bad} differ (timings masked; figures not compared)")
    return 1 if bad else 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="what", required=True)
    r = sub.add_parser("run")
    r.add_argument("out", type=Path)
    r.add_argument("--only", choices=("identify", "reproduce", "compare"))
    r.add_argument("--names", help="comma-separated identify runs to make (default: all)")
    d = sub.add_parser("diff")
    d.add_argument("old", type=Path)
    d.add_argument("new", type=Path)
    d.add_argument("--subset", action="store_true", help="NEW holds some of OLD's runs")
    a = p.parse_args()
    if a.what == "run":
        run(a.out, a.only, None if a.names is None else set(a.names.split(",")))
        return 0
    return diff(a.old, a.new, a.subset)


if __name__ == "__main__":
    sys.exit(main())
