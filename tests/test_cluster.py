"""The batch script on a Dask cluster (``--cluster``): a scheduler and two workers on 127.0.0.1,
one worker killed mid-run; every file is written once, byte for byte as ``--jobs 1`` writes it."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

distributed = pytest.importorskip(
    "distributed", reason="--cluster needs Dask's distributed scheduler: "
                          "pip install 'dask[distributed]'")

REPO = Path(__file__).resolve().parent.parent
SCRIPT = REPO / "blender_scripts" / "unwrap.py"
# Bound of every wait of these tests, in seconds (a bound, never a measurement).
DEADLINE = 600


def _grid_obj(path: Path, n: int) -> None:
    """A wavy n×n quad grid (a disk)."""
    lines = [f"v {i} {j} {0.3 * np.sin(i) * np.cos(j):.6f}"
             for j in range(n + 1) for i in range(n + 1)]
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            lines.append(f"f {a} {a + 1} {a + n + 2} {a + n + 1}")
    path.write_text("\n".join(lines) + "\n")


def _tube_obj(path: Path, around: int = 12, rings: int = 5) -> None:
    """An open cylinder: a band that needs a cut (automatic seams) to unwrap."""
    lines = []
    for r in range(rings + 1):
        for k in range(around):
            t = 2 * np.pi * k / around
            lines.append(f"v {np.cos(t):.6f} {np.sin(t):.6f} {0.4 * r:.6f}")
    for r in range(rings):
        for k in range(around):
            a, b = r * around + k + 1, r * around + (k + 1) % around + 1
            lines.append(f"f {a} {b} {b + around} {a + around}")
    path.write_text("\n".join(lines) + "\n")


def _meshes(folder: Path) -> list[str]:
    folder.mkdir()
    _grid_obj(folder / "grid4.obj", 4)
    _grid_obj(folder / "grid8.obj", 8)
    _grid_obj(folder / "grid12.obj", 12)
    _tube_obj(folder / "tube.obj")
    (folder / "square.off").write_text(
        "OFF\n5 4 0\n0 0 0\n1 0 0\n1 1 0.2\n0 1 0\n0.5 0.5 0.4\n"
        "3 0 1 4\n3 1 2 4\n3 2 3 4\n3 3 0 4\n")
    return sorted(p.name for p in folder.iterdir())


def _run(*args, timeout=DEADLINE):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, stdin=subprocess.DEVNULL)


def _stop(procs) -> None:
    """Stop the processes this test started, with everything they started (their sessions)."""
    for p in procs:
        if p.poll() is None:
            try:
                os.killpg(p.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
    for p in procs:
        try:
            p.wait(timeout=30)
        except subprocess.TimeoutExpired:
            pass
        try:  # also what is left of the session of a process already gone
            os.killpg(p.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        if p.poll() is None:
            p.wait(timeout=30)


@pytest.fixture
def local_cluster(tmp_path):
    """``(address, client, worker processes)`` of a scheduler and two one-thread workers
    started as processes on 127.0.0.1; always stopped at the end."""
    procs, client = [], None
    logs = tmp_path / "cluster-logs"
    logs.mkdir()

    def start(name, *argv):
        with open(logs / f"{name}.log", "w") as log:
            p = subprocess.Popen([sys.executable, "-m", *argv], stdout=log,
                                 stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                 cwd=tmp_path, start_new_session=True)
        procs.append(p)
        return p

    try:
        scheduler_file = tmp_path / "scheduler.json"
        scheduler = start("scheduler", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                          "--port", "0", "--no-dashboard", "--scheduler-file", str(scheduler_file))
        deadline = time.monotonic() + DEADLINE
        while not scheduler_file.is_file():
            assert scheduler.poll() is None, (logs / "scheduler.log").read_text()
            assert time.monotonic() < deadline, "the scheduler did not start"
            time.sleep(0.1)
        time.sleep(0.2)  # the file is written in one go; let it be complete
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:"), address
        workers = [start(f"worker{k}", "distributed.cli.dask_worker", address, "--nthreads", "1",
                         "--no-nanny", "--no-dashboard", "--host", "127.0.0.1",
                         "--name", f"worker{k}", "--local-directory", str(tmp_path / f"w{k}"),
                         "--death-timeout", "120")
                   for k in range(2)]
        client = distributed.Client(address, timeout=60, set_as_default=False)
        client.wait_for_workers(2, timeout=DEADLINE)
        yield address, client, workers
    finally:
        if client is not None:
            client.close()
        _stop(procs)


def _children(pid: int) -> set[int]:
    """Live processes whose parent is ``pid`` (Linux /proc)."""
    out = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            fields = stat[stat.rindex(")") + 2:].split()
            if int(fields[1]) == pid and fields[0] != "Z":
                out.add(int(entry.name))
    return out


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2:].split()[0] != "Z"


def _comparable(report):
    """A batch report without what differs from run to run: times (also in the summary
    lines) and the output folder."""
    import re

    def strip(value):
        if isinstance(value, dict):
            return {k: strip(v) for k, v in value.items() if k not in ("seconds", "output")}
        if isinstance(value, list):
            return [strip(v) for v in value]
        if isinstance(value, str):
            return re.sub(r" in [0-9.]+ s", " in - s", value)
        return value

    return strip(report)


def test_cluster_batch_survives_a_killed_worker(tmp_path, local_cluster):
    address, client, workers = local_cluster
    names = _meshes(tmp_path / "in")
    ref, ref_report = tmp_path / "ref", tmp_path / "ref.json"
    r = _run(tmp_path / "in", ref, "--jobs", "1", "--report", ref_report)
    assert r.returncode == 0, r.stdout + r.stderr
    expected = sorted(p.name for p in ref.iterdir())
    assert len(expected) == 2 * len(names)  # every output and its layout

    out, out_report = tmp_path / "out", tmp_path / "out.json"
    driver = subprocess.Popen(
        [sys.executable, str(SCRIPT), str(tmp_path / "in"), str(out), "--cluster", address,
         "--report", str(out_report)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL,
        start_new_session=True)
    killed, orphans = None, set()
    try:
        # once the first file is written, kill a worker that is running a file
        deadline = time.monotonic() + DEADLINE
        while killed is None:
            assert time.monotonic() < deadline, "no worker could be killed mid-run"
            assert driver.poll() is None, "the batch ended before a worker was killed"
            if out.is_dir() and any(p.suffix == ".obj" and not p.name.startswith(".")
                                    for p in out.iterdir()):
                busy = [addr for addr, keys in client.processing().items() if keys]
                pids = client.run(os.getpid, workers=busy) if busy else {}
                for worker in workers:
                    if worker.pid in pids.values() and worker.poll() is None:
                        if sys.platform.startswith("linux"):
                            orphans = _children(worker.pid)
                        worker.send_signal(signal.SIGKILL)
                        worker.wait(timeout=60)
                        killed = worker
                        break
            time.sleep(0.05)
        stdout, stderr = driver.communicate(timeout=DEADLINE)
    finally:
        if driver.poll() is None:
            os.killpg(driver.pid, signal.SIGKILL)
            driver.wait(timeout=60)
    text = stdout + stderr
    assert driver.returncode == 0, text
    assert "Traceback" not in text
    # the unwrap the killed worker was running died with it
    deadline = time.monotonic() + DEADLINE
    while any(_alive(pid) for pid in orphans):
        assert time.monotonic() < deadline, f"processes {orphans} outlived their worker"
        time.sleep(0.1)

    # every file once: one line each, all ok, every output and layout, nothing else (no
    # partial file of the killed attempt)
    for name in names:
        lines = [ln for ln in stdout.splitlines() if ln.split("] ")[-1].startswith(f"{name}:")]
        assert len(lines) == 1 and ": ok: " in lines[0], (name, text)
    assert f"{len(names)} files, {len(names)} ok, 0 not" in stdout, text
    assert sorted(p.name for p in out.iterdir()) == expected
    for name in expected:
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name
    # the same report as --jobs 1, but for times and the output folder
    assert _comparable(json.loads(out_report.read_text())) == \
        _comparable(json.loads(ref_report.read_text()))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_cluster_that_cannot_be_reached_is_one_line_and_writes_nothing(tmp_path):
    _meshes(tmp_path / "in")
    address = f"tcp://127.0.0.1:{_free_port()}"
    r = _run(tmp_path / "in", tmp_path / "out", "--cluster", address)
    assert r.returncode == 1, r.stdout + r.stderr
    assert "Traceback" not in r.stderr
    errors = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(errors) == 1 and "--cluster" in errors[0] and address in errors[0], r.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("extra,named", [
    (["--cluster", "no-port-here"], "--cluster"),
    (["--cluster", "udp://127.0.0.1:8786"], "--cluster"),
    (["--cluster", "tcp://127.0.0.1:8786", "--jobs", "2"], "--jobs and --cluster"),
])
def test_cluster_arguments_are_checked_before_anything_runs(tmp_path, extra, named):
    _meshes(tmp_path / "in")
    r = _run(tmp_path / "in", tmp_path / "out", *extra)
    assert r.returncode == 1, r.stdout + r.stderr
    errors = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(errors) == 1 and named in errors[0], r.stderr
    assert not (tmp_path / "out").exists()


def test_cluster_needs_a_batch(tmp_path):
    src = tmp_path / "grid.obj"
    _grid_obj(src, 4)
    r = _run(src, tmp_path / "out.obj", "--cluster", "tcp://127.0.0.1:8786")
    assert r.returncode == 1, r.stdout + r.stderr
    errors = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(errors) == 1 and "--cluster" in errors[0] and "batch" in errors[0], r.stderr
    assert not (tmp_path / "out.obj").exists()
