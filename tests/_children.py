"""Child processes that tests signal or kill in the middle of their work (shared by the tests
of mavac.io, the meshcat scene and the bad-input matrix)."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import threading
import time

# Writes half a CSV through mavac.io.write_csv (target: argv[1]), says "writing", sleeps.
HALF_WRITTEN_CSV = """
import sys, time
from mavac.io import write_csv

class HalfWritten:
    def to_csv(self, path, **kwargs):
        with open(path, "w") as f:
            f.write("a,b\\n1,")
            f.flush()
            print("writing", flush=True)
            time.sleep(120)

write_csv(HalfWritten(), sys.argv[1])
"""

# Opens a meshcat scene, prints "server <pid>", then waits in short sleeps (a signal that
# another thread takes is acted on at once). SIGINT raises KeyboardInterrupt even when the
# child inherits it ignored, as background jobs do.
IN_MESHCAT_SCENE = """
import signal, time
from mavac.viz.meshcat_scene import scene

signal.signal(signal.SIGINT, signal.default_int_handler)
with scene() as vis:
    print("server", vis.window.server_proc.pid, flush=True)
    for _ in range(1200):
        time.sleep(0.1)
"""


def start(code: str, *args) -> subprocess.Popen:
    """``python -c code args`` with its stdout readable as text."""
    return subprocess.Popen([sys.executable, "-c", code, *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)


def wait_line(proc: subprocess.Popen, prefix: str) -> str:
    """The first line of the child's stdout that starts with ``prefix``."""
    line = ""
    while not line.startswith(prefix):
        line = proc.stdout.readline()
        if not line:
            raise RuntimeError(f"child ended before printing {prefix!r}")
    return line


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def gone_within(pid: int, seconds: float) -> bool:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if not alive(pid):
            return True
        time.sleep(0.1)
    return False


def end(proc: subprocess.Popen) -> None:
    """Kill the child if it still runs and release its pipe."""
    if proc.poll() is None:
        proc.kill()
    proc.wait(timeout=30)
    proc.stdout.close()


def server_left_after(sig: int, code: str = IN_MESHCAT_SCENE) -> bool:
    """Send ``sig`` to a child inside a meshcat scene (``code``, which prints ``server <pid>``);
    whether its meshcat server is still running 10 s after the child ended. An orphan found is
    killed, not left behind."""
    proc = start(code)
    server = None
    try:
        server = int(wait_line(proc, "server").split()[-1])
        proc.send_signal(sig)
        proc.wait(timeout=60)
        return not gone_within(server, 10)
    finally:
        end(proc)
        if server is not None and alive(server):
            os.kill(server, 9)


def listening_ips(vis) -> set:
    """The addresses the meshcat server of ``vis`` listens on (ZeroMQ and the web server)."""
    import psutil

    proc = psutil.Process(vis.window.server_proc.pid)
    return {c.laddr.ip for c in proc.net_connections(kind="inet") if c.status == psutil.CONN_LISTEN}


def print_counts(counts: dict, outcomes, *, total: bool = False) -> None:
    """An audit's table: one row per class of ``counts`` (``{class: {outcome: n}}``), one column
    per outcome, the row's total, and with ``total`` a last row summing the classes."""
    width = max(map(len, outcomes)) + 2
    rows = dict(counts)
    if total:
        rows["all"] = {o: sum(row[o] for row in counts.values()) for o in outcomes}
    print(f"\n{'class':12s}" + "".join(f"{o:>{width}s}" for o in outcomes) + f"{'total':>8s}")
    for klass, row in rows.items():
        print(f"{klass:12s}" + "".join(f"{row[o]:{width}d}" for o in outcomes) + f"{sum(row.values()):8d}")


@contextlib.contextmanager
def ctrl_c_as_from_a_terminal(servers: list):
    """SIGINT raises KeyboardInterrupt in the block, as a terminal delivers it, even when the tests
    run as a background job (SIGINT ignored); another thread is alive, which a process-wide signal
    may be handed to. On leaving, the handler is restored and any process of ``servers`` (the
    block fills it) still running is killed, not left behind."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    idle = threading.Event()
    threading.Thread(target=idle.wait, daemon=True).start()
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        idle.set()
        for proc in servers:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
