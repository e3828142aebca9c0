"""matplotlib helpers. Figures are saved with :func:`save` into ``figures_dir()``."""

from __future__ import annotations

import matplotlib as mpl
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


def _in_notebook() -> bool:
    try:
        from IPython import get_ipython
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and hasattr(shell, "kernel")


def save(fig, name: str, close: bool = True):
    """Save ``fig`` as ``figures_dir()/name`` (PNG unless the name says otherwise).

    In a notebook the figure is also shown inline: displayed here when it is closed, else by the
    inline backend at the end of the cell.
    """
    path = savefig(fig, figures_dir() / name)
    if close:
        if _in_notebook():
            from IPython.display import display

            display(fig)
        plt.close(fig)
    return path


def discrete_colorbar(fig, ax, colors, labels, title: str, **kwargs):
    """A colour bar for a categorical colouring: one block per colour, labelled.

    Parameters
    ----------
    colors : (k, 3 or 4) float in [0, 1]
    labels : k str
    title : str
        Colour bar label.
    """
    k = len(colors)
    cmap = mpl.colors.ListedColormap(np.asarray(colors, float)[:, :3])
    norm = mpl.colors.BoundaryNorm(np.arange(k + 1) - 0.5, k)
    bar = fig.colorbar(mpl.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, ticks=np.arange(k), **kwargs)
    bar.ax.set_yticklabels(labels) if bar.orientation == "vertical" else bar.ax.set_xticklabels(labels)
    bar.set_label(title)
    return bar


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


def sparse_3d_ticks(ax, nbins: int = 4):
    """At most ``nbins + 1`` round ticks per axis of a 3-D axis, none at the ends of x and y.

    matplotlib's default (up to 9 ticks) overlaps its labels on a panel a few inches wide, and a
    tick at an end of x shares the box's corner with the tick at an end of y.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.Axes3D
        Limits already set (e.g. by :func:`set_equal_3d`).
    nbins : int, >= 1
        Most tick intervals per axis (:class:`matplotlib.ticker.MaxNLocator`).
    """
    for axis, (lo, hi) in zip((ax.xaxis, ax.yaxis, ax.zaxis), (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())):
        ticks = mpl.ticker.MaxNLocator(nbins=nbins, steps=[1, 2, 5, 10]).tick_values(lo, hi)
        margin = 0.05 * (hi - lo) if axis is not ax.zaxis else -1e-9 * (hi - lo)  # z's ends meet no other labels
        axis.set_ticks(ticks[(ticks > lo + margin) & (ticks < hi - margin)])
