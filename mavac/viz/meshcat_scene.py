"""meshcat scenes of machines, parts and robots, exported as self-contained static HTML.

:func:`scene` starts meshcat's server in its own session (so no signal to our process group
reaches it), listening on 127.0.0.1 only and dying with our process (:mod:`.meshcat_server`),
and always terminates it (``Visualizer.close`` is broken in meshcat 0.3.2: its window has no
``close``), so no test or notebook leaves a server running: on an error, on Ctrl-C (SIGINT), on
SIGTERM (what ``kill`` and ``timeout`` send) and on SIGKILL. It swallows the server URL meshcat
prints (the server is gone once the file is written, so the URL would be a dead link).

The exported page opens on a camera that frames the scene (:func:`frame_camera`), can hide
layers until the reader ticks them in the controls (:func:`set_visible`), carries a legend of
the colours as a small HTML overlay (:func:`save_html` with ``legend=``) and can play an
animation of the robot (:func:`animate`, :func:`robot_node_transforms`).
"""

from __future__ import annotations

import contextlib
import html as _html
import io
import math
import signal
import subprocess
import threading

import numpy as np

from ..geometry.transforms import check_transform, check_transforms
from ..io import write_text
from ..validate import check_points

#: vertical field of view of meshcat's default perspective camera, degrees
CAMERA_FOV_DEG = 75.0


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


#: signals held while the server starts, acted on once the block that ends it is entered
_HELD_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


@contextlib.contextmanager
def _signals_held():
    """Inside the block SIGINT, SIGTERM and SIGHUP (those with a Python handler) are recorded,
    not acted on; yields ``release``, which restores the handlers and sends the recorded
    signals again (also run on leaving the block). Main thread only, where handlers run."""
    received, previous = [], {}
    if threading.current_thread() is threading.main_thread():
        for sig in _HELD_SIGNALS:
            if callable(signal.getsignal(sig)):
                previous[sig] = signal.signal(sig, lambda signum, frame: received.append(signum))

    def release():
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        previous.clear()
        while received:
            signal.raise_signal(received.pop(0))

    try:
        yield release
    finally:
        release()


@contextlib.contextmanager
def scene():
    """A fresh meshcat visualizer whose server is shut down on exit: on error, SIGINT and
    SIGTERM too (:func:`sigterm_as_interrupt`), also when they arrive while it starts.

    The server (:mod:`mavac.viz.meshcat_server`) listens on 127.0.0.1 only and dies with this
    process even when it is killed outright, which runs no ``finally``.
    """
    import meshcat

    from .meshcat_server import start_server

    with sigterm_as_interrupt(), _signals_held() as release:
        proc, zmq_url = start_server()
        try:
            with contextlib.redirect_stdout(io.StringIO()):  # the URL of a server that will not outlive us
                vis = meshcat.Visualizer(zmq_url=zmq_url)
        except BaseException:
            _stop(proc)
            raise
        vis.window.server_proc = proc  # what shutdown() ends
        try:
            release()  # a Ctrl-C that came while the server started acts here
            yield vis
        finally:
            shutdown(vis)


def shutdown(vis) -> None:
    """Terminate the meshcat server subprocess of ``vis`` and close its socket."""
    window = vis.window
    with contextlib.suppress(Exception):
        window.zmq_socket.close(linger=0)
    proc = getattr(window, "server_proc", None)
    if proc is not None:
        _stop(proc)


def _stop(proc: subprocess.Popen) -> None:
    """Terminate (then kill) a server process and release its pipe."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=5)
    if proc.stdout is not None:
        proc.stdout.close()


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


def add_spheres(vis, name: str, centres, colors, radius: float = 0.02) -> None:
    """Add one sphere node per centre, ``<name>/<i>`` (so each can be hidden or animated alone).

    Parameters
    ----------
    centres : (n, 3) float, m
    colors : (n, 3) float in [0, 1]
    radius : float, m
    """
    import meshcat.geometry as g

    T = np.eye(4)
    for i, (p, c) in enumerate(zip(np.asarray(centres, float).reshape(-1, 3), colors)):
        T[:3, 3] = p
        vis[f"{name}/{i}"].set_object(g.Sphere(float(radius)), g.MeshLambertMaterial(color=_rgb_int(c)))
        vis[f"{name}/{i}"].set_transform(T)


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
    viz = MeshcatVisualizer(robot.model, collision_model=None, visual_model=shown)  # each shape once
    viz.initViewer(viewer=vis)
    viz.loadViewerModel(rootNodeName=name)
    viz.display(np.asarray(q, float))
    if world_T_base is not None:
        vis[name].set_transform(check_transform("world_T_base", world_T_base))


def robot_node_transforms(robot, qs, geometry: str = "collision") -> dict:
    """Poses of the robot's shape nodes (as :func:`add_robot` names them) for each configuration.

    Parameters
    ----------
    robot : RobotModel
    qs : (k, nq) float, rad
    geometry : {"collision", "visual"}

    Returns
    -------
    dict
        ``"visuals/<shape name>" -> (k, 4, 4)`` float, in the robot's root frame (unscaled: the
        shapes keep the scale :func:`add_robot` gave them).
    """
    import pinocchio as pin

    shown = robot.collision_model if geometry == "collision" else robot.visual_model
    data, gdata = robot.model.createData(), shown.createData()
    qs = np.atleast_2d(np.asarray(qs, dtype=float))
    out = {f"visuals/{g.name}": np.zeros((len(qs), 4, 4)) for g in shown.geometryObjects}
    for i, q in enumerate(qs):
        pin.forwardKinematics(robot.model, data, q)
        pin.updateGeometryPlacements(robot.model, data, shown, gdata)
        for k, g in enumerate(shown.geometryObjects):
            out[f"visuals/{g.name}"][i] = gdata.oMg[k].homogeneous
    return out


def animate(vis, tracks: dict, times=None, fps: int = 30, repetitions: int = 1, play: bool = True,
            hide_at: dict | None = None) -> None:
    """Play node poses as a meshcat animation (kept in the static HTML, replayable in the controls).

    Parameters
    ----------
    tracks : dict
        Node path (relative to ``vis``) -> (k, 4, 4) float poses, one per key; all the same k.
    times : (k,) int, optional
        Frame number of each key (increasing); three.js interpolates between keys (linearly for
        positions, spherically for rotations). Default ``0, 1, ..., k - 1``.
    fps : int
        Frames per second.
    hide_at : dict, optional
        Node path -> frame (int >= 1) from which the node is hidden (visible before it).
    """
    from meshcat.animation import Animation

    if not tracks:
        return
    tracks = {path: check_transforms(f"tracks[{path!r}]", poses) for path, poses in tracks.items()}
    lengths = {len(v) for v in tracks.values()}
    if len(lengths) != 1:
        raise ValueError(f"every track must have the same number of keys, got {sorted(lengths)}")
    k = lengths.pop()
    times = np.arange(k) if times is None else np.asarray(times, dtype=np.int64)
    if times.shape != (k,) or np.any(np.diff(times) <= 0):
        raise ValueError(f"times must be {k} increasing frame numbers")
    anim = Animation(default_framerate=int(fps))
    for i, t in enumerate(times.tolist()):
        with anim.at_frame(vis, t) as frame:
            for path, poses in tracks.items():
                frame[path].set_transform(poses[i])
    for path, t in (hide_at or {}).items():
        if int(t) < 1:
            raise ValueError(f"hide_at[{path!r}] must be a frame >= 1, got {t}")
        for key, shown in ((0, True), (int(t), False)):
            with anim.at_frame(vis, key) as frame:
                frame[path].set_property("visible", "boolean", shown)
    vis.set_animation(anim, play=play, repetitions=int(repetitions))


def frame_camera(vis, lower, upper, direction=(1.0, -1.3, 0.8), margin: float = 0.9) -> None:
    """Aim the viewer's camera at the box ``[lower, upper]`` (metres) so it fills the view.

    The orbit target is the box centre; the camera looks from ``direction`` (world frame) at the
    distance where the box's bounding sphere fits meshcat's 75 deg field of view, times ``margin``.
    """
    lo, hi = check_points("lower", lower)[0], check_points("upper", upper)[0]
    d = check_points("direction", direction)[0]
    if np.linalg.norm(d) == 0:
        raise ValueError("direction must be a non-zero vector")
    d = d / np.linalg.norm(d)
    radius = max(float(np.linalg.norm(hi - lo)) / 2.0, 1e-3)
    offset = d * margin * radius / math.sin(math.radians(CAMERA_FOV_DEG / 2.0))
    target = np.eye(4)
    target[:3, 3] = (lo + hi) / 2.0
    vis["/Cameras/default"].set_transform(target)
    # the camera node sits in meshcat's y-up "rotated" frame (Rx(90 deg)): world (x, y, z) = (x, -z, y)
    vis["/Cameras/default/rotated/<object>"].set_property("position", [offset[0], offset[2], -offset[1]])


def set_visible(vis, name: str, visible: bool) -> None:
    """Show or hide a layer; the reader can still toggle it in the viewer's controls."""
    vis[name].set_property("visible", bool(visible))


def _css_rgb(color) -> str:
    r, g, b = (int(round(255 * float(c))) for c in color[:3])
    return f"rgb({r},{g},{b})"


def legend_html(entries, title: str = "", colorbar=None, notes=()) -> str:
    """A small fixed overlay: coloured swatches with labels, an optional colour bar, notes.

    Parameters
    ----------
    entries : list of (color (3,) in [0, 1], label)
    title : str
    colorbar : (cmap name, vmin, vmax, label), optional
        A horizontal gradient of a matplotlib colormap with its end values.
    notes : list of str
        Extra lines (e.g. which layers are hidden).
    """
    rows = [f'<div class="mavac-row"><span class="mavac-swatch" style="background:{_css_rgb(c)}"></span>'
            f"{_html.escape(label)}</div>" for c, label in entries]
    if colorbar is not None:
        import matplotlib

        cmap, vmin, vmax, label = colorbar
        stops = ", ".join(_css_rgb(matplotlib.colormaps[cmap](t)) for t in np.linspace(0, 1, 11))
        rows.append(f'<div class="mavac-cbar-label">{_html.escape(label)}</div>'
                    f'<div class="mavac-cbar" style="background:linear-gradient(to right, {stops})"></div>'
                    f'<div class="mavac-cbar-ends"><span>{vmin:g}</span><span>{vmax:g}</span></div>')
    rows += [f'<div class="mavac-note">{_html.escape(n)}</div>' for n in notes]
    head = f'<div class="mavac-title">{_html.escape(title)}</div>' if title else ""
    return ('<div id="mavac-legend">' + head + "".join(rows) + "</div>"
            "<style>#mavac-legend{position:fixed;left:10px;bottom:10px;max-width:360px;padding:8px 10px;"
            "background:rgba(255,255,255,0.88);border:1px solid #999;border-radius:4px;"
            "font:12px/1.35 sans-serif;color:#111;z-index:10;pointer-events:none}"
            ".mavac-title{font-weight:bold;margin-bottom:4px}.mavac-row{white-space:nowrap}"
            ".mavac-swatch{display:inline-block;width:11px;height:11px;margin-right:6px;border:1px solid #555;"
            "vertical-align:-1px}.mavac-cbar{height:10px;border:1px solid #555;margin-top:2px}"
            ".mavac-cbar-ends{display:flex;justify-content:space-between}.mavac-note{color:#444;margin-top:3px}"
            "</style>")


def save_html(vis, path, legend: str | None = None):
    """Write the scene as one self-contained HTML file (atomic write), with an optional overlay
    (``legend``, from :func:`legend_html`)."""
    page = vis.static_html()
    if legend:
        page = page.replace("</body>", legend + "\n</body>", 1)
    return write_text(page, path)
