"""Notebook 01: machines, parts and robot models measured against the papers' descriptions."""

from __future__ import annotations

import time

import numpy as np
import pandas as pd
import pinocchio as pin
import trimesh

from ..geometry.machines import MACHINE_NAMES, dust_heaps, exposed_area, load_machine, machine_from_mesh
from ..geometry.parts import PART_NAMES, load_part
from ..robots import kinematics
from ..robots.models import load_robot


def machine_summary(*, names=MACHINE_NAMES, spacing: float = 0.10, seed: int = 0) -> pd.DataFrame:
    """Size (m), exposed area (m^2) and dust-heap count at ``spacing`` for each machine.

    Columns: ``machine, size_x, size_y, size_z, exposed_area, heaps, faces, watertight``.
    """
    rows = []
    for name in names:
        machine = load_machine(name)
        ext = machine.mesh.extents
        rows.append(dict(machine=name, size_x=ext[0], size_y=ext[1], size_z=ext[2],
                         exposed_area=exposed_area(machine),
                         heaps=len(dust_heaps(machine, spacing=spacing, seed=seed)),
                         faces=len(machine.mesh.faces), watertight=bool(machine.mesh.is_watertight)))
    return pd.DataFrame(rows)


def closed_block_summary(size=(2.0, 1.0, 1.0), *, spacing: float = 0.10, seed: int = 0) -> dict:
    """Exposed area (m^2) and heap count of a filled block of ``size`` (m): what any closed
    footprint of that size gives, for comparison with a bench of separate boxes."""
    block = machine_from_mesh(trimesh.creation.box(extents=size), name="closed_block")
    return dict(size=tuple(float(v) for v in size), exposed_area=exposed_area(block),
                heaps=len(dust_heaps(block, spacing=spacing, seed=seed)))


def part_summary(names=PART_NAMES, seed: int = 0) -> pd.DataFrame:
    """Size (m), triangle count, largest face (m^2), stain patches and passes per part.

    Columns: ``part, size_x, size_y, size_z, faces, max_face_area, stain_patches,
    passes_1, passes_2, passes_3``.
    """
    rows = []
    for name in names:
        part = load_part(name, seed=seed)
        ext = part.mesh.extents
        counts = np.bincount(part.passes, minlength=4)
        rows.append(dict(part=name, size_x=ext[0], size_y=ext[1], size_z=ext[2], faces=len(part.mesh.faces),
                         max_face_area=float(part.mesh.area_faces.max()), stain_patches=len(part.stain_faces),
                         passes_1=int(counts[1]), passes_2=int(counts[2]), passes_3=int(counts[3])))
    return pd.DataFrame(rows)


def random_configurations(robot, n: int, seed: int = 0) -> np.ndarray:
    """``n`` configurations drawn uniformly within the joint limits, (n, nq) rad."""
    rng = np.random.default_rng(seed)
    return rng.uniform(robot.q_lower, robot.q_upper, size=(n, robot.nq))


def reach_envelope(robot, n: int = 5000, seed: int = 0) -> np.ndarray:
    """Tool positions (n, 3), metres, in the base frame, from random in-limit configurations."""
    return kinematics.fk(robot, random_configurations(robot, n, seed))[:, :3, 3]


def ik_accuracy(*, robot_names=("ur10_mobile", "puma560"), n: int = 1000, seed: int = 0) -> pd.DataFrame:
    """IK round trips on reachable targets (FK of random in-limit configurations).

    For each robot, full-pose ``ik`` and position + tool-axis ``ik_axis`` (closed form where
    the robot has one) are run on the same targets, batched. Columns: ``robot, ik, targets,
    success_rate, position_error_max, rotation_error_max, seconds, targets_per_second``
    (errors over the successful targets; metres and radians).
    """
    rows = []
    for name in robot_names:
        robot = load_robot(name)
        targets = kinematics.fk(robot, random_configurations(robot, n, seed))
        rng = np.random.default_rng(seed)
        for kind in ("pose", "axis"):
            t0 = time.perf_counter()
            if kind == "pose":
                res = kinematics.ik(robot, targets, rng=rng)
            else:
                res = kinematics.ik_axis(robot, targets[:, :3, 3], targets[:, :3, 2], rng=rng)
            seconds = time.perf_counter() - t0
            ok = res.success
            rows.append(dict(robot=name, ik=kind, targets=n, success_rate=float(ok.mean()),
                             position_error_max=float(res.position_error[ok].max(initial=0.0)),
                             rotation_error_max=float(res.rotation_error[ok].max(initial=0.0)),
                             seconds=seconds, targets_per_second=n / seconds))
    return pd.DataFrame(rows)


def robot_summary(robot_names=("ur10_mobile", "puma560")) -> pd.DataFrame:
    """Joint count, tool frame, camera frame and the reach: the largest distance (m) from the
    shoulder (joint 2 origin) to the tool frame over random in-limit configurations."""
    rows = []
    for name in robot_names:
        robot = load_robot(name)
        pts = reach_envelope(robot, 4000, seed=0)
        data = robot.model.createData()
        pin.forwardKinematics(robot.model, data, robot.q_home)
        shoulder = data.oMi[2].translation
        rows.append(dict(robot=name, nq=robot.nq, tool_frame=robot.tool_frame, camera_frame=robot.camera_frame,
                         reach=float(np.linalg.norm(pts - shoulder, axis=1).max())))
    return pd.DataFrame(rows)
