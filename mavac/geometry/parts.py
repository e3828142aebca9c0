"""Kabir et al.'s test parts: triangulated surfaces with a stain of patches and pass counts.

Synthetic objects (Kabir, Sec. IX-A, Fig. 6): Sine 1.6 x 1.6 x 0.5 m, Schwefel 0.6 x 0.6 x
0.35 m, Concave bowl 1.2 x 1.2 x 0.53 m, Hyperboloid of one sheet 1.2 x 1.2 x 0.412 m; "the
area of each triangular face is less than 1.5 cm^2" and the stain has "about 4000 to 5000
stain patches", with "not more than three cleaning passes".

Physical parts (Kabir, Sec. IX-C): a plastic bowl (convex side cleaned) and a 3-D printed ship
hull, "represented as a mesh of 15,644 and 22,764 triangles", stain of "1000 and 5709
triangles", "each triangle had a surface area of less than 10 mm^2". The paper prints the
dimensions as 21.5 mm x 21.5 mm x 9.5 mm and 20.1 mm x 18.0 mm x 14.0 mm, but those only work
in centimetres: a 21.5 mm bowl would be smaller than the scrubbing tool, and 15,644 triangles
on it would average 0.03 mm^2, making the 10 mm^2 bound meaningless; in cm the mean triangle is
about 3-4 mm^2. So we use 21.5 x 21.5 x 9.5 cm and 20.1 x 18.0 x 14.0 cm.

All surfaces are open (not watertight) single sheets, triangulated on a regular (u, v) grid,
with face normals on the side the tool cleans from (outward/upward). Part frame: origin at the
centre of the bounding-box bottom, z up, the part resting on z = 0.

The stain is a smooth random field thresholded at its k-th largest value, so it has exactly k
faces; intensity rises to 1 at the blob cores and passes come from intensity thresholds. The
distribution, per ``seed`` (:func:`stain_from_field`): k uniform on 4000-5000 (synthetic
objects); the number of Gaussian blobs uniform on ``stain_blobs``; each blob's centre a face
drawn with probability proportional to its area (uniform over the surface), its weight uniform
on [0.6, 1], its width uniform on [0.06, 0.12] x the part's bounding-box diagonal. The
synthetic objects carry 4-8 blobs, so the stain is several regions spread over the part as the
red regions of Kabir Fig. 6 are (the paper gives no count; 4-8 is ours). The physical parts
keep 2-4 blobs: "We applied different layers of stain on different regions" (Sec. IX-C).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import trimesh

from ..validate import check_int
from .mesh import check_mesh

#: every part ``load_part`` knows
PART_NAMES = ("sine", "schwefel", "concave_bowl", "hyperboloid", "bowl", "hull")
#: Kabir Fig. 6 objects
SYNTHETIC_NAMES = ("sine", "schwefel", "concave_bowl", "hyperboloid")
#: Gaussian blobs (min, max) of a synthetic object's stain: Kabir Fig. 6 draws the stain as red
#: regions spread over each part; the count is ours (uniform on 4-8)
SYNTHETIC_STAIN_BLOBS = (4, 8)
#: Kabir, Sec. IX-A: "The area of each triangular face is less than 1.5 cm^2"
SYNTHETIC_MAX_FACE_AREA = 1.5e-4
#: Kabir, Sec. IX-C: "Each triangle had a surface area of less than 10 mm^2"
PHYSICAL_MAX_FACE_AREA = 1e-5
#: Kabir, Sec. IX-A: "about 4000 to 5000 stain patches on each object"
SYNTHETIC_STAIN_RANGE = (4000, 5000)
#: Kabir, Sec. IX-C: "The stain region consisted of 1000 and 5709 triangles"
BOWL_STAIN_FACES = 1000
HULL_STAIN_FACES = 5709


@dataclass(eq=False)
class Part:
    """A part to clean: a triangle mesh in the part frame and its stain patches.

    Attributes
    ----------
    name : str
    mesh : trimesh.Trimesh
        Metres, part frame (origin at the centre of the bounding-box bottom, z up, resting on
        z = 0); face normals point to the side the tool cleans from.
    stain_faces : (k,) int
        Indices of the stained faces (Kabir's patches p_i), unique.
    passes : (k,) int in 1..3
        Cleaning passes N_i each patch needs.
    intensity : (k,) float in (0, 1]
        Stain intensity of each patch (passes are derived from it).
    notes : str
    """

    name: str
    mesh: trimesh.Trimesh
    stain_faces: np.ndarray
    passes: np.ndarray
    intensity: np.ndarray
    notes: str = field(default="")

    def __post_init__(self):
        check_mesh("mesh", self.mesh)
        n_faces = len(self.mesh.faces)
        stain = np.asarray(self.stain_faces)
        if stain.ndim != 1 or len(stain) == 0 or not np.issubdtype(stain.dtype, np.integer):
            raise ValueError(f"stain_faces must be a non-empty (k,) integer array, got "
                             f"shape {stain.shape} dtype {stain.dtype}")
        if stain.min() < 0 or stain.max() >= n_faces:
            raise ValueError(f"stain_faces must index faces in [0, {n_faces - 1}], got "
                             f"[{stain.min()}, {stain.max()}]")
        if len(np.unique(stain)) != len(stain):
            raise ValueError("stain_faces must not repeat a face")
        passes = np.asarray(self.passes)
        if passes.shape != stain.shape or not np.all(np.isin(passes, (1, 2, 3))):
            raise ValueError(f"passes must be a ({len(stain)},) array of integers in 1..3")
        intensity = np.asarray(self.intensity, dtype=np.float64)
        if intensity.shape != stain.shape or not np.all((intensity > 0) & (intensity <= 1)):
            raise ValueError(f"intensity must be a ({len(stain)},) array of floats in (0, 1]")
        self.stain_faces = stain.astype(np.int64)
        self.passes = passes.astype(np.int64)
        self.intensity = intensity

    @property
    def stain_mesh(self) -> trimesh.Trimesh:
        """Submesh of the stained faces, in ``stain_faces`` order."""
        return self.mesh.submesh([self.stain_faces], append=True)

    @property
    def patch_vertices(self) -> np.ndarray:
        """(k, 3, 3) float, metres: the three corners of each patch."""
        return np.asarray(self.mesh.vertices)[np.asarray(self.mesh.faces)[self.stain_faces]]

    @property
    def patch_normals(self) -> np.ndarray:
        """(k, 3) float: outward unit normal of each patch."""
        return np.asarray(self.mesh.face_normals)[self.stain_faces]

    @property
    def patch_areas(self) -> np.ndarray:
        """(k,) float, m^2: area of each patch."""
        return np.asarray(self.mesh.area_faces)[self.stain_faces]


# ---- triangulation helpers -------------------------------------------------------------


def _grid_faces(n_u: int, n_v: int, wrap_u: bool = False) -> np.ndarray:
    """Two triangles per cell of a vertex grid indexed ``i * n_v + j`` (i along u).

    ``n_u`` and ``n_v`` are vertex counts; ``wrap_u`` joins the last u row to the first.
    Every triangle is wound the same way, so the sheet is consistently oriented.
    """
    rows = n_u if wrap_u else n_u - 1
    i, j = np.meshgrid(np.arange(rows), np.arange(n_v - 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    i1 = (i + 1) % n_u
    a, b, c, d = i * n_v + j, i1 * n_v + j, i1 * n_v + j + 1, i * n_v + j + 1
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.int64)


def _concentric_disc(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Shirley-Chiu equal-area map of an (n+1) x (n+1) square grid onto the unit disc.

    Returns (vertices (m, 2), faces (2 n^2, 3)); cells keep equal area, so triangles are even
    in size with no pole at the centre (unlike a polar grid). ``n`` even puts vertices on the
    x and y axes at radius 1, so the bounding box is exact.
    """
    a, b = np.meshgrid(np.linspace(-1, 1, n + 1), np.linspace(-1, 1, n + 1), indexing="ij")
    a, b = a.ravel(), b.ravel()
    r = np.where(np.abs(a) > np.abs(b), a, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        phi = np.where(np.abs(a) > np.abs(b), np.pi / 4 * b / a, np.pi / 2 - np.pi / 4 * a / b)
    phi = np.where(r == 0, 0.0, phi)
    xy = np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)
    # split each cell along the diagonal that points away from the centre: the map bends
    # along the square's diagonals, and the other split would give sliver + oversized pairs
    faces = _grid_faces(n + 1, n + 1)
    quads = np.concatenate([faces[: n * n], faces[n * n:][:, [2]]], axis=1)  # a, b, c, d
    centre = xy[quads].mean(axis=1)
    anti = centre[:, 0] * centre[:, 1] < 0
    a, b, c, d = quads.T
    first = np.where(anti[:, None], np.stack([a, b, d], 1), np.stack([a, b, c], 1))
    second = np.where(anti[:, None], np.stack([b, c, d], 1), np.stack([a, c, d], 1))
    return xy, np.concatenate([first, second])


def _to_part_frame(vertices: np.ndarray) -> np.ndarray:
    """Translate so the bounding-box bottom centre is the origin."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    return vertices - np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])


def _oriented(vertices: np.ndarray, faces: np.ndarray, outward) -> tuple[np.ndarray, np.ndarray]:
    """Flip the (consistently wound) sheet if its normals point against ``outward``.

    ``outward(centroids (n, 3)) -> (n, 3)`` gives the intended side at each face.
    """
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    agreement = np.einsum("ij,ij->i", mesh.face_normals, outward(mesh.triangles_center))
    if np.sum(agreement * mesh.area_faces) < 0:
        faces = faces[:, ::-1]
    vertices = _to_part_frame(vertices)
    vertices.setflags(write=False)
    faces = np.ascontiguousarray(faces)
    faces.setflags(write=False)
    return vertices, faces


def _up(centres: np.ndarray) -> np.ndarray:
    return np.broadcast_to([0.0, 0.0, 1.0], centres.shape)


def _radial(centres: np.ndarray) -> np.ndarray:
    out = centres.copy()
    out[:, 2] = 0.0
    return out


def _height_field(n: int, size_xy: float, height, z_range: float):
    """Regular (n+1)^2 grid over a square, z = height(x, y) rescaled to ``z_range``."""
    x, y = np.meshgrid(np.linspace(-size_xy / 2, size_xy / 2, n + 1),
                       np.linspace(-size_xy / 2, size_xy / 2, n + 1), indexing="ij")
    z = height(x, y)
    z = (z - z.min()) / np.ptp(z) * z_range
    return np.stack([x.ravel(), y.ravel(), z.ravel()], 1), _grid_faces(n + 1, n + 1)


# ---- geometry (cached: pure functions of nothing) -----------------------------------------


@lru_cache(maxsize=None)
def _sine_geometry():
    # Fig. 6(a): 1600 x 1600 x 500 mm; two periods per side; n = 128 keeps faces < 1.5 cm^2
    # and puts the crests (x, y = +-0.2, +-0.6 m) on grid vertices so the height is exact.
    k = 2 * np.pi * 2 / 1.6
    v, f = _height_field(128, 1.6, lambda x, y: np.sin(k * x) + np.sin(k * y), 0.5)
    return _oriented(v, f, _up)


@lru_cache(maxsize=None)
def _schwefel_geometry():
    # Fig. 6(b): 600 x 600 x 350 mm; the Schwefel function on its usual domain [-500, 500]^2.
    def schwefel(x, y):
        u, w = x / 0.6 * 1000, y / 0.6 * 1000
        return 418.9829 * 2 - u * np.sin(np.sqrt(np.abs(u))) - w * np.sin(np.sqrt(np.abs(w)))

    v, f = _height_field(128, 0.6, schwefel, 0.35)
    return _oriented(v, f, _up)


@lru_cache(maxsize=None)
def _concave_bowl_geometry():
    # Fig. 6(c): 1200 x 1200 x 530 mm paraboloid, cleaned on the inside (normals up).
    xy, f = _concentric_disc(96)
    xy = xy * 0.6
    z = 0.53 * (np.linalg.norm(xy, axis=1) / 0.6) ** 2
    return _oriented(np.column_stack([xy, z]), f, _up)


@lru_cache(maxsize=None)
def _hyperboloid_geometry():
    # Fig. 6(d): 1200 x 1200 x 412 mm one-sheet hyperboloid r(z) = a sqrt(1 + z^2 / c^2),
    # waist radius a = 0.4 m, end radius 0.6 m at z = +-0.206 m; cleaned on the outside.
    a, half_height, end_radius = 0.4, 0.206, 0.6
    c = half_height / np.sqrt((end_radius / a) ** 2 - 1)
    n_theta, n_z = 256, 49
    theta, z = np.meshgrid(np.linspace(0, 2 * np.pi, n_theta, endpoint=False),
                           np.linspace(-half_height, half_height, n_z), indexing="ij")
    r = a * np.sqrt(1 + (z / c) ** 2)
    v = np.stack([(r * np.cos(theta)).ravel(), (r * np.sin(theta)).ravel(), z.ravel()], 1)
    return _oriented(v, _grid_faces(n_theta, n_z, wrap_u=True), _radial)


@lru_cache(maxsize=None)
def _bowl_geometry():
    # Kabir IX-C plastic bowl, upside down so its convex outside is cleaned: 21.5 x 21.5 x
    # 9.5 cm (see module docstring for cm vs mm); flat-topped foot, steepening towards the
    # rim. n = 88 gives 15,488 triangles (paper: 15,644).
    radius, height = 0.1075, 0.095
    xy, f = _concentric_disc(88)
    rho = np.linalg.norm(xy, axis=1)
    z = height * (1 - rho**2.5)
    return _oriented(np.column_stack([xy * radius, z]), f, _up)


def _arc_length_resample(curve: np.ndarray, n: int) -> np.ndarray:
    """``n`` points evenly spaced along a dense polyline ``curve (m, d)``."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(curve, axis=0), axis=1))])
    t = np.linspace(0, s[-1], n)
    return np.stack([np.interp(t, s, curve[:, k]) for k in range(curve.shape[1])], axis=1)


@lru_cache(maxsize=None)
def _hull_geometry():
    # Kabir IX-C 3-D printed ship hull, resting keel-up on its deck: 20.1 x 18.0 x 14.0 cm.
    # "Convex, concave, and flat regions": flat bottom and sides, convex bilges, concave
    # fillets where a keel ridge meets the bottom, bow narrowing and rising. Open at the deck
    # and the transom. 100 x 116 vertices give 22,770 triangles (paper: 22,764).
    n_s, n_t = 100, 116
    length, beam, depth = 0.201, 0.180, 0.140
    phi = np.linspace(0, np.pi, 2001)
    stations = []
    for s in np.linspace(0, 1, n_s):  # s = 0 transom, s = 1 bow
        bow = max(0.0, (s - 0.55) / 0.45)
        half_beam = beam / 2 * (1 - 0.55 * bow**2)
        body_depth = 0.78 * depth * (1 - 0.25 * bow**2)
        # superellipse section (exponent 4): flat sides and bottom, rounded bilges
        y = half_beam * np.sign(np.cos(phi)) * np.abs(np.cos(phi)) ** 0.5
        z = body_depth * np.abs(np.sin(phi)) ** 0.5
        keel = 0.22 * depth * (1 - 0.5 * bow) * np.exp(-(y / (0.09 * beam)) ** 2)
        curve = np.stack([y, z + keel], axis=1)
        section = _arc_length_resample(curve, n_t)
        stations.append(np.column_stack([np.full(n_t, (s - 0.5) * length), section]))
    v = np.concatenate(stations)
    lo, hi = v.min(axis=0), v.max(axis=0)
    v = (v - lo) / (hi - lo) * np.array([length, beam, depth])  # exact paper extents

    def away_from_core(centres):
        core = np.zeros_like(centres)
        core[:, 0] = centres[:, 0]
        core[:, 1] = beam / 2
        return centres - core

    return _oriented(v, _grid_faces(n_s, n_t), away_from_core)


_GEOMETRY = {
    "sine": _sine_geometry,
    "schwefel": _schwefel_geometry,
    "concave_bowl": _concave_bowl_geometry,
    "hyperboloid": _hyperboloid_geometry,
    "bowl": _bowl_geometry,
    "hull": _hull_geometry,
}


# ---- stain ----------------------------------------------------------------------------------


def stain_from_field(mesh: trimesh.Trimesh, n_stain: int, rng: np.random.Generator,
                     *, pass_range: tuple[int, int] = (1, 3), n_blobs: tuple[int, int] = (2, 4)):
    """A stain of exactly ``n_stain`` faces: a smooth random field's top faces.

    Parameters
    ----------
    mesh : trimesh.Trimesh
    n_stain : int
        Number of stained faces k.
    rng : numpy.random.Generator
    pass_range : (int, int)
        Smallest and largest number of passes (within 1..3).
    n_blobs : (int, int)
        Range of the number of Gaussian blobs in the field.

    Returns
    -------
    stain_faces : (k,) int, sorted
    passes : (k,) int
    intensity : (k,) float in (0, 1]
        ``(f - f_k) / (f_max - f_k)`` with ``f_k`` the field just outside the stain; passes
        split (0, 1] into equal intensity bands.
    """
    n_faces = len(mesh.faces)
    n_stain = check_int("n_stain", n_stain, 1, n_faces - 1)
    centres = mesh.triangles_center
    diagonal = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    count = int(rng.integers(n_blobs[0], n_blobs[1] + 1))
    seeds = rng.choice(n_faces, size=count, replace=False, p=mesh.area_faces / mesh.area)
    weights = rng.uniform(0.6, 1.0, size=count)
    sigmas = diagonal * rng.uniform(0.06, 0.12, size=count)
    d2 = ((centres[:, None, :] - centres[seeds][None, :, :]) ** 2).sum(axis=2)
    field_values = (weights * np.exp(-d2 / (2 * sigmas**2))).sum(axis=1)
    order = np.argsort(-field_values, kind="stable")
    stain = np.sort(order[:n_stain])
    floor, top = field_values[order[n_stain]], field_values[order[0]]
    intensity = np.clip((field_values[stain] - floor) / (top - floor), 1e-6, 1.0)
    lo, hi = pass_range
    levels = hi - lo + 1
    passes = lo + np.minimum((intensity * levels).astype(np.int64), levels - 1)
    return stain, passes, intensity


def _build(name: str, seed: int, n_stain: int | None, pass_range, notes: str, stain_blobs=(2, 4)) -> Part:
    seed = check_int("seed", seed, 0, 2**63 - 1)
    if len(stain_blobs) != 2:
        raise ValueError(f"stain_blobs must be a (min, max) pair of blob counts, got {stain_blobs!r}")
    lo, hi = (check_int("stain_blobs", b, 1, 50) for b in stain_blobs)
    if lo > hi:
        raise ValueError(f"stain_blobs: min {lo} must be <= max {hi}")
    vertices, faces = _GEOMETRY[name]()
    mesh = trimesh.Trimesh(vertices.copy(), faces.copy(), process=False)
    rng = np.random.default_rng(seed)
    if n_stain is None:
        n_stain = int(rng.integers(SYNTHETIC_STAIN_RANGE[0], SYNTHETIC_STAIN_RANGE[1] + 1))
    stain, passes, intensity = stain_from_field(mesh, n_stain, rng, pass_range=pass_range, n_blobs=(lo, hi))
    return Part(name, mesh, stain, passes, intensity, notes)


def sine_part(seed: int = 0, *, stain_blobs=SYNTHETIC_STAIN_BLOBS) -> Part:
    """Kabir Fig. 6(a): sine surface 1.6 x 1.6 x 0.5 m, 32,768 faces < 1.5 cm^2.

    The stain has 4000-5000 faces (count drawn from ``seed``) needing 1-3 passes, in
    ``stain_blobs`` regions (:data:`SYNTHETIC_STAIN_BLOBS`).
    """
    return _build("sine", seed, None, (1, 3),
                  "Kabir Fig. 6(a): z = sin(kx) + sin(ky), two periods, scaled to 1.6 x 1.6 x 0.5 m", stain_blobs)


def schwefel_part(seed: int = 0, *, stain_blobs=SYNTHETIC_STAIN_BLOBS) -> Part:
    """Kabir Fig. 6(b): Schwefel surface 0.6 x 0.6 x 0.35 m, 32,768 faces < 1.5 cm^2.

    The stain has 4000-5000 faces (count drawn from ``seed``) needing 1-3 passes, in
    ``stain_blobs`` regions (:data:`SYNTHETIC_STAIN_BLOBS`).
    """
    return _build("schwefel", seed, None, (1, 3),
                  "Kabir Fig. 6(b): Schwefel function on [-500, 500]^2, scaled to 0.6 x 0.6 x 0.35 m", stain_blobs)


def concave_bowl_part(seed: int = 0, *, stain_blobs=SYNTHETIC_STAIN_BLOBS) -> Part:
    """Kabir Fig. 6(c): paraboloid bowl 1.2 x 1.2 x 0.53 m, cleaned inside, faces < 1.5 cm^2.

    The stain has 4000-5000 faces (count drawn from ``seed``) needing 1-3 passes, in
    ``stain_blobs`` regions (:data:`SYNTHETIC_STAIN_BLOBS`).
    """
    return _build("concave_bowl", seed, None, (1, 3),
                  "Kabir Fig. 6(c) ('Conic' in Table II): paraboloid, normals into the bowl", stain_blobs)


def hyperboloid_part(seed: int = 0, *, stain_blobs=SYNTHETIC_STAIN_BLOBS) -> Part:
    """Kabir Fig. 6(d): hyperboloid of one sheet 1.2 x 1.2 x 0.412 m, cleaned outside.

    Faces < 1.5 cm^2; the stain has 4000-5000 faces (count drawn from ``seed``) needing 1-3
    passes, in ``stain_blobs`` regions (:data:`SYNTHETIC_STAIN_BLOBS`).
    """
    return _build("hyperboloid", seed, None, (1, 3),
                  "Kabir Fig. 6(d): waist radius 0.4 m, end radius 0.6 m, normals outward", stain_blobs)


def bowl_part(seed: int = 0) -> Part:
    """Kabir IX-C plastic bowl, convex side up: 21.5 x 21.5 x 9.5 cm, triangles < 10 mm^2.

    Stain of 1000 triangles (paper) needing 2-3 passes ("three and two cleaning passes for
    setup 1 and all other setups"). Sizes are in cm although the paper prints mm (see the
    module docstring).
    """
    return _build("bowl", seed, BOWL_STAIN_FACES, (2, 3),
                  "Kabir IX-C bowl: paper prints 21.5 mm x 21.5 mm x 9.5 mm; we use cm")


def hull_part(seed: int = 0) -> Part:
    """Kabir IX-C 3-D printed ship hull, keel up: 20.1 x 18.0 x 14.0 cm, triangles < 10 mm^2.

    Stain of 5709 triangles (paper), one pass each ("it took a single cleaning pass for all
    the setups"). Sizes are in cm although the paper prints mm (see the module docstring).
    """
    return _build("hull", seed, HULL_STAIN_FACES, (1, 1),
                  "Kabir IX-C hull: paper prints 20.1 mm x 18.0 mm x 14.0 mm; we use cm")


_BUILDERS = {
    "sine": sine_part,
    "schwefel": schwefel_part,
    "concave_bowl": concave_bowl_part,
    "hyperboloid": hyperboloid_part,
    "bowl": bowl_part,
    "hull": hull_part,
}


def load_part(name: str, seed: int = 0, *, stain_blobs=None) -> Part:
    """The part called ``name`` (one of :data:`PART_NAMES`) with the stain of ``seed``.

    ``stain_blobs``: ``(min, max)`` Gaussian blobs of the stain field (synthetic objects only;
    default :data:`SYNTHETIC_STAIN_BLOBS`).
    """
    if name not in _BUILDERS:
        raise ValueError(f"name must be one of {PART_NAMES}, got {name!r}")
    if stain_blobs is None:
        return _BUILDERS[name](seed)
    if name not in SYNTHETIC_NAMES:
        raise ValueError(f"stain_blobs applies to the synthetic objects {SYNTHETIC_NAMES}, not {name!r}")
    return _BUILDERS[name](seed, stain_blobs=tuple(stain_blobs))


def part_from_mesh(mesh: trimesh.Trimesh, stain_faces, passes, name: str = "custom", *,
                   intensity=None, notes: str = "") -> Part:
    """Make a :class:`Part` from your own mesh and stain.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Metres (see :func:`mavac.geometry.mesh.load_mesh`), normals on the side to clean. It is
        copied and translated into the part frame (bounding-box bottom centre at the origin);
        the translation is kept in ``mesh.metadata["mavac_part_offset"]`` (subtracted).
    stain_faces : (k,) int
        Stained face indices.
    passes : (k,) int in 1..3
        Passes per stained face.
    name : str
    intensity : (k,) float in (0, 1], optional
        Defaults to ``passes / 3``.
    notes : str
    """
    check_mesh("mesh", mesh)
    passes_array = np.asarray(passes)
    if intensity is None:
        intensity = passes_array / 3.0
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    framed = _to_part_frame(vertices)
    copy = trimesh.Trimesh(framed, np.asarray(mesh.faces).copy(), process=False)
    copy.metadata["mavac_part_offset"] = vertices[0] - framed[0]
    return Part(name, copy, np.asarray(stain_faces), passes_array, intensity, notes)
