"""MAVAC's three test machines as closed, outward-oriented meshes (metres, z up, floor z = 0).

The paper (MAVAC, Experimental setup) cleans "a self-made test bench measuring 2 m x 1 m x 1 m
... made of four boxes, representing varying levels of machine complexity, including
concavities", and "a sanding machine and a milling machine in a fabrication laboratory" with
"complex structures with concavities and hard-to-reach areas"; the surfaces range "from 5 to
6 m^2" (Discussion). The meshes are not published, so we build procedural stand-ins from boxes
and cylinders with manifold3d booleans (watertight, consistently outward normals). Each
machine is centred on the world origin in x and y and stands on the floor. The test bench is
four separate boxes (one mesh of four bodies): a filled 2 x 1 x 1 m block alone would have
8 m^2 of exposed surface.

Dust heaps: "green dust heaps are evenly distributed at intervals of 10 cm on the surface,
including within the concavities". :func:`dust_heaps` spreads them over every surface dust can
rest on (upward-facing, concavities included); the count is whatever our geometry gives, a
measured output and not tuned to the paper's 144-160.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import trimesh
from scipy.spatial import ConvexHull, QhullError

from ..tolerances import FLOOR_NORMAL_Z, FLOOR_TOLERANCE
from ..validate import check_instance, check_points, check_positive, check_range
from .mesh import check_mesh
from .surface import sample_surface

#: names ``load_machine`` accepts
MACHINE_NAMES = ("test_bench", "sanding_machine", "milling_machine")
#: dust rests on faces whose normal is within 60 degrees of vertical (cos 60 = 0.5)
DUST_MIN_NORMAL_Z = 0.5


@dataclass(eq=False)
class Machine:
    """A machine to clean.

    Attributes
    ----------
    name : str
    mesh : trimesh.Trimesh
        Metres, world frame, standing on z = 0, normals outward.
    footprint : (k, 2) float, metres
        Floor polygon (counter-clockwise) the mobile base must stay out of: the convex hull of
        the machine's shadow on the floor, so overhangs are included.
    notes : str
    """

    name: str
    mesh: trimesh.Trimesh
    footprint: np.ndarray
    notes: str = field(default="")

    def __post_init__(self):
        check_mesh("mesh", self.mesh)
        footprint = check_points("footprint", self.footprint, dim=2)
        x, y = footprint[:, 0], footprint[:, 1]
        if len(footprint) < 3 or np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) <= 0:
            raise ValueError("footprint must be a counter-clockwise polygon of >= 3 (x, y) "
                             "points, metres")
        self.footprint = footprint


def _box(lo, hi) -> trimesh.Trimesh:
    return trimesh.creation.box(bounds=np.array([lo, hi], dtype=np.float64))


def _cylinder(radius: float, z0: float, z1: float, x: float, y: float,
              sections: int = 32) -> trimesh.Trimesh:
    cyl = trimesh.creation.cylinder(radius=radius, height=z1 - z0, sections=sections)
    cyl.apply_translation([x, y, (z0 + z1) / 2])
    return cyl


def _union(parts) -> trimesh.Trimesh:
    return trimesh.boolean.union(parts, engine="manifold")


def _difference(solid, cuts) -> trimesh.Trimesh:
    return trimesh.boolean.difference([solid, *cuts], engine="manifold")


def footprint_from_mesh(mesh: trimesh.Trimesh) -> np.ndarray:
    """Counter-clockwise convex hull (k, 2) of the mesh's vertices projected on the floor.

    Raises ``ValueError`` when that shadow has no area (every vertex on one vertical plane or
    line, e.g. a single vertical triangle): such a mesh has no footprint.
    """
    xy = np.asarray(check_mesh("mesh", mesh).vertices)[:, :2]
    try:
        hull = ConvexHull(xy)
    except QhullError:
        raise ValueError("mesh has a floor shadow of zero area (all its vertices lie on one "
                         "vertical plane or line), so it has no footprint; a machine needs a "
                         "solid or a surface that spans x and y") from None
    return xy[hull.vertices].copy()  # scipy gives 2-D hull vertices counter-clockwise


def _finish(mesh: trimesh.Trimesh):
    """Centre on the origin in x, y, floor at z = 0; freeze arrays for the cache."""
    lo, hi = mesh.bounds
    mesh.apply_translation([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
    vertices = np.array(mesh.vertices, dtype=np.float64)
    faces = np.array(mesh.faces, dtype=np.int64)
    vertices.setflags(write=False)
    faces.setflags(write=False)
    return vertices, faces


#: Test bench layout (ours): four boxes along x, each TEST_BENCH_BOX_WIDTH wide, the rest of
#: the paper's 2 m split into three equal gaps. The paper gives the outer size (2 x 1 x 1 m),
#: "four boxes, representing varying levels of machine complexity, including concavities", and
#: 5-6 m^2 of exposed surface for its machines (Discussion); a filled 2 x 1 x 1 m block alone
#: has 8 m^2, so the boxes stand apart and leave part of the footprint empty. 0.3 m wide boxes
#: with heights 0.3 / 0.5 / 0.7 / 1.0 m rising with complexity give 5.8 m^2.
TEST_BENCH_BOX_WIDTH = 0.3


def _bench_slots(width: float = TEST_BENCH_BOX_WIDTH, length: float = 2.0, n: int = 4):
    """x ranges of ``n`` boxes of ``width`` spread over ``length`` with equal gaps."""
    gap = (length - n * width) / (n - 1)
    return [(i * (width + gap), i * (width + gap) + width) for i in range(n)]


@lru_cache(maxsize=None)
def _test_bench_geometry():
    # Four separate boxes (gaps of 0.27 m), complexity increasing with x.
    (a0, a1), (b0, b1), (c0, c1), (d0, d1) = _bench_slots()
    # 1: a plain box, 0.3 m high (no concavity)
    box1 = _box([a0, 0.3, 0.0], [a1, 0.7, 0.3])
    # 2: an open-top pocket, 25 cm deep, seen from above
    box2 = _difference(_box([b0, 0.2, 0.0], [b1, 0.8, 0.5]),
                       [_box([b0 + 0.07, 0.3, 0.25], [b1 - 0.07, 0.7, 0.6])])
    # 3: across the whole 1 m depth, a top slab overhangs a low step: a horizontal recess
    #    0.35 m high and 0.5 m deep, open only to the front (-y)
    box3 = _union([_box([c0, 0.5, 0.0], [c1, 1.0, 0.7]),
                   _box([c0, 0.0, 0.55], [c1, 1.0, 0.7]),
                   _box([c0, 0.0, 0.0], [c1, 0.5, 0.2])])
    # 4: the 1 m tower, split by a 0.1 m slot above a 0.3 m plinth (a deep, narrow concavity)
    box4 = _difference(_box([d0, 0.3, 0.0], [d1, 0.7, 1.0]),
                       [_box([d0 - 0.1, 0.45, 0.3], [d1 + 0.1, 0.55, 1.1])])
    return _finish(trimesh.util.concatenate([box1, box2, box3, box4]))


@lru_cache(maxsize=None)
def _sanding_machine_geometry():
    # Wide-belt sander: cabinet with a through feed tunnel (workpieces travel along y),
    # in-/out-feed conveyor tables cantilevered at the tunnel floor, dust-extraction ducts on
    # top, a belt-tensioning well, a side control box, and toe-kick recesses at the floor.
    cabinet = _box([0.0, 0.0, 0.0], [0.95, 0.65, 0.9])
    cuts = [
        _box([0.1, -0.1, 0.6], [0.85, 0.75, 0.72]),  # feed tunnel, 12 cm high
        _box([-0.1, -0.1, -0.1], [1.05, 0.06, 0.1]),  # front toe-kick
        _box([-0.1, 0.59, -0.1], [1.05, 0.75, 0.1]),  # back toe-kick
        _box([0.3, 0.22, 0.8], [0.65, 0.43, 1.0]),  # belt-tensioning well on top
    ]
    body = _difference(cabinet, cuts)
    extras = [
        _box([0.1, -0.22, 0.56], [0.85, 0.0, 0.6]),  # in-feed table
        _box([0.1, 0.65, 0.56], [0.85, 0.87, 0.6]),  # out-feed table
        _cylinder(0.07, 0.85, 1.1, 0.16, 0.325),  # extraction ducts
        _cylinder(0.07, 0.85, 1.1, 0.79, 0.325),
        _box([0.95, 0.15, 0.65], [1.07, 0.45, 0.95]),  # control box, cantilevered
    ]
    return _finish(_union([body, *extras]))


@lru_cache(maxsize=None)
def _milling_machine_geometry():
    # Enclosed bench CNC mill on a cabinet stand: the enclosure is open at the front (door
    # open), with the machine table (T-slots), column and overhanging spindle head inside;
    # a coolant tank beside the stand and a cantilevered control pendant.
    stand = _difference(_box([0.0, 0.0, 0.0], [0.75, 0.6, 0.65]),
                        [_box([-0.1, -0.1, -0.1], [0.85, 0.06, 0.1])])  # toe-kick
    shell = _difference(_box([0.0, 0.0, 0.65], [0.75, 0.6, 1.15]),
                        [_box([0.03, 0.03, 0.68], [0.72, 0.57, 1.12]),  # hollow enclosure
                         _box([0.1, -0.1, 0.75], [0.65, 0.1, 1.05])])  # open front door
    table = _difference(_box([0.15, 0.12, 0.68], [0.6, 0.36, 0.78]),
                        [_box([0.1, y, 0.76], [0.65, y + 0.016, 0.85])
                         for y in (0.16, 0.23, 0.3)])  # T-slots: narrow grooves
    inside = [
        table,
        _box([0.3, 0.43, 0.68], [0.45, 0.57, 1.12]),  # column on the back wall
        _box([0.32, 0.24, 0.93], [0.43, 0.43, 1.05]),  # spindle head (overhang)
        _cylinder(0.025, 0.83, 0.93, 0.375, 0.31),  # spindle
    ]
    outside = [
        _box([0.75, 0.3, 0.0], [0.93, 0.6, 0.3]),  # coolant tank
        _box([0.75, 0.05, 0.8], [0.85, 0.25, 1.05]),  # control pendant, cantilevered
    ]
    return _finish(_union([stand, shell, *inside, *outside]))


_GEOMETRY = {
    "test_bench": _test_bench_geometry,
    "sanding_machine": _sanding_machine_geometry,
    "milling_machine": _milling_machine_geometry,
}
_NOTES = {
    "test_bench": "MAVAC test bench 2 x 1 x 1 m: four separate boxes 0.27 m apart (plain box, "
                  "open-top pocket, slab overhanging a step, tower split by a 0.1 m slot)",
    "sanding_machine": "stand-in wide-belt sander: feed tunnel, cantilevered conveyor tables, "
                       "ducts, tensioning well, control box, toe-kick recesses",
    "milling_machine": "stand-in enclosed CNC mill on a stand: open-front enclosure with table "
                       "(T-slots), column and spindle head inside, coolant tank, pendant",
}


def machine_from_mesh(mesh: trimesh.Trimesh, *, name: str = "custom", notes: str = "") -> Machine:
    """Wrap your own machine mesh (metres, z up, see :func:`mavac.geometry.mesh.load_mesh`).

    The mesh is copied and lowered so its lowest point is on the floor (z = 0); x and y are
    kept. The footprint is the convex hull of its floor shadow.
    """
    copy = check_mesh("mesh", mesh).copy()
    copy.apply_translation([0.0, 0.0, -copy.bounds[0, 2]])
    return Machine(name, copy, footprint_from_mesh(copy), notes)


def _build(name: str) -> Machine:
    vertices, faces = _GEOMETRY[name]()
    mesh = trimesh.Trimesh(vertices.copy(), faces.copy(), process=False)
    return Machine(name, mesh, footprint_from_mesh(mesh), _NOTES[name])


def test_bench() -> Machine:
    """MAVAC test bench, 2 x 1 x 1 m: four separate boxes of increasing complexity with
    concavities, 5.8 m^2 exposed (a mesh of four bodies)."""
    return _build("test_bench")


test_bench.__test__ = False  # not a pytest test despite the name


def sanding_machine() -> Machine:
    """Stand-in for MAVAC's sanding machine (a wide-belt sander, exposed area 5-6 m^2)."""
    return _build("sanding_machine")


def milling_machine() -> Machine:
    """Stand-in for MAVAC's milling machine (an enclosed CNC mill, exposed area 5-6 m^2)."""
    return _build("milling_machine")


def load_machine(name: str) -> Machine:
    """The machine called ``name``, one of :data:`MACHINE_NAMES`."""
    if name not in _GEOMETRY:
        raise ValueError(f"name must be one of {MACHINE_NAMES}, got {name!r}")
    return _build(name)


def on_floor(z, normal_z) -> np.ndarray:
    """Whether surface pieces at height ``z`` (m) with normal z-component ``normal_z`` are the
    machine's base standing on the floor: on it (:data:`mavac.tolerances.FLOOR_TOLERANCE`) and
    facing down (:data:`mavac.tolerances.FLOOR_NORMAL_Z`), so not exposed. Arrays broadcast."""
    return (np.asarray(z) <= FLOOR_TOLERANCE) & (np.asarray(normal_z) < FLOOR_NORMAL_Z)


def _floor_faces(mesh: trimesh.Trimesh) -> np.ndarray:
    """(n,) bool: downward faces lying on the floor (the machine's base)."""
    top = np.asarray(mesh.vertices)[np.asarray(mesh.faces)][:, :, 2].max(axis=1)
    return on_floor(top, np.asarray(mesh.face_normals)[:, 2])


def exposed_area(machine: Machine) -> float:
    """Area (m^2) of every face except the downward faces standing on the floor."""
    mesh = check_instance("machine", machine, Machine).mesh
    return float(np.asarray(mesh.area_faces)[~_floor_faces(mesh)].sum())


def dust_heaps(machine: Machine, *, spacing: float = 0.10, seed: int = 0,
               min_normal_z: float = DUST_MIN_NORMAL_Z) -> np.ndarray:
    """Dust heap positions about ``spacing`` apart on the surfaces dust can rest on.

    MAVAC (Experimental setup): "green dust heaps are evenly distributed at intervals of 10 cm
    on the surface, including within the concavities". We take every face whose normal is
    within ``arccos(min_normal_z)`` of vertical, concavities included (cavity floors, the
    feed tunnel, inside the enclosure), and Poisson-disk sample it with
    :func:`mavac.geometry.surface.sample_surface`, so the count is about
    ``area / spacing**2``. The count is a measured output of our geometry, not tuned to the
    paper's 144-160.

    Parameters
    ----------
    machine : Machine
    spacing : float, metres
        Distance between heaps (> 0); the paper's 0.10 m by default.
    seed : int
    min_normal_z : float in [0, 1]
        Smallest upward normal component of a face that holds dust.

    Returns
    -------
    (n, 3) float, metres: heap positions on the machine surface.
    """
    check_instance("machine", machine, Machine)
    check_positive("spacing", spacing)
    check_range("min_normal_z", min_normal_z, 0.0, 1.0)
    mesh = machine.mesh
    upward = np.flatnonzero(np.asarray(mesh.face_normals)[:, 2] >= min_normal_z)
    if len(upward) == 0:
        return np.zeros((0, 3))
    resting = mesh.submesh([upward], append=True)
    return sample_surface(resting, spacing, seed=seed).points
