"""matplotlib helpers. Figures are saved with :func:`save` into ``figures_dir()``."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from ..config import figures_dir
from ..io import savefig


def new_figure(ncols: int = 1, nrows: int = 1, size=(5.0, 4.0), projection: str | None = None):
    """A figure and its axes (matplotlib picks Agg itself on a machine without a display)."""
    kw = {"subplot_kw": {"projection": projection}} if projection else {}
    fig, axes = plt.subplots(nrows, ncols, figsize=(size[0] * ncols, size[1] * nrows), squeeze=False, **kw)
    return fig, axes.ravel() if axes.size > 1 else axes[0, 0]


def save(fig, name: str, close: bool = True):
    """Save ``fig`` as ``figures_dir()/name`` (PNG unless the name says otherwise)."""
    path = savefig(fig, figures_dir() / name)
    if close:
        plt.close(fig)
    return path


def plot_mesh(ax, mesh, color=(0.75, 0.75, 0.8), alpha: float = 0.6, face_colors=None, max_faces: int = 60000,
              seed: int = 0):
    """Draw a trimesh mesh on a 3-D axis (subsampled above ``max_faces`` faces, seeded)."""
    faces = np.arange(len(mesh.faces))
    if len(faces) > max_faces:
        faces = np.sort(np.random.default_rng(seed).choice(faces, max_faces, replace=False))
    tris = mesh.vertices[mesh.faces[faces]]
    coll = Poly3DCollection(tris, linewidths=0.0, alpha=alpha)
    coll.set_facecolor(np.asarray(face_colors)[faces] if face_colors is not None else color)
    ax.add_collection3d(coll)
    lo, hi = mesh.bounds
    set_equal_3d(ax, lo, hi)
    return coll


def set_equal_3d(ax, lo, hi):
    """Equal aspect box for a 3-D axis from bounds ``lo`` and ``hi`` (3,)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c, r = (lo + hi) / 2, float(np.max(hi - lo)) / 2 or 1.0
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
