"""A process interrupted inside a meshcat scene does not leave the meshcat server running."""

import os
import signal

import pytest
from _children import (IN_MESHCAT_SCENE, alive, ctrl_c_as_from_a_terminal, end, gone_within, listening_ips,
                       server_left_after, start, wait_line)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_signal_inside_scene_ends_the_server(sig):
    proc = start(IN_MESHCAT_SCENE)
    server = None
    try:
        server = int(wait_line(proc, "server").split()[-1])
        assert alive(server)
        proc.send_signal(sig)
        code = proc.wait(timeout=60)
        assert gone_within(server, 10), "meshcat server left running"
        assert code == -sig  # once the server is down the process still ends by the signal
    finally:
        end(proc)
        if server is not None and alive(server):
            os.kill(server, signal.SIGKILL)  # the orphan this test found, not to leave it behind


def test_handler_is_restored_after_the_scene():
    from mavac.viz.meshcat_scene import sigterm_as_interrupt

    before = signal.getsignal(signal.SIGTERM)
    with sigterm_as_interrupt():
        assert signal.getsignal(signal.SIGTERM) is not before
    assert signal.getsignal(signal.SIGTERM) is before


def test_ctrl_c_while_the_server_starts_still_ends_it(monkeypatch):
    """A SIGINT that arrives while the server starts (before the block that shuts it down) must
    not leave the server running."""
    from mavac.viz import meshcat_scene as ms
    from mavac.viz import meshcat_server

    servers, real = [], meshcat_server.start_server

    def starting():
        proc, url = real()
        servers.append(proc)
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C just as the server is up
        return proc, url

    monkeypatch.setattr(meshcat_server, "start_server", starting)
    with ctrl_c_as_from_a_terminal(servers):
        with pytest.raises(KeyboardInterrupt):
            with ms.scene():
                pass
        assert servers and servers[0].poll() is not None


def test_the_server_dies_with_a_parent_killed_outright():
    """SIGKILL runs no cleanup: the kernel's parent-death signal ends the server."""
    assert not server_left_after(signal.SIGKILL), "meshcat server left running after its parent was killed"


def test_the_server_listens_on_loopback_only():
    from mavac.viz import meshcat_scene as ms

    with ms.scene() as vis:
        listening = listening_ips(vis)
    assert listening == {"127.0.0.1"}, listening
