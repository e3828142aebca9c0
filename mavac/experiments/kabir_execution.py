"""Notebook 09: tables and figures of Kabir et al.'s execution stage -- tool paths (Sec. VI,
Fig. 3), stain perception (Sec. VII, Figs. 4-5) and ICP registration (Sec. VII).

The pipeline itself is in the library (:mod:`mavac.scrubbing.execution`, :mod:`mavac.vision.icp`);
each function here turns its results into a DataFrame or draws them on matplotlib axes it is
given, so the notebook only calls, saves and shows.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from ..paper import paper_scalar
from ..params import ICPParams, LissajousParams
from ..planning.setcover import execution_time_area_passes
from ..scrubbing.execution import StainPerception, cover_from_patches
from ..scrubbing.toolpath import ToolPath
from ..vision.icp import icp_error_study, icp_summary
from ..viz.plots import plot_mesh


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
    params = toolpaths[0].params
    cover = cover_from_patches(patches, len(part.stain_faces))
    area = execution_time_area_passes(cover, part.patch_areas, part.passes,
                                      params.tool_width_m * params.tool_speed_m_s)
    te = np.array([tp.t_execution_s for tp in toolpaths])
    return pd.DataFrame(dict(setup=np.arange(1, len(te) + 1), t_e_toolpath_s=te,
                             t_contact_s=[tp.t_contact_s for tp in toolpaths],
                             t_reposition_s=[tp.t_reposition_s for tp in toolpaths],
                             t_e_area_model_s=area, ratio=te / area))


def plot_toolpath(ax, part, toolpath: ToolPath, title: str = ""):
    """Part surface, contact segments (one colour per pass) and repositioning moves on a 3-D axis."""
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


def icp_tables(mesh, n_poses: int, noise_levels, init_perturbations, *, seed: int = 0,
               params: ICPParams = ICPParams(), n_points: int = 2000) -> tuple[pd.DataFrame, pd.DataFrame]:
    """:func:`mavac.vision.icp.icp_error_study` and its per-condition summary (basin of convergence)."""
    study = icp_error_study(mesh, n_poses, noise_levels, init_perturbations, np.random.default_rng(seed),
                            params=params, n_points=n_points)
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
