# SPDX-License-Identifier: GPL-3.0-or-later
"""The batch of ``unwrap.py``, one file per task: on this machine (``--jobs``) or on the workers
of a Dask cluster (``--cluster``).

Both run :func:`unwrap_file`, which unwraps one file the same way wherever it runs: a fresh
Python process running ``unwrap.py`` on that single file, whose JSON report it hands back. The
files are therefore the same whichever way the batch ran.

On a cluster, every worker needs the Python environment of ``unwrap.py`` (``bpy``, ``numpy``,
``uvflat``) and must see ``unwrap.py``, the input files and the output folder under the same
paths as this machine (a shared file system). This module needs nothing on the workers' path:
:func:`connect` sends it to the scheduler and the workers (Dask ``upload_file``). It imports
only the standard library (Dask itself only in :func:`connect` and :func:`map_on_cluster`).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import uuid
from pathlib import Path

# Seconds to reach the scheduler of --cluster before giving up.
CONNECT_TIMEOUT = 10
# Times a task that raised is run again (Dask ``retries=``). A task whose worker died is run
# again by the scheduler itself, up to ``distributed.scheduler.allowed-failures`` times (3 by
# default), after which the file is reported as failed.
RETRIES = 2

# Linux: the unwrap process gets SIGKILL when the thread that started it ends (prctl
# PR_SET_PDEATHSIG, kept across exec), so a worker that dies takes its unwrap with it.
_DIE_WITH_PARENT = (
    "import ctypes, os, signal, sys\n"
    "ctypes.CDLL(None).prctl(1, int(signal.SIGKILL))\n"
    "if os.getppid() != int(sys.argv[1]):\n"
    "    os._exit(1)\n"
    "os.execv(sys.argv[2], sys.argv[2:])\n"
)


class ClusterError(Exception):
    """The cluster cannot be used (Dask missing, scheduler unreachable): one line."""


def _command(cmd):
    if sys.platform.startswith("linux"):
        return [sys.executable, "-c", _DIE_WITH_PARENT, str(os.getpid()), *cmd]
    return cmd


def unwrap_file(source, out, *, script, options, cwd, run_id):
    """Unwrap ``source`` into ``out`` (and its layout, ``out``'s name with ``_uv.png``) with a
    fresh Python process running ``script`` on that one file with ``options``, in folder
    ``cwd``. Returns ``(exit status, report or None, stderr)``; the report's ``output`` is
    ``out`` as given.

    The process writes under hidden names beside ``out`` (``.<run_id>-<attempt>-<name>``),
    renamed to the final names once it has finished: an attempt cut short (its worker died and
    the task runs again elsewhere) leaves no partial file under a final name, and every final
    file is written in one piece by one attempt.
    """
    target = Path(cwd, out)
    png = target.with_name(target.stem + "_uv.png")
    stage = target.with_name(f".{run_id}-{uuid.uuid4().hex[:8]}-{target.name}")
    stage_png = stage.with_name(stage.stem + "_uv.png")
    try:
        with tempfile.TemporaryDirectory(prefix="uvflat-file-") as tmp:
            report = Path(tmp) / "report.json"
            cmd = [sys.executable, str(script), str(source), str(stage), *options,
                   "--report", str(report)]
            r = subprocess.run(_command(cmd), cwd=cwd, capture_output=True, text=True,
                               stdin=subprocess.DEVNULL)
            # the report is written last, once the output and its layout are
            data = json.loads(report.read_text()) if report.is_file() else None
        if data is not None:
            os.replace(stage, target)
            os.replace(stage_png, png)
            data["output"] = str(out)
        return r.returncode, data, r.stderr.replace(str(stage), str(target))
    finally:
        for leftover in (stage, stage_png):
            leftover.unlink(missing_ok=True)


def remove_leftovers(folder: Path, run_id: str) -> None:
    """Delete the hidden files of ``run_id``'s attempts that did not finish."""
    for path in Path(folder).glob(f".{run_id}-*"):
        try:
            path.unlink()
        except OSError:
            pass


def check_available() -> None:
    """Raise ClusterError unless Dask's distributed scheduler can be imported."""
    import importlib.util

    if importlib.util.find_spec("distributed") is None:
        raise ClusterError("--cluster needs Dask's distributed scheduler: "
                           "pip install 'dask[distributed]'")


def check_address(address: str) -> None:
    """Raise ClusterError unless Dask is there and ``address`` reads as a scheduler address
    (``[tcp://|tls://]host:port``); nothing is contacted."""
    check_available()
    from distributed.comm.addressing import parse_address, parse_host_port

    expected = "expected a scheduler address such as tcp://host:8786"
    try:
        scheme, location = parse_address(address.strip())
        host, _ = parse_host_port(location)
    except (ValueError, TypeError) as ex:
        raise ClusterError(f"--cluster {address!r}: {ex} ({expected})") from None
    if scheme not in ("tcp", "tls") or not host:
        raise ClusterError(f"--cluster {address!r}: not a TCP scheduler address ({expected})")


# The name this module is sent to the cluster under (unique, unlike "cluster").
TASK_MODULE = "uvflat_batch_task"


def connect(address, log=print):
    """Connect to the Dask cluster whose scheduler is at ``address`` (e.g. tcp://host:8786)
    and send it this module. Returns ``(client, unwrap_file)``: the Dask client and
    :func:`unwrap_file` as the cluster imports it. Raises ClusterError if Dask is missing or
    the scheduler cannot be reached."""
    check_available()
    import importlib.util
    import shutil

    from distributed import Client

    try:
        client = Client(address, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as ex:
        detail = str(ex).strip().splitlines()[0] if str(ex).strip() else type(ex).__name__
        raise ClusterError(f"--cluster {address}: cannot reach the scheduler ({detail})") from None
    try:
        # the scheduler and every worker (also those that join later) import this very file
        # as TASK_MODULE; the tasks name its unwrap_file
        with tempfile.TemporaryDirectory(prefix="uvflat-task-") as tmp:
            copy = Path(tmp) / f"{TASK_MODULE}.py"
            shutil.copyfile(__file__, copy)
            client.upload_file(str(copy))
            spec = importlib.util.spec_from_file_location(TASK_MODULE, copy)
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
        sys.modules[TASK_MODULE] = module
        workers = client.scheduler_info().get("workers", {})
    except Exception as ex:  # noqa: BLE001 - one line, the client closed
        client.close()
        raise ClusterError(f"--cluster {address}: cannot send the task code "
                           f"({type(ex).__name__}: {str(ex).strip()[:200]})") from None
    threads = sum(w.get("nthreads", 0) for w in workers.values())
    log(f"cluster {address}: {len(workers)} worker{'s' * (len(workers) != 1)}, "
        f"{threads} thread{'s' * (threads != 1)}")
    return client, module.unwrap_file


def map_on_cluster(client, fn, items):
    """Run ``fn(*item)`` for every item on the cluster of Dask ``client``, one task each;
    yields ``(item, result)`` as tasks finish. A task that raised (after ``RETRIES`` more
    tries), or whose workers kept dying, yields ``(item, (1, None, message))``."""
    from distributed import as_completed

    token = uuid.uuid4().hex[:8]
    futures = {}
    for k, item in enumerate(items):
        future = client.submit(fn, *item, key=f"uvflat-unwrap-{token}-{k}", pure=False,
                               retries=RETRIES)
        futures[future] = item
    for future in as_completed(futures, loop=client.loop):
        item = futures[future]
        try:
            result = future.result()
        except Exception as ex:  # noqa: BLE001 - reported as the file's error
            text = str(ex).strip().splitlines()[0] if str(ex).strip() else ""
            result = (1, None, f"{type(ex).__name__}: {text}" if text else type(ex).__name__)
        yield item, result
