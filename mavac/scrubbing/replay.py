"""Meshcat replay of a SIMULATED two-arm cell run (:class:`mavac.scrubbing.run.PartRun`): both
arms, the part, its tool paths and its stain, which fades as the passes remove it.

The stain is drawn in :data:`STAIN_LEVELS` shells, one per thickness level, each a little
further out along the vertex normals than the last (no z-fighting): a face shows the colour of
the highest level its stain is still above. The stain only thins (a pass removes, nothing
adds), so every face of a shell needs one moment, the end of the pass that took it below the
level, at which it disappears; faces that disappear together are one node of the animation.
"""

from __future__ import annotations

import numpy as np
import trimesh

from ..params import BimanualCellParams, ToolpathParams
from .cell import cell_robots, flange_T_part

#: Stain thickness levels (layers; 1 = a full stain) of the shells, with their colours: the page
#: shows the stain above 2 %, a third and two thirds (ours: three shades read at a glance).
STAIN_LEVELS = ((0.02, (0.80, 0.66, 0.45)), (1 / 3, (0.62, 0.42, 0.22)), (2 / 3, (0.42, 0.25, 0.10)))
#: Offset of each shell along the vertex normals, metres per level (ours: above depth-buffer noise
#: at the page's framing, below what the eye reads as a gap).
SHELL_STEP = 4e-4
#: The page opens on the part's positions plus this many bounding radii of the part around them
#: (ours: the part fills about a third of the view, the pad's approach and the wrists show).
FRAME_RADII = 2.0
FPS = 30
PATH_COLOR = (0.9, 0.1, 0.1)
PART_COLOR = (0.85, 0.85, 0.8)


def _keys(run, max_keys: int):
    """Replay keys: sample indices kept, their frames (increasing, FPS) and each track's end frame."""
    lengths = np.array([len(c) for c, _, _ in run.execution.tracks])
    t = np.cumsum(np.concatenate([np.full(n, dt) for n, (_, _, dt) in zip(lengths, run.execution.tracks)]))
    keep = np.unique(np.linspace(0, len(t) - 1, min(max_keys, len(t))).astype(int))
    frames = np.maximum.accumulate(np.round(t[keep] * FPS).astype(int))
    frames = frames + np.arange(len(frames))  # strictly increasing
    # the frame of the first kept sample at or after each track's last sample
    last = np.cumsum(lengths) - 1
    ends = frames[np.minimum(np.searchsorted(keep, last), len(keep) - 1)]
    return keep, frames, ends


#: most keyframes of a replay (ours: three.js interpolates between them; with two arms and a
#: 20k-face part, 400 keys took a page past 5 MB, 200 keep it near 4 MB)
MAX_KEYS = 200


def replay_tracks(run, holder, cell: BimanualCellParams, *, max_keys: int = MAX_KEYS):
    """Keyframes of the whole run, at most ``max_keys`` evenly spaced samples: ``(times (k,) int
    frames at 30 fps, q_cleaner (k, 7), q_holder (k, 7), world_T_part (k, 4, 4), track_ends)``,
    ``track_ends`` the frame at which each of ``run.execution.tracks`` ends."""
    import pinocchio as pin

    keep, frames, ends = _keys(run, max_keys)
    qc = np.concatenate([c for c, _, _ in run.execution.tracks])[keep]
    qh = np.concatenate([h for _, h, _ in run.execution.tracks])[keep]
    model, data = holder.model, holder.model.createData()
    fid = model.getFrameId("flange")
    parts = []
    for q in qh:
        pin.framesForwardKinematics(model, data, q)
        parts.append(cell.world_T_holder @ data.oMf[fid].homogeneous @ flange_T_part(cell))
    return frames, qc, qh, np.array(parts), ends


def stain_shells(mesh: trimesh.Trimesh, initial, states, end_frames) -> list[tuple[int, trimesh.Trimesh, tuple, int]]:
    """The stain's shells, split by when they vanish.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Part frame, metres.
    initial : (F,) float
        Stain thickness per face before cleaning, layers.
    states : list of (F,) float
        Thickness after each pass (non-increasing).
    end_frames : (len(states),) int
        Frame at which each pass ends.

    Returns
    -------
    list of ``(level index, shell mesh, colour, vanish frame or 0 for never)``.
    """
    history = np.vstack([initial, *states]) if len(states) else np.asarray(initial)[None]
    out = []
    for i, (level, color) in enumerate(STAIN_LEVELS):
        above = history > level
        faces = np.flatnonzero(above[0])
        # index of the first state at or below the level (len(history): never)
        gone = np.where(above[:, faces].all(axis=0), len(history), np.argmin(above[:, faces], axis=0))
        for g in np.unique(gone):
            pick = faces[gone == g]
            frame = 0 if g == len(history) else max(int(end_frames[g - 1]), 1)
            out.append((i, _shell(mesh, pick, SHELL_STEP * (i + 1)), color, frame))
    return out


def _shell(mesh: trimesh.Trimesh, faces, offset: float) -> trimesh.Trimesh:
    """The faces, their shared vertices moved ``offset`` m along the vertex normals (one copy of
    each vertex keeps the page small)."""
    shell = mesh.submesh([faces], append=True)
    return trimesh.Trimesh(shell.vertices + offset * shell.vertex_normals, shell.faces, process=False)


def replay_html(run, path, *, cell: BimanualCellParams = BimanualCellParams(),
                toolpath: ToolpathParams = ToolpathParams()):
    """One meshcat HTML replaying the cell: both arms, the part and its tool paths, animated,
    and the stain fading pass by pass (:func:`stain_shells`).

    The meshcat server is shut down on exit (also on error or interrupt).
    """
    from ..viz import meshcat_scene as ms
    from ..viz.scenes import robot_tracks

    cleaner, holder = cell_robots(cell, toolpath)
    frames, qc, qh, parts, ends = replay_tracks(run, holder, cell)
    states = run.execution.stain_states
    shells = stain_shells(run.state.mesh, run.state.initial, [s for _, s in states],
                          [ends[i - 1] for i, _ in states])
    with ms.scene() as vis:
        ms.add_robot(vis, "cleaner", cleaner, qc[0], world_T_base=cell.world_T_cleaner)
        ms.add_robot(vis, "holder", holder, qh[0], world_T_base=cell.world_T_holder)
        ms.add_mesh(vis, "part", run.state.mesh, color=PART_COLOR, world_T_mesh=parts[0])
        hide = {}
        for j, (level, shell, color, frame) in enumerate(shells):
            ms.add_mesh(vis, f"part/stain/{level}_{j}", shell, color=color)
            if frame:
                hide[f"part/stain/{level}_{j}"] = frame
        for i, (_, pts) in enumerate(run.execution.paths):
            ms.add_lines(vis, f"paths/{i}", pts[:-1], pts[1:], color=PATH_COLOR)
        tracks = {**robot_tracks(cleaner, "cleaner", np.repeat(cell.world_T_cleaner[None], len(qc), 0), qc),
                  **robot_tracks(holder, "holder", np.repeat(cell.world_T_holder[None], len(qh), 0), qh),
                  "part": parts}
        ms.animate(vis, tracks, times=frames, fps=FPS, hide_at=hide)
        centres = parts[:, :3, 3]
        margin = FRAME_RADII * float(np.linalg.norm(run.state.mesh.extents)) / 2.0
        ms.frame_camera(vis, centres.min(axis=0) - margin, centres.max(axis=0) + margin)
        entries = [(PATH_COLOR, "tool path (contact)")]
        entries += [(c, f"stain above {lv:.2g} of a full layer") for lv, c in reversed(STAIN_LEVELS)]
        legend = ms.legend_html(entries, title=f"{run.name}: SIMULATED two-arm cell, {run.status}, "
                                               f"{100 * run.stain_removed:.1f} % of the stain removed",
                                notes=["the stain fades as each pass removes it; replay under Animations"])
        return ms.save_html(vis, path, legend=legend)
