"""meshcat scenes of machines, parts and robots, exported as self-contained static HTML.

``meshcat.Visualizer()`` starts a server subprocess in its own session (so no signal to our
process group reaches it); :func:`scene` always terminates it (``Visualizer.close`` is broken
in meshcat 0.3.2: its window has no ``close``), so no test or notebook leaves a server running:
on an error, on Ctrl-C (SIGINT) and on SIGTERM (what ``kill`` and ``timeout`` send).
"""

from __future__ import annotations

import contextlib
import signal
import subprocess
import threading

import numpy as np

from ..geometry.transforms import check_transform
from ..io import write_text


def _rgb_int(color) -> int:
    r, g, b = (int(round(255 * float(c))) for c in color[:3])
    return (r << 16) + (g << 8) + b


@contextlib.contextmanager
def sigterm_as_interrupt():
    """Inside the block SIGTERM raises ``KeyboardInterrupt``, as SIGINT does, so ``finally``
    clauses run (the default action of SIGTERM ends the process at once and runs none).

    On leaving the block the previous handler is restored and a SIGTERM that arrived is sent
    again to it, so the process still ends as it was asked to (with the default handler: by
    SIGTERM) once the cleanup is done. Only the main thread can handle signals: elsewhere, or
    when SIGTERM is ignored, the block runs unchanged.
    """
    previous = signal.getsignal(signal.SIGTERM)
    if threading.current_thread() is not threading.main_thread() or previous in (signal.SIG_IGN, None):
        yield
        return
    received = []

    def interrupt(signum, frame):
        received.append(signum)
        if len(received) == 1:  # a second SIGTERM must not interrupt the cleanup
            raise KeyboardInterrupt("SIGTERM")

    signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
        if received:
            signal.raise_signal(signal.SIGTERM)


@contextlib.contextmanager
def scene():
    """A fresh meshcat visualizer whose server is shut down on exit: on error, SIGINT and
    SIGTERM too (:func:`sigterm_as_interrupt`)."""
    import meshcat

    with sigterm_as_interrupt():
        vis = meshcat.Visualizer()
        try:
            yield vis
        finally:
            shutdown(vis)


def shutdown(vis) -> None:
    """Terminate the meshcat server subprocess of ``vis`` and close its socket."""
    window = vis.window
    proc = getattr(window, "server_proc", None)
    with contextlib.suppress(Exception):
        window.zmq_socket.close(linger=0)
    if proc is not None and proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=5)


def add_mesh(vis, name: str, mesh, color=(0.7, 0.7, 0.7), opacity: float = 1.0, world_T_mesh=None) -> None:
    """Add a trimesh mesh (metres) under ``name``."""
    import meshcat.geometry as g

    geom = g.TriangularMeshGeometry(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.uint32))
    material = g.MeshLambertMaterial(color=_rgb_int(color), opacity=opacity, transparent=opacity < 1.0)
    vis[name].set_object(geom, material)
    if world_T_mesh is not None:
        vis[name].set_transform(check_transform("world_T_mesh", world_T_mesh))


def add_points(vis, name: str, points, colors=None, size: float = 0.01) -> None:
    """Add a point cloud; ``colors`` is (3,) or (n, 3) in [0, 1]."""
    import meshcat.geometry as g

    pts = np.asarray(points, float).reshape(-1, 3)
    if colors is None:
        colors = (0.1, 0.4, 0.9)
    cols = np.broadcast_to(np.asarray(colors, float), pts.shape)
    vis[name].set_object(g.PointCloud(pts.T, cols.T, size=size))


def add_lines(vis, name: str, starts, ends, color=(0.9, 0.1, 0.1)) -> None:
    """Add line segments from ``starts`` (n, 3) to ``ends`` (n, 3)."""
    import meshcat.geometry as g

    s = np.asarray(starts, float).reshape(-1, 3)
    e = np.asarray(ends, float).reshape(-1, 3)
    seg = np.empty((2 * len(s), 3))
    seg[0::2], seg[1::2] = s, e
    vis[name].set_object(g.LineSegments(g.PointsGeometry(seg.T), g.LineBasicMaterial(color=_rgb_int(color))))


def add_triad(vis, name: str, world_T_frame, length: float = 0.1) -> None:
    """Add an RGB (x, y, z) axis triad at ``world_T_frame`` (4, 4)."""
    import meshcat.geometry as g

    vis[name].set_object(g.triad(length))
    vis[name].set_transform(check_transform("world_T_frame", world_T_frame))


def add_robot(vis, name: str, robot, q, world_T_base=None, geometry: str = "collision") -> None:
    """Add a :class:`mavac.robots.models.RobotModel` at configuration ``q`` (nq,).

    ``geometry="collision"`` (default) shows the collision model, which includes the mobile
    base box, vacuum tool and camera and keeps exported HTML small (about 2 MB for the UR10
    against 13 MB with the visual meshes); ``"visual"`` shows the visual meshes.
    """
    from pinocchio.visualize import MeshcatVisualizer

    if geometry not in ("collision", "visual"):
        raise ValueError(f"geometry must be 'collision' or 'visual', got {geometry!r}")
    shown = robot.collision_model if geometry == "collision" else robot.visual_model
    viz = MeshcatVisualizer(robot.model, shown, shown)
    viz.initViewer(viewer=vis)
    viz.loadViewerModel(rootNodeName=name)
    viz.display(np.asarray(q, float))
    if world_T_base is not None:
        vis[name].set_transform(check_transform("world_T_base", world_T_base))


def save_html(vis, path):
    """Write the scene as one self-contained HTML file (atomic write)."""
    return write_text(vis.static_html(), path)
