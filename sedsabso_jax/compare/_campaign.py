"""A comparison campaign: every task (one algorithm on one problem, :mod:`._run`) run in
this process or on Dask workers (:mod:`._dask`), each result kept as one JSON file
(``OUT/tasks/<problem>/<algorithm>.json``, written atomically as soon as the task is
done), then every algorithm's COCO folder (``OUT/coco/<algorithm>/``) written from them.

An interrupted campaign resumes: a task whose file holds the same settings is read back,
not run again; a file with other settings is an error (use another ``--out``), never
silently mixed in. A task that runs twice (its worker died, Dask ran it again elsewhere)
writes the same file with the same numbers: nothing is lost or counted twice.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Iterable, Iterator

from .._output import PathLike, write_text
from . import _bbob, _cocodata
from . import _problems as P
from . import _run as R

#: progress(label, done, total, elapsed seconds)
ProgressFn = Callable[[str, int, int, float], None]


def task_path(out_dir: PathLike, task: R.Task) -> str:
    return os.path.join(out_dir, "tasks", task.problem, f"{task.algorithm}.json")


def load_finished(path: PathLike, settings: R.Settings, task: R.Task) -> dict | None:
    """A task's document if its file exists with these settings; None if it does not
    exist. Raises ValueError when it holds other settings or cannot be read."""
    if not os.path.exists(path):
        return None
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except (OSError, json.JSONDecodeError) as err:
        raise ValueError(f"{path}: cannot be read as a comparison result ({err}); remove it "
                         f"to run that task again") from None
    want = R.task_settings(settings, task)
    if not isinstance(doc, dict) or doc.get("schema") != R.SCHEMA or doc.get("settings") != want:
        have = doc.get("settings", {}) if isinstance(doc, dict) else {}
        diff = sorted(k for k in set(want) | set(have) if want.get(k) != have.get(k))
        raise ValueError(f"{path} holds results of other settings ({', '.join(diff) or 'schema'}"
                         f"); use another --out, or the settings it was run with")
    return doc


def serial(tasks: list[R.Task], settings: R.Settings) -> Iterator[tuple[R.Task, dict]]:
    """Run the tasks one after the other in this process."""
    for task in tasks:
        yield task, R.run_task(task, settings)


def merged(docs: Iterable[dict]) -> list[dict]:
    """Task documents -> one document per problem, its algorithms side by side (in the
    tasks' order)."""
    out: dict[str, dict] = {}
    for doc in docs:
        name = doc["problem"]["name"]
        if name not in out:
            out[name] = {**doc, "algorithms": {}}
        out[name]["algorithms"].update(doc["algorithms"])
    return list(out.values())


def coco_entries(docs: Iterable[dict], algorithm: str) -> list[_cocodata.Entry]:
    """The COCO entries of one algorithm from the BBOB task documents."""
    entries = []
    for doc in docs:
        a = doc["algorithms"].get(algorithm)
        if doc["problem"]["suite"] != "bbob" or a is None:
            continue
        function, dim = _bbob.parse_name(doc["problem"]["name"]) or (0, 0)
        c = a["coco"]
        entries.append(_cocodata.Entry(
            function, dim, c["comment"], tuple(a["instance_of_run"]),
            tuple(c["f_opt"]), tuple(map(tuple, c["dat"])), tuple(map(tuple, c["tdat"]))))
    return entries


def write_coco(docs: list[dict], algorithms: Iterable[str], out_dir: PathLike) -> list[str]:
    """Every algorithm's COCO folder ``OUT/coco/<algorithm>`` from the task documents;
    returns the folders written (none without BBOB tasks)."""
    written = []
    for name in algorithms:
        entries = coco_entries(docs, name)
        if entries:
            path = os.path.join(out_dir, "coco", name)
            _cocodata.write_folder(path, name, entries)
            written.append(path)
    return written


def _executor(workers: int | None, scheduler: str | None, timeout: float):
    if workers is None and scheduler is None:
        return None
    from . import _dask  # Dask only when asked for

    return _dask.Executor(workers=workers, scheduler=scheduler, timeout=timeout)


def compare(settings: R.Settings, out_dir: PathLike, progress: ProgressFn | None = None, *,
            workers: int | None = None, scheduler: str | None = None,
            scheduler_timeout: float = 20.0) -> list[dict]:
    """Run (or read back) every task of the comparison, write their files and the COCO
    folders; returns one document per problem.

    ``workers``: that many worker processes on this machine (a Dask ``LocalCluster``);
    ``scheduler``: the address of a running Dask scheduler to send the tasks to; neither:
    every task in this process (Dask is not imported). The same settings give the same
    numbers either way. Nothing is written before the tasks can run: bad settings or
    files are a ValueError, an unreachable scheduler a RuntimeError."""
    settings.check()
    if workers is not None and (isinstance(workers, bool) or workers < 1):
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    if workers is not None and scheduler is not None:
        raise ValueError("give either workers (a cluster on this machine) or a scheduler's "
                         "address, not both")
    tasks = settings.tasks()
    paths = {t: task_path(out_dir, t) for t in tasks}
    docs = {t: load_finished(paths[t], settings, t) for t in tasks}  # bad files fail first
    todo = [t for t in tasks if docs[t] is None]
    dims = {t.dim for t in todo if t.dim is not None}
    dims |= {P.load_problem(t.problem, settings.instances).dim for t in todo
             if t.dim is None}
    R.check_dimensions(settings, dims)
    executor = _executor(workers, scheduler, scheduler_timeout) if todo else None
    t0 = time.perf_counter()
    done = len(tasks) - len(todo)
    try:
        results = serial(todo, settings) if executor is None else executor.run(todo, settings)
        if progress and todo:
            progress("starting", done, len(tasks), 0.0)
        for task, doc in results:
            os.makedirs(os.path.dirname(paths[task]), exist_ok=True)
            # compact: a task holds runs x lines of numbers
            write_text(paths[task], json.dumps(doc, allow_nan=False, separators=(",", ":"))
                       + "\n")
            docs[task] = doc
            done += 1
            if progress:
                progress(f"{task.problem} {task.algorithm}", done, len(tasks),
                         time.perf_counter() - t0)
    finally:
        if executor is not None:
            executor.close()
    finished = [docs[t] for t in tasks]
    write_coco([d for d in finished if d is not None], settings.algorithms, out_dir)
    return merged(d for d in finished if d is not None)

