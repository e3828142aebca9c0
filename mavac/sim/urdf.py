"""A URDF that pybullet loads, written from a robot built in pinocchio.

Our robots are pinocchio models assembled in code (the UR10 of example-robot-data appended on
the MiR200-sized base, with the vacuum tool and the camera frame), so there is no URDF file to
hand to pybullet. :func:`urdf_from_pinocchio` writes one from the same model:

* one link per pinocchio joint (named after the joint's BODY frame, e.g. ``wrist_3_link``),
  with that joint's inertia; the root link is the universe (the robot base frame);
* one revolute (or prismatic) URDF joint per pinocchio joint, origin = ``jointPlacements``,
  axis from the joint type, limits from the model;
* every other frame (``tool0``, ``tool_tip``, ``camera``, the UR10's ``base_link``...) as a
  massless link on a fixed joint, so pybullet's link poses can be compared with pinocchio's
  frames by name;
* the geometry objects (boxes, cylinders, spheres, meshes) on the link of their parent joint,
  with their placement; meshes by absolute path (``package://`` resolved). The visual model is
  the collision model: example-robot-data's visual meshes are COLLADA, which pybullet's
  TinyRenderer does not load, and the collision STLs have the same outline.
"""

from __future__ import annotations

import math
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
import pinocchio as pin

from ..io import atomic_path
from ..validate import check_path

# Massless links are not allowed by pybullet's Featherstone solver; fixed frame links get this
# mass (kg) and inertia (kg m^2), ~0 against the UR10's 0.2-13 kg links.
_TINY_MASS = 1e-6
_TINY_INERTIA = 1e-9
_AXES = {"RX": (1, 0, 0), "RY": (0, 1, 0), "RZ": (0, 0, 1), "PX": (1, 0, 0), "PY": (0, 1, 0), "PZ": (0, 0, 1)}


def _fmt(values) -> str:
    return " ".join(f"{float(v):.10g}" for v in values)


def _origin(placement) -> str:
    """URDF ``<origin>`` of a pinocchio SE3 (xyz + fixed-axis roll-pitch-yaw)."""
    rpy = pin.rpy.matrixToRpy(np.asarray(placement.rotation))
    return f'<origin xyz="{_fmt(placement.translation)}" rpy="{_fmt(rpy)}"/>'


def _joint_kind(joint_model) -> tuple[str, tuple]:
    """(URDF type, axis) of a 1-dof pinocchio joint."""
    short = joint_model.shortname()
    for key, axis in _AXES.items():
        if short.endswith(key):
            return ("prismatic" if key[0] == "P" else "revolute"), axis
    if short in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"):
        kind = "revolute" if "Revolute" in short else "prismatic"
        return kind, tuple(np.asarray(joint_model.axis, dtype=float))
    raise ValueError(f"urdf_from_pinocchio supports 1-dof revolute/prismatic joints, got {short}")


def _shape_xml(geometry) -> str:
    """URDF ``<geometry>`` of a coal shape (box, cylinder, sphere, mesh by path)."""
    name = type(geometry.geometry).__name__
    shape = geometry.geometry
    if name == "Box":
        return f'<box size="{_fmt(2.0 * np.asarray(shape.halfSide))}"/>'
    if name == "Cylinder":
        return f'<cylinder radius="{shape.radius:.10g}" length="{2.0 * shape.halfLength:.10g}"/>'
    if name == "Sphere":
        return f'<sphere radius="{shape.radius:.10g}"/>'
    if geometry.meshPath:
        path = _resolve_mesh(geometry.meshPath)
        return f'<mesh filename={quoteattr(str(path))} scale="{_fmt(geometry.meshScale)}"/>'
    raise ValueError(f"geometry {geometry.name!r}: shape {name} has no URDF equivalent")


def _resolve_mesh(mesh_path: str) -> Path:
    """Absolute path of a mesh (``package://example-robot-data/robots/...`` resolved)."""
    prefix = "package://example-robot-data/robots/"
    if mesh_path.startswith(prefix):
        import example_robot_data

        mesh_path = str(Path(example_robot_data.getModelPath("ur_description/urdf/ur10_robot.urdf"))
                        / "robots" / mesh_path[len(prefix):])
    path = Path(mesh_path).resolve()
    if not path.is_file():
        raise ValueError(f"mesh file {path} does not exist")
    return path


def _link_names(model) -> dict[int, str]:
    """Link name per pinocchio joint: the BODY frame at the joint's origin, else ``<joint>_link``."""
    names = {0: model.names[0]}
    for f in model.frames:
        j = f.parentJoint
        if (j not in names and f.type == pin.FrameType.BODY
                and np.allclose(f.placement.homogeneous, np.eye(4))):
            names[j] = f.name
    for j in range(1, model.njoints):
        names.setdefault(j, f"{model.names[j]}_link")
    return names


def _inertial_xml(inertia) -> str:
    m = max(float(inertia.mass), _TINY_MASS)
    inertia_matrix = np.asarray(inertia.inertia, dtype=float)
    if float(inertia.mass) <= 0.0:
        inertia_matrix = np.eye(3) * _TINY_INERTIA
    I = inertia_matrix
    return (f'<inertial><origin xyz="{_fmt(inertia.lever)}" rpy="0 0 0"/><mass value="{m:.10g}"/>'
            f'<inertia ixx="{I[0, 0]:.10g}" ixy="{I[0, 1]:.10g}" ixz="{I[0, 2]:.10g}" iyy="{I[1, 1]:.10g}" '
            f'iyz="{I[1, 2]:.10g}" izz="{I[2, 2]:.10g}"/></inertial>')


def _geometry_xml(collision_model, joint: int) -> list[str]:
    out = []
    for g in collision_model.geometryObjects:
        if g.parentJoint != joint:
            continue
        origin, shape = _origin(g.placement), _shape_xml(g)
        rgba = _fmt(np.asarray(g.meshColor, dtype=float)) if len(g.meshColor) == 4 else "0.7 0.7 0.7 1"
        out.append(f'<visual>{origin}<geometry>{shape}</geometry>'
                   f'<material name="{g.name}_m"><color rgba="{rgba}"/></material></visual>')
        out.append(f"<collision>{origin}<geometry>{shape}</geometry></collision>")
    return out


def _joint_xml(model, j: int, links: dict) -> str:
    kind, axis = _joint_kind(model.joints[j])
    iq = model.joints[j].idx_q
    lo, hi = float(model.lowerPositionLimit[iq]), float(model.upperPositionLimit[iq])
    effort, velocity = float(model.effortLimit[model.joints[j].idx_v]), float(model.velocityLimit[model.joints[j].idx_v])
    limit = (f'<limit lower="{lo:.10g}" upper="{hi:.10g}" effort="{effort:.10g}" velocity="{velocity:.10g}"/>'
             if math.isfinite(lo) and math.isfinite(hi) else "")
    return (f'<joint name="{model.names[j]}" type="{kind}"><parent link="{links[model.parents[j]]}"/>'
            f'<child link="{links[j]}"/>{_origin(model.jointPlacements[j])}<axis xyz="{_fmt(axis)}"/>'
            f"{limit}</joint>")


def _frame_links_xml(model, links: dict) -> list[str]:
    """Fixed links for every non-joint frame that is not already a joint's link."""
    taken = set(links.values())
    out = []
    for f in model.frames:
        if f.type == pin.FrameType.JOINT or f.name in taken:
            continue
        taken.add(f.name)
        out.append(f'<link name="{f.name}">{_inertial_xml(pin.Inertia.Zero())}</link>')
        out.append(f'<joint name="{f.name}_frame" type="fixed"><parent link="{links[f.parentJoint]}"/>'
                   f'<child link="{f.name}"/>{_origin(f.placement)}</joint>')
    return out


def urdf_text(model, collision_model) -> str:
    """The URDF of :func:`urdf_from_pinocchio` as a string."""
    links = _link_names(model)
    parts = [f'<?xml version="1.0"?>\n<robot name="{model.name or "robot"}">']
    for j in range(model.njoints):
        inertial = _inertial_xml(model.inertias[j] if j > 0 else pin.Inertia.Zero())
        parts.append(f'<link name="{links[j]}">{inertial}{"".join(_geometry_xml(collision_model, j))}</link>')
    parts += [_joint_xml(model, j, links) for j in range(1, model.njoints)]
    parts += _frame_links_xml(model, links)
    parts.append("</robot>\n")
    return "\n".join(parts)


def urdf_from_pinocchio(model, collision_model, path, visual_model=None) -> Path:
    """Write a URDF pybullet can load for a pinocchio model.

    Parameters
    ----------
    model : pinocchio.Model
        Kinematic tree of 1-dof revolute/prismatic joints (root = the robot base frame).
    collision_model : pinocchio.GeometryModel
        Geometry written as both ``<collision>`` and ``<visual>`` (see the module docstring).
    path : str or Path
        Output file, written atomically (:func:`mavac.io.atomic_path`).
    visual_model : pinocchio.GeometryModel, optional
        Accepted for symmetry with pinocchio's loaders; not written (COLLADA meshes).

    Returns
    -------
    Path
        ``path``.
    """
    if not isinstance(model, pin.Model):
        raise ValueError(f"model must be a pinocchio.Model, got {type(model).__name__}")
    if not isinstance(collision_model, pin.GeometryModel):
        raise ValueError(f"collision_model must be a pinocchio.GeometryModel, got {type(collision_model).__name__}")
    path = check_path("path", path)
    text = urdf_text(model, collision_model)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text)
    return path


def robot_urdf(robot, folder=None) -> Path:
    """URDF of a :class:`mavac.robots.models.RobotModel`, written once per content into
    ``folder`` (default the package cache, :func:`mavac.config.cache_dir` / ``urdf``)."""
    import hashlib

    from ..config import cache_dir

    text = urdf_text(robot.model, robot.collision_model)
    digest = hashlib.sha256(text.encode()).hexdigest()[:16]
    folder = Path(cache_dir() / "urdf" if folder is None else folder)
    path = folder / f"{robot.name}_{digest}.urdf"
    if not path.is_file():
        urdf_from_pinocchio(robot.model, robot.collision_model, path)
    return path
