"""Robot models used by both papers, built as pinocchio models with coal collision geometry.

* ``ur10_mobile``: stand-in for MAVAC's Doosan M1013 on a MiR200 (README, "Stand-ins"):
  the UR10 of example-robot-data mounted at the centre of the top of a MiR200-sized box,
  carrying the vacuum tool (tube + sphere) and an Azure Kinect on the flange.
* ``puma560``: Kabir et al.'s simulated Puma 560, built from Corke's standard DH table.
* ``iiwa7``: stand-in for Kabir et al.'s KUKA LBR iiwa 7 R800 (Sec. IX-C): pybullet_data's
  ``kuka_iiwa/model.urdf`` (the real LBR iiwa, the nearest model a dependency ships), loaded
  into pinocchio from the same URDF that pybullet loads, with a flange frame and optionally
  the abrasive pad tool appended.

The root (universe) frame of every model is the robot *base* frame; its pose in the world is
``world_T_base`` (for the mobile robot: ``se2_to_matrix(x, y, theta)``, base frame on the
floor under the centre of the platform).
"""

from __future__ import annotations

import functools
import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import coal
import example_robot_data
import numpy as np
import pinocchio as pin

from ..geometry.transforms import se2_to_matrix  # noqa: F401  (re-exported: world_T_base of a spot)
from ..config import cache_dir
from ..io import write_text
from ..validate import check_nonnegative, check_positive, check_range
from .kinematics import estimate_manipulability_max

# MiR200 footprint and deck height (MiR200 datasheet: 890 x 580 mm, 352 mm high); MAVAC,
# "Experimental setup": the arm is mounted at the centre of the MiR200.
MIR200_SIZE = (0.89, 0.58, 0.35)
# Vacuum tool of MAVAC Fig. 5: a long tube ending in a perforated sphere (dimensions ours).
TOOL_TUBE_LENGTH = 0.40
#: tube lengths a user may build, m (ours: the sphere ahead of the camera body, at most the
#: UR10's 1.3 m reach)
TOOL_TUBE_RANGE = (0.1, 1.3)
TOOL_TUBE_RADIUS = 0.02
TOOL_SPHERE_RADIUS = 0.025
# Azure Kinect DK body 103 x 39 x 126 mm (Microsoft hardware specification), mounted on top
# of the tube next to the flange.
KINECT_SIZE = (0.039, 0.103, 0.126)  # along camera x (optical axis), y, z
# Masses on the flange (dynamics only; kinematics and collision do not read them): Azure
# Kinect DK 440 g (hardware specification); tube with its share of the hose 0.4 kg and
# perforated sphere 0.1 kg (ours, the paper gives no tool mass). pybullet needs them: the bare
# UR10 wrist (0.2 kg) is too light for a 240 Hz impedance loop to be stable.
KINECT_MASS = 0.44
TOOL_TUBE_MASS = 0.4
TOOL_SPHERE_MASS = 0.1

# Corke's standard DH Puma 560 (Robotics Toolbox for MATLAB, models/mdl_puma560.m;
# kinematics from Corke & Armstrong-Helouvry, ICRA 1994; joint limits from Wang & Chen,
# IEEE T-RA 7(4) 1991, as quoted in that file). Columns: a, d, alpha (m, m, rad).
PUMA560_DH = np.array(
    [
        [0.0, 0.0, np.pi / 2],
        [0.4318, 0.0, 0.0],
        [0.0203, 0.15005, -np.pi / 2],
        [0.0, 0.4318, np.pi / 2],
        [0.0, 0.0, -np.pi / 2],
        [0.0, 0.0, 0.0],
    ]
)
PUMA560_QLIM_DEG = np.array(
    [[-160, 160], [-45, 225], [-225, 45], [-110, 170], [-100, 100], [-266, 266]], dtype=float
)
# Robotics Toolbox for Python (models/DH/Puma560.py): "from mounting surface to shoulder axis".
PUMA560_PEDESTAL_HEIGHT = 0.672
# Ours, approximate like the link radii: the pedestal column under the shoulder, 0.10 m radius.
PUMA560_PEDESTAL_RADIUS = 0.10

ROBOT_NAMES = ("ur10_mobile", "puma560", "iiwa7")

# KUKA LBR iiwa datasheet: the flange sits 126 mm past axis 6; pybullet_data's URDF puts joint 7
# 81 mm past it, so the flange is 45 mm past joint 7's origin along its axis.
IIWA_FLANGE_OFFSET = 0.045
# Abrasive pad tool (ours, the paper gives none): a 0.2 kg holder of radius 20 mm and a pad
# disc 10 mm thick; the disc's diameter is the pad width (ToolpathParams.tool_width_m).
PAD_THICKNESS = 0.01
PAD_HOLDER_RADIUS = 0.02
PAD_MASS = 0.2


@dataclass
class RobotModel:
    """A fixed-base serial arm: pinocchio kinematic model plus coal collision geometry.

    Attributes
    ----------
    name : str
    model : pinocchio.Model
        Root (universe) = robot base frame.
    collision_model, visual_model : pinocchio.GeometryModel
    tool_frame : str
        Frame whose z axis is the tool axis (pointing out of the tool into the surface).
    camera_frame : str or None
        Camera frame, MAVAC convention: optical axis = camera x axis (= tool z).
    q_home : (nq,) float, rad
        A collision-free, non-singular configuration.
    notes : str
    dh : (nq, 3) float or None
        Standard DH table (a, d, alpha) when the model was built from one (enables the
        closed-form inverse kinematics).
    urdf_path : str or None
        The URDF the model was built from, when it was (pybullet loads the same file).
    manipulability_max : float or None
        Normaliser of the Yoshikawa manipulability at ``tool_frame`` (see
        ``kinematics.maneuverability``), estimated once per model.

    Notes
    -----
    A robot made by this module's builders pickles as its builder call (plus ``q_home``) and
    is rebuilt on unpickling: the UR10 meshes would otherwise weigh ~200 MB per pickle
    (joblib workers). In-place edits of its pinocchio models are not carried over; build a
    new ``RobotModel`` (or ``dataclasses.replace``) to get a fully pickled copy.
    """

    name: str
    model: pin.Model
    collision_model: pin.GeometryModel
    visual_model: pin.GeometryModel
    tool_frame: str
    camera_frame: str | None
    q_home: np.ndarray
    notes: str = ""
    dh: np.ndarray | None = None
    manipulability_max: float | None = None
    urdf_path: str | None = None
    # derived data (kinematic chains...), each entry tied to the pinocchio model it came from
    _cache: dict = field(default_factory=dict, repr=False, compare=False)
    _build: tuple | None = field(default=None, init=False, repr=False, compare=False)

    def __reduce_ex__(self, protocol):
        if self._build is None:
            return super().__reduce_ex__(protocol)
        return (_rebuild, (*self._build, np.array(self.q_home)))

    @property
    def nq(self) -> int:
        return int(self.model.nq)

    @property
    def q_lower(self) -> np.ndarray:
        return np.array(self.model.lowerPositionLimit, dtype=float)

    @property
    def q_upper(self) -> np.ndarray:
        return np.array(self.model.upperPositionLimit, dtype=float)


def _translation(x=0.0, y=0.0, z=0.0) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([x, y, z], dtype=float))


def _geometry(name, parent_joint, parent_frame, shape, placement, color=(0.6, 0.6, 0.6, 1.0)):
    g = pin.GeometryObject(name, parent_joint, parent_frame, placement, shape)
    g.meshColor = np.asarray(color, dtype=float)
    return g


def _add_to_both(collision, visual, geometry):
    collision.addGeometryObject(geometry)
    visual.addGeometryObject(geometry.copy())


_MANIPULABILITY_MAX: dict = {}  # per builder call: the estimate is deterministic


def _finish(robot: RobotModel, builder: str, kwargs: dict) -> RobotModel:
    """Attach the manipulability normaliser (estimated once per process) and the pickling key."""
    key = (builder, tuple(sorted(kwargs.items())))
    if key not in _MANIPULABILITY_MAX:
        _MANIPULABILITY_MAX[key] = estimate_manipulability_max(robot)
    robot.manipulability_max = _MANIPULABILITY_MAX[key]
    robot._build = (builder, dict(kwargs))
    return robot


def _rebuild(builder: str, kwargs: dict, q_home: np.ndarray) -> RobotModel:
    robot = load_robot(builder, **kwargs)
    robot.q_home = q_home
    return robot


def _add_tool_inertia(model, joint: int, joint_T_flange: pin.SE3, joint_T_camera: pin.SE3, L: float) -> None:
    """Tube of length ``L`` (m; thin rod along the tool z), sphere and Kinect (box) as inertia on
    the wrist."""
    r = TOOL_TUBE_RADIUS
    rod = np.diag([TOOL_TUBE_MASS * (3 * r**2 + L**2) / 12] * 2 + [TOOL_TUBE_MASS * r**2 / 2])
    model.appendBodyToJoint(joint, pin.Inertia(TOOL_TUBE_MASS, np.array([0.0, 0.0, L / 2]), rod), joint_T_flange)
    sphere = pin.Inertia.FromSphere(TOOL_SPHERE_MASS, TOOL_SPHERE_RADIUS)
    model.appendBodyToJoint(joint, pin.Inertia(TOOL_SPHERE_MASS, np.array([0.0, 0.0, L]), sphere.inertia),
                            joint_T_flange)
    model.appendBodyToJoint(joint, pin.Inertia.FromBox(KINECT_MASS, *KINECT_SIZE), joint_T_camera)


@functools.cache
def _ur10_description():
    """example-robot-data's UR10, parsed once per process (0.4 s a parse; trials build a robot
    each): read only, ``pin.appendModel`` copies it into every new model."""
    return example_robot_data.load("ur10")


def _add_vacuum_tool(model, collision, visual, L: float) -> None:
    """MAVAC's vacuum tool on the flange ``tool0``: a tube of length ``L`` (m) ending in the sphere
    (frame ``tool_tip``), and the Azure Kinect on top of the tube (frame ``camera``), with their
    collision geometry and inertia."""
    flange_id = model.getFrameId("tool0")
    flange = model.frames[flange_id]
    joint = flange.parentJoint
    joint_T_flange = flange.placement
    tool_grey = (0.75, 0.75, 0.8, 1.0)
    tube = _geometry(
        "tool_tube", joint, flange_id, coal.Cylinder(TOOL_TUBE_RADIUS, L), joint_T_flange * _translation(z=L / 2),
        tool_grey,
    )
    sphere = _geometry(
        "tool_sphere", joint, flange_id, coal.Sphere(TOOL_SPHERE_RADIUS),
        joint_T_flange * _translation(z=L), tool_grey,
    )
    _add_to_both(collision, visual, tube)
    _add_to_both(collision, visual, sphere)
    joint_T_tip = joint_T_flange * _translation(z=L)
    model.addFrame(pin.Frame("tool_tip", joint, flange_id, joint_T_tip, pin.FrameType.OP_FRAME))
    # Camera on top of the tube (flange +x side), near the flange; camera x = tool z,
    # camera y = tool y, camera z = -tool x (right-handed).
    flange_R_camera = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    cam_offset = TOOL_TUBE_RADIUS + KINECT_SIZE[2] / 2 + 0.005
    flange_T_camera = pin.SE3(flange_R_camera, np.array([cam_offset, 0.0, 0.06]))
    joint_T_camera = joint_T_flange * flange_T_camera
    model.addFrame(pin.Frame("camera", joint, flange_id, joint_T_camera, pin.FrameType.OP_FRAME))
    camera_body = _geometry("camera_body", joint, flange_id, coal.Box(*KINECT_SIZE), joint_T_camera, (0.1, 0.1, 0.1, 1.0))
    _add_to_both(collision, visual, camera_body)
    _add_tool_inertia(model, joint, joint_T_flange, joint_T_camera, L)


def ur10_mobile(*, tube_length: float = TOOL_TUBE_LENGTH) -> RobotModel:
    """UR10 (example-robot-data) on a MiR200-sized SE(2) base, with vacuum tool and camera.

    Base frame: on the floor under the centre of the platform, x forward (long side), z up.
    The arm base sits at the centre of the box top, ``base_T_arm`` = translation (0, 0, 0.35).
    Frames ``tool_tip`` (centre of the tool sphere, z along the tube) and ``camera``
    (x = optical axis = tool z) are attached to the flange ``tool0``.
    Joint limits are those of example-robot-data's ``ur10_robot.urdf`` (+-2 pi, elbow +-pi).

    Parameters
    ----------
    tube_length : float, metres
        Flange to the tool sphere's centre, in :data:`TOOL_TUBE_RANGE` (default
        :data:`TOOL_TUBE_LENGTH`); the camera stays where it is, next to the flange. Another
        length is another robot, named ``ur10_mobile_tube<mm>mm``.
    """
    L = check_range("tube_length", tube_length, *TOOL_TUBE_RANGE)
    ur = _ur10_description()
    root = pin.Model()
    root.name = "ur10_mobile"
    root_frame = root.addFrame(pin.Frame("mobile_base", 0, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    base_T_arm = _translation(z=MIR200_SIZE[2])
    empty_c, empty_v = pin.GeometryModel(), pin.GeometryModel()
    model, collision = pin.appendModel(root, ur.model, empty_c, ur.collision_model, root_frame, base_T_arm)
    _, visual = pin.appendModel(root, ur.model, empty_v, ur.visual_model, root_frame, base_T_arm)

    # The example-robot-data "ee_link" box duplicates the flange; the tool replaces it.
    for geometry_model in (collision, visual):
        if geometry_model.existGeometryName("ee_link_0"):
            geometry_model.removeGeometryObject("ee_link_0")

    box = coal.Box(*MIR200_SIZE)
    _add_to_both(
        collision,
        visual,
        _geometry("mir200_base", 0, root_frame, box, _translation(z=MIR200_SIZE[2] / 2), (0.3, 0.3, 0.35, 1.0)),
    )

    _add_vacuum_tool(model, collision, visual, L)

    # Elbow up, tool tip ~(1.0, 0, 0.8) m pointing forward and 60 deg down, wrist away from
    # q5 = 0 (wrist singularity); a high-maneuverability IK solution for that target.
    q_home = np.array([-0.22, -1.46, 1.31, -1.94, -1.46, 0.0])
    robot = RobotModel(
        # another tube is another robot: its plans do not run on this one (run_trial checks names)
        name="ur10_mobile" if L == TOOL_TUBE_LENGTH else f"ur10_mobile_tube{round(1000 * L)}mm",
        model=model,
        collision_model=collision,
        visual_model=visual,
        tool_frame="tool_tip",
        camera_frame="camera",
        q_home=q_home,
        notes=(
            "Stand-in for MAVAC's Doosan M1013 on a MiR200: UR10 (example-robot-data, ur10_robot.urdf) "
            f"at the centre of a 0.89 x 0.58 x 0.35 m box; vacuum tool = {L:.2f} m tube (r 2 cm) + "
            "5 cm sphere on tool0; Azure Kinect on top of the tube, optical axis = camera x = tool z."
        ),
    )
    return _finish(robot, "ur10_mobile", {} if L == TOOL_TUBE_LENGTH else {"tube_length": L})


def _dh_placement(a: float, d: float, alpha: float) -> pin.SE3:
    """Constant part ``Tz(d) Tx(a) Rx(alpha)`` of a standard DH link transform."""
    c, s = np.cos(alpha), np.sin(alpha)
    R = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    return pin.SE3(R, np.array([a, 0.0, d]))


def _cylinder_between(name, joint, frame, p0, p1, radius, color):
    """A coal cylinder from ``p0`` to ``p1`` (joint frame) attached to ``joint``."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    axis = p1 - p0
    length = float(np.linalg.norm(axis))
    z = axis / length
    R = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), z).matrix()
    return _geometry(name, joint, frame, coal.Cylinder(radius, length), pin.SE3(R, (p0 + p1) / 2), color)


def puma560(tool_length: float = 0.0) -> RobotModel:
    """Puma 560 from Corke's standard DH parameters (``mdl_puma560``), base frame at the shoulder.

    Joint ``i`` rotates about ``z_{i-1}``; pinocchio joint ``i+1`` is placed at
    ``Tz(d_i) Tx(a_i) Rx(alpha_i)`` in joint ``i``'s frame, so the chain reproduces
    ``A_i = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``. Frame ``tool`` sits ``tool_length`` m along
    ``z_6``. Collision geometry: one cylinder per link (radii ours, approximate), a pedestal of
    0.672 m below the shoulder, and the tool shaft.

    Parameters
    ----------
    tool_length : float, metres, >= 0
    """
    check_nonnegative("tool_length", tool_length)
    tool_length = float(tool_length)
    model = pin.Model()
    model.name = "puma560"
    lower = np.deg2rad(PUMA560_QLIM_DEG[:, 0])
    upper = np.deg2rad(PUMA560_QLIM_DEG[:, 1])
    parent, placement = 0, pin.SE3.Identity()
    joints = []
    for i in range(6):
        jid = model.addJoint(
            parent, pin.JointModelRZ(), placement, f"joint{i + 1}",
            np.full(1, 100.0), np.full(1, 5.0), lower[i : i + 1], upper[i : i + 1],
        )
        model.addFrame(pin.Frame(f"link{i + 1}", jid, 0, pin.SE3.Identity(), pin.FrameType.BODY))
        joints.append(jid)
        a, d, alpha = PUMA560_DH[i]
        parent, placement = jid, _dh_placement(a, d, alpha)
    flange_frame = model.addFrame(pin.Frame("flange", joints[-1], 0, placement, pin.FrameType.OP_FRAME))
    joint_T_tool = placement * _translation(z=tool_length)
    model.addFrame(pin.Frame("tool", joints[-1], flange_frame, joint_T_tool, pin.FrameType.OP_FRAME))

    a2, d3, d4 = PUMA560_DH[1, 0], PUMA560_DH[2, 1], PUMA560_DH[3, 1]
    collision, visual = pin.GeometryModel(), pin.GeometryModel()
    grey, orange = (0.7, 0.7, 0.7, 1.0), (0.9, 0.5, 0.1, 1.0)
    fid = {j: model.getFrameId(f"link{j}") for j in range(1, 7)}
    parts = [
        # pedestal under the shoulder housing (universe)
        _cylinder_between("pedestal", 0, 0, [0, 0, -PUMA560_PEDESTAL_HEIGHT], [0, 0, -0.25],
                          PUMA560_PEDESTAL_RADIUS, grey),
        # shoulder housing: vertical cylinder around z0 (joint 1 frame)
        _cylinder_between("link1", joints[0], fid[1], [0, 0, -0.25], [0, 0, 0.10], 0.09, grey),
        # upper arm: from the shoulder to the elbow along x of joint 2, offset towards d3
        _cylinder_between("link2", joints[1], fid[2], [0, 0, 0.10], [a2, 0, 0.10], 0.06, grey),
        # elbow housing about the elbow axis (z of joint 3)
        _cylinder_between("link3", joints[2], fid[3], [0, 0, 0.04], [0, 0, d3 + 0.05], 0.06, grey),
        # forearm: along z of joint 4 from just past the elbow to before the wrist centre
        _cylinder_between("link4", joints[3], fid[4], [0, 0, 0.10], [0, 0, d4 - 0.06], 0.045, grey),
        # wrist: about z of joint 5 through the wrist centre
        _cylinder_between("link5", joints[4], fid[5], [0, 0, -0.04], [0, 0, 0.04], 0.04, grey),
    ]
    if tool_length > 0.06:
        parts.append(
            _cylinder_between("tool", joints[5], fid[6], [0, 0, 0.05], [0, 0, tool_length], 0.02, orange)
        )
    for g in parts:
        _add_to_both(collision, visual, g)

    # Corke's nominal pose qn = [0, pi/4, pi, 0, pi/4, 0] with q3 = pi taken as -pi (inside
    # [-225, 45] deg).
    q_home = np.array([0.0, np.pi / 4, -np.pi, 0.0, np.pi / 4, 0.0])
    robot = RobotModel(
        name="puma560",
        model=model,
        collision_model=collision,
        visual_model=visual,
        tool_frame="tool",
        camera_frame=None,
        q_home=q_home,
        notes=(
            "Puma 560, standard DH of Corke's mdl_puma560 (Corke & Armstrong-Helouvry 1994); joint "
            "limits from Wang & Chen 1991 as in mdl_puma560; base frame at the shoulder "
            f"(pedestal 0.672 m below); tool_length = {tool_length} m along z6."
        ),
        dh=PUMA560_DH.copy(),
    )
    return _finish(robot, "puma560", {"tool_length": tool_length})


def _iiwa_tool_urdf(tool_length: float, pad_width: float) -> str:
    """URDF links appended to link 7: the flange frame and, if ``tool_length > 0``, the pad tool.

    Every link has an explicit inertial so that pybullet and pinocchio agree on the masses
    (pybullet gives a link without one a mass of 1 kg).
    """
    tiny = '<inertial><mass value="1e-6"/><inertia ixx="1e-9" ixy="0" ixz="0" iyy="1e-9" iyz="0" izz="1e-9"/></inertial>'
    out = (f'<joint name="flange_joint" type="fixed"><parent link="lbr_iiwa_link_7"/><child link="flange"/>'
           f'<origin xyz="0 0 {IIWA_FLANGE_OFFSET}"/></joint><link name="flange">{tiny}</link>')
    if tool_length <= 0:
        return out
    holder = tool_length - PAD_THICKNESS
    i_xx = PAD_MASS * (3 * PAD_HOLDER_RADIUS**2 + tool_length**2) / 12
    i_zz = PAD_MASS * PAD_HOLDER_RADIUS**2 / 2
    r = pad_width / 2
    return out + (
        f'<joint name="tool_joint" type="fixed"><parent link="flange"/><child link="tool"/>'
        f'<origin xyz="0 0 0"/></joint>'
        f'<link name="tool"><inertial><origin xyz="0 0 {tool_length / 2}"/><mass value="{PAD_MASS}"/>'
        f'<inertia ixx="{i_xx}" ixy="0" ixz="0" iyy="{i_xx}" iyz="0" izz="{i_zz}"/></inertial>'
        f'<visual><origin xyz="0 0 {holder / 2}"/><geometry><cylinder radius="{PAD_HOLDER_RADIUS}" '
        f'length="{holder}"/></geometry></visual>'
        f'<collision><origin xyz="0 0 {holder / 2}"/><geometry><cylinder radius="{PAD_HOLDER_RADIUS}" '
        f'length="{holder}"/></geometry></collision></link>'
        f'<joint name="pad_joint" type="fixed"><parent link="tool"/><child link="pad"/>'
        f'<origin xyz="0 0 {holder}"/></joint>'
        f'<link name="pad">{tiny}<visual><origin xyz="0 0 {PAD_THICKNESS / 2}"/><geometry><cylinder radius="{r}" '
        f'length="{PAD_THICKNESS}"/></geometry><material name="pad"><color rgba="0.2 0.5 0.2 1"/></material>'
        f'</visual><collision><origin xyz="0 0 {PAD_THICKNESS / 2}"/><geometry><cylinder radius="{r}" '
        f'length="{PAD_THICKNESS}"/></geometry></collision></link>'
        f'<joint name="pad_face_joint" type="fixed"><parent link="pad"/><child link="pad_face"/>'
        f'<origin xyz="0 0 {PAD_THICKNESS}"/></joint><link name="pad_face">{tiny}</link>')


def iiwa_urdf(tool_length: float = 0.0, pad_width: float = 0.03) -> Path:
    """pybullet_data's ``kuka_iiwa/model.urdf`` with absolute mesh paths, a ``flange`` link and,
    when ``tool_length > 0``, the pad tool (``tool`` holder, ``pad`` disc, ``pad_face`` frame
    ``tool_length`` m past the flange), written once into :func:`mavac.config.cache_dir`.

    Parameters
    ----------
    tool_length : float, metres, >= 0
        Flange to pad face; 0 for a bare flange (the holding arm).
    pad_width : float, metres, > 0
        Pad diameter (only with a tool).
    """
    import pybullet_data

    tool_length = float(check_nonnegative("tool_length", tool_length))
    pad_width = float(check_positive("pad_width", pad_width))
    if 0 < tool_length <= PAD_THICKNESS:
        raise ValueError(f"tool_length must be 0 or > the pad thickness {PAD_THICKNESS} m, got {tool_length}")
    folder = Path(pybullet_data.getDataPath()) / "kuka_iiwa"
    text = (folder / "model.urdf").read_text()
    text = text.replace('filename="meshes/', f'filename="{folder}/meshes/')
    text = text.replace("</robot>", _iiwa_tool_urdf(tool_length, pad_width) + "\n</robot>")
    key = hashlib.sha256(text.encode()).hexdigest()[:16]
    path = cache_dir() / "urdf" / f"iiwa7_{key}.urdf"
    if not path.is_file() or path.read_text() != text:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text(text, path)
    return path


def iiwa7(tool_length: float = 0.0, pad_width: float = 0.03) -> RobotModel:
    """KUKA LBR iiwa from pybullet_data's ``kuka_iiwa/model.urdf`` (stand-in for the iiwa 7 R800).

    Base frame = the URDF's ``lbr_iiwa_link_0`` (on the mounting plate, z up along joint 1).
    ``tool_frame`` is ``pad_face`` (centre of the pad's contact face, z out of the tool) when
    ``tool_length > 0``, else ``flange``. Joint limits are the URDF's (+-170, +-120, +-170,
    +-120, +-170, +-120, +-175 deg); collision geometry = the URDF's link meshes and tool
    cylinders (coal BVHs).

    Parameters
    ----------
    tool_length : float, metres, >= 0
        Flange to pad face (0: the bare flange, for the holding arm).
    pad_width : float, metres
        Pad diameter.
    """
    path = iiwa_urdf(tool_length, pad_width)
    model = pin.buildModelFromUrdf(str(path))
    model.name = "iiwa7"
    collision = pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.COLLISION)
    visual = pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.VISUAL)
    tool = "pad_face" if tool_length > 0 else "flange"
    # Elbow bent, flange 0.5 m in front of the base at 0.55 m height, pointing down (ours).
    q_home = np.array([0.0, 0.6, 0.0, -1.4, 0.0, 1.1, 0.0])
    robot = RobotModel(
        name="iiwa7", model=model, collision_model=collision, visual_model=visual, tool_frame=tool,
        camera_frame=None, q_home=q_home, urdf_path=str(path),
        notes=("KUKA LBR iiwa from pybullet_data kuka_iiwa/model.urdf (stand-in for the paper's iiwa 7 R800), "
               f"flange {IIWA_FLANGE_OFFSET} m past joint 7; tool_length = {tool_length} m to the pad face, "
               f"pad width {pad_width} m."),
    )
    return _finish(robot, "iiwa7", {"tool_length": tool_length, "pad_width": pad_width})


def load_robot(name: str, **kwargs) -> RobotModel:
    """Robot by name: ``"ur10_mobile"``, ``"puma560"`` or ``"iiwa7"`` (kwargs go to the builder)."""
    builders = {"ur10_mobile": ur10_mobile, "puma560": puma560, "iiwa7": iiwa7}
    if name not in builders:
        raise ValueError(f"name must be one of {ROBOT_NAMES}, got {name!r}")
    return builders[name](**kwargs)
