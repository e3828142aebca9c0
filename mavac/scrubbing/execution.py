"""Kabir et al.'s execution stage as a pipeline: what happens after the setup planner.

* :func:`toolpaths_for_plan` -- the multi-pass tool path of every setup of a plan, with the
  part where the setup puts it (Sec. VI);
* :func:`perceive_scrub_pass` -- one scrubbing pass seen by the camera (Sec. VII, Figs. 4-5):
  render the stain, scrub it with the SIMULATED wear model, render again, one 2-cluster
  K-means for both binary masks, ``C_p`` over the stained region, and the passes per pixel
  by ``N_c``-colour quantisation;
* :func:`scrub_experiment` -- the simulated black box of the GPR learner (Sec. VIII) for a part.

The perception itself (rendering, K-means, C_p, quantisation) is shared and lives in
:mod:`mavac.vision.stain`; the wear model in :mod:`mavac.scrubbing.wear`.
"""

from __future__ import annotations

from typing import NamedTuple

import cv2
import numpy as np

from ..params import LissajousParams, ScrubModel, SetupSpaceParams, ToolpathParams
from ..setups.reach import base_T_part
from .wear import ScrubExperiment, render_stain_states, scrub_faces, stain_hardness
from ..validate import check_indices, check_int, check_points
from ..vision.stain import (cleaning_performance, face_index_image, passes_from_image, stain_masks_kmeans,
                            view_of_faces)
from .toolpath import ToolPath, reachable_from_robot, toolpath_for_setup


def toolpaths_for_plan(part, setups, patches, robot, *, params: ToolpathParams = ToolpathParams(),
                       space: SetupSpaceParams = SetupSpaceParams()) -> list[ToolPath]:
    """Tool path of every setup of a plan.

    Parameters
    ----------
    part : Part
    setups : (k, 3) float
        ``(x, y, alpha)`` in execution order (e.g. ``SetupPlan.setups``).
    patches : list of (k_j,) int
        Patches each setup cleans (e.g. ``SetupPlan.patches``).
    robot : RobotModel
        IK of every waypoint (world = robot base frame).
    params : ToolpathParams
    space : SetupSpaceParams
        Pose of the part for a setup (:func:`mavac.setups.reach.base_T_part`).
    """
    poses = base_T_part(check_points("setups", setups), space)
    if len(patches) != len(poses):
        raise ValueError(f"patches must hold one index array per setup ({len(poses)}), got {len(patches)}")
    reachable = reachable_from_robot(robot)
    return [toolpath_for_setup(part, T, p, params, reachable=reachable) for T, p in zip(poses, patches)]


def cover_from_patches(patches, n_patches: int) -> np.ndarray:
    """Cover matrix ``(k, n)`` bool of a plan: row j marks the patches setup j cleans."""
    n_patches = check_int("n_patches", n_patches, 0)
    cover = np.zeros((len(patches), n_patches), dtype=bool)
    for j, p in enumerate(patches):
        cover[j, check_indices(f"patches[{j}]", p, n_patches)] = True
    return cover


class StainPerception(NamedTuple):
    """One scrubbing pass seen by the camera (images (H, W, 3) uint8, masks (H, W) bool).

    Attributes
    ----------
    before, after : (H, W, 3) uint8
        Stain images before and after the pass.
    mask_before, mask_after : (H, W) bool
        K-means stain masks.
    region : (H, W) bool
        Pixels of stained faces (the paper's ``I_h x I_w``).
    cleaning_performance : float
        ``C_p`` of the pass.
    passes_estimated, passes_true : (H, W) int
        Passes per pixel from the ``N_c``-colour quantisation and from the part (-1 off the part).
    passes_agreement : float
        Fraction of the part's pixels where the two agree.
    """

    before: np.ndarray
    after: np.ndarray
    mask_before: np.ndarray
    mask_after: np.ndarray
    region: np.ndarray
    cleaning_performance: float
    passes_estimated: np.ndarray
    passes_true: np.ndarray
    passes_agreement: float


def _face_values(part, values, fill=0) -> np.ndarray:
    """Per-face array of the part: ``values`` on the stained faces, ``fill`` elsewhere."""
    out = np.full(len(part.mesh.faces), fill, dtype=np.asarray(values).dtype)
    out[part.stain_faces] = values
    return out


def perceive_scrub_pass(part, rng: np.random.Generator, *, lissajous: LissajousParams = LissajousParams(),
                        image_size=(128, 128), n_clusters: int = 4, noise_std: float = 0.02,
                        model: ScrubModel = ScrubModel()) -> StainPerception:
    """One SIMULATED scrubbing pass seen by the camera, segmented like Kabir Sec. VII.

    The stain (per-face intensity, as thickness in layers) is rendered before and after
    :func:`mavac.scrubbing.wear.scrub_faces`; one 2-cluster K-means gives both binary masks and
    ``C_p`` over the stained region; ``N_c``-colour quantisation of the before image (3x3
    median filtered against pixel noise, as the binary masks are) gives the passes per pixel
    (Fig. 5), compared with the part's own passes (pixels of stained faces; the clean part
    is 0 passes).

    Parameters
    ----------
    part : Part
    rng : numpy.random.Generator
        Process noise of the scrub, pixel noise, K-means seed.
    lissajous : LissajousParams
        Operating parameters of the pass.
    image_size : (int, int)
    n_clusters : int
        The paper's ``N_c``.
    noise_std : float
        Pixel noise, colour units in [0, 1].
    model : ScrubModel
    """
    mesh = part.mesh
    stain = _face_values(part, np.asarray(part.intensity, dtype=float))
    fi = face_index_image(mesh, view_of_faces(mesh, part.stain_faces), image_size)
    on_part = fi >= 0
    after = scrub_faces(stain, lissajous, rng=rng, model=model)
    images = render_stain_states(mesh, (stain, after), fi, model=model, noise_std=noise_std, rng=rng)
    seed = int(rng.integers(2**31 - 1))
    m_before, m_after = stain_masks_kmeans(images, seed, region_mask=on_part)
    face_passes = _face_values(part, np.asarray(part.passes, dtype=int))
    true = np.where(on_part, face_passes[np.where(on_part, fi, 0)], -1)
    region = on_part & (true > 0)
    est = passes_from_image(cv2.medianBlur(images[0], 3), n_clusters=n_clusters, seed=seed, region_mask=on_part)
    agreement = float(np.mean(est[on_part] == true[on_part]))
    return StainPerception(images[0], images[1], m_before, m_after, region,
                           cleaning_performance(m_before, m_after, region), est, true, agreement)


def scrub_experiment(part, rng: np.random.Generator, *, model: ScrubModel = ScrubModel()) -> ScrubExperiment:
    """The SIMULATED black box of the GPR learner for ``part``: its stain (intensity as
    thickness in layers) and a per-face hardness drawn from ``rng``
    (:func:`mavac.scrubbing.wear.stain_hardness`)."""
    face_stain = _face_values(part, np.asarray(part.intensity, dtype=float))
    hardness = stain_hardness(len(face_stain), rng, model)
    return ScrubExperiment(part.mesh, face_stain, hardness)
