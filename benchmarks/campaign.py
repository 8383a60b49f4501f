"""A COCO campaign on Dask distributed: the same comparison on 1 and on 2 local worker
processes (``sj.compare.compare(..., workers=N)``, Dask's ``LocalCluster``), and in this
process without Dask, with the same seeds: wall time and whether the numbers agree.

The campaign: COCO's bbob suite, functions 1-24 in 10-D, COCO's 15 instances, LDWPSO and
evosax's CMA-ES, ``--budget`` evaluations per run (10000d): 48 tasks of 15 runs. Each run
of the workers starts a fresh cluster (its start and shutdown timed with it) with a fresh
compilation cache, so the workers compile each (algorithm, dimension) as a user's first
campaign does. A warm-up campaign (1 function, 2 workers) comes first; then 1 and 2
workers alternate ``--repeats`` times, and the fastest of each counts (a shared machine
only ever adds time). The numbers: every task file, timings left out, bit for bit equal
across the three. The JSON keeps the load averages before and after.

    python -m benchmarks.campaign [--json benchmarks/results/campaign_cpu_2core.json]
                                  [--budget 10000d] [--repeats 2] [--quick]

Typical output (2-core AMD EPYC VM shared with other jobs, load average 2.3-4.8 from
them; about 26 minutes; benchmarks/results/campaign_cpu_2core.json):

    device: cpu (AMD EPYC, 2 cores), jax 0.10.2; 48 tasks
    serial (no Dask): 369.1 s
    1 worker: 306.6 s
    2 workers: 189.7 s
    1 worker: 333.8 s
    2 workers: 183.6 s
    speed-up 2 workers / 1: 1.67x (fastest of 2 each); numbers equal: serial = 1 = 2 workers
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import jax

import sedsabso_jax as sj
from benchmarks.device import describe, device_info
from benchmarks.output import to_json


def settings(budget: str, functions: str) -> sj.compare.Settings:
    return sj.compare.Settings(suite="bbob", algorithms=("LDWPSO", "CMA_ES"), budget=budget,
                               functions=functions, dimensions=(10,))


def numbers(out: Path) -> tuple[dict, int]:
    """Every task file's document without its timings; how many tasks compiled."""
    docs, compiled = {}, 0
    for path in sorted((out / "tasks").rglob("*.json")):
        doc = json.loads(path.read_text())
        for a in doc["algorithms"].values():
            compiled += a.pop("compile_s") > 0
            a.pop("run_s")
        docs[str(path.relative_to(out))] = doc
    return docs, compiled


def timed(s: sj.compare.Settings, workers: int | None) -> tuple[float, dict, int]:
    """Wall seconds of the campaign (cluster start and shutdown included), its numbers
    and how many tasks compiled."""
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        sj.compare.compare(s, out, workers=workers)
        seconds = time.perf_counter() - t0
        found, compiled = numbers(Path(out))
    return seconds, found, compiled


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--json", default=None)
    parser.add_argument("--budget", default="10000d")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--quick", action="store_true", help="functions 1-10, 300d, once")
    args = parser.parse_args()
    jax.config.update("jax_enable_x64", True)
    budget, repeats = ("300d", 1) if args.quick else (args.budget, args.repeats)
    s = settings(budget, "1-10" if args.quick else "1-24")
    info = device_info()
    tasks = len(s.tasks())
    print(f"device: {describe(info)}, jax {info['jax']}; {tasks} tasks", flush=True)
    timed(settings(budget, "1"), 2)  # warm-up: imports, files, a cluster
    load = [os.getloadavg()]
    serial_s, serial, serial_compiled = timed(s, None)
    print(f"serial (no Dask): {serial_s:.1f} s", flush=True)
    runs: dict[int, list[float]] = {1: [], 2: []}
    same, compiled = True, {}
    for _ in range(repeats):
        for workers in (1, 2):
            seconds, found, compiled[workers] = timed(s, workers)
            runs[workers].append(seconds)
            same &= found == serial
            print(f"{workers} worker{'s' if workers > 1 else ''}: {seconds:.1f} s", flush=True)
    load.append(os.getloadavg())
    speed_up = min(runs[1]) / min(runs[2])
    print(f"speed-up 2 workers / 1: {speed_up:.2f}x (fastest of {repeats} each); numbers "
          f"{'equal: serial = 1 = 2 workers' if same else 'DIFFER'}")
    if args.json:
        Path(args.json).write_text(to_json({
            "device": info, "settings": {"suite": s.suite, "algorithms": s.algorithms,
                                         "functions": s.functions, "dimensions": s.dimensions,
                                         "instances": s.instances, "budget": s.budget},
            "tasks": tasks, "serial_s": serial_s, "one_worker_s": runs[1],
            "two_workers_s": runs[2], "speed_up": speed_up, "numbers_equal": same,
            "tasks_compiling": {"serial": serial_compiled, "1": compiled[1], "2": compiled[2]},
            "load_average_before_after": load}))


if __name__ == "__main__":
    main()
