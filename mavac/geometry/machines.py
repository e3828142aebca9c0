"""MAVAC's test machines as closed, outward-oriented meshes (metres, z up, floor z = 0).

The paper (MAVAC, Experimental setup) cleans "a self-made test bench measuring 2 m x 1 m x 1 m
... designed based on a real industrial machine and ... made of four boxes, representing
varying levels of machine complexity, including concavities", and "a sanding machine and a
milling machine in a fabrication laboratory" with "complex structures with concavities and
hard-to-reach areas". Table 2 has two tests: the test bench, and the sanding and the milling
machine "cleaned during the same cleaning test" (``"sanding_milling"``, one mesh of two
bodies). The meshes are not published, so we build procedural stand-ins from boxes and
cylinders with manifold3d booleans (watertight, consistently outward normals). Each scene is
centred on the world origin in x and y and stands on the floor.

Sizes. Every dimension cites its source in a comment: the paper's text, the heap count, or
"ours" with a reason (the paper's figures are not in our text copy, so none is scaled from a
figure). The heaps lie "at intervals of 10 cm" on the upward surfaces, so a scene's upward
area fixes its heap count (about area / 0.01 m^2). One dimension per test is derived from
Table 2's mean heap count: the depth of three bench boxes (145.6 heaps) and the sander's
length (156.2 heaps for sanding + milling). Table 2's counts are then met: 146 and 156 heaps.

The mill is built from the paper's constraints on it (a Roland SRM-20 at its datasheet size):
its enclosure floor is in view through the open front (no sill hides it), the enclosure stays
too small for the tool (the paper's own failure there: "detected dust inside the box", no valid
route), and its roof is low enough for a downward camera's guard (:data:`DOWNWARD_CAMERA_MAX_Z`).
:class:`StandIn` holds the free dimensions (bench height, sill, the sander's shelf) that the
sensitivity table of notebook 05 varies.

Conflict with the Discussion. The Discussion gives "144 to 160 dust heaps distributed across
surfaces ranging from 5 to 6 m^2". At 10 cm spacing 5-6 m^2 of dust-bearing surface would
hold 500-600 heaps, so the 5-6 m^2 can only be the whole exposed surface. We follow the heap
count; the exposed areas it leaves are 6.5 m^2 for the test bench and 7.2 m^2 for sanding +
milling (4.1 + 3.1 m^2), above the Discussion's 6 m^2.

Dust heaps: "green dust heaps are evenly distributed at intervals of 10 cm on the surface,
including within the concavities". :func:`dust_heaps` spreads them over every surface dust can
rest on (upward-facing, concavities included). :mod:`mavac.cleaning.regions` labels each heap
open or enclosed from the geometry.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import trimesh
from scipy.spatial import ConvexHull, QhullError

from ..tolerances import FLOOR_NORMAL_Z, FLOOR_TOLERANCE, MACHINE_FRAME_DECIMALS
from ..validate import check_instance, check_points, check_positive, check_range
from .mesh import check_mesh, local_origin
from .surface import sample_surface

#: the three machines of the paper, one scene each (the offline notebooks 01-04 sweep these)
MACHINE_NAMES = ("test_bench", "sanding_machine", "milling_machine")
#: the scenes of MAVAC Table 2: the test bench, and the sanding and milling machine cleaned
#: "during the same cleaning test" (one mesh of two bodies)
SCENE_NAMES = ("test_bench", "sanding_milling")
#: every name ``load_machine`` accepts
LOADABLE_NAMES = MACHINE_NAMES + ("sanding_milling",)
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
    file_offset : (3,) float, metres
        Where the machine frame's origin is in the mesh it was made from
        (:func:`machine_from_mesh`): a point ``p`` of the machine is ``p + file_offset`` there.
    """

    name: str
    mesh: trimesh.Trimesh
    footprint: np.ndarray
    notes: str = field(default="")
    file_offset: np.ndarray = field(default_factory=lambda: np.zeros(3))

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


#: Test bench (MAVAC, Experimental setup): "2 m x 1 m x 1 m ... made of four boxes,
#: representing varying levels of machine complexity, including concavities". Source of each
#: number: paper = that sentence; heaps = Table 2; ours = our choice, with its reason.
#: Each box is 2 m / 4 = 0.5 m long in x (paper: four boxes over 2 m; ours: equal shares,
#: side by side, so the bench is one 2 m machine).
TEST_BENCH_BOX_WIDTH = 0.5
#: Box 3 (the overhang) spans the paper's full 1 m depth; boxes 1, 2 and 4 are
#: TEST_BENCH_DEPTH deep, derived from the heap count: their upward area 3 * 0.5 * d plus box
#: 3's 0.75 m^2 (slab top 0.5 + step under it 0.25) equals Table 2's mean of 145.6 test-bench
#: heaps at 10 cm spacing (1.456 m^2), so d = (1.456 - 0.75) / 1.5 = 0.471 m.
TEST_BENCH_DEPTH = 0.471
#: box heights, rising with complexity (ours; the tallest is the paper's 1 m)
TEST_BENCH_HEIGHTS = (0.3, 0.5, 0.7, 1.0)


def _bench_slots(width: float = TEST_BENCH_BOX_WIDTH, n: int = 4):
    """x ranges of ``n`` adjacent boxes of ``width`` (m)."""
    return [(i * width, (i + 1) * width) for i in range(n)]


@lru_cache(maxsize=None)
def _test_bench_geometry():
    (a0, a1), (b0, b1), (c0, c1), (d0, d1) = _bench_slots()
    h1, h2, h3, h4 = TEST_BENCH_HEIGHTS
    y0 = 1.0 - TEST_BENCH_DEPTH  # boxes 1, 2, 4 stand at the back (ours): box 3 overhangs in front
    # 1: a plain box (no concavity)
    box1 = _box([a0, y0, 0.0], [a1, 1.0, h1])
    # 2: an open-top pocket seen from above: 7 cm walls, 25 cm deep (ours: a tray-like cavity)
    box2 = _difference(_box([b0, y0, 0.0], [b1, 1.0, h2]),
                       [_box([b0 + 0.07, y0 + 0.07, h2 - 0.25], [b1 - 0.07, 0.93, h2 + 0.1])])
    # 3: a 15 cm top slab over the full 1 m depth overhangs a 0.2 m step: a recess 0.35 m high
    #    and 0.5 m deep, open to the front and sides (ours: a machine table over a base)
    box3 = _union([_box([c0, 0.5, 0.0], [c1, 1.0, h3]),
                   _box([c0, 0.0, h3 - 0.15], [c1, 1.0, h3]),
                   _box([c0, 0.0, 0.0], [c1, 0.5, 0.2])])
    # 4: the 1 m tower split by a 0.1 m slot above a 0.3 m plinth (ours: a deep, narrow
    #    concavity, the hardest of the four)
    ym = (y0 + 1.0) / 2
    box4 = _difference(_box([d0, y0, 0.0], [d1, 1.0, h4]),
                       [_box([d0 - 0.1, ym - 0.05, 0.3], [d1 + 0.1, ym + 0.05, h4 + 0.1])])
    return _finish(_union([box1, box2, box3, box4]))


#: Milling machine. The paper: "a sanding machine and a milling machine in a fabrication
#: laboratory"; "the robot detected dust inside the box. However, the path planner failed to
#: generate a valid route due to the tool's large size". Ours: the bench CNC mill of a fab lab,
#: the Roland monoFab SRM-20 (Roland DG, SRM-20 specifications: external dimensions 451.0 (W) x
#: 426.6 (D) x 426.2 (H) mm; table 232.2 x 156.6 mm), its front cover open, on a bench cabinet.
MILL_BODY_SIZE = (0.451, 0.4266, 0.4262)
#: SRM-20 table (X x Y, m), datasheet above; 4 cm on its carriage above the enclosure floor (ours)
MILL_TABLE_SIZE = (0.2322, 0.1566)
MILL_TABLE_HEIGHT = 0.04
#: casing (ours): 2 cm side walls, 3 cm base and roof, an 8 cm back (gantry and electronics)
MILL_WALL, MILL_SLAB, MILL_BACK = 0.02, 0.03, 0.08
#: bench cabinet under the mill (ours: the 0.75 x 0.6 m cabinet of a bench tool, the mill
#: centred on its top)
MILL_BENCH_SIZE = (0.75, 0.6)
#: Highest camera the robot holds looking straight down (optical axis within 10 deg of -z)
#: 0.85 m from its base centre, i.e. over the middle of a 0.6 m deep machine whose front is
#: 0.545 m away (half the MiR200's 0.89 m plus the 0.10 m base clearance, OnlineParams):
#: 1.38 m, pinocchio forward kinematics of ``ur10_mobile`` maximised with scipy SLSQP (ours,
#: collisions ignored; tests/test_machines.py checks it). A guard sits L_d = 0.5 m along the
#: surface normal (MAVAC, "Local exploration"; CameraParams.L_d), so the roof's guard is
#: reachable only for a roof at most 1.38 - 0.5 = 0.88 m high.
DOWNWARD_CAMERA_MAX_Z = 1.38
#: bench height: the SRM-20's roof at DOWNWARD_CAMERA_MAX_Z - L_d (rounded down to 5 mm)
MILL_BENCH_HEIGHT = 0.45
#: Sanding machine: the paper says only "a sanding machine ... in a fabrication laboratory"
#: and that both machines "feature complex structures with concavities and hard-to-reach
#: areas". Ours: a combination belt-and-disc sander, the usual sander of a fab lab, on an open
#: shelf stand (its shelf is the sander's concavity; ``StandIn(sander_shelf="closed")`` is the
#: closed cabinet of the previous stand-in); the overhanging disc table and the corners between
#: belt housing, disc and stand top are its other concavities.
#: SANDER_LENGTH is derived from the heap count: the mill as built has 0.593 m^2 upward
#: (:func:`upward_area`), so the pair's upward area equals Table 2's mean of 156.2 sanding +
#: milling heaps at 10 cm spacing (1.562 m^2) when the sander's is 0.969 m^2, i.e.
#: D * L (stand top) + (L - 2 t) * (D - t) (shelf floor) + 0.065 m^2 (disc table and disc-guard
#: top, less the stand top under the disc) = 0.969 with D = 0.6, t = 0.02:
#: L = (0.969 - 0.065 + 0.04 * 0.58) / 1.18 = 0.786 m.
SANDER_LENGTH = 0.786
#: stand depth D (ours: the mill bench's 0.6 m, a common cabinet depth)
SANDER_DEPTH = 0.6
#: stand height (ours: puts the disc table at 0.72 m, a bench-tool working height)
SANDER_STAND_HEIGHT = 0.6
#: open shelf stand (ours): 2 cm sides and back, 3 cm top, its shelf floor on a 10 cm plinth
SANDER_PANEL, SANDER_TOP, SANDER_PLINTH = 0.02, 0.03, 0.10
#: legal ``StandIn.sander_shelf`` values
SANDER_SHELVES = ("open", "closed")


@dataclass(frozen=True)
class StandIn:
    """The free dimensions of the sanding + milling stand-in (the paper gives none of them).

    Attributes
    ----------
    mill_bench_height : float, metres
        Height of the bench under the mill (:data:`MILL_BENCH_HEIGHT`, from the camera's
        downward reach); the roof is at ``mill_bench_height + 0.4262``. Range [0.1, 1.0].
    mill_sill : float, metres
        Height of the enclosure opening's lower edge above the enclosure floor (0: the open
        front cover of the SRM-20, nothing in front of its floor). Range [0, 0.15].
    sander_shelf : {"open", "closed"}
        The sander's stand: an open shelf (default) or a closed cabinet with a toe-kick.
    """

    mill_bench_height: float = MILL_BENCH_HEIGHT
    mill_sill: float = 0.0
    sander_shelf: str = "open"

    def __post_init__(self):
        check_range("mill_bench_height", self.mill_bench_height, 0.1, 1.0)
        check_range("mill_sill", self.mill_sill, 0.0, 0.15)
        if self.sander_shelf not in SANDER_SHELVES:
            raise ValueError(f"sander_shelf must be one of {SANDER_SHELVES}, got {self.sander_shelf!r}")


def _sander_stand(shelf: str):
    """The sander's stand: an open shelf, or a closed cabinet with a 6 x 10 cm toe-kick."""
    L, D, H = SANDER_LENGTH, SANDER_DEPTH, SANDER_STAND_HEIGHT
    if shelf == "closed":
        return _difference(_box([0.0, 0.0, 0.0], [L, D, H]), [_box([-0.1, -0.1, -0.1], [L + 0.1, 0.06, 0.1])])
    t = SANDER_PANEL
    return _difference(_box([0.0, 0.0, 0.0], [L, D, H]),
                       [_box([t, -0.1, SANDER_PLINTH], [L - t, D - t, H - SANDER_TOP])])


@lru_cache(maxsize=None)
def _sanding_machine_geometry(shelf: str = "open"):
    L, D, H = SANDER_LENGTH, SANDER_DEPTH, SANDER_STAND_HEIGHT
    parts = [
        # belt housing along x at the back, 0.2 m tall, 23 cm deep (ours: a 150 mm belt
        # with its frame), leaving 0.25 m of stand top at the right for the disc
        _box([0.05, D - 0.28, H - 0.01], [L - 0.25, D - 0.05, H + 0.2]),
        # disc and guard, 0.15 m radius (ours: a 300 mm disc), axis along y, facing front,
        # sunk 3 cm into the stand top (ours: one solid, no grazing faces)
        _cylinder_y(0.15, L - 0.15, D - 0.28, D - 0.2, H + 0.12),
        # disc work table in front of the disc, 10 cm above the stand top (ours): dust falls
        # on it and under it
        _box([L - 0.3, D - 0.48, H + 0.1], [L, D - 0.28, H + 0.12]),
        # table bracket down to the stand (ours: holds the table, keeps one body)
        _box([L - 0.17, D - 0.34, H - 0.01], [L - 0.13, D - 0.28, H + 0.11]),
    ]
    return _finish(_union([_sander_stand(shelf), *parts]))


def _cylinder_y(radius: float, x: float, y0: float, y1: float, z: float,
                sections: int = 32) -> trimesh.Trimesh:
    """Cylinder of ``radius`` (m) along y from ``y0`` to ``y1``, axis at (x, z)."""
    cyl = trimesh.creation.cylinder(radius=radius, height=y1 - y0, sections=sections)
    cyl.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    cyl.apply_translation([x, (y0 + y1) / 2, z])
    return cyl


def mill_heights(stand_in: StandIn | None = None) -> dict:
    """Heights (m) of the mill's dust-bearing levels: ``roof`` (top of the SRM-20),
    ``enclosure_floor`` (inside the box) and ``table`` (its machine table)."""
    s = StandIn() if stand_in is None else check_instance("stand_in", stand_in, StandIn)
    floor = s.mill_bench_height + MILL_SLAB
    return dict(roof=s.mill_bench_height + MILL_BODY_SIZE[2], enclosure_floor=floor, table=floor + MILL_TABLE_HEIGHT)


@lru_cache(maxsize=None)
def _milling_machine_geometry(bench_height: float = MILL_BENCH_HEIGHT, sill: float = 0.0):
    bw, bd = MILL_BENCH_SIZE
    w, d, h = MILL_BODY_SIZE
    x0, y0 = (bw - w) / 2, (bd - d) / 2  # the mill centred on the bench (ours)
    x1, y1, top = x0 + w, y0 + d, bench_height + h
    floor = bench_height + MILL_SLAB
    # bench cabinet with a 6 cm x 10 cm toe-kick (ours: as the sander's closed cabinet)
    bench = _difference(_box([0.0, 0.0, 0.0], [bw, bd, bench_height]),
                        [_box([-0.1, -0.1, -0.1], [bw + 0.1, 0.06, 0.1])])
    # the SRM-20's casing, front cover open: the opening spans the inside from `sill` above
    # the enclosure floor to the roof (sill 0: a camera outside sees the floor)
    inner = _box([x0 + MILL_WALL, y0 - 0.1, floor + sill], [x1 - MILL_WALL, y1 - MILL_BACK, top - MILL_SLAB])
    body = _difference(_box([x0, y0, bench_height - 0.01], [x1, y1, top]),
                       [inner, _box([x0 + MILL_WALL, y0 + 0.01, floor], [x1 - MILL_WALL, y1 - MILL_BACK, top - MILL_SLAB])])
    tw, td = MILL_TABLE_SIZE
    cx, cy = (x0 + x1) / 2, (y0 + y1 - MILL_BACK) / 2
    inside = [
        # machine table on its carriage (SRM-20 table size; carriage height ours)
        _box([cx - tw / 2, cy - td / 2, floor - 0.01], [cx + tw / 2, cy + td / 2, floor + MILL_TABLE_HEIGHT]),
        # spindle head hanging from the gantry under the roof, 10 x 10 x 15 cm (ours)
        _box([cx - 0.05, cy - 0.05, top - MILL_SLAB - 0.15], [cx + 0.05, cy + 0.05, top - MILL_SLAB + 0.01]),
        # 4 cm spindle, 8 cm above the table (ours: the SRM-20's 60.5 mm Z travel above its table)
        _cylinder(0.02, floor + MILL_TABLE_HEIGHT + 0.08, top - MILL_SLAB - 0.14, cx, cy),
    ]
    return _finish(_union([bench, body, *inside]))


#: Gap (m) between the sanding and the milling machine in the combined scene. The paper
#: cleaned both "during the same cleaning test" but gives no layout; ours: 1.0 m, so that
#: the facing sides stay open to view, with their fronts on one line (y = min).
SANDING_MILLING_GAP = 1.0


@lru_cache(maxsize=None)
def _sanding_milling_geometry(stand_in: StandIn = StandIn()):
    sander = trimesh.Trimesh(*_sanding_machine_geometry(stand_in.sander_shelf), process=False)
    mill = trimesh.Trimesh(*_milling_machine_geometry(stand_in.mill_bench_height, stand_in.mill_sill), process=False)
    sander, mill = sander.copy(), mill.copy()
    mill.apply_translation([sander.bounds[1, 0] + SANDING_MILLING_GAP - mill.bounds[0, 0],
                            sander.bounds[0, 1] - mill.bounds[0, 1], 0.0])
    return _finish(trimesh.util.concatenate([sander, mill]))  # two bodies, one mesh


_GEOMETRY = {
    "test_bench": lambda s: _test_bench_geometry(),
    "sanding_machine": lambda s: _sanding_machine_geometry(s.sander_shelf),
    "milling_machine": lambda s: _milling_machine_geometry(s.mill_bench_height, s.mill_sill),
    "sanding_milling": _sanding_milling_geometry,
}
_NOTES = {
    "test_bench": "MAVAC test bench 2 x 1 x 1 m: four adjacent 0.5 m boxes (plain box, open-top "
                  "pocket, slab overhanging a step, tower split by a 0.1 m slot); upward area "
                  "from Table 2's mean heap count",
    "sanding_machine": "stand-in belt-and-disc sander on an open shelf stand (or a closed cabinet): "
                       "belt housing, disc with a work table over the stand top",
    "milling_machine": "stand-in Roland SRM-20 bench CNC mill (datasheet size), front cover open, "
                       "on a bench cabinet: table, spindle head and spindle inside",
    "sanding_milling": "MAVAC Table 2's one test of both machines: sander and mill side by side, "
                       f"{SANDING_MILLING_GAP} m apart, fronts aligned; upward area from Table "
                       "2's mean heap count",
}


def machine_from_mesh(mesh: trimesh.Trimesh, *, name: str = "custom", notes: str = "") -> Machine:
    """Wrap your own machine mesh (metres, z up, see :func:`mavac.geometry.mesh.load_mesh`).

    The mesh is copied, lowered so its lowest point is on the floor (z = 0), and moved by whole
    metres in x and y so its centre is within half a metre of the origin
    (:func:`mavac.geometry.mesh.local_origin`): the plan of a machine does not depend on where the
    file put it, and a mesh already there keeps its x and y. ``Machine.file_offset`` is the move.
    The moved coordinates are rounded to 1 nm (:data:`mavac.tolerances.MACHINE_FRAME_DECIMALS`):
    a file 10 km away holds them only to ~1e-12 m, and that noise alone changed which guard cell
    a point on a face lying on a cell boundary fell in, and so the plan.
    The footprint is the convex hull of its floor shadow.
    """
    copy = check_mesh("mesh", mesh).copy()
    offset = local_origin(copy.vertices) + [0.0, 0.0, copy.bounds[0, 2]]
    copy.apply_translation(-offset)
    # drop the float64 noise of far-away coordinates, so a moved file gives the same mesh
    copy.vertices = np.round(copy.vertices, MACHINE_FRAME_DECIMALS) + 0.0  # +0.0: no -0.0
    return Machine(name, copy, footprint_from_mesh(copy), notes, file_offset=offset)


def _build(name: str, stand_in: StandIn | None = None) -> Machine:
    stand_in = StandIn() if stand_in is None else check_instance("stand_in", stand_in, StandIn)
    vertices, faces = _GEOMETRY[name](stand_in)
    mesh = trimesh.Trimesh(vertices.copy(), faces.copy(), process=False)
    notes = _NOTES[name] + ("" if stand_in == StandIn() or name == "test_bench" else f"; {stand_in}")
    return Machine(name, mesh, footprint_from_mesh(mesh), notes)


def test_bench() -> Machine:
    """MAVAC test bench, 2 x 1 x 1 m: four adjacent boxes of increasing complexity with
    concavities (one body); upward area from Table 2's heap count."""
    return _build("test_bench")


test_bench.__test__ = False  # not a pytest test despite the name


def sanding_machine(*, stand_in: StandIn | None = None) -> Machine:
    """Stand-in for MAVAC's sanding machine (a belt-and-disc sander on a shelf stand)."""
    return _build("sanding_machine", stand_in)


def milling_machine(*, stand_in: StandIn | None = None) -> Machine:
    """Stand-in for MAVAC's milling machine (a Roland SRM-20, front cover open, on a bench)."""
    return _build("milling_machine", stand_in)


def sanding_milling(*, stand_in: StandIn | None = None) -> Machine:
    """MAVAC Table 2's sanding + milling test: both stand-ins side by side, one mesh of two
    bodies (:data:`SANDING_MILLING_GAP` apart)."""
    return _build("sanding_milling", stand_in)


def load_machine(name: str, *, stand_in: StandIn | None = None) -> Machine:
    """The machine or scene called ``name``, one of :data:`LOADABLE_NAMES`.

    ``"sanding_milling"`` is MAVAC Table 2's combined test: the sanding and the milling
    machine side by side in one mesh of two bodies. ``stand_in`` sets the free dimensions of
    the sander and the mill (:class:`StandIn`; default the nominal ones); the test bench has none.
    """
    if name not in _GEOMETRY:
        raise ValueError(f"name must be one of {LOADABLE_NAMES}, got {name!r}")
    return _build(name, stand_in)


def upward_area(machine: Machine, *, min_normal_z: float = DUST_MIN_NORMAL_Z) -> float:
    """Area (m^2) of the faces dust rests on (normal within ``arccos(min_normal_z)`` of
    vertical): at 10 cm spacing, :func:`dust_heaps` puts about ``100 * area`` heaps there."""
    mesh = check_instance("machine", machine, Machine).mesh
    check_range("min_normal_z", min_normal_z, 0.0, 1.0)
    return float(np.asarray(mesh.area_faces)[np.asarray(mesh.face_normals)[:, 2] >= min_normal_z].sum())


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
    under the sander's disc table, inside the milling enclosure), and Poisson-disk sample it with
    :func:`mavac.geometry.surface.sample_surface`, so the count is about
    ``area / spacing**2``; the scenes' upward areas are sized so that this count is Table 2's
    (see the module docstring).

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
