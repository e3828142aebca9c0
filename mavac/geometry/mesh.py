"""Reading a user's mesh file into metres, refusing what cannot be right, repairing the rest.

``load_mesh`` is the entry point for people who bring their own machine or part (MAVAC assumes
"at least a coarse representation of the machine", e.g. from photogrammetry). CAD exports are
often in millimetres or inches and contain degenerate or duplicated triangles; we convert,
repair what is safe to repair, and say what we did (``warnings.warn`` and
``mesh.metadata["mavac_repairs"]``).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import trimesh

from ..validate import ParameterTypeError, check_path

#: metres per unit for the units ``load_mesh`` accepts
UNIT_SCALE = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
UNIT_WORDS = {"m": "metres", "cm": "centimetres", "mm": "millimetres", "in": "inches"}
#: file types handed to trimesh's loaders
MESH_SUFFIXES = (".stl", ".obj", ".ply", ".dae")
#: plausible size (bounding-box diagonal) of a machine or part, metres
MIN_SIZE = 1e-3
MAX_SIZE = 100.0


def _suggest_unit(diagonal_in_file_units: float) -> str | None:
    """The unit that makes the mesh a plausible size, closest to 1 m across."""
    best, best_score = None, np.inf
    for unit, scale in UNIT_SCALE.items():
        size = diagonal_in_file_units * scale
        if MIN_SIZE <= size <= MAX_SIZE:
            score = abs(np.log10(size))
            if score < best_score:
                best, best_score = unit, score
    return best


def _read(path: Path) -> trimesh.Trimesh:
    try:
        loaded = trimesh.load(str(path), force="mesh", process=False)
    except Exception as exc:  # the loaders raise many types; one clear message for all
        hint = " (reading .dae needs the pycollada package)" if path.suffix.lower() == ".dae" else ""
        raise ValueError(f"path {str(path)!r} could not be read as a mesh{hint}: {exc}") from exc
    if not isinstance(loaded, trimesh.Trimesh):
        raise ValueError(f"path {str(path)!r} holds no triangle mesh (got {type(loaded).__name__})")
    return loaded


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


def repair_mesh(mesh: trimesh.Trimesh) -> dict:
    """Remove degenerate and duplicate faces, merge coincident vertices, drop unused ones,
    make the winding consistent.

    Works in place on ``mesh``. Returns the counts ``{"degenerate_faces", "duplicate_faces",
    "merged_vertices", "unreferenced_vertices", "rewound_faces", "inverted"}``;
    ``rewound_faces`` were flipped to agree with their neighbours, ``inverted`` is True when a
    closed mesh was inside out and has been flipped so its normals point outward.
    """
    n_vertices = len(mesh.vertices)
    mesh.merge_vertices()
    merged = n_vertices - len(mesh.vertices)
    keep = mesh.nondegenerate_faces()
    degenerate = int((~keep).sum())
    mesh.update_faces(keep)
    unique = mesh.unique_faces()
    duplicate = int((~unique).sum())
    mesh.update_faces(unique)
    n_vertices = len(mesh.vertices)
    mesh.remove_unreferenced_vertices()
    unreferenced = n_vertices - len(mesh.vertices)
    inverted, rewound = False, 0
    if len(mesh.faces):
        before = np.array(mesh.faces)
        trimesh.repair.fix_winding(mesh)
        rewound = int(np.any(np.asarray(mesh.faces) != before, axis=1).sum())
        if mesh.is_watertight and mesh.volume < 0:
            mesh.invert()
            inverted = True
    return {"degenerate_faces": degenerate, "duplicate_faces": duplicate,
            "merged_vertices": merged, "unreferenced_vertices": unreferenced,
            "rewound_faces": rewound, "inverted": inverted}


def load_mesh(path, units: str = "m") -> trimesh.Trimesh:
    """Read an STL, OBJ, PLY or DAE file as one triangle mesh in metres.

    Parameters
    ----------
    path : str or Path
        Mesh file; a file with several bodies is concatenated into one mesh.
    units : {"m", "cm", "mm", "in"}
        Unit of the coordinates in the file; the result is always in metres.

    Returns
    -------
    trimesh.Trimesh
        Repaired mesh in metres. ``mesh.metadata["mavac_repairs"]`` holds the repair counts
        (see :func:`repair_mesh`) and ``"watertight"``; ``mesh.metadata["mavac_units"]`` the
        unit read.

    Raises
    ------
    ValueError
        Unknown ``units``; missing file or unsupported type; a file with no faces; NaN or
        infinite coordinates; a size implausible for ``units`` (bounding-box diagonal outside
        [1 mm, 100 m] after conversion; the message names the unit that would fit).

    Warns
    -----
    UserWarning
        When faces were removed or rewound, when a closed mesh was inside out, and when it is
        not watertight (accepted: coarse scans often have holes).
    """
    if units not in UNIT_SCALE:
        raise ValueError(f"units must be one of {sorted(UNIT_SCALE)}, got {units!r}")
    path = check_path("path", path)
    if not path.is_file():
        raise ValueError(f"path {str(path)!r} does not exist or is not a file")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise ValueError(f"path {str(path)!r}: unsupported file type {path.suffix!r}; "
                         f"use one of {', '.join(MESH_SUFFIXES)}")
    mesh = _read(path)
    if len(mesh.faces) == 0 or len(mesh.vertices) == 0:
        raise ValueError(f"mesh in {str(path)!r} is empty (no faces); export the surface again")
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    if not np.all(np.isfinite(vertices)):
        bad = int((~np.isfinite(vertices)).any(axis=1).sum())
        raise ValueError(f"mesh in {str(path)!r} has {bad} vertices with NaN or infinite "
                         "coordinates; repair the file in the exporting tool")
    diagonal = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    size = diagonal * UNIT_SCALE[units]
    if not MIN_SIZE <= size <= MAX_SIZE:
        fit = _suggest_unit(diagonal)
        hint = (f"if the file is in {UNIT_WORDS[fit]} pass units='{fit}'" if fit and fit != units
                else f"expected between {MIN_SIZE * 1000:g} mm and {MAX_SIZE:g} m")
        raise ValueError(f"mesh is {size:.4g} m across after reading it in '{units}'; {hint}")
    mesh = trimesh.Trimesh(vertices * UNIT_SCALE[units], np.asarray(mesh.faces), process=False)
    repairs = repair_mesh(mesh)
    if len(mesh.faces) == 0:
        raise ValueError(f"mesh in {str(path)!r} has only degenerate faces; export it again")
    repairs["watertight"] = bool(mesh.is_watertight)
    mesh.metadata["mavac_repairs"] = repairs
    mesh.metadata["mavac_units"] = units
    mesh.metadata["file_path"] = str(path)
    fixed = {k: repairs[k] for k in ("degenerate_faces", "duplicate_faces", "rewound_faces")
             if repairs[k]}
    if fixed:
        warnings.warn(f"{path.name}: removed " + ", ".join(f"{v} {k.replace('_', ' ')}"
                                                           for k, v in fixed.items()),
                      stacklevel=2)
    if repairs["inverted"]:
        warnings.warn(f"{path.name}: closed mesh was inside out; flipped its normals outward",
                      stacklevel=2)
    if not repairs["watertight"]:
        warnings.warn(f"{path.name}: mesh is not watertight (open boundary or non-manifold "
                      "edges); accepted, but inside/outside tests on it are unreliable",
                      stacklevel=2)
    return mesh
