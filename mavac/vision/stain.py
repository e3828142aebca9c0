"""Stain perception (Kabir et al., Sec. VII, Figs. 4-5).

* :func:`render_stain_image` -- our stand-in for the camera: an orthographic render of the
  per-triangle stain intensity over the part colour, with pixel noise (trimesh/embree rays,
  one batched cast for all pixels). Flat albedo, no lighting.
* :func:`stain_mask_kmeans` / :func:`stain_masks_kmeans` -- binary stain masks by 2-cluster
  K-means on RGB pixels (Sec. VII).
* :func:`cleaning_performance` -- ``C_p = (N_p^- - N_p^+) / (I_h I_w)`` (Sec. VII).
* :func:`passes_from_image` -- pixelwise vector quantisation into ``N_c`` colours mapped to
  0..N_c-1 cleaning passes by RGB norm (Fig. 5).

Images are ``(H, W, 3)`` RGB, uint8 or float in [0, 1] (:func:`check_image` converts the
float ones explicitly and refuses any other dtype, range or shape).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import trimesh
from sklearn.cluster import KMeans

from ..geometry.mesh import check_mesh
from ..parallel import single_thread
from ..validate import (check_array, check_bool_array, check_indices, check_int, check_nonnegative,
                        check_points, check_range, check_size)


#: Pixels a rendered image may have: 4096 x 4096, 1000 times the 128 x 128 images we measure
#: with (one ray per pixel; ~17 M rays already take tens of seconds).
MAX_PIXELS = 4096 * 4096


@dataclass(frozen=True)
class OrthoView:
    """Orthographic camera: looks along ``direction``; the image is centred on ``center``
    and spans ``width`` x ``height`` metres (image x along ``right``, rows downward)."""

    direction: tuple
    center: tuple
    width: float
    height: float

    def basis(self):
        """Unit ``(direction, right, down)`` vectors of the image plane, each (3,)."""
        d = np.asarray(self.direction, dtype=float)
        d = d / np.linalg.norm(d)
        helper = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
        right = np.cross(d, helper)
        right /= np.linalg.norm(right)
        down = np.cross(d, right)
        return d, right, down


def view_of_faces(mesh: trimesh.Trimesh, faces=None, *, direction=None, margin: float = 0.05) -> OrthoView:
    """Orthographic view framing ``faces`` (default all) seen along ``direction``.

    Parameters
    ----------
    mesh : trimesh.Trimesh
    faces : (k,) int, optional
        Faces to frame; default every face.
    direction : (3,) float, optional
        Viewing direction; default minus the area-weighted mean normal of ``faces`` (the
        camera faces the stain), falling back to looking down -z.
    margin : float
        Relative margin around the projected bounding box.
    """
    check_mesh("mesh", mesh)
    faces = np.arange(len(mesh.faces)) if faces is None else check_indices("faces", faces, len(mesh.faces))
    if faces.size == 0:
        raise ValueError("faces must select at least one face to frame")
    if direction is None:
        mean_normal = (mesh.face_normals[faces] * mesh.area_faces[faces, None]).sum(axis=0)
        n = np.linalg.norm(mean_normal)
        direction = -mean_normal / n if n > 1e-9 else np.array([0.0, 0.0, -1.0])
    direction = check_points("direction", direction, 3)[0]
    if np.linalg.norm(direction) < 1e-12:
        raise ValueError("direction must be a non-zero vector")
    check_nonnegative("margin", margin)
    probe = OrthoView(tuple(direction), (0.0, 0.0, 0.0), 1.0, 1.0)
    _, right, down = probe.basis()
    pts = mesh.vertices[np.unique(mesh.faces[faces])]
    u, w = pts @ right, pts @ down
    centre_uw = np.array([u.min() + u.max(), w.min() + w.max()]) / 2
    centroid = pts.mean(axis=0)
    centre = centroid + (centre_uw[0] - centroid @ right) * right + (centre_uw[1] - centroid @ down) * down
    width = max(np.ptp(u), 1e-6) * (1 + 2 * margin)
    height = max(np.ptp(w), 1e-6) * (1 + 2 * margin)
    return OrthoView(tuple(direction), tuple(centre), float(width), float(height))


def face_index_image(mesh: trimesh.Trimesh, view, image_size=(96, 96)) -> np.ndarray:
    """Index of the first face hit by each pixel's ray (``-1`` for background).

    Parameters
    ----------
    mesh : trimesh.Trimesh
    view : OrthoView or (3,) float viewing direction (then the whole mesh is framed)
    image_size : (int, int)
        ``(H, W)`` pixels.

    Returns
    -------
    (H, W) int
    """
    check_mesh("mesh", mesh)
    view = view if isinstance(view, OrthoView) else view_of_faces(mesh, direction=view, margin=0.02)
    if np.shape(image_size) != (2,):
        raise ValueError(f"image_size must be a pair (H, W) of pixel counts, got {image_size!r}")
    H, W = (check_int("image_size", s, 1) for s in image_size)
    check_size("image_size", image_size, H * W, MAX_PIXELS, "pixels (one ray each)")
    d, right, down = view.basis()
    center = np.asarray(view.center, dtype=float)
    # Pixel centres, image aspect follows the pixel grid; square pixels covering the view.
    pixel = max(view.width / W, view.height / H)
    cols = (np.arange(W) - (W - 1) / 2) * pixel
    rows = (np.arange(H) - (H - 1) / 2) * pixel
    uu, ww = np.meshgrid(cols, rows)
    back = float(np.ptp(mesh.vertices @ d)) + np.abs((mesh.vertices - center) @ d).max() + 1.0
    origins = center + uu.reshape(-1, 1) * right + ww.reshape(-1, 1) * down - back * d
    directions = np.broadcast_to(d, origins.shape)
    hit = mesh.ray.intersects_first(ray_origins=origins, ray_directions=directions)
    return np.asarray(hit, dtype=int).reshape(H, W)


def _rgb(name: str, colour) -> np.ndarray:
    c = np.asarray(colour, dtype=float).reshape(-1)
    if c.shape != (3,) or np.any(c < 0) or np.any(c > 1):
        raise ValueError(f"{name} must be 3 RGB values in [0, 1], got {colour!r}")
    return c


#: Ours: the default colours of :func:`render_stain_image`, RGB in [0, 1]: a brown stain on an
#: off-white part, black background.
STAIN_RGB = (0.35, 0.22, 0.12)
PART_RGB = (0.92, 0.92, 0.88)
BACKGROUND_RGB = (0.0, 0.0, 0.0)


def render_stain_image(mesh: trimesh.Trimesh, face_stain, view, *, image_size=(96, 96),
                       stain_rgb=STAIN_RGB, part_rgb=PART_RGB, noise_std: float = 0.02,
                       rng: np.random.Generator | None = None, background_rgb=BACKGROUND_RGB,
                       face_index=None) -> np.ndarray:
    """Orthographic image of a stained part (our camera stand-in).

    Each pixel takes the colour of the first face hit: ``part + s (stain - part)`` for the
    face's stain intensity ``s`` in [0, 1], plus Gaussian pixel noise.

    Parameters
    ----------
    mesh : trimesh.Trimesh
    face_stain : (F,) float in [0, 1]
        Stain intensity per face (0 clean, 1 full stain colour).
    view : OrthoView or (3,) float viewing direction
    image_size : (int, int)
        ``(H, W)`` pixels.
    stain_rgb, part_rgb, background_rgb : (3,) float in [0, 1]
    noise_std : float
        Pixel noise standard deviation, in colour units of [0, 1].
    rng : numpy.random.Generator, optional
        Needed when ``noise_std > 0``.
    face_index : (H, W) int, optional
        Precomputed :func:`face_index_image` for this view (skips the ray cast).

    Returns
    -------
    (H, W, 3) uint8 RGB image.
    """
    face_stain = check_array("face_stain", face_stain, float)
    if face_stain.shape != (len(check_mesh("mesh", mesh).faces),):
        raise ValueError(f"face_stain must have shape ({len(mesh.faces)},), got {face_stain.shape}")
    if not np.all((face_stain >= 0) & (face_stain <= 1)):
        raise ValueError("face_stain must be in [0, 1]")
    stain_c, part_c, back_c = _rgb("stain_rgb", stain_rgb), _rgb("part_rgb", part_rgb), _rgb("background_rgb", background_rgb)
    check_nonnegative("noise_std", noise_std)
    if noise_std > 0 and rng is None:
        raise ValueError("rng is required when noise_std > 0")
    if face_index is None:
        face_index = face_index_image(mesh, view, image_size)
    return stain_pixels(face_stain, face_index, stain_c, part_c, back_c, noise_std, rng)


def stain_pixels(face_stain: np.ndarray, face_index: np.ndarray, stain_c, part_c, back_c, noise_std: float,
                 rng: np.random.Generator | None) -> np.ndarray:
    """:func:`render_stain_image`'s pixels from its checked inputs (no checks: the loops that
    render the same part many times check it once); colours (3,) in [0, 1]. (H, W, 3) uint8."""
    stain_c, part_c, back_c = (np.asarray(c, dtype=float) for c in (stain_c, part_c, back_c))
    on_part = face_index >= 0
    s = np.where(on_part, face_stain[np.where(on_part, face_index, 0)], 0.0)
    colour = part_c + s[..., None] * (stain_c - part_c)
    colour = np.where(on_part[..., None], colour, back_c)
    if noise_std > 0:
        colour += rng.normal(0.0, noise_std, colour.shape)
    colour *= 255
    return np.clip(np.rint(colour, out=colour), 0, 255, out=colour).astype(np.uint8)


def _value_range(a: np.ndarray) -> str:
    if a.size == 0:
        return "empty"
    if a.dtype.kind not in "biuf":
        return "not numeric"
    nan = " with NaN" if a.dtype.kind == "f" and np.isnan(a).any() else ""
    if nan and np.isnan(a).all():
        return "all NaN"
    return f"[{np.nanmin(a)}, {np.nanmax(a)}]{nan}"


def check_image(name: str, image) -> np.ndarray:
    """A non-empty ``(H, W, 3)`` RGB image as uint8: uint8 is taken as it is, a float image
    in [0, 1] is scaled by 255 and rounded (as :func:`render_stain_image` writes its pixels).

    Every other dtype (uint16, int, bool), a float outside [0, 1] or with NaN, another shape
    or an empty image is refused with a ``ValueError`` naming ``name``, the dtype, the value
    range and the shape: a silent cast would wrap or truncate the colours.
    """
    a = check_array(name, image)
    shape_ok = a.ndim == 3 and a.shape[2] == 3 and a.size > 0
    if shape_ok and a.dtype == np.uint8:
        return a
    if shape_ok and a.dtype.kind == "f" and np.all((a >= 0.0) & (a <= 1.0)):
        return np.rint(a * 255.0).astype(np.uint8)
    raise ValueError(f"{name} must be a non-empty (H, W, 3) RGB image, uint8 or float in [0, 1]; "
                     f"got dtype {a.dtype}, range {_value_range(a)}, shape {a.shape}")


def _region(region_mask, shape) -> np.ndarray:
    if region_mask is None:
        return np.ones(shape, dtype=bool)
    region = check_bool_array("region_mask", region_mask)
    if region.shape != shape:
        raise ValueError(f"region_mask must have shape {shape}, got {region.shape}")
    return region


# K-means is fitted on at most this many pixels (seeded subsample), then labels every pixel.
_MAX_FIT_PIXELS = 2048


def _fit_sample(pixels: np.ndarray, seed: int) -> np.ndarray:
    if len(pixels) <= _MAX_FIT_PIXELS:
        return pixels
    pick = np.random.default_rng(seed).choice(len(pixels), _MAX_FIT_PIXELS, replace=False)
    return pixels[pick]


def _fill_outside(image: np.ndarray, region: np.ndarray) -> np.ndarray:
    """Paint pixels outside ``region`` with the region's median colour, so filtering does
    not bleed the background into the part's border pixels."""
    if region.all() or not region.any():
        return image
    out = image.copy()
    out[~region] = median_colour(image[region])
    return out


def median_colour(pixels: np.ndarray) -> np.ndarray:
    """``np.median(pixels, axis=0).astype(np.uint8)`` of (n, 3) uint8 pixels, n >= 1, by
    counting each channel's values: the two middle values of the sorted channel, their mean
    truncated (numpy's median of an even count is the mean of the middle two). (3,) uint8."""
    n = len(pixels)
    out = np.empty(3, dtype=np.uint8)
    for c in range(3):
        cdf = np.cumsum(np.bincount(pixels[:, c], minlength=256))
        lo, hi = np.searchsorted(cdf, [(n - 1) // 2, n // 2], side="right")
        out[c] = (lo + hi) // 2
    return out


def stain_masks_kmeans(images, seed: int = 0, *, region_mask=None, light_stain: bool = False,
                       part_rgb=None, min_contrast: float = 0.08, denoise: bool = True) -> list:
    """Binary stain masks of several images of the same part with ONE 2-cluster K-means.

    The paper clusters each image into two colours (Sec. VII). Fitting the clusters on the
    before and after images together gives both the same threshold; with a fully cleaned
    part a per-image 2-cluster split would otherwise cut the noise of the clean colour in two.

    Parameters
    ----------
    images : sequence of (H, W, 3) uint8, or float in [0, 1]
    seed : int
        K-means seed.
    region_mask : (H, W) bool, optional
        Pixels that belong to the part (clustered); others are never stain.
    light_stain : bool
        Stain lighter than the part (the stain cluster is then the brighter one).
    part_rgb : (3,) float in [0, 1], optional
        Known clean part colour: the stain cluster is the one farther from it. Without it,
        the stain is the darker cluster (brighter with ``light_stain``).
    min_contrast : float
        Minimum distance between the two cluster colours (in [0, 1] colour units, per
        sqrt(3)) for a stain to be declared at all; below it every mask is empty.
    denoise : bool
        3x3 median filter before clustering (OpenCV) against pixel noise.

    Returns
    -------
    list of (H, W) bool
    """
    if isinstance(images, np.ndarray) and images.ndim == 3:
        raise ValueError(f"images must be a sequence of (H, W, 3) images, got one array of shape "
                         f"{images.shape}; use stain_mask_kmeans for one image")
    images = [check_image(f"images[{i}]", im) for i, im in enumerate(images)]
    if not images:
        raise ValueError("images must contain at least one image")
    shape = images[0].shape[:2]
    if any(im.shape[:2] != shape for im in images):
        raise ValueError("images must all have the same size")
    check_int("seed", seed, 0)
    check_range("min_contrast", min_contrast, 0.0, 1.0)
    region = _region(region_mask, shape)
    if denoise:
        images = [cv2.medianBlur(_fill_outside(im, region), 3) for im in images]
    stacked = np.concatenate([im[region].reshape(-1, 3) for im in images])
    masks = [np.zeros(shape, dtype=bool) for _ in images]
    if len(stacked) < 2 or np.array_equal(stacked.min(axis=0), stacked.max(axis=0)):  # one colour
        return masks
    pixels = stacked.astype(float) / 255.0
    with single_thread():  # small problem: threads only add contention
        km = KMeans(n_clusters=2, n_init=1, random_state=seed).fit(_fit_sample(pixels, seed))
        labels = km.predict(pixels)
    centres = km.cluster_centers_
    if np.linalg.norm(centres[0] - centres[1]) / np.sqrt(3) < min_contrast:
        return masks
    if part_rgb is not None:
        stain_cluster = int(np.argmax(np.linalg.norm(centres - _rgb("part_rgb", part_rgb), axis=1)))
    else:
        norms = np.linalg.norm(centres, axis=1)
        stain_cluster = int(np.argmax(norms) if light_stain else np.argmin(norms))
    labels = labels == stain_cluster
    start = 0
    for mask in masks:
        n = int(region.sum())
        mask[region] = labels[start:start + n]
        start += n
    return masks


def stain_mask_kmeans(image, seed: int = 0, *, region_mask=None, light_stain: bool = False,
                      part_rgb=None, min_contrast: float = 0.08, denoise: bool = True) -> np.ndarray:
    """Binary stain mask of one image by 2-cluster K-means on RGB (Kabir, Sec. VII, Fig. 4).

    See :func:`stain_masks_kmeans` for the parameters. Returns ``(H, W)`` bool (True = stain).
    """
    return stain_masks_kmeans([check_image("image", image)], seed, region_mask=region_mask,
                              light_stain=light_stain, part_rgb=part_rgb, min_contrast=min_contrast,
                              denoise=denoise)[0]


def cleaning_performance(mask_before, mask_after, region_mask=None) -> float:
    """Cleaning performance of one pass, ``C_p = (N_p^- - N_p^+) / (I_h I_w)`` (Sec. VII).

    Parameters
    ----------
    mask_before, mask_after : (H, W) bool
        Stain pixels (the paper's black pixels) before and after the pass.
    region_mask : (H, W) bool, optional
        Target region; its pixel count is ``I_h x I_w`` (default: the whole image).

    Returns
    -------
    float -- in [-1, 1]; 0 when there is no stain (or an empty region).
    """
    before = check_bool_array("mask_before", mask_before)
    after = check_bool_array("mask_after", mask_after)
    if before.shape != after.shape or before.ndim != 2:
        raise ValueError(f"mask_before and mask_after must be (H, W) of the same shape, "
                         f"got {before.shape} and {after.shape}")
    region = _region(region_mask, before.shape)
    area = int(region.sum())
    if area == 0:
        return 0.0
    return float((int(before[region].sum()) - int(after[region].sum())) / area)


def passes_from_image(image, *, n_clusters: int = 4, seed: int = 0, light_stain: bool = False,
                      region_mask=None) -> np.ndarray:
    """Cleaning passes per pixel by colour quantisation (Kabir, Sec. VII, Fig. 5).

    K-means quantises the pixel colours into ``n_clusters`` (the paper's N_c); clusters are
    ranked by the norm of their RGB colour: the largest norm needs 0 passes, the smallest
    ``n_clusters - 1``. With ``light_stain`` (light stain on a dark part) the order flips.

    Parameters
    ----------
    image : (H, W, 3) uint8, or float in [0, 1]
    n_clusters : int >= 2
    seed : int
    light_stain : bool
    region_mask : (H, W) bool, optional
        Pixels to classify; others get -1.

    Returns
    -------
    (H, W) int -- passes in 0..n_clusters-1, -1 outside ``region_mask``.
    """
    image = check_image("image", image)
    n_clusters = check_int("n_clusters", n_clusters, 2, 16)
    check_int("seed", seed, 0)
    region = _region(region_mask, image.shape[:2])
    pixels = image[region].reshape(-1, 3).astype(float) / 255.0
    if len(np.unique(pixels, axis=0)) < n_clusters:
        raise ValueError(f"n_clusters = {n_clusters} exceeds the number of distinct colours in the image")
    with single_thread():
        km = KMeans(n_clusters=n_clusters, n_init=2, random_state=seed).fit(_fit_sample(pixels, seed))
        labels = km.predict(pixels)
    norms = np.linalg.norm(km.cluster_centers_, axis=1)
    order = np.argsort(norms) if light_stain else np.argsort(-norms)
    passes_of_cluster = np.empty(n_clusters, dtype=int)
    passes_of_cluster[order] = np.arange(n_clusters)
    out = np.full(image.shape[:2], -1, dtype=int)
    out[region] = passes_of_cluster[labels]
    return out
