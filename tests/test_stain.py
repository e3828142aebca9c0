"""Stain perception (Kabir, Sec. VII): rendering, K-means masks, C_p, passes."""

import numpy as np
import pytest
import trimesh

from mavac.vision.stain import (cleaning_performance, face_index_image, median_colour, passes_from_image,
                                render_stain_image, stain_mask_kmeans, stain_masks_kmeans,
                                view_of_faces)


@pytest.fixture(scope="module")
def sphere():
    return trimesh.creation.icosphere(subdivisions=3, radius=0.1)


def _cap_stain(mesh, level=0.9):
    stain = np.zeros(len(mesh.faces))
    stain[mesh.triangles_center[:, 0] > 0.03] = level
    return stain


def test_face_index_image_hits_the_part(sphere):
    fi = face_index_image(sphere, [0, 0, -1.0], (40, 40))
    assert fi.shape == (40, 40)
    assert fi[20, 20] >= 0 and fi[0, 0] == -1  # centre on the sphere, corner off it
    # Looking down -z, every hit face faces the camera.
    hit = np.unique(fi[fi >= 0])
    assert np.all(sphere.face_normals[hit, 2] > 0)


def test_kmeans_mask_recovers_stain_region(sphere):
    stain = _cap_stain(sphere)
    view = view_of_faces(sphere, direction=[0, 0, -1.0])
    fi = face_index_image(sphere, view, (64, 64))
    img = render_stain_image(sphere, stain, view, image_size=(64, 64), noise_std=0.03,
                             rng=np.random.default_rng(0), face_index=fi)
    assert img.dtype == np.uint8 and img.shape == (64, 64, 3)
    truth = (fi >= 0) & (stain[np.maximum(fi, 0)] > 0)
    mask = stain_mask_kmeans(img, seed=0, region_mask=fi >= 0)
    iou = (mask & truth).sum() / (mask | truth).sum()
    assert iou > 0.9


def test_light_stain_and_part_colour_rules(sphere):
    stain = _cap_stain(sphere)
    view = view_of_faces(sphere, direction=[0, 0, -1.0])
    fi = face_index_image(sphere, view, (48, 48))
    truth = (fi >= 0) & (stain[np.maximum(fi, 0)] > 0)
    dark_part, light_stain = (0.1, 0.1, 0.15), (0.9, 0.9, 0.8)
    img = render_stain_image(sphere, stain, view, stain_rgb=light_stain, part_rgb=dark_part,
                             noise_std=0.0, face_index=fi)
    kw = dict(region_mask=fi >= 0, denoise=False)  # noise-free image: exact masks
    light = stain_mask_kmeans(img, 0, light_stain=True, **kw)
    by_part = stain_mask_kmeans(img, 0, part_rgb=dark_part, **kw)
    dark_rule = stain_mask_kmeans(img, 0, **kw)
    assert np.array_equal(light, truth) and np.array_equal(by_part, truth)
    assert np.array_equal(dark_rule, (fi >= 0) & ~truth)


def test_no_stain_gives_empty_mask_and_zero_cp(sphere):
    clean = np.zeros(len(sphere.faces))
    rng = np.random.default_rng(1)
    imgs = [render_stain_image(sphere, clean, [0, 0, -1.0], image_size=(32, 32), rng=rng) for _ in range(2)]
    fi = face_index_image(sphere, [0, 0, -1.0], (32, 32))
    before, after = stain_masks_kmeans(imgs, 0, region_mask=fi >= 0)
    assert not before.any() and not after.any()
    assert cleaning_performance(before, after) == 0.0
    empty = np.zeros((4, 4), bool)
    assert cleaning_performance(empty, empty, region_mask=empty) == 0.0


def test_cleaning_performance_formula():
    before = np.zeros((10, 10), bool)
    before[:5] = True  # 50 stain pixels
    after = np.zeros((10, 10), bool)
    after[:1] = True  # 10 left
    assert cleaning_performance(before, after) == pytest.approx(40 / 100)
    region = np.zeros((10, 10), bool)
    region[:5] = True
    assert cleaning_performance(before, after, region) == pytest.approx(40 / 50)


def test_passes_ordering_and_flip():
    levels = np.array([0.95, 0.65, 0.35, 0.05])  # colour norms from bright to dark
    img = np.repeat(np.repeat(levels, 8)[None, :], 8, axis=0)[..., None] * np.ones(3)
    img = (img * 255).astype(np.uint8)
    passes = passes_from_image(img, n_clusters=4, seed=0)
    columns = passes[0, ::8]
    assert list(columns) == [0, 1, 2, 3]  # brightest -> 0 passes, darkest -> N_c - 1
    flipped = passes_from_image(img, n_clusters=4, seed=0, light_stain=True)
    assert list(flipped[0, ::8]) == [3, 2, 1, 0]
    region = np.zeros(img.shape[:2], bool)
    region[:, :16] = True
    assert (passes_from_image(img, n_clusters=2, seed=0, region_mask=region)[:, 16:] == -1).all()


def test_render_is_deterministic(sphere):
    stain = _cap_stain(sphere, 0.5)
    a = render_stain_image(sphere, stain, [0, 0, -1.0], image_size=(24, 24), rng=np.random.default_rng(3))
    b = render_stain_image(sphere, stain, [0, 0, -1.0], image_size=(24, 24), rng=np.random.default_rng(3))
    assert np.array_equal(a, b)


def test_bad_inputs(sphere):
    stain = _cap_stain(sphere)
    with pytest.raises(ValueError, match="face_stain"):
        render_stain_image(sphere, stain[:-1], [0, 0, -1.0])
    with pytest.raises(ValueError, match="face_stain"):
        render_stain_image(sphere, stain * 2, [0, 0, -1.0])
    with pytest.raises(ValueError, match="stain_rgb"):
        render_stain_image(sphere, stain, [0, 0, -1.0], stain_rgb=(2, 0, 0))
    with pytest.raises(ValueError, match="noise_std"):
        render_stain_image(sphere, stain, [0, 0, -1.0], noise_std=-1)
    with pytest.raises(ValueError, match="rng"):
        render_stain_image(sphere, stain, [0, 0, -1.0], noise_std=0.1, rng=None)
    with pytest.raises(ValueError, match="image_size"):
        face_index_image(sphere, [0, 0, -1.0], (0, 10))
    with pytest.raises(ValueError, match="direction"):
        view_of_faces(sphere, direction=[0, 0, 0])
    with pytest.raises(ValueError, match="image"):
        stain_mask_kmeans(np.zeros((4, 4)))
    with pytest.raises(ValueError, match="region_mask"):
        stain_mask_kmeans(np.zeros((4, 4, 3), np.uint8), region_mask=np.ones((3, 3), bool))
    with pytest.raises(ValueError, match="mask_before"):
        cleaning_performance(np.zeros((2, 2)), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="n_clusters"):
        passes_from_image(np.zeros((4, 4, 3), np.uint8), n_clusters=1)
    with pytest.raises(ValueError, match="n_clusters"):
        passes_from_image(np.zeros((4, 4, 3), np.uint8), n_clusters=3)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 257, 1000])
def test_median_colour_is_numpys_median_truncated_to_uint8(n):
    rng = np.random.default_rng(n)
    for spread in (256, 3):  # spread 3: many ties, even counts whose middle values differ by one
        pixels = rng.integers(0, spread, (n, 3)).astype(np.uint8) + np.uint8(200 if spread == 3 else 0)
        assert median_colour(pixels).tolist() == np.median(pixels, axis=0).astype(np.uint8).tolist()


def test_one_coloured_images_give_empty_masks():
    images = [np.full((8, 8, 3), 90, dtype=np.uint8)] * 2
    assert not any(m.any() for m in stain_masks_kmeans(images, 0))
