"""Tasks on Dask distributed: an embedded ``LocalCluster`` of worker processes on this
machine (``--workers N``), or a running cluster (``--scheduler ADDRESS``; e.g. one that
dask-jobqueue starts on SLURM), which must answer Dask's handshake within the timeout
(:func:`check_scheduler`). Imported only when one of them is asked for.

Each task is one Dask task. Compiled code is kept per (algorithm, dimension): in each
worker's memory (the driver's cache) and in JAX's persistent compilation cache, which
the workers share (this process's directory, or for a ``LocalCluster`` without one a
temporary directory for the campaign). The tasks go out in the order of :func:`order`:
first one task of every (algorithm, dimension), so that the workers compile different
ones side by side, then the rest grouped by (algorithm, dimension), which a worker finds
compiled in its memory or on disk. A worker that dies takes its running task with it;
the scheduler runs it again on another worker (up to
``distributed.scheduler.allowed-failures`` times, 3 by default). Results come back to
this process, which alone writes files.

The workers run in this process's JAX mode (64-bit or not), through a worker plugin that
also reaches workers started later. The ``LocalCluster``'s workers run XLA on one thread
each (:data:`WORKER_ENV`), so that N workers on N cores do not compete for them; workers
you start yourself should be given the same environment (dask-jobqueue:
``job_script_prologue``).
"""

from __future__ import annotations

import asyncio
import logging
import shutil
import tempfile
import uuid
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor

try:
    import distributed
    from distributed.diagnostics.plugin import WorkerPlugin
except ImportError:  # pragma: no cover - the extra is missing
    raise ValueError("--workers and --scheduler need Dask distributed: pip install "
                     "'sedsabso-jax[compare]'") from None

from . import _run as R

#: the environment of the LocalCluster's workers: XLA's CPU code on one thread
WORKER_ENV = {"XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false"}


class JaxSetup(WorkerPlugin):
    """Puts a worker's JAX in the caller's 64-bit mode and compilation cache directory
    before it runs a task."""

    name = "sedsabso-jax-setup"

    def __init__(self, x64: bool, cache_dir: str | None):
        self.x64, self.cache_dir = x64, cache_dir

    def setup(self, worker) -> None:
        import jax

        jax.config.update("jax_enable_x64", self.x64)
        if self.cache_dir:
            jax.config.update("jax_compilation_cache_dir", self.cache_dir)


def order(tasks: list[R.Task]) -> list[R.Task]:
    """The tasks as they are sent: the first of every (algorithm, dimension), then the
    others grouped by (algorithm, dimension)."""
    def group(t: R.Task) -> tuple[str, str]:  # identification: one problem a group
        return t.algorithm, f"{t.dim:02d}" if t.dim else t.problem

    ordered = sorted(tasks, key=lambda t: (*group(t), t.problem))
    first = list({group(t): t for t in reversed(ordered)}.values())[::-1]
    return first + [t for t in ordered if t not in first]


def check_scheduler(address: str, timeout: float) -> None:
    """Connect to ``address`` and exchange Dask's handshake, all within ``timeout``
    seconds, or raise a RuntimeError of one line. ``distributed.Client(timeout=...)``
    bounds only the connection: a server that is not a Dask scheduler (an HTTP server)
    never answers the handshake and the client waits for ever; other bytes may be read
    as huge frames (MemoryError). Runs in its own thread and event loop, so that it also
    works under a caller's running loop (a notebook)."""
    try:  # a malformed address is bad input (exit status 2), not an unreachable scheduler
        scheme, location = distributed.comm.parse_address(address)
        distributed.comm.registry.get_backend(scheme)
        if scheme in ("tcp", "tls"):
            distributed.comm.parse_host_port(location)
    except ValueError as err:
        raise ValueError(f"scheduler address {address!r}: {_first_line(err)}; expected e.g. "
                         "tcp://10.0.0.5:8786") from None

    async def handshake() -> None:
        comm = await distributed.comm.connect(address, timeout=timeout)
        await comm.close()

    async def bounded() -> None:
        await asyncio.wait_for(handshake(), timeout)

    try:
        with ThreadPoolExecutor(max_workers=1) as pool:
            pool.submit(asyncio.run, bounded()).result()
    except TimeoutError:  # before OSError, which it is: no listener, or no handshake back
        raise _unreachable(address, timeout, "no Dask scheduler answered (is one listening "
                           "there?)") from None
    except OSError as err:  # nothing listens, or the connection was closed
        raise _unreachable(address, timeout, _first_line(err)) from None
    except Exception as err:  # unreadable bytes: not a Dask scheduler
        raise _unreachable(address, timeout, "its answer is not Dask's handshake "
                           f"({type(err).__name__}: {_first_line(err)})") from None


def _first_line(err: BaseException) -> str:
    """The error's first line, else its type's name."""
    text = str(err).strip()
    return text.splitlines()[0] if text else type(err).__name__


def _unreachable(address: str, timeout: float, why: str) -> RuntimeError:
    return RuntimeError(f"cannot reach the Dask scheduler at {address} within {timeout:g} "
                        f"s: {why}")


class Executor:
    """A Dask client (and the LocalCluster it owns, if any) that runs tasks."""

    def __init__(self, workers: int | None = None, scheduler: str | None = None,
                 timeout: float = 20.0):
        import jax

        self.cluster, self.cache = None, None
        if workers is not None:
            self.cluster = distributed.LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True,
                dashboard_address=None, silence_logs=logging.ERROR, env=WORKER_ENV)
            self.client = distributed.Client(self.cluster)
        elif scheduler is None:
            raise ValueError("give workers or a scheduler's address")
        else:
            check_scheduler(scheduler, timeout)
            try:
                self.client = distributed.Client(scheduler, timeout=timeout)
            except (OSError, TimeoutError) as err:
                raise _unreachable(scheduler, timeout, _first_line(err)) from None
        cache = jax.config.jax_compilation_cache_dir  # type: ignore[attr-defined]
        if not cache and self.cluster is not None:
            cache = self.cache = tempfile.mkdtemp(prefix="sedsabso-jax-xla-")
        self.client.register_plugin(JaxSetup(bool(jax.config.jax_enable_x64),  # type: ignore[attr-defined]
                                             cache or None))

    def run(self, tasks: list[R.Task], settings: R.Settings
            ) -> Iterator[tuple[R.Task, dict]]:
        """Submit every task; yield ``(task, document)`` as they finish."""
        campaign = uuid.uuid4().hex[:8]
        futures = {}
        for task in order(tasks):
            key = f"sedsabso-jax-{campaign}-{task.problem}-{task.algorithm}"
            futures[self.client.submit(R.run_task, task, settings, key=key, pure=False)] = task
        for future in distributed.as_completed(list(futures)):
            try:
                doc = future.result()
            except distributed.KilledWorker as err:
                raise RuntimeError(f"a task's workers died too often: {err}") from None
            yield futures[future], doc
            future.release()

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        if self.cache is not None:
            shutil.rmtree(self.cache, ignore_errors=True)
