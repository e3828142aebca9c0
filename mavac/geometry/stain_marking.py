"""Marking a stain on your own part: which faces are stained, how many passes each needs.

Kabir et al. clean a stain made of triangular patches p_i, each needing N_i passes (Sec. III),
and pose "the constraint that surface area of the patch needs to be smaller than the surface
area of the cleaning tool tip" (Sec. IV); their synthetic patches are under 1.5 cm^2 (Sec. IX-A).
A part exported from CAD has no stain and often large triangles, so this module

* selects faces by an explicit mask or index list, a normal cone ("faces within 30 deg of up"),
  a box or a sphere (face centres), or the colours painted in the file (per-vertex or per-face);
  selectors of one kind are united, different kinds intersected;
* gives each stained face its passes from a constant or from an intensity in (0, 1]
  (1-3 passes in equal intensity bands, as :func:`mavac.geometry.parts.stain_from_field`);
* warns when stained triangles are larger than the tool tip, and optionally splits them
  (each split turns a triangle into four; the neighbours are left as they are, so the mesh gains
  T-junctions, which neither the reach test nor ray casting minds).

:func:`mark_stain` returns a :class:`mavac.geometry.parts.Part` ready for
:func:`mavac.setups.setup_plan.plan_setups`; :func:`parse_stain` reads the command line's ``--stain``.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import trimesh

from ..validate import (check_array, check_bool_array, check_indices, check_int, check_points, check_positive,
                        check_range, check_size)
from .mesh import check_mesh
from .parts import SYNTHETIC_MAX_FACE_AREA, Part, part_from_mesh

#: largest patch area before a warning, m^2: Kabir IX-A, "less than 1.5 cm^2"
TOOL_TIP_AREA = SYNTHETIC_MAX_FACE_AREA
#: named directions for normal cones (``"up:30"``)
DIRECTIONS = {"up": (0, 0, 1), "down": (0, 0, -1), "+x": (1, 0, 0), "-x": (-1, 0, 0), "x": (1, 0, 0),
              "+y": (0, 1, 0), "-y": (0, -1, 0), "y": (0, 1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1),
              "z": (0, 0, 1)}


def _mesh(mesh) -> trimesh.Trimesh:
    return check_mesh("mesh", mesh)


def faces_in_cone(mesh, direction=(0.0, 0.0, 1.0), angle_deg: float = 30.0) -> np.ndarray:
    """Faces whose normal is within ``angle_deg`` of ``direction``, (n_faces,) bool."""
    check_range("angle_deg", angle_deg, 0.0, 180.0)
    d = check_points("direction", direction)[0]
    norm = float(np.linalg.norm(d))
    if norm < 1e-12:
        raise ValueError("direction must be a non-zero vector")
    cos = np.asarray(_mesh(mesh).face_normals) @ (d / norm)
    return cos >= math.cos(math.radians(angle_deg)) - 1e-12


def faces_in_box(mesh, lower, upper) -> np.ndarray:
    """Faces whose centre lies in the axis-aligned box ``[lower, upper]`` (metres), (n_faces,) bool."""
    lo, hi = check_points("lower", lower)[0], check_points("upper", upper)[0]
    if np.any(lo > hi):
        raise ValueError(f"box: lower {lo.tolist()} must be <= upper {hi.tolist()} on every axis")
    c = np.asarray(_mesh(mesh).triangles_center)
    return np.all((c >= lo) & (c <= hi), axis=1)


def faces_in_sphere(mesh, centre, radius: float) -> np.ndarray:
    """Faces whose centre lies within ``radius`` (metres) of ``centre``, (n_faces,) bool."""
    check_positive("radius", radius)
    c = check_points("centre", centre)[0]
    return np.linalg.norm(np.asarray(_mesh(mesh).triangles_center) - c, axis=1) <= radius


def face_colors(mesh) -> np.ndarray | None:
    """(n_faces, 3) float RGB in [0, 1] painted in the file (vertex colours averaged), or None."""
    kind = getattr(_mesh(mesh).visual, "kind", None)
    if kind == "vertex":
        rgb = np.asarray(mesh.visual.vertex_colors, dtype=float)[:, :3] / 255.0
        return rgb[np.asarray(mesh.faces)].mean(axis=1)
    if kind == "face":
        return np.asarray(mesh.visual.face_colors, dtype=float)[:, :3] / 255.0
    return None


def faces_from_colors(mesh, stain_color=None, tolerance: float = 0.25):
    """Stained faces and their intensity from the colours painted in the file.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        With per-vertex or per-face colours (PLY, OBJ; kept by
        :func:`mavac.geometry.mesh.load_mesh`).
    stain_color : (3,) float in [0, 1], optional
        The stain's colour: faces within ``tolerance`` (RGB distance) of it are stained. Default:
        split the face colours in two with K-means (Kabir Sec. VII) and take the darker cluster as
        the stain (Kabir's convention for a dark stain on a light part).
    tolerance : float
        RGB distance for ``stain_color``.

    Returns
    -------
    stained : (n_faces,) bool
    intensity : (n_faces,) float in [0, 1]
        How far each face's colour has moved from the clean colour towards the stain's
        (1 at the most stain-like face), 0 off the stain.
    """
    rgb = face_colors(mesh)
    if rgb is None:
        raise ValueError("the mesh has no per-vertex or per-face colours; select the stain with a mask, "
                         "a normal cone, a box or a sphere instead")
    check_positive("tolerance", tolerance)
    if stain_color is None:
        from sklearn.cluster import KMeans

        if len(np.unique(np.round(rgb, 6), axis=0)) < 2:
            raise ValueError("every face has the same colour: no painted stain to find")
        km = KMeans(n_clusters=2, n_init=10, random_state=0).fit(rgb)
        centres = km.cluster_centers_
        stain_k = int(np.argmin(np.linalg.norm(centres, axis=1)))
        stained = km.labels_ == stain_k
        stain_c, clean_c = centres[stain_k], centres[1 - stain_k]
    else:
        stain_c = check_points("stain_color", stain_color)[0]
        stained = np.linalg.norm(rgb - stain_c, axis=1) <= tolerance
        clean_c = rgb[~stained].mean(axis=0) if (~stained).any() else 1.0 - stain_c
    span = clean_c - stain_c
    t = np.clip(((clean_c - rgb) @ span) / max(float(span @ span), 1e-12), 0.0, 1.0)
    intensity = np.where(stained, t / max(float(t[stained].max()), 1e-12) if stained.any() else 0.0, 0.0)
    return stained, intensity


def passes_from_intensity(intensity, pass_range=(1, 3)) -> np.ndarray:
    """Passes in ``pass_range`` from intensities in (0, 1]: equal intensity bands
    (the convention of :func:`mavac.geometry.parts.stain_from_field`)."""
    if np.shape(pass_range) != (2,):
        raise ValueError(f"pass_range must be a pair (low, high), got {pass_range!r}")
    lo, hi = (check_int("pass_range", v, 1, 3) for v in pass_range)
    if not lo <= hi:
        raise ValueError(f"pass_range must satisfy 1 <= low <= high <= 3, got {pass_range!r}")
    x = check_array("intensity", intensity, float)
    if not np.all((x > 0) & (x <= 1)):
        raise ValueError("intensity must be in (0, 1] on every stained face")
    levels = hi - lo + 1
    return lo + np.minimum((x * levels).astype(np.int64), levels - 1)


def oversized_patches(areas, max_area: float = TOOL_TIP_AREA) -> str | None:
    """A warning text when stain patches are larger than ``max_area`` (m^2), else None."""
    a = np.asarray(areas, dtype=float)
    big = a > max_area
    if not big.any():
        return None
    return (f"{int(big.sum())} of {len(a)} stain patches are larger than the tool tip "
            f"({max_area * 1e4:.3g} cm^2; Kabir's patches are under 1.5 cm^2), the largest "
            f"{a.max() * 1e4:.3g} cm^2: a patch counts as cleaned only when the tool reaches all three "
            "corners, so large patches make reach and time coarse; split them (subdivide=True, "
            "or --subdivide on the command line)")


#: Faces a subdivision may create: ~50 times the largest of our parts (hull, 22,770 faces, x 4 per
#: round where needed); a tiny ``max_area`` would otherwise exhaust memory (each round quadruples).
MAX_SUBDIVIDED_FACES = 1_000_000


def _check_subdivision_size(areas: np.ndarray, max_area: float, max_rounds: int) -> None:
    rounds = np.clip(np.ceil(np.log(np.maximum(areas / max_area, 1.0)) / np.log(4.0)), 0, max_rounds)
    check_size("max_area", max_area, float(np.sum(4.0 ** rounds)), MAX_SUBDIVIDED_FACES, "faces")


def subdivide_faces(mesh, stained, max_area: float = TOOL_TIP_AREA, max_rounds: int = 8):
    """Split stained faces into four until none is larger than ``max_area``.

    Parameters
    ----------
    mesh : trimesh.Trimesh
    stained : (n_faces,) bool
    max_area : float, m^2
    max_rounds : int
        Each round quarters the area; 8 rounds divide it by 65,536.

    Returns
    -------
    mesh : trimesh.Trimesh
        New mesh; unstained faces keep their indices, children are appended.
    parent : (n_new_faces,) int
        Original face of every face of the new mesh.
    """
    check_positive("max_area", max_area)
    max_rounds = check_int("max_rounds", max_rounds, 0)
    mesh = _mesh(mesh)
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    parent = np.arange(len(faces))
    stained = check_bool_array("stained", stained).copy()
    if stained.shape != (len(faces),):
        raise ValueError(f"stained must have shape ({len(faces)},), got {stained.shape}")
    _check_subdivision_size(np.asarray(mesh.area_faces)[stained], max_area, max_rounds)
    for _ in range(max_rounds):
        area = trimesh.triangles.area(vertices[faces])
        split = np.flatnonzero(stained & (area > max_area))
        if len(split) == 0:
            break
        vertices, faces, index = trimesh.remesh.subdivide(vertices, faces, face_index=split, return_index=True)
        new_parent = np.empty(len(faces), dtype=np.int64)
        new_stained = np.zeros(len(faces), dtype=bool)
        keep = np.setdiff1d(np.arange(len(parent)), split)
        new_parent[: len(keep)] = parent[keep]
        new_stained[: len(keep)] = stained[keep]
        for old, new in index.items():
            new_parent[new] = parent[old]
            new_stained[new] = True
        parent, stained = new_parent, new_stained
    return trimesh.Trimesh(vertices, faces, process=False), parent


def _selectors(value) -> list:
    """One cone, box or sphere (its first item a 3-vector), or a list of them, as a list."""
    single = len(value) == 2 and len(value[0]) == 3 and all(np.isscalar(c) for c in value[0])
    return [value] if single else list(value)


def _selection(mesh, faces, cone, box, sphere, colors):
    """AND of the given kinds of selector (OR within a kind), and the intensity the colours give (or None)."""
    n = len(mesh.faces)
    mask = np.ones(n, dtype=bool)
    intensity = None
    if faces is not None:
        sel = np.zeros(n, dtype=bool)
        sel[check_indices("faces", faces, n)] = True
        mask &= sel
    for value, select in ((cone, faces_in_cone), (box, faces_in_box), (sphere, faces_in_sphere)):
        if value is not None:
            mask &= np.logical_or.reduce([select(mesh, *v) for v in _selectors(value)])
    if colors is not None:
        stained, intensity = faces_from_colors(mesh, **(colors or {}))
        mask &= stained
    if all(v is None for v in (faces, cone, box, sphere, colors)):
        raise ValueError("give at least one stain selector: faces, cone, box, sphere or colors")
    return mask, intensity


def _face_values(name, values, mask, n):
    """Per-stained-face values from a scalar, an (n_faces,) or a (k,) array."""
    v = check_array(name, values, float)
    k = int(mask.sum())
    if v.ndim == 0:
        return np.full(k, float(v))
    if v.shape == (n,):
        return v[mask]
    if v.shape == (k,):
        return v
    raise ValueError(f"{name} must be a number, an ({n},) array over all faces or a ({k},) array over "
                     f"the stained faces, got shape {v.shape}")


def mark_stain(mesh, *, faces=None, cone=None, box=None, sphere=None, colors=None, passes=None,
               intensity=None, pass_range=(1, 3), subdivide: bool = False,
               max_patch_area: float = TOOL_TIP_AREA, name: str = "part") -> Part:
    """A :class:`~mavac.geometry.parts.Part` whose stain is the faces the selectors pick.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The part, metres (see :func:`mavac.geometry.mesh.load_mesh` with ``role="part"``).
    faces : (n_faces,) bool or (k,) int, optional
        Explicit stained faces.
    cone : (direction (3,), angle_deg), or a list of them (their union), optional
        Faces whose outward normal is within the angle of the direction (``((0, 0, 1), 30)``:
        "faces within 30 deg of up").
    box : (lower (3,), upper (3,)), or a list of them (their union), optional, metres
        Faces whose centre is in the box.
    sphere : (centre (3,), radius), or a list of them (their union), optional, metres
        Faces whose centre is in the sphere.
    colors : dict or {}, optional
        Stain from the colours in the file; keyword arguments of :func:`faces_from_colors`
        (``{}`` for the automatic two-colour split).
    passes : int or array, optional
        Passes (1-3): a constant, or per face. Default: from ``intensity``, else from the colours,
        else 1.
    intensity : float or array in (0, 1], optional
        Stain intensity per face (all faces or stained faces); passes come from it in equal bands
        of ``pass_range``.
    subdivide : bool
        Split stained faces larger than ``max_patch_area`` (each split makes four).
    max_patch_area : float, m^2
        Tool-tip area; default 1.5 cm^2 (Kabir IX-A).
    name : str

    Returns
    -------
    Part
        In the part frame (see :func:`mavac.geometry.parts.part_from_mesh`).

    Warns
    -----
    UserWarning
        When stained faces are larger than ``max_patch_area`` and ``subdivide`` is False.
    """
    mesh = _mesh(mesh)
    check_positive("max_patch_area", max_patch_area)
    n = len(mesh.faces)
    mask, color_intensity = _selection(mesh, faces, cone, box, sphere, colors)
    if not mask.any():
        raise ValueError("the stain selectors picked no face; widen the cone, box or sphere")
    if mask.all():
        raise ValueError("the stain selectors picked every face; a part needs some unstained surface")
    if intensity is None and passes is None and color_intensity is not None:
        intensity = np.maximum(color_intensity, 1e-6)
    inten = None if intensity is None else _face_values("intensity", intensity, mask, n)
    if passes is not None:
        p = _face_values("passes", passes, mask, n)
        if not np.all(np.isin(p, (1, 2, 3))):
            raise ValueError("passes must be integers in 1..3")
        p = p.astype(np.int64)
    elif inten is not None:
        p = passes_from_intensity(inten, pass_range)
    else:
        p = np.ones(int(mask.sum()), dtype=np.int64)
    if inten is None:
        inten = p / 3.0
    stain = np.flatnonzero(mask)
    if subdivide:
        full_p = np.zeros(n, dtype=np.int64)
        full_i = np.zeros(n)
        full_p[stain], full_i[stain] = p, inten
        mesh, parent = subdivide_faces(mesh, mask, max_patch_area)
        stain = np.flatnonzero(mask[parent])
        p, inten = full_p[parent][stain], full_i[parent][stain]
    else:
        message = oversized_patches(np.asarray(mesh.area_faces)[stain], max_patch_area)
        if message:
            warnings.warn(f"{name}: {message}", stacklevel=2)
    return part_from_mesh(mesh, stain, p, name, intensity=inten)


#: how a stain spec is written (``--help`` and error messages)
STAIN_GRAMMAR = ("up:30, down:45, +x:20 (also -x, +y, -y, +z, -z; x = +x), a direction vector x,y,z:30, "
                 "box:x0,y0,z0,x1,y1,z1, sphere:x,y,z,r, colors, colors:#rrggbb or faces:i,j,k; join several "
                 "with ',' (selectors of one kind are united, different kinds intersected)")
_ARITY = {"box": 6, "sphere": 4}


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _vector_end(tokens: list[str], j: int) -> bool:
    """Whether tokens j, j+1, j+2 are a direction vector with its angle (``0,0,1:30``)."""
    return (j + 2 < len(tokens) and _number(tokens[j]) and _number(tokens[j + 1])
            and ":" in tokens[j + 2] and _number(tokens[j + 2].partition(":")[0]))


def _stain_selectors(spec: str) -> list[tuple[str, list[str], str]]:
    """Split a spec at its joining commas: (kind, arguments, text) per selector; a cone's
    arguments are its direction's three components and its angle (empty for the default)."""
    tokens = [t.strip() for t in str(spec).split(",")]
    out, i = [], 0
    while i < len(tokens):
        start = i
        kind, _, first = tokens[i].partition(":")
        kind, i = kind.lower(), i + 1
        if kind in _ARITY:
            args, i = [first, *tokens[i:i + _ARITY[kind] - 1]], i + _ARITY[kind] - 1
        elif kind == "faces":
            args = [first]
            while i < len(tokens) and tokens[i].isdigit() and not _vector_end(tokens, i):
                args, i = [*args, tokens[i]], i + 1
        elif kind in DIRECTIONS:
            kind, args = "cone", [*map(str, DIRECTIONS[kind]), first]
        elif _number(kind):  # a direction vector: its angle follows the third component
            last, _, angle = (tokens[i + 1] if i + 1 < len(tokens) else "").partition(":")
            kind, args, i = "cone", [tokens[i - 1], tokens[i] if i < len(tokens) else "", last, angle], i + 2
        else:
            args = [first] if first else []
        out.append((kind, args, ",".join(tokens[start:i])))
    return out


def _stain_value(kind: str, args: list[str], scale: float):
    """(keyword of :func:`mark_stain`, value) of one selector; ValueError if malformed."""
    if kind == "cone":
        return "cone", (tuple(float(v) for v in args[:3]), float(args[3]) if args[3] else 30.0)
    if kind in _ARITY and len(args) == _ARITY[kind]:
        v = [float(x) * scale for x in args]
        return kind, ((v[:3], v[3:]) if kind == "box" else (v[:3], v[3]))
    if kind == "colors" and len(args) <= 1:
        return "colors", {"stain_color": _hex_rgb(args[0])} if args else {}
    if kind == "faces":
        ids = [int(x) for x in args]
        if max(ids) >= 2 ** 62:  # beyond any mesh; numpy would raise OverflowError
            raise ValueError(f"stain spec faces: index {max(ids)} is beyond any mesh's faces")
        return "faces", np.array(ids, dtype=np.int64)
    raise ValueError


def parse_stain(spec: str, scale: float = 1.0) -> dict:
    """Keyword arguments of :func:`mark_stain` from a command-line stain spec.

    A spec is selectors joined with ``,`` (:data:`STAIN_GRAMMAR`): a normal cone ``up:30`` (or
    ``down``, ``+x`` ... ``-z``, ``x``, or a vector ``x,y,z:30``; the half-angle in degrees,
    default 30), ``box:x0,y0,z0,x1,y1,z1``, ``sphere:x,y,z,r``, ``colors`` or
    ``colors:#rrggbb``, ``faces:i,j,k``. Selectors of one kind are united (``up:30,down:30``:
    top and bottom), different kinds intersected (``up:30,box:...``: the top inside the box).
    Whole numbers after ``faces:`` are face indices, so a direction vector there needs its angle.
    Lengths are in the file's units and multiplied by ``scale`` (metres per unit).
    """
    out: dict = {}
    for kind, args, text in _stain_selectors(spec):
        try:
            key, value = _stain_value(kind, args, scale)
        except ValueError as exc:
            if str(exc).startswith("stain spec"):
                raise
            raise ValueError(f"stain spec {text!r} not understood; use {STAIN_GRAMMAR}") from None
        if key == "colors" and key in out:
            raise ValueError("stain spec: give colors once")
        out.setdefault(key, []).append(value)
    return {k: v[0] if len(v) == 1 else (np.concatenate(v) if k == "faces" else v) for k, v in out.items()}


def _hex_rgb(text: str) -> tuple[float, float, float]:
    h = text.strip().lstrip("#")
    if len(h) != 6:
        raise ValueError
    return tuple(int(h[i:i + 2], 16) / 255.0 for i in (0, 2, 4))
