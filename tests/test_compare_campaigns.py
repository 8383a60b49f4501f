"""Campaigns on Dask distributed: two local worker processes, one of them killed while
tasks run, give the serial campaign's numbers bit for bit (nothing lost, nothing counted
twice); a restarted campaign runs only its unfinished tasks; an unreachable scheduler is
one line and exit status 1 within 30 s with nothing written, and so is a server that is not
a Dask scheduler (HTTP, random bytes) within the timeout and a margin; without the flags Dask is
not imported, and without Dask the flags name the extra to install (without cocopp, a
note names it)."""

from __future__ import annotations

import contextlib
import http.server
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from conftest import SMALL_CAMPAIGN

import sedsabso_jax.compare
from sedsabso_jax import cli
from sedsabso_jax.compare import _campaign as campaign
from sedsabso_jax.compare import _run as R

TIMINGS = ("compile_s", "run_s")


def _numbers(out) -> dict:
    """Every task file's document without its timings, and every COCO file's text."""
    found = {}
    for path in sorted((out / "tasks").rglob("*.json")):
        doc = json.loads(path.read_text())
        for a in doc["algorithms"].values():
            for key in TIMINGS:
                a.pop(key)
        found[str(path.relative_to(out))] = doc
    for path in sorted((out / "coco").rglob("*")):
        if path.is_file():
            found[str(path.relative_to(out))] = path.read_text()
    return found


def _settings(*flags: str) -> R.Settings:
    args = cli.build_parser().parse_args([*SMALL_CAMPAIGN, *flags, "--out", "unused"])
    return R.Settings(suite=args.suite, algorithms=tuple(args.algorithms.split(",")),
                      budget=args.budget, functions=args.functions,
                      dimensions=args.dimensions, instances=args.instances)


def test_two_workers_one_killed_give_the_serial_numbers(small_campaign, tmp_path):
    """f1 of the small campaign (two tasks: LDWPSO and CMA-ES) on two worker processes;
    when the first task is done, the worker running the other is killed."""
    distributed = pytest.importorskip("distributed")
    serial, _, _ = small_campaign
    out = tmp_path / "dask"
    killed, finished = [], []

    def progress(label, done, total, elapsed):
        finished.append(label)
        if done == 1:  # one task done, the other running: kill its worker
            client = distributed.default_client()
            busy = [w for w, keys in client.processing().items() if keys]
            pids = client.run(os.getpid)
            os.kill(pids[busy[0]], signal.SIGKILL)
            killed.append((pids[busy[0]], client.processing()[busy[0]]))

    docs = campaign.compare(_settings("--functions", "1"), out, progress, workers=2)
    assert killed and killed[0][1], "no worker was killed while it ran a task"
    assert len(docs) == 1 and finished[0] == "starting" and len(finished) == 1 + 2
    assert len(set(finished[1:])) == 2  # each task reported once
    ours = _numbers(out)
    theirs = {k: v for k, v in _numbers(serial).items() if "f01" in k or "_f1" in k}
    assert sorted(ours) == sorted(theirs) and len(ours) == 2 + 2 * 3
    for name in theirs:
        assert ours[name] == theirs[name], name  # bit for bit
    info = (out / "coco" / "CMA_ES" / "bbobexp_f1.info").read_text().splitlines()[2]
    assert [part.split(":")[0] for part in info.split(", ")[1:]] == [
        "1", "2", "3", "4", "5", *map(str, range(101, 111))]  # each instance once


def test_a_restarted_campaign_runs_only_unfinished_tasks(small_campaign, tmp_path):
    serial, _, _ = small_campaign
    out = tmp_path / "restart"
    shutil.copytree(serial / "tasks", out / "tasks")
    lost = out / "tasks" / "bbob-f21-gallagher-101-d02" / "LDWPSO.json"
    lost.unlink()  # interrupted before this task was written
    stamps = {p: p.stat().st_mtime_ns for p in (out / "tasks").rglob("*.json")}
    ran = []
    campaign.compare(_settings(), out, lambda label, *_: ran.append(label))
    assert ran == ["starting", "bbob-f21-gallagher-101-d02 LDWPSO"]
    assert stamps == {p: p.stat().st_mtime_ns for p in stamps}
    assert _numbers(out)[str(lost.relative_to(out))] == _numbers(serial)[
        str(lost.relative_to(out))]
    assert _numbers(out) == _numbers(serial)


def test_unreachable_scheduler_is_one_line_and_status_1(tmp_path, capsys):
    pytest.importorskip("distributed")
    out = tmp_path / "none"
    t0 = time.perf_counter()
    code = cli.main([*SMALL_CAMPAIGN, "--functions", "1", "--scheduler",
                     "tcp://127.0.0.1:9", "--scheduler-timeout", "2", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 1 and time.perf_counter() - t0 < 30
    assert err.startswith("sedsabso-jax: error: cannot reach the Dask scheduler at "
                          "tcp://127.0.0.1:9 within 2 s") and err.count("\n") == 1
    assert not out.exists()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args) -> None:  # the test checks stderr: the server keeps quiet
        pass


@contextlib.contextmanager
def _http_server():
    """A plain HTTP server on the loopback; yields its port."""
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _QuietHandler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        yield server.server_address[1]
    finally:
        server.shutdown()
        server.server_close()


@contextlib.contextmanager
def _noise_server():
    """A TCP server on the loopback that sends each connection 64 KiB of seeded random
    bytes and keeps it open; yields its port."""
    listener = socket.create_server(("127.0.0.1", 0))
    noise, accepted = np.random.default_rng(0).bytes(1 << 16), []

    def serve() -> None:
        with contextlib.suppress(OSError):  # the listener closed: done
            while True:
                conn, _ = listener.accept()
                accepted.append(conn)
                with contextlib.suppress(OSError):
                    conn.sendall(noise)

    threading.Thread(target=serve, daemon=True).start()
    try:
        yield listener.getsockname()[1]
    finally:
        listener.close()
        for conn in accepted:
            conn.close()


def _main_within(argv: list[str], limit: float) -> tuple[int, float]:
    """``cli.main(argv)``'s exit status and seconds; a failure if it runs past ``limit``
    (in a thread, so that a hang fails the test instead of stopping the suite)."""
    done: list[int] = []
    thread = threading.Thread(target=lambda: done.append(cli.main(argv)), daemon=True)
    t0 = time.perf_counter()
    thread.start()
    thread.join(limit)
    seconds = time.perf_counter() - t0
    assert done, f"sedsabso-jax {' '.join(argv)} still ran after {limit:g} s"
    return done[0], seconds


@pytest.mark.parametrize("server", [_http_server, _noise_server], ids=["http", "random-bytes"])
def test_a_server_that_is_not_a_scheduler_is_one_line_and_status_1(server, tmp_path, capsys):
    pytest.importorskip("distributed")
    out, timeout, margin = tmp_path / "none", 2, 8
    with server() as port:
        address = f"tcp://127.0.0.1:{port}"
        code, seconds = _main_within([*SMALL_CAMPAIGN, "--functions", "1", "--scheduler",
                                      address, "--scheduler-timeout", str(timeout), "--out",
                                      str(out)], timeout + margin)
    err = capsys.readouterr().err
    assert code == 1, err
    assert err.startswith(f"sedsabso-jax: error: cannot reach the Dask scheduler at {address} "
                          f"within {timeout} s: ") and err.count("\n") == 1, err
    assert not out.exists()


def test_a_running_scheduler_passes_the_handshake_check():
    distributed = pytest.importorskip("distributed")
    from sedsabso_jax.compare import _dask

    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as c:
        _dask.check_scheduler(c.scheduler_address, 10)  # no error


def test_a_malformed_scheduler_address_is_bad_input(tmp_path, capsys):
    pytest.importorskip("distributed")
    out = tmp_path / "none"
    assert cli.main([*SMALL_CAMPAIGN, "--functions", "1", "--scheduler", "http://127.0.0.1:9",
                     "--out", str(out)]) == 2
    assert capsys.readouterr().err.startswith(
        "sedsabso-jax: error: scheduler address 'http://127.0.0.1:9': unknown address scheme "
        "'http'")
    assert not out.exists()


def test_without_flags_no_dask_and_without_dask_the_extra(small_campaign, tmp_path, capsys,
                                                         monkeypatch):
    done = tmp_path / "done"  # finished tasks: the command reads them, writes the rest
    shutil.copytree(small_campaign[0] / "tasks", done / "tasks")
    argv = [*SMALL_CAMPAIGN, "--out", str(done)]
    run = subprocess.run(
        [sys.executable, "-c", f"import sys; from sedsabso_jax import cli; code = cli.main("
         f"{argv!r}); print(code, 'distributed' in sys.modules, 'dask' in sys.modules)"],
        capture_output=True, text=True, timeout=300, env={**os.environ, "JAX_PLATFORMS": "cpu"})
    assert run.stdout.strip().splitlines()[-1] == "0 False False", run.stderr[-2000:]
    monkeypatch.setitem(sys.modules, "distributed", None)  # an import of it fails
    monkeypatch.delitem(sys.modules, "sedsabso_jax.compare._dask", raising=False)
    monkeypatch.delattr(sedsabso_jax.compare, "_dask", raising=False)
    out = tmp_path / "none"
    assert cli.main([*SMALL_CAMPAIGN, "--functions", "1", "--workers", "2", "--out",
                     str(out)]) == 2
    assert capsys.readouterr().err == ("sedsabso-jax: error: --workers and --scheduler need "
                                       "Dask distributed: pip install "
                                       "'sedsabso-jax[compare]'\n")
    assert not out.exists()


def test_without_cocopp_a_note_names_the_extra(small_campaign, tmp_path, capsys, monkeypatch):
    done = tmp_path / "done"  # finished tasks: nothing runs
    shutil.copytree(small_campaign[0] / "tasks", done / "tasks")
    monkeypatch.setitem(sys.modules, "cocopp", None)  # an import of it fails
    assert cli.main([*SMALL_CAMPAIGN, "--out", str(done)]) == 0
    assert capsys.readouterr().err == ("sedsabso-jax: note: COCO's figures and tables (python "
                                       "-m cocopp, see report.md) need cocopp: pip install "
                                       "'sedsabso-jax[compare]'\n")
