"""How right a command's progress lines are: run it with stderr piped (not a terminal, so
it writes lines), time each line as it comes, and set each line's time left against the
time actually left until its last line (``... 100%``: the results are printed right after
it; the seconds the process takes to exit are shown apart).

    python tools/progress_log.py sedsabso-jax identify --robot kuka_lwr4 \\
        --data measurements_1.npz --validate measurements_2.npz

prints each line with its predicted and actual time left and their ratio, then the worst
factor (the issue's goal: within 2 at every line; times under a second count as one).
"""

from __future__ import annotations

import re
import subprocess
import sys
import time

LEFT = re.compile(r"~([\d.]+) (s|min) left|(<1) s left")


def predicted(line: str) -> float | None:
    """The time left a line states, in seconds (None: it states none)."""
    m = LEFT.search(line)
    if m is None:
        return None
    if m.group(3):
        return 0.5
    return float(m.group(1)) * (60.0 if m.group(2) == "min" else 1.0)


def main(command: list[str]) -> float:
    t0 = time.perf_counter()
    run = subprocess.Popen(command, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                           text=True, bufsize=1)
    assert run.stderr is not None
    lines = [(time.perf_counter() - t0, line.rstrip("\n")) for line in run.stderr]
    run.wait()
    end = time.perf_counter() - t0
    last = next((t for t, line in reversed(lines) if " 100%, " in line), end)
    print(f"exit status {run.returncode}; last line at {last:.1f} s, exit {end - last:.1f} "
          f"s after it")
    worst = 1.0
    for t, line in lines:
        left = predicted(line)
        if left is None:
            print(f"{t:7.1f} s {'':31} {line}")
            continue
        ratio = max(left, 1.0) / max(last - t, 1.0)
        worst = max(worst, ratio, 1 / ratio)
        print(f"{t:7.1f} s  left {left:6.0f} s, actual {last - t:6.1f} s, x{ratio:4.2f}  {line}")
    print(f"worst factor {worst:.2f}")
    return worst


if __name__ == "__main__":
    main(sys.argv[1:])
