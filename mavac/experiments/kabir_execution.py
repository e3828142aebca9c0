"""Notebook 09: Kabir et al.'s execution stage -- tool paths (Sec. VI, Fig. 3), stain
perception (Sec. VII, Figs. 4-5) and ICP registration (Sec. VII), on our simulated parts.

Each function returns plain data (DataFrames, arrays, dataclasses) or draws on matplotlib
axes it is given; the notebook only calls them, saves the figures and writes the CSVs.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pandas as pd

from ..params import ICPParams, LissajousParams, ScrubModel, SetupSpaceParams, ToolpathParams
from ..scrubbing.toolpath import ToolPath, reachable_from_robot, toolpath_for_setup


# ---------------------------------------------------------------- setups and tool paths


def setup_toolpaths(part, setups, patches, robot, params: ToolpathParams = ToolpathParams(),
                    space: SetupSpaceParams = SetupSpaceParams()) -> list[ToolPath]:
    """Tool path of every setup of a plan.

    Parameters
    ----------
    part : Part
    setups : (k, 3) float
        ``(x, y, alpha)`` in execution order (e.g. ``SetupPlan.setups``).
    patches : list of (k_j,) int
        Patches each setup cleans (e.g. ``SetupPlan.patches``).
    robot : RobotModel
        IK of every waypoint (world = robot base frame).
    params : ToolpathParams
    space : SetupSpaceParams
        Pose of the part for a setup (:func:`mavac.setups.reach.base_T_part`).
    """
    from ..setups.reach import base_T_part

    poses = base_T_part(np.asarray(setups, dtype=float).reshape(-1, 3), space)
    reachable = reachable_from_robot(robot)
    return [toolpath_for_setup(part, T, np.asarray(p, dtype=np.int64), params, reachable=reachable)
            for T, p in zip(poses, patches)]


def toolpath_table(part_name: str, toolpaths: list[ToolPath]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Per-setup and per-pass summaries of tool paths.

    Returns
    -------
    setups : DataFrame
        ``part, setup, passes, path_length_m, t_contact_s, t_reposition_s, repositionings``
        (setup numbered from 1 in execution order).
    passes : DataFrame
        ``part, setup, pass, patches, path_length_m, reposition_length_m, repositionings,
        coverage``.
    """
    rows, per_pass = [], []
    for j, tp in enumerate(toolpaths, start=1):
        rows.append(dict(part=part_name, setup=j, passes=len(tp.passes), path_length_m=tp.path_length_m,
                         t_contact_s=tp.t_contact_s, t_reposition_s=tp.t_reposition_s,
                         repositionings=tp.repositionings))
        for p in tp.passes:
            per_pass.append(dict(part=part_name, setup=j, **{"pass": p.pass_number},
                                 patches=len(p.patch_ids), path_length_m=p.path_length_m,
                                 reposition_length_m=p.reposition_length_m,
                                 repositionings=len(p.repositions), coverage=p.coverage))
    return pd.DataFrame(rows), pd.DataFrame(per_pass)


def execution_time_models(part, patches, toolpaths: list[ToolPath]) -> pd.DataFrame:
    """t^e of each setup from its tool path against the planner's simple area model
    (:func:`mavac.planning.setcover.execution_time_area_passes`) at the same sweep rate,
    tool width x tool speed.

    Returns
    -------
    DataFrame
        ``setup, t_e_toolpath_s, t_contact_s, t_reposition_s, t_e_area_model_s, ratio``.
    """
    from ..planning.setcover import execution_time_area_passes

    params = toolpaths[0].params
    cover = np.zeros((len(patches), len(part.stain_faces)), dtype=bool)
    for j, p in enumerate(patches):
        cover[j, np.asarray(p, dtype=np.int64)] = True
    area = execution_time_area_passes(cover, part.patch_areas, part.passes,
                                      params.tool_width_m * params.tool_speed_m_s)
    te = np.array([tp.t_execution_s for tp in toolpaths])
    return pd.DataFrame(dict(setup=np.arange(1, len(te) + 1), t_e_toolpath_s=te,
                             t_contact_s=[tp.t_contact_s for tp in toolpaths],
                             t_reposition_s=[tp.t_reposition_s for tp in toolpaths],
                             t_e_area_model_s=area, ratio=te / area))


def longest_segment(toolpath: ToolPath, pass_number: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The longest contact segment of a pass and its normals (for the Fig. 3 overlay)."""
    p = toolpath.passes[pass_number - 1]
    i = int(np.argmax([len(s) for s in p.segments]))
    return p.segments[i], p.normals[i]


def plot_toolpath(ax, part, toolpath: ToolPath, title: str = ""):
    """Part surface, contact segments (one colour per pass) and repositioning moves on a 3-D axis."""
    from ..viz.plots import plot_mesh

    mesh = part.mesh.copy()
    mesh.apply_transform(toolpath.world_T_part)
    colours = np.full((len(mesh.faces), 4), (0.8, 0.8, 0.82, 1.0))
    colours[part.stain_faces] = (0.85, 0.35, 0.3, 1.0)
    plot_mesh(ax, mesh, face_colors=colours, alpha=0.35, max_faces=8000)
    cmap = {1: "tab:blue", 2: "tab:green", 3: "tab:purple"}
    for p in toolpath.passes:
        lift = 0.002 * p.pass_number  # draw later passes slightly above the earlier ones
        for k, (s, n) in enumerate(zip(p.segments, p.normals)):
            q = s + lift * n
            ax.plot(q[:, 0], q[:, 1], q[:, 2], color=cmap.get(p.pass_number, "k"), lw=0.9,
                    label=f"pass {p.pass_number}" if k == 0 else None)
        for k, r in enumerate(p.repositions):
            ax.plot(r[:, 0], r[:, 1], r[:, 2], color="tab:orange", lw=0.7, ls="--",
                    label="repositioning" if (k == 0 and p.pass_number == 1) else None)
    ax.set_title(title)
    ax.legend(loc="upper left", fontsize=7)


def plot_overlay(ax, segment: np.ndarray, overlay, speed: float, length: float = 0.06):
    """Fig. 3(b): the first ``length`` metres of a nominal path and its Lissajous overlay
    (sampled at ``speed`` m/s), projected on the plane of the path's two main directions, mm."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(segment, axis=0), axis=1))])
    # both curves end at the same arc length (a nominal cut at its last waypoint would look short)
    s_end = min(length, s[-1])
    s_cut = np.append(s[s < s_end], s_end)
    nominal = np.stack([np.interp(s_cut, s, segment[:, k]) for k in range(3)], axis=1)
    over = overlay.positions[overlay.t <= s_end / speed]
    centre = nominal.mean(axis=0)
    _, _, vt = np.linalg.svd(over - centre, full_matrices=False)
    for pts, style in ((over, dict(color="tab:red", lw=0.8)), (nominal, dict(color="k", lw=1.5))):
        uv = (pts - centre) @ vt[:2].T * 1000.0
        ax.plot(uv[:, 0], uv[:, 1], **style)
    ax.set_aspect("equal")
    ax.set_xlabel("along path [mm]")
    ax.set_ylabel("across path [mm]")
    ax.set_title("Lissajous overlay (red) on the nominal spline (black)", fontsize=9)


# ---------------------------------------------------------------- stain perception



class StainPerception(NamedTuple):
    """Figs. 4-5 on a simulated part (images are (H, W, 3) uint8, masks (H, W) bool)."""

    before: np.ndarray
    after: np.ndarray
    mask_before: np.ndarray
    mask_after: np.ndarray
    region: np.ndarray
    cleaning_performance: float
    passes_estimated: np.ndarray
    passes_true: np.ndarray
    passes_agreement: float


def stain_perception(part, rng: np.random.Generator, params: LissajousParams = LissajousParams(),
                     image_size=(128, 128), n_clusters: int = 4, noise_std: float = 0.02,
                     model: ScrubModel = ScrubModel()) -> StainPerception:
    """One SIMULATED scrubbing pass seen by the camera, segmented like Kabir Sec. VII.

    The stain (per-face intensity, as thickness in layers) is rendered before and after
    :func:`mavac.sim.wear.scrub_faces`; one 2-cluster K-means gives both binary masks and
    ``C_p`` over the stained region; ``N_c``-colour quantisation of the before image (3x3
    median filtered against pixel noise, as the binary masks are) gives the passes per pixel
    (Fig. 5), compared with the part's own passes (pixels of stained faces; the clean part
    is 0 passes).
    """
    import cv2

    from ..sim.wear import scrub_faces, stain_opacity
    from ..vision.stain import (cleaning_performance, face_index_image, passes_from_image,
                                render_stain_image, stain_masks_kmeans, view_of_faces)

    mesh = part.mesh
    stain = np.zeros(len(mesh.faces))
    stain[part.stain_faces] = part.intensity
    view = view_of_faces(mesh, part.stain_faces)
    fi = face_index_image(mesh, view, image_size)
    on_part = fi >= 0
    after = scrub_faces(stain, params, rng=rng, model=model)
    images = [render_stain_image(mesh, stain_opacity(s, model), view, image_size, noise_std=noise_std,
                                 rng=rng, face_index=fi) for s in (stain, after)]
    seed = int(rng.integers(2**31 - 1))
    m_before, m_after = stain_masks_kmeans(images, seed, region_mask=on_part)
    face_passes = np.zeros(len(mesh.faces), dtype=int)
    face_passes[part.stain_faces] = part.passes
    true = np.where(on_part, face_passes[np.where(on_part, fi, 0)], -1)
    region = on_part & (true > 0)
    est = passes_from_image(cv2.medianBlur(images[0], 3), n_clusters=n_clusters, seed=seed, region_mask=on_part)
    agreement = float(np.mean(est[on_part] == true[on_part]))
    return StainPerception(images[0], images[1], m_before, m_after, region,
                           cleaning_performance(m_before, m_after, region), est, true, agreement)


def passes_confusion(sp: StainPerception) -> pd.DataFrame:
    """Fraction of the part's pixels needing ``true`` passes that Fig. 5's quantisation assigns
    ``estimated`` passes (rows sum to 1)."""
    on = sp.passes_true >= 0
    return pd.crosstab(pd.Series(sp.passes_true[on], name="true"),
                       pd.Series(sp.passes_estimated[on], name="estimated"), normalize="index")


def plot_fig4(axes, sp: StainPerception):
    """Kabir Fig. 4 layout, clockwise from top-left: before, after, after (binary), before (binary).
    ``axes`` is a flat sequence of 4 axes in row order. Stain pixels are black in the binary images."""
    panels = [(sp.before, "before cleaning"), (sp.after, "after cleaning"),
              (~sp.mask_before, "before (binary)"), (~sp.mask_after, "after (binary)")]
    for ax, (img, title) in zip(axes, panels):
        ax.imshow(img, cmap="gray" if img.ndim == 2 else None, vmin=0, vmax=1 if img.ndim == 2 else None)
        ax.set_title(title, fontsize=9)
        ax.axis("off")


def plot_fig5(axes, sp: StainPerception):
    """Kabir Fig. 5: the stain image, its N_c-colour quantisation into passes, and our true passes."""
    import matplotlib.pyplot as plt

    cmap = plt.get_cmap("viridis", int(max(sp.passes_estimated.max(), sp.passes_true.max())) + 2)
    for ax, (img, title) in zip(axes, [(sp.before, "stain image"),
                                       (sp.passes_estimated, "passes from N_c colours"),
                                       (sp.passes_true, "true passes (simulated)")]):
        if img.ndim == 2:
            ax.imshow(np.ma.masked_less(img, 0), cmap=cmap, vmin=-0.5, vmax=cmap.N - 0.5)
        else:
            ax.imshow(img)
        ax.set_title(title, fontsize=9)
        ax.axis("off")


# ---------------------------------------------------------------- ICP


def icp_tables(mesh, n_poses: int, noise_levels, init_perturbations, seed: int = 0,
               params: ICPParams = ICPParams(), n_points: int = 2000) -> tuple[pd.DataFrame, pd.DataFrame]:
    """:func:`mavac.vision.icp.icp_error_study` and its per-condition summary (basin of convergence)."""
    from ..vision.icp import icp_error_study, icp_summary

    study = icp_error_study(mesh, n_poses, noise_levels, init_perturbations, np.random.default_rng(seed),
                            params, n_points=n_points)
    return study, icp_summary(study)


def plot_icp_basin(ax, summary: pd.DataFrame):
    """Success rate against the initial rotation error, one line per noise level."""
    for noise, g in summary.groupby("noise_std_m"):
        ax.plot(np.degrees(g["init_angle_rad"]), g["success_rate"], marker="o", label=f"noise {noise * 1000:.1f} mm")
    ax.set_xlabel("initial rotation error [deg] (offset grows with it)")
    ax.set_ylabel("success rate")
    ax.set_ylim(-0.05, 1.05)
    ax.legend(fontsize=7)


# ---------------------------------------------------------------- paper vs ours


def paper_vs_ours(part_name: str, setup_table: pd.DataFrame, lissajous: LissajousParams = LissajousParams()
                  ) -> pd.DataFrame:
    """Kabir's numbers for this stage next to ours (``data/paper_values.csv``).

    Rows: setups in the solution (Table VII), passes of setup 1 and of the other setups
    (Sec. IX-C), and the Fig. 3 overlay parameters we use.
    """
    from ..paper import paper_scalar

    passes = setup_table["passes"].to_numpy(dtype=float)
    rows = [
        ("Table VII", "solution_size", f"part={part_name}", float(len(setup_table))),
        ("Sec. IX-C", "passes", f"part={part_name};setup=1", passes[0] if len(passes) else np.nan),
        ("Sec. IX-C", "passes", f"part={part_name};setup=other", passes[1:].max() if len(passes) > 1 else np.nan),
        ("Fig. 3", "f_x", "", lissajous.f_x),
        ("Fig. 3", "kappa", "", lissajous.kappa_x),
        ("Fig. 3", "A_x", "", lissajous.A_x),
        ("Fig. 3", "v", "", lissajous.v),
        ("Fig. 3", "f_n", "", lissajous.f_n),
        ("Sec. VIII", "f_y_over_f_x", "", lissajous.f_y_ratio),
        ("Sec. VIII", "A_y_over_A_x", "", lissajous.A_y / lissajous.A_x),
        ("Sec. VIII", "phase", "", lissajous.phase),
    ]
    return pd.DataFrame([dict(ref=ref, quantity=q, condition=c, paper=paper_scalar("kabir", ref, q, c), ours=o)
                         for ref, q, c, o in rows])
