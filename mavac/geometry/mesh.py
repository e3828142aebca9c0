"""Reading a user's mesh file into metres, refusing what cannot be right, repairing the rest.

``load_mesh`` is the entry point for people who bring their own machine or part (MAVAC assumes
"at least a coarse representation of the machine", e.g. from photogrammetry). CAD exports are
often in millimetres or inches and contain degenerate or duplicated triangles; we convert,
check the size against what the object is (a machine or a part), repair what is safe to
repair, and say what we did (``warnings.warn`` and ``mesh.metadata["mavac_repairs"]``).

Size check. A unit mistake changes the size by a factor of 10-1000, so it is caught by the
size range of the object's role: a machine is about 0.3 m to 5 m across (MAVAC's test bench is
2 m, a wide-belt sander or bench mill about 1-1.5 m), a part about 2 cm to 2 m (Kabir's parts
run from a 20 cm ship hull to a 1.6 m sine surface). "Across" is the largest side of the
bounding box. Outside the range the file is refused, and the message names every unit under
which it would fall in range.
"""

from __future__ import annotations

import importlib.util
import math
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import trimesh

from ..validate import ParameterTypeError, check_path

#: metres per unit for the units ``load_mesh`` accepts
UNIT_SCALE = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
UNIT_WORDS = {"m": "metres", "cm": "centimetres", "mm": "millimetres", "in": "inches"}
#: file types handed to trimesh's loaders
MESH_SUFFIXES = (".stl", ".obj", ".ply", ".dae")
#: plausible size (largest bounding-box side, metres) of each role; ``None`` accepts either
ROLE_SIZES = {"machine": (0.3, 5.0), "part": (0.02, 2.0), None: (0.02, 5.0)}
ROLE_WORDS = {"machine": "a machine", "part": "a part", None: "a machine or a part"}


def _size_range(role) -> tuple[float, float]:
    if role not in ROLE_SIZES:
        raise ValueError(f"role must be 'machine', 'part' or None, got {role!r}")
    return ROLE_SIZES[role]


def units_in_range(extent_in_file_units: float, role=None) -> list[str]:
    """Units under which a mesh whose largest side is ``extent_in_file_units`` fits ``role``.

    Parameters
    ----------
    extent_in_file_units : float
        Largest bounding-box side, in the file's own numbers.
    role : {"machine", "part", None}

    Returns
    -------
    list of str
        Keys of :data:`UNIT_SCALE`, largest unit first.
    """
    lo, hi = _size_range(role)
    return [u for u, s in UNIT_SCALE.items() if lo <= extent_in_file_units * s <= hi]


def collada_unit(path) -> float | None:
    """Metres per unit declared by a COLLADA file's ``<asset><unit meter="..."/>``, or None
    (none declared, or XML the mesh reader will report); ValueError when the declared value is
    not a positive number."""
    try:
        for _, elem in ET.iterparse(str(path), events=("start",)):
            tag = elem.tag.rsplit("}", 1)[-1]
            if tag == "unit" and elem.get("meter") is not None:
                text = elem.get("meter")
                try:
                    meter = float(text)
                except ValueError:
                    meter = math.nan
                if not (np.isfinite(meter) and meter > 0):
                    raise ValueError(f"{Path(path).name} declares <unit meter=\"{text}\">, not a positive "
                                     "number of metres; pass units= (--units) to say the file's unit")
                return meter
            if tag in ("library_geometries", "library_visual_scenes"):
                return None  # <asset> comes first; stop before the bulk of the file
    except ET.ParseError:
        return None
    return None


def _unit_name(scale: float) -> str:
    for unit, s in UNIT_SCALE.items():
        if np.isclose(scale, s, rtol=1e-9):
            return unit
    return f"{scale:g} m"


def _read(path: Path) -> trimesh.Trimesh:
    try:
        loaded = trimesh.load(str(path), force="mesh", process=False)
    except Exception as exc:  # the loaders raise many types; one clear message for all
        hint = " (reading .dae needs the pycollada package)" if path.suffix.lower() == ".dae" and \
            importlib.util.find_spec("collada") is None else ""
        raise ValueError(f"path {str(path)!r} could not be read as a mesh{hint}: {exc}") from exc
    if not isinstance(loaded, trimesh.Trimesh):
        raise ValueError(f"path {str(path)!r} holds no triangle mesh (got {type(loaded).__name__})")
    return loaded


def local_origin(vertices) -> np.ndarray:
    """Whole-metre point nearest the centre of ``vertices``' bounding box, on z = 0, (3,) float:
    the origin of computations that must not depend on where the mesh sits in x and y.

    Embree (Open3D ray casting) takes float32, ~1 mm apart at 10 km, so vertices and ray origins
    are cast relative to it; voxel grids are anchored at it. Whole metres make moved copies of a
    mesh give the same float32 values and cells, and leave a mesh centred within half a metre of
    the world origin as it was.
    """
    v = np.asarray(vertices, dtype=np.float64)
    centre = np.round((v.min(axis=0) + v.max(axis=0)) / 2.0) if len(v) else np.zeros(3)
    return np.array([centre[0], centre[1], 0.0])  # z = 0: machines stand on the floor


def check_mesh(name: str, mesh) -> trimesh.Trimesh:
    """A ``trimesh.Trimesh`` with at least one face, finite vertices and faces that index
    them: the check every function taking a user's mesh runs first (``load_mesh`` refuses the
    same in files; a mesh built in memory has not been through it).

    Raises ``TypeError`` for another type, ``ValueError`` naming ``name`` otherwise.
    """
    if not isinstance(mesh, trimesh.Trimesh):
        raise ParameterTypeError(f"{name} must be a trimesh.Trimesh, got {type(mesh).__name__}")
    faces = np.asarray(mesh.faces)
    if len(faces) == 0:
        raise ValueError(f"{name} must have at least one face")
    vertices = np.asarray(mesh.vertices)
    bad = int((~np.isfinite(vertices)).any(axis=1).sum())
    if bad:
        raise ValueError(f"{name} has {bad} vertices with NaN or infinite coordinates")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise ValueError(f"{name} has faces indexing vertices outside [0, {len(vertices) - 1}]")
    return mesh


def _colors(mesh: trimesh.Trimesh) -> dict:
    """Per-vertex or per-face colours stored in the file (a stain can be painted on), if any."""
    kind = getattr(mesh.visual, "kind", None)
    if kind == "vertex":
        return {"vertex_colors": np.asarray(mesh.visual.vertex_colors)}
    if kind == "face":
        return {"face_colors": np.asarray(mesh.visual.face_colors)}
    return {}


def _keep_majority_orientation(mesh: trimesh.Trimesh, before: np.ndarray) -> np.ndarray:
    """After ``fix_winding``: in each connected sheet whose faces were mostly flipped, flip the
    sheet back, so the author's orientation survives where most faces agreed with it.

    Returns the (n,) bool mask of faces whose orientation differs from ``before``.
    """
    faces = np.asarray(mesh.faces)
    flipped = np.any(faces != before, axis=1)
    if not flipped.any():
        return flipped
    labels = np.zeros(len(faces), dtype=np.int64)
    for k, comp in enumerate(trimesh.graph.connected_components(mesh.face_adjacency,
                                                                 nodes=np.arange(len(faces)))):
        labels[comp] = k
    area = np.asarray(mesh.area_faces)
    share = np.bincount(labels, area * flipped) / np.maximum(np.bincount(labels, area), 1e-300)
    back = share[labels] > 0.5
    if back.any():
        new = faces.copy()
        new[back] = new[back][:, ::-1]
        mesh.faces = new
        flipped = np.any(np.asarray(mesh.faces) != before, axis=1)
    return flipped


def repair_mesh(mesh: trimesh.Trimesh) -> dict:
    """Remove degenerate and duplicate faces, merge coincident vertices, drop unused ones,
    make the winding consistent.

    Works in place on ``mesh``. Returns the counts ``{"degenerate_faces", "duplicate_faces",
    "merged_vertices", "unreferenced_vertices", "flipped_faces", "inverted"}`` and
    ``"watertight_as_loaded"`` (coincident vertices merged, before any face was removed).
    ``flipped_faces`` were turned over (not removed) to agree with their neighbours; in each
    connected sheet the orientation most of its area already had is kept. ``inverted`` is True
    when a closed mesh was inside out and has been turned so its normals point outward.
    """
    n_vertices = len(mesh.vertices)
    mesh.merge_vertices()
    merged = n_vertices - len(mesh.vertices)
    watertight_as_loaded = bool(mesh.is_watertight)  # before removing faces, which may open it
    keep = mesh.nondegenerate_faces()
    degenerate = int((~keep).sum())
    mesh.update_faces(keep)
    unique = mesh.unique_faces()
    duplicate = int((~unique).sum())
    mesh.update_faces(unique)
    n_vertices = len(mesh.vertices)
    mesh.remove_unreferenced_vertices()
    unreferenced = n_vertices - len(mesh.vertices)
    inverted, flipped = False, 0
    if len(mesh.faces):
        before = np.array(mesh.faces)
        trimesh.repair.fix_winding(mesh)
        flipped = int(_keep_majority_orientation(mesh, before).sum())
        if mesh.is_watertight and mesh.volume < 0:
            mesh.invert()
            inverted = True
    return {"degenerate_faces": degenerate, "duplicate_faces": duplicate,
            "merged_vertices": merged, "unreferenced_vertices": unreferenced,
            "flipped_faces": flipped, "inverted": inverted, "watertight_as_loaded": watertight_as_loaded}


def _resolve_units(path: Path, units):
    """Metres per unit and its name; COLLADA's own unit when ``units`` is None."""
    try:
        declared = collada_unit(path) if path.suffix.lower() == ".dae" else None
    except ValueError:  # a broken declaration: an error unless units says the unit
        if units is None:
            raise
        declared = None
    if units is None:
        scale = 1.0 if declared is None else declared
        return scale, _unit_name(scale)
    if units not in UNIT_SCALE:
        raise ValueError(f"units must be one of {sorted(UNIT_SCALE)} (or None), got {units!r}")
    if declared is not None and not np.isclose(declared, UNIT_SCALE[units], rtol=1e-6):
        warnings.warn(f"{path.name} declares <unit meter=\"{declared:g}\"> ({_unit_name(declared)}) but "
                      f"units='{units}' was passed; reading it in '{units}' as asked (pass units=None to "
                      "use the file's unit)", stacklevel=3)
    return UNIT_SCALE[units], units


def _check_size(path: Path, extent_file: float, scale: float, unit: str, role) -> None:
    lo, hi = _size_range(role)
    size = extent_file * scale
    if lo <= size <= hi:
        return
    fits = [u for u in units_in_range(extent_file, role) if u != unit]
    range_text = f"{ROLE_WORDS[role]} is expected to be {lo:g} m to {hi:g} m across"
    if fits:
        options = " or ".join(f"units='{u}' ({extent_file * UNIT_SCALE[u]:.3g} m)" for u in fits)
        hint = f"if the file is in {UNIT_WORDS[fits[0]]}, pass {options}" if len(fits) == 1 else \
            f"pass the file's unit: {options}"
    else:
        hint = "no unit (m, cm, mm, in) brings it into that range; check the export"
    raise ValueError(f"{path.name}: mesh is {size:.4g} m across after reading it in '{unit}', but "
                     f"{range_text}; {hint}")


def _warn_repairs(name: str, repairs: dict) -> None:
    removed = {k: repairs[k] for k in ("degenerate_faces", "duplicate_faces") if repairs[k]}
    if removed:
        warnings.warn(f"{name}: removed " + ", ".join(f"{v} {k.replace('_', ' ')}" for k, v in removed.items()),
                      stacklevel=3)
    if repairs["flipped_faces"]:
        what = (f"{name}: flipped {repairs['flipped_faces']} faces (turned over, not removed) so every face "
                "agrees with its neighbours")
        if not repairs["watertight"]:
            what += ("; the mesh is open, so which side is 'outward' was taken from the majority of each "
                     "sheet: normals-based stain selection (e.g. a normal cone 'up:30') uses these normals")
        warnings.warn(what, stacklevel=3)
    if repairs["inverted"]:
        warnings.warn(f"{name}: closed mesh was inside out; turned all its faces so normals point outward",
                      stacklevel=3)
    if not repairs["watertight_as_loaded"]:  # not when removing degenerate faces opened it
        warnings.warn(f"{name}: mesh is not watertight (open boundary or non-manifold edges); accepted, but "
                      "inside/outside tests on it are unreliable", stacklevel=3)


def load_mesh(path, units: str | None = None, *, role: str | None = None) -> trimesh.Trimesh:
    """Read an STL, OBJ, PLY or DAE file as one triangle mesh in metres.

    Parameters
    ----------
    path : str or Path
        Mesh file; a file with several bodies is concatenated into one mesh.
    units : {"m", "cm", "mm", "in"} or None
        Unit of the coordinates in the file; the result is always in metres. None: the unit a
        COLLADA file declares (``<unit meter=...>``), metres for every other file.
    role : {"machine", "part"} or None
        What the mesh is; sets the plausible size (largest bounding-box side): a machine 0.3-5 m,
        a part 0.02-2 m, None either (0.02-5 m).

    Returns
    -------
    trimesh.Trimesh
        Repaired mesh in metres. ``mesh.metadata["mavac_repairs"]`` holds the repair counts
        (see :func:`repair_mesh`) and ``"watertight"``; ``mesh.metadata["mavac_units"]`` the
        unit read and ``"mavac_scale"`` its metres per unit. Per-vertex or per-face colours in
        the file are kept (``mesh.visual``), e.g. for :func:`mavac.geometry.stain_marking.faces_from_colors`.

    Raises
    ------
    ValueError
        Unknown ``units`` or ``role``; missing file or unsupported type; a file with no faces;
        NaN or infinite coordinates; a size outside the role's range (the message names the
        units under which the file would be in range).

    Warns
    -----
    UserWarning
        When faces were removed or flipped (on an open mesh: that normals-based stain
        selection is affected), when a closed mesh was inside out, when it is not watertight
        (accepted: coarse scans often have holes), and when a COLLADA file declares a unit
        other than ``units``.
    """
    _size_range(role)
    path = check_path("path", path)
    if not path.is_file():
        raise ValueError(f"path {str(path)!r} does not exist or is not a file")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise ValueError(f"path {str(path)!r}: unsupported file type {path.suffix!r}; "
                         f"use one of {', '.join(MESH_SUFFIXES)}")
    scale, unit = _resolve_units(path, units)
    mesh = _read(path)
    if len(mesh.faces) == 0 or len(mesh.vertices) == 0:
        raise ValueError(f"mesh in {str(path)!r} is empty (no faces); export the surface again")
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    if not np.all(np.isfinite(vertices)):
        bad = int((~np.isfinite(vertices)).any(axis=1).sum())
        raise ValueError(f"mesh in {str(path)!r} has {bad} vertices with NaN or infinite "
                         "coordinates; repair the file in the exporting tool")
    _check_size(path, float(np.ptp(vertices, axis=0).max()), scale, unit, role)
    mesh = trimesh.Trimesh(vertices * scale, np.asarray(mesh.faces), process=False, **_colors(mesh))
    repairs = repair_mesh(mesh)
    if len(mesh.faces) == 0:
        raise ValueError(f"mesh in {str(path)!r} has only degenerate faces; export it again")
    repairs["watertight"] = bool(mesh.is_watertight)
    mesh.metadata.update(mavac_repairs=repairs, mavac_units=unit, mavac_scale=scale, file_path=str(path))
    _warn_repairs(path.name, repairs)
    return mesh
