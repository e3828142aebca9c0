"""Looking at the part after a pass (Kabir et al. Sec. VII, IX-C): the SIMULATED stain on it,
its camera image, K-means, C_p of the pass and the residue left to re-plan.

:class:`StainState` holds the stain thickness per face (layers) and its hardness;
:func:`perceive` renders the stain states, segments them with one K-means and measures
``C_p``; :func:`residue_faces` turns the last mask into the stain faces still to clean.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.parts import Part
from ..params import ScrubModel
from ..vision.stain import cleaning_performance, face_index_image, stain_masks_kmeans, view_of_faces
from .wear import render_stain_states, stain_hardness


@dataclass
class StainState:
    """SIMULATED stain on a part: thickness per face (layers), hardness, and the camera view.

    Attributes
    ----------
    mesh : trimesh.Trimesh
    initial, thickness : (F,) float
    hardness : (F,) float
    face_index : (H, W) int
        :func:`mavac.vision.stain.face_index_image` of the view framing the stain.
    """

    mesh: object
    initial: np.ndarray
    thickness: np.ndarray
    hardness: np.ndarray
    face_index: np.ndarray
    images: list = field(default_factory=list)

    @classmethod
    def from_part(cls, part: Part, rng: np.random.Generator, *, image_size: int, model: ScrubModel = ScrubModel()):
        F = len(part.mesh.faces)
        s = np.zeros(F)
        s[part.stain_faces] = part.intensity
        view = view_of_faces(part.mesh, part.stain_faces)
        return cls(part.mesh, s.copy(), s, stain_hardness(F, rng, model),
                   face_index_image(part.mesh, view, (image_size, image_size)))

    def scrub(self, removal, rng: np.random.Generator, model: ScrubModel = ScrubModel()) -> None:
        """Apply one pass's measured removal with process noise (log-normal per pass and face)."""
        eps = rng.lognormal(0.0, model.batch_noise) * rng.lognormal(0.0, model.face_noise, len(removal))
        self.thickness = np.clip(self.thickness - removal * eps / self.hardness, 0.0, 1.0)


def perceive(state: StainState, before, faces, rng: np.random.Generator, *, model: ScrubModel = ScrubModel(),
             noise_std: float = 0.02) -> dict:
    """Camera images of the initial, before-pass and current stain, one K-means for all three,
    C_p of the pass over its patches' pixels and the residue fraction of the whole stain.

    Returns
    -------
    dict: ``C_p``, ``residue_fraction``, ``image`` (current, (H, W, 3) uint8), ``mask`` (current
    stain mask), ``region`` (pixels of the initially stained faces).
    """
    fi = state.face_index
    on = fi >= 0
    idx = np.where(on, fi, 0)
    images = render_stain_states(state.mesh, (state.initial, before, state.thickness), fi, model=model,
                                 noise_std=noise_std, rng=rng)
    m0, mb, ma = stain_masks_kmeans(images, int(rng.integers(2**31 - 1)), region_mask=on)
    region = on & (state.initial[idx] > 0)
    pass_region = on & np.isin(idx, faces) & (before[idx] > 0)
    cp = cleaning_performance(mb, ma, pass_region) if pass_region.any() else float("nan")
    residue = float((ma & region).sum() / max((m0 & region).sum(), 1))
    return {"C_p": cp, "residue_fraction": residue, "image": images[2], "mask": ma, "region": region}


def residue_faces(state: StainState, mask, stain_faces) -> tuple[np.ndarray, int]:
    """Stain faces the camera still sees stained (most of their pixels in ``mask``), and how
    many stain faces the camera does not see at all."""
    fi = state.face_index
    on = fi >= 0
    counts = np.bincount(fi[on], minlength=len(state.initial))
    stained = np.bincount(fi[on & mask], minlength=len(state.initial))
    faces = np.asarray(stain_faces)
    seen = counts[faces] > 0
    dirty = seen & (stained[faces] * 2 > counts[faces])
    return faces[dirty], int((~seen).sum())
