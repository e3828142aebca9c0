"""SIMULATED scrubbing: a black box standing in for Kabir et al.'s physical cleaning
experiments (Sec. VIII, IX-C). It is our model, not the paper's physics.

Removal follows Preston's wear law: removed stain thickness (in stain layers)
``W = k_p * p * c * D`` with pressure ``p``, contact fraction ``c`` and relative sliding
distance ``D`` while a surface point is under the tool:

* the foam compresses, its contact area grows as ``a_c (1 + f_n / f_foam)``, so the
  pressure ``p = f_n / (a_c (1 + f_n / f_foam))`` saturates -- pushing harder pays less;

* nominal speed ``u = v * tool_speed_at_vmax``; a point stays under the tool for
  ``w / u`` seconds (contact width ``w``);
* the Lissajous force only makes the sponge slide when it beats Coulomb friction: slip force
  amplitude ``F_s = max(A - mu f_n, 0)`` -- a high normal force makes the tool stick;
* the impedance (stiffness ``kappa``, apparent mass ``m``, damping ratio ``zeta``) turns
  ``F_s`` into a displacement ``X = (F_s / kappa) / sqrt((1 - r^2)^2 + (2 zeta r)^2)``,
  ``r = 2 pi f / sqrt(kappa / m)``, for x (``f_x``) and y (``0.4 f_x``): the best
  frequency is near resonance, and the best resonance depends on kappa;
* the controller's path-deviation limit ``X_max`` caps the amplitude softly,
  ``X / sqrt(1 + (X / X_max)^2)``, so a soft spring does not win by itself;
* ``D = (w / u) sqrt(u^2 + V^2)`` with ``V`` the RMS oscillation velocity (RMS relative
  speed approximates the mean sliding speed) -- faster travel cleans less;
* ``c = 1 / (1 + (A / (lambda f_n))^q)``: a lateral force large against the normal force
  tips the sponge and makes it chatter (loss of contact).

So the optimum is interior and couples the parameters: more f_n presses harder but sticks,
more A slides more but tips, f_x has a resonance that depends on kappa. A face of stain
thickness ``s`` (in layers; a part's stain intensity) and hardness ``h`` keeps
``max(s - W eps / h, 0)``, with log-normal process noise ``eps`` (per face and per
experiment). The camera sees the thickness through Beer-Lambert opacity
(:func:`stain_opacity`). :class:`ContactWear` applies the same law to the contact the
pybullet cell measures (:mod:`mavac.scrubbing.scrub`). Cleaning performance is then MEASURED like in the paper:
before/after images (:func:`mavac.vision.stain.render_stain_image`, pixel noise) -> K-means
masks -> C_p.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field, replace

import numpy as np
import trimesh

from ..geometry.mesh import check_mesh
from ..geometry.transforms import transform_each_point
from ..params import OPERATION_PARAMS, LissajousParams, ScrubModel
from ..validate import check_array, check_instance, check_int, check_nonnegative, check_points, check_positive
from ..vision.stain import (BACKGROUND_RGB, PART_RGB, STAIN_RGB, OrthoView, cleaning_performance,
                            face_index_image, stain_masks_kmeans, stain_pixels, view_of_faces)


def lissajous_from_vector(x, base: LissajousParams = LissajousParams()) -> LissajousParams:
    """Operation vector ``(v, f_n, kappa, f_x, A_x)`` -> LissajousParams.

    As in the paper (Sec. VIII) ``kappa_y = kappa_x`` and ``A_y = A_x``; the other fields
    (f_y ratio, phase, speed mapping) come from ``base``.
    """
    x = check_points("x", x, len(OPERATION_PARAMS))
    if len(x) != 1:
        raise ValueError(f"x must be a single operation vector, got {len(x)} rows")
    v, f_n, kappa, f_x, A = (float(c) for c in x[0])
    return replace(base, v=v, f_n=f_n, kappa_x=kappa, kappa_y=kappa, f_x=f_x, A_x=A, A_y=A)


def vector_from_lissajous(params: LissajousParams) -> np.ndarray:
    """LissajousParams -> operation vector ``(v, f_n, kappa_x, f_x, A_x)``, (5,)."""
    return np.array([params.v, params.f_n, params.kappa_x, params.f_x, params.A_x])


def stain_opacity(thickness, model: ScrubModel = ScrubModel()) -> np.ndarray:
    """Stain colour weight seen by the camera for a thickness in layers (Beer-Lambert).

    ``(1 - exp(-t / d)) / (1 - exp(-1 / d))`` with optical depth ``d``: 0 -> 0, 1 -> 1.
    """
    t = np.asarray(thickness, dtype=float)
    d = model.optical_depth
    return np.clip(-np.expm1(-t / d) / -np.expm1(-1.0 / d), 0.0, 1.0)


def stain_hardness(n_faces: int, rng: np.random.Generator, model: ScrubModel = ScrubModel()) -> np.ndarray:
    """Per-face stain hardness, log-normal with median 1 and ``model.hardness_sigma``, (n_faces,)."""
    n_faces = check_int("n_faces", n_faces, 1)
    return rng.lognormal(0.0, model.hardness_sigma, n_faces)


def _displacement(force, kappa, f, mass, zeta, max_dev):
    """Steady-state amplitude of a driven mass-spring-damper, softly capped at max_dev."""
    r = 2 * np.pi * f / np.sqrt(kappa / mass)
    x = (force / kappa) / np.sqrt((1 - r**2) ** 2 + (2 * zeta * r) ** 2)
    return x / np.sqrt(1 + (x / max_dev) ** 2)


def removal_from_vector(X, *, model: ScrubModel = ScrubModel(),
                        base: LissajousParams = LissajousParams()) -> np.ndarray:
    """Noise-free Preston removal ``W`` (stain layers per pass) for operation vectors.

    Parameters
    ----------
    X : (n, 5) float
        Rows ``(v, f_n [N], kappa [N/m], f_x [Hz], A_x [N])`` (``OPERATION_PARAMS``).
    model : ScrubModel
    base : LissajousParams
        Supplies ``f_y_ratio`` and ``tool_speed_at_vmax``.

    Returns
    -------
    (n,) float, stain layers removed at unit hardness.
    """
    X = check_points("X", X, len(OPERATION_PARAMS))
    v, f_n, kappa, f_x, A = X.T
    if np.any(v <= 0) or np.any(kappa <= 0) or np.any(f_x <= 0) or np.any(f_n < 0) or np.any(A < 0):
        raise ValueError("X rows need v > 0, f_n >= 0, kappa > 0, f_x > 0, A_x >= 0")
    u = v * base.tool_speed_at_vmax
    slip = np.maximum(A - model.friction * f_n, 0.0)
    f_y = base.f_y_ratio * f_x
    amp_x = _displacement(slip, kappa, f_x, model.mass, model.damping_ratio, model.max_deviation)
    amp_y = _displacement(slip, kappa, f_y, model.mass, model.damping_ratio, model.max_deviation)
    v_rms_sq = ((2 * np.pi * f_x * amp_x) ** 2 + (2 * np.pi * f_y * amp_y) ** 2) / 2
    sliding = model.contact_width / u * np.sqrt(u**2 + v_rms_sq)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(f_n > 0, A / (model.tipping_ratio * np.maximum(f_n, 1e-12)), np.inf)
    contact = 1.0 / (1.0 + ratio**model.tipping_exponent)
    pressure = f_n / (model.contact_area * (1.0 + f_n / model.foam_force))
    return model.preston * pressure * contact * sliding


def removal_depth(params: LissajousParams, model: ScrubModel = ScrubModel()) -> float:
    """Noise-free Preston removal ``W`` (stain layers) for one set of operation parameters."""
    return float(removal_from_vector(vector_from_lissajous(params)[None], model=model, base=params)[0])


def scrub_faces(face_stain, params: LissajousParams, *, hardness=None,
                rng: np.random.Generator | None = None, model: ScrubModel = ScrubModel()) -> np.ndarray:
    """SIMULATED scrubbing pass over every face: ``max(s - W eps / h, 0)``.

    Parameters
    ----------
    face_stain : (F,) float in [0, 1]
        Stain intensity (= thickness in layers) per face.
    params : LissajousParams
    hardness : (F,) float > 0, optional
        Stain hardness per face (default 1).
    rng : numpy.random.Generator, optional
        Process noise (log-normal per face and per pass); ``None`` gives the noise-free model.
    model : ScrubModel

    Returns
    -------
    (F,) float in [0, 1] -- stain after the pass.
    """
    check_instance("params", params, LissajousParams)
    check_instance("model", model, ScrubModel)
    face_stain = check_array("face_stain", face_stain, float)
    if face_stain.ndim != 1 or not np.all((face_stain >= 0) & (face_stain <= 1)):
        raise ValueError("face_stain must be a 1-D array in [0, 1]")
    hardness = np.ones_like(face_stain) if hardness is None else np.asarray(hardness, dtype=float)
    if hardness.shape != face_stain.shape or not np.all(hardness > 0):
        raise ValueError(f"hardness must be positive with shape {face_stain.shape}")
    removal = removal_depth(params, model) / hardness
    if rng is not None:
        batch = rng.lognormal(0.0, model.batch_noise)
        removal = removal * batch * rng.lognormal(0.0, model.face_noise, face_stain.shape)
    return np.clip(face_stain - removal, 0.0, 1.0)


def measure_cp(part_mesh: trimesh.Trimesh, face_stain, params: LissajousParams,
               *, rng: np.random.Generator | None = None, hardness=None, view: OrthoView | None = None,
               image_size=(96, 96), model: ScrubModel = ScrubModel(), noise_std: float = 0.02,
               face_index=None, kmeans_seed: int | None = None) -> float:
    """SIMULATED cleaning experiment measured like the paper: scrub, photograph, K-means, C_p.

    Renders the part before and after :func:`scrub_faces`, segments both images with one
    2-cluster K-means and returns ``C_p`` over the target region (pixels of the initially
    stained faces, the paper's ``I_h x I_w``).

    Parameters
    ----------
    part_mesh : trimesh.Trimesh
    face_stain : (F,) float in [0, 1]
        Initial stain thickness (layers); faces with stain > 0 form the target region.
    params : LissajousParams
    rng : numpy.random.Generator, optional
        Process and pixel noise and the K-means seed; ``None`` gives the noise-free measurement.
    hardness : (F,) float, optional
    view : OrthoView, optional
        Default: framed on the stained faces, looking against their mean normal.
    image_size : (int, int)
    model : ScrubModel
    noise_std : float
        Pixel noise (colour units in [0, 1]); ignored when ``rng`` is None.
    face_index : (H, W) int, optional
        Cached :func:`face_index_image` for ``view`` and ``image_size``.
    kmeans_seed : int, optional
        Default: drawn from ``rng`` (0 without rng).

    Returns
    -------
    float -- C_p.
    """
    face_stain = np.asarray(face_stain, dtype=float)
    stained = np.flatnonzero(face_stain > 0)
    if stained.size == 0:
        return 0.0
    if face_index is None:
        view = view_of_faces(part_mesh, stained) if view is None else view
        face_index = face_index_image(part_mesh, view, image_size)
    after = scrub_faces(face_stain, params, hardness=hardness, rng=rng, model=model)
    if kmeans_seed is None:
        kmeans_seed = int(rng.integers(2**31 - 1)) if rng is not None else 0
    return _cp_from_images(part_mesh, face_stain, after, face_index, model,
                           noise_std if rng is not None else 0.0, rng, kmeans_seed)


def render_stain_states(mesh: trimesh.Trimesh, states, face_index, *, model: ScrubModel = ScrubModel(),
                        noise_std: float = 0.02, rng: np.random.Generator | None = None) -> list:
    """Camera images of several stain states of one part (thickness seen through
    :func:`stain_opacity`), rendered in order with pixel noise from ``rng``.

    Parameters
    ----------
    mesh : trimesh.Trimesh
    states : sequence of (F,) float
        Stain thickness per face (layers), e.g. before and after a pass.
    face_index : (H, W) int
        :func:`mavac.vision.stain.face_index_image` of the view.

    Returns
    -------
    list of (H, W, 3) uint8
    """
    n_faces = len(check_mesh("mesh", mesh).faces)
    check_nonnegative("noise_std", noise_std)
    if noise_std > 0 and rng is None:
        raise ValueError("rng is required when noise_std > 0")
    opacities = [stain_opacity(s, model) for s in states]
    for i, o in enumerate(opacities):
        if o.shape != (n_faces,) or np.isnan(o).any():
            raise ValueError(f"states[{i}] must be a thickness per face, shape ({n_faces},), without NaN")
    return [stain_pixels(o, face_index, STAIN_RGB, PART_RGB, BACKGROUND_RGB, noise_std, rng) for o in opacities]


def _cp_from_images(mesh, before, after, face_index, model, noise_std, rng, kmeans_seed) -> float:
    """Render both stain states, segment them with one K-means, C_p over the stained pixels."""
    images = render_stain_states(mesh, (before, after), face_index, model=model, noise_std=noise_std, rng=rng)
    on_part = face_index >= 0
    region = on_part & (before[np.where(on_part, face_index, 0)] > 0)
    before_mask, after_mask = stain_masks_kmeans(images, kmeans_seed, region_mask=on_part)
    return cleaning_performance(before_mask, after_mask, region)


@dataclass
class ScrubExperiment:
    """The SIMULATED black box of the GPR learner: ``experiment(x, rng) -> measured C_p``.

    ``x`` is an operation vector ``(v, f_n, kappa, f_x, A_x)``. :meth:`mean` is the
    noise-free model (no process or pixel noise) for many vectors at once: the noise-free
    scrub depends on ``x`` only through the removal ``W(x)``, so C_p is tabulated once
    against ``W`` through the same render + K-means pipeline and interpolated.

    Parameters
    ----------
    mesh : trimesh.Trimesh
    face_stain : (F,) float in [0, 1]
    hardness : (F,) float > 0
    image_size : (int, int)
    model : ScrubModel
    base : LissajousParams
    noise_std : float
    table_points : int
        W samples of the noise-free table.
    """

    mesh: trimesh.Trimesh
    face_stain: np.ndarray
    hardness: np.ndarray
    image_size: tuple = (96, 96)
    model: ScrubModel = ScrubModel()
    base: LissajousParams = LissajousParams()
    noise_std: float = 0.02
    table_points: int = 48
    view: OrthoView = field(init=False)
    face_index: np.ndarray = field(init=False, repr=False)
    _table: tuple | None = field(init=False, default=None, repr=False)

    def __post_init__(self):
        check_mesh("mesh", self.mesh)
        self.face_stain = check_array("face_stain", self.face_stain, float)
        self.hardness = check_array("hardness", self.hardness, float)
        stained = np.flatnonzero(self.face_stain > 0)
        if stained.size == 0:
            raise ValueError("face_stain has no stained face")
        self.view = view_of_faces(self.mesh, stained)
        self.face_index = face_index_image(self.mesh, self.view, self.image_size)

    def params(self, x) -> LissajousParams:
        """Operation vector -> LissajousParams."""
        return lissajous_from_vector(x, self.base)

    def __call__(self, x, rng: np.random.Generator | None = None) -> float:
        """Run one simulated experiment at ``x`` and measure C_p (noisy when ``rng`` is given)."""
        return measure_cp(self.mesh, self.face_stain, self.params(x), rng=rng, hardness=self.hardness,
                          view=self.view, model=self.model, noise_std=self.noise_std,
                          face_index=self.face_index)

    def _cp_of_removal(self, removal: float) -> float:
        after = np.clip(self.face_stain - removal / self.hardness, 0.0, 1.0)
        return _cp_from_images(self.mesh, self.face_stain, after, self.face_index, self.model, 0.0, None, 0)

    def mean(self, X) -> np.ndarray:
        """Noise-free C_p for operation vectors ``X`` (n, 5) -> (n,)."""
        if self._table is None:
            w_all = float(np.max(self.face_stain * self.hardness))
            grid = np.linspace(0.0, 1.02 * w_all, self.table_points)
            self._table = (grid, np.array([self._cp_of_removal(w) for w in grid]))
        grid, cp = self._table
        return np.interp(removal_from_vector(X, model=self.model, base=self.base), grid, cp)


class ContactWear:
    """Per-face Preston removal from MEASURED contact, accumulated step by step: the faces under
    the pad lose ``preston x pressure x sliding``. Under the pad: within ``pad_radius`` m of
    the pad axis through the contact centroid, within ``depth`` m along that axis of the
    centroid (the real surface, where the pad meets the part's exact mesh), and facing the pad.

    Parameters
    ----------
    part_mesh : trimesh.Trimesh
        Part frame, metres.
    pad_radius : float, m
    preston : float
        Stain layers per (Pa x m of sliding).
    depth : float, m
        Farthest a credited face may lie from the surface under the pad, along the pad axis.

    Attributes
    ----------
    removal : (F,) float
        Removal so far per face (stain layers at unit hardness).
    deepest : float, m
        Deepest a credited face lay below the contact centroid along the pad axis (-inf before
        any wear).
    """

    def __init__(self, part_mesh: trimesh.Trimesh, pad_radius: float, preston: float, *, depth: float):
        from scipy.spatial import cKDTree

        mesh = check_mesh("part_mesh", part_mesh)
        self.centres = np.asarray(mesh.triangles_center)
        self.normals = np.asarray(mesh.face_normals)
        self.tree = cKDTree(self.centres)
        self.radius = float(check_positive("pad_radius", pad_radius))
        self.preston = float(check_positive("preston", preston))
        self.depth = float(check_positive("depth", depth))
        self.removal = np.zeros(len(self.centres))
        self.deepest = -np.inf

    def add_steps(self, part_T_world, centres, axes, pressure, sliding) -> None:
        """Steps of contact, in order, at once.

        Parameters
        ----------
        part_T_world : (n, 4, 4) float
            Pose of the world in the part frame at each step.
        centres : (n, 3) float, m
            Contact centroid on the part at each step, world frame.
        axes : (n, 3) float
            Pad axis (tool z, into the surface) at each step, world frame.
        pressure : (n,) float, Pa
        sliding : (n,) float, m

        The sums equal those of one step at a time: each face's increments are added in step
        order (``numpy.add.at``).
        """
        c = transform_each_point(part_T_world, centres)
        if len(c) == 0:
            return
        a = np.einsum("nij,nj->ni", np.asarray(part_T_world)[:, :3, :3], np.asarray(axes, dtype=float))
        faces = self.tree.query_ball_point(c, float(np.hypot(self.radius, self.depth)))
        counts = np.array([len(f) for f in faces], dtype=np.intp)
        index = np.fromiter(itertools.chain.from_iterable(faces), dtype=np.intp, count=int(counts.sum()))
        step = np.repeat(np.arange(len(c)), counts)
        rel = self.centres[index] - c[step]
        along = np.einsum("ij,ij->i", rel, a[step])
        across = np.linalg.norm(rel - along[:, None] * a[step], axis=1)
        facing = np.einsum("ij,ij->i", self.normals[index], a[step]) < 0
        under = (np.abs(along) <= self.depth) & (across <= self.radius) & facing
        if under.any():
            self.deepest = max(self.deepest, float(along[under].max()))
        amount = self.preston * np.asarray(pressure, dtype=float) * np.asarray(sliding, dtype=float)
        np.add.at(self.removal, index[under], amount[step[under]])
