"""Self-contained HTML view of a Kabir setup plan: the Puma 560, the table, the part moved through
its setups in order, and the arm touching a patch of each (built on :mod:`mavac.viz.scenes`)."""

from __future__ import annotations

import math

import numpy as np
import trimesh

from ..geometry.transforms import check_transforms
from ..params import SetupPlanParams
from ..robots.kinematics import ik_axis
from ..robots.models import puma560
from ..viz import meshcat_scene as ms
from ..viz.scenes import (
    ARM_FRAMES,
    FPS,
    GREY,
    HOLD_FRAMES,
    RED,
    WOOD,
    Keys,
    add_colored_mesh,
    robot_tracks,
    setup_colors,
)
from .reach import base_T_part

#: the table is nearly opaque (at 0.35 its brown read grey-violet) yet shows the Puma's pedestal
#: when a large part's table reaches round it
TABLE_OPACITY = 0.8


def _setup_arm(robot, part, patches, base_T_part) -> np.ndarray:
    """An arm configuration touching one patch of a setup: the first corner of the patch nearest
    the middle of that setup's patches (every corner of a cleaned patch has an IK solution)."""
    if len(patches) == 0:
        return robot.q_home
    corners = part.patch_vertices[patches]
    mid = corners.mean(axis=(0, 1))
    i = int(np.argmin(np.linalg.norm(corners.mean(axis=1) - mid, axis=1)))
    p = base_T_part[:3, :3] @ corners[i, 0] + base_T_part[:3, 3]
    a = -(base_T_part[:3, :3] @ part.patch_normals[patches[i]])
    res = ik_axis(robot, p[None], a[None], q0=robot.q_home)
    return res.q[0] if bool(res.success[0]) else robot.q_home


def setup_motion(robot, part, plan, base_T_parts):
    """Animation keys of a setup plan: per setup, the part is placed (arm at home), then the arm
    touches one of the setup's patches (:func:`_setup_arm`). Returns ``times (f,)``,
    ``setups (f, 3)`` and ``qs (f, nq)`` as :func:`pose_set_motion`."""
    base_T_parts = check_transforms("base_T_parts", base_T_parts)
    keys = Keys(plan.setups[0], robot.q_home)
    for j, setup in enumerate(plan.setups):
        if j:
            keys.arm_to(robot.q_home)
            keys.add(setup, robot.q_home, 2 * ARM_FRAMES)  # the part is re-placed on the table
        keys.arm_to(_setup_arm(robot, part, plan.patches[j], base_T_parts[j]))
        keys.hold(2 * HOLD_FRAMES)
    return keys.arrays()


def setup_plan_html(plan, part, path, robot=None, params=None):
    """Meshcat page of a :class:`~mavac.setups.setup_plan.SetupPlan`: the Puma 560, the table, the part
    moved through its setups in order, the arm touching a patch of each; stain patches coloured by
    the setup that cleans them (unreachable ones red)."""
    params = SetupPlanParams() if params is None else params
    robot = puma560(tool_length=params.reach.tool_length) if robot is None else robot
    space = params.space
    k = len(plan.setups)
    colors = setup_colors(k)
    face_rgb = np.tile(GREY, (len(part.mesh.faces), 1))
    for j, patches in enumerate(plan.patches):
        face_rgb[part.stain_faces[patches]] = colors[j]
    face_rgb[part.stain_faces[plan.uncoverable]] = RED
    setups = plan.setups if k else np.zeros((1, 3))
    Ts = base_T_part(setups, space)
    r = float(np.linalg.norm(part.mesh.extents[:2])) / 2
    floor = -0.672  # Puma 560 shoulder height above the floor (see SetupSpaceParams.table_z)
    lo = [space.origin_x + space.x_min - r, space.origin_y + space.y_min - r, floor]
    hi = [space.origin_x + space.x_max + r, space.origin_y + space.y_max + r, space.table_z]
    with ms.scene() as vis:
        ms.add_mesh(vis, "table", trimesh.creation.box(bounds=[lo, hi]), color=WOOD, opacity=TABLE_OPACITY)
        add_colored_mesh(vis, "part", part.mesh, face_rgb, Ts[0])
        ms.add_robot(vis, "robot", robot, robot.q_home)
        if k:
            times, setups_k, qs = setup_motion(robot, part, plan, Ts)
            tracks = robot_tracks(robot, "robot", np.repeat(np.eye(4)[None], len(times), 0), qs)
            tracks["part"] = base_T_part(setups_k, space)
            ms.animate(vis, tracks, times=times, fps=FPS)
        # frame the arm (joint 1 at the origin) and the part's placements, not the whole table
        centres = Ts[:, :3, 3]
        reach = max(r, 0.25)
        ms.frame_camera(vis, np.minimum(centres.min(axis=0) - reach, [-0.2, -0.2, -0.3]),
                        np.maximum(centres.max(axis=0) + reach, [0.2, 0.2, float(part.mesh.extents[2]) + 0.3]),
                        direction=(0.3, -1.3, 0.8))
        entries = [(colors[j], f"setup {j + 1}: x = {s[0]:.2f} m, y = {s[1]:.2f} m, alpha = "
                               f"{math.degrees(s[2]):.0f} deg, {len(plan.patches[j])} patches")
                   for j, s in enumerate(plan.setups)]
        entries += [(RED, f"stain no setup reaches ({len(plan.uncoverable)} patches)"), (GREY, "clean surface"),
                    (WOOD, "table (top at the Puma's shoulder height)")]
        cert = ("no certificate" if plan.certificate_cost is None
                else f"proven optimum {plan.certificate_cost:.0f} s")
        title = (f"{plan.part_name}: no solution" if plan.status == "no_solution" else
                 f"{plan.part_name}: {k} setups, T = {plan.cost:.0f} s ({plan.status}, {cert})")
        legend = ms.legend_html(entries, title=title,
                                notes=["the part moves through the setups in order; the arm touches a patch "
                                       "of each; replay under Animations"] + list(plan.warnings)[:2])
        return ms.save_html(vis, path, legend=legend)
