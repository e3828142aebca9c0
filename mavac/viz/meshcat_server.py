"""meshcat's server, started so that it serves this machine only and dies with the process that
started it (``python -m mavac.viz.meshcat_server --parent PID``, run by :func:`start_server`).

meshcat's own start (``meshcat.Visualizer()``) runs ``meshcat.servers.zmqserver``: its ZeroMQ
socket listens on 127.0.0.1, but its tornado web server on every interface, and in a session of
its own, so a parent killed outright (SIGKILL, the OOM killer) leaves it running and answering
HTTP from other machines. Here the same server is started with two changes:

* the web server listens on 127.0.0.1 only;
* on Linux the kernel sends it SIGTERM when its parent dies (``prctl(PR_SET_PDEATHSIG)``), and it
  exits at once if the parent is already gone when it starts.

:func:`mavac.viz.meshcat_scene.scene` still terminates it on leaving the block; this covers the
deaths that run no ``finally``.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import signal
import subprocess
import sys

#: the only address the server's sockets are bound to
LOOPBACK = "127.0.0.1"
#: Linux ``prctl`` option: the signal the kernel sends a process when its parent thread dies
PR_SET_PDEATHSIG = 1


def _die_with_parent(parent: int) -> None:
    """SIGTERM when ``parent`` dies (Linux); exit now if it already has."""
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    if os.getppid() != parent:  # died before the prctl took hold: we were re-parented
        sys.exit(0)


def _listen_on_loopback() -> None:
    """Bind every tornado web server of this process to 127.0.0.1 (meshcat passes no address)."""
    import tornado.web

    listen = tornado.web.Application.listen

    def loopback_listen(self, port, address=LOOPBACK, **kwargs):
        return listen(self, port, address=LOOPBACK, **kwargs)

    tornado.web.Application.listen = loopback_listen


def main(argv=None) -> None:
    """Serve meshcat on 127.0.0.1 until SIGTERM, SIGINT or the parent's death; prints
    ``zmq_url=...`` and ``web_url=...`` as meshcat's server does."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parent", type=int, required=True, help="pid of the process the server dies with")
    args = parser.parse_args(argv)
    _die_with_parent(args.parent)
    _listen_on_loopback()
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    bridge = ZMQWebSocketBridge(host=LOOPBACK)
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass


def start_server() -> tuple[subprocess.Popen, str]:
    """Start the server for this process; returns ``(process, zmq_url)``.

    The server runs in its own session (a Ctrl-C to our process group does not reach it; the
    caller terminates it) and dies with the calling thread's process
    (:data:`PR_SET_PDEATHSIG` follows the thread that started it: start it from the thread
    that will use it).

    Raises
    ------
    RuntimeError
        The server exited before giving its address.
    """
    proc = subprocess.Popen([sys.executable, "-u", "-m", "mavac.viz.meshcat_server", "--parent", str(os.getpid())],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, start_new_session=True)
    try:
        for line in proc.stdout:
            if line.startswith("zmq_url="):
                return proc, line.strip().split("=", 1)[1]
        raise RuntimeError(f"the meshcat server exited before giving its address (exit code {proc.wait()})")
    except BaseException:
        proc.kill()
        proc.wait()
        raise


if __name__ == "__main__":  # pragma: no cover
    main()
