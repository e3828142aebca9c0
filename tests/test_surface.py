import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from mavac.geometry.surface import SurfacePoints, buried, sample_surface


@pytest.fixture(scope="module")
def sphere():
    return trimesh.creation.icosphere(subdivisions=3, radius=0.5)


def test_count_follows_area_over_spacing_squared(sphere):
    sample = sample_surface(sphere, 0.05, seed=0)
    assert len(sample) == round(sphere.area / 0.05**2)
    assert sample.points.shape == sample.normals.shape == (len(sample), 3)
    assert sample.face_index.shape == (len(sample),)


def test_points_lie_on_their_faces(sphere):
    sample = sample_surface(sphere, 0.04, seed=1)
    closest = trimesh.triangles.closest_point(sphere.triangles[sample.face_index], sample.points)
    assert np.linalg.norm(closest - sample.points, axis=1).max() < 1e-5


def test_normals_are_outward_face_normals(sphere):
    sample = sample_surface(sphere, 0.04, seed=2)
    np.testing.assert_allclose(sample.normals, sphere.face_normals[sample.face_index])
    np.testing.assert_allclose(np.linalg.norm(sample.normals, axis=1), 1.0)
    assert np.all(np.einsum("ij,ij->i", sample.normals, sample.points) > 0)


def test_points_are_evenly_spread(sphere):
    spacing = 0.04
    sample = sample_surface(sphere, spacing, seed=3)
    gaps, _ = cKDTree(sample.points).query(sample.points, k=2)
    assert gaps[:, 1].min() > 0.5 * spacing  # Poisson disk: no clumps
    assert 0.7 * spacing < gaps[:, 1].mean() < 1.2 * spacing


def test_same_seed_same_points(sphere):
    a, b = sample_surface(sphere, 0.05, seed=11), sample_surface(sphere, 0.05, seed=11)
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.face_index, b.face_index)
    assert not np.array_equal(a.points, sample_surface(sphere, 0.05, seed=12).points)


def test_subset_keeps_rows_together(sphere):
    sample = sample_surface(sphere, 0.1, seed=0)
    mask = sample.points[:, 2] > 0
    part = sample.subset(mask)
    assert isinstance(part, SurfacePoints)
    np.testing.assert_array_equal(part.face_index, sample.face_index[mask])
    np.testing.assert_array_equal(part.normals, sample.normals[mask])


@pytest.mark.parametrize("spacing", [0.0, -0.01, float("nan"), float("inf"), "a", 10.0, 1e-5])
def test_refuses_bad_spacing(sphere, spacing):
    with pytest.raises(ValueError, match="spacing"):
        sample_surface(sphere, spacing)


def test_refuses_bad_seed_and_empty_mesh(sphere):
    with pytest.raises(ValueError, match="seed"):
        sample_surface(sphere, 0.1, seed=-3)
    with pytest.raises(ValueError, match="mesh"):
        sample_surface(trimesh.Trimesh(), 0.1)


def test_spacing_errors_point_at_a_unit_mistake():
    # a 40 mm part read in the wrong unit: "larger than the mesh" names its size and units=
    tiny = trimesh.creation.box([0.04, 0.02, 0.01])
    with pytest.raises(ValueError, match=r"larger than the mesh itself .* 0.04 m across: if it is really "
                                         r"larger, it was read in the wrong units \(load_mesh\(path, units=...\)\)"):
        sample_surface(tiny, 0.5)
    huge = trimesh.creation.box([400.0, 200.0, 100.0])  # a 40 cm part read in mm as metres
    with pytest.raises(ValueError, match=r"would give 28,000,000 points .* 400 m across: if it is really smaller"):
        sample_surface(huge, 0.1)


def test_only_closed_bodies_bury_points():
    """Box a's end lies inside box b and b's lower end inside a: with one face of b removed,
    b has no inside, so only b's points inside a are buried."""
    a = trimesh.creation.box(bounds=[[0.0, 0.0, 0.0], [1.0, 0.6, 0.6]])
    b = trimesh.creation.box(bounds=[[0.5, 0.0, 0.0], [1.5, 0.6, 0.9]])
    closed = trimesh.util.concatenate([a, b])
    sample = sample_surface(closed, 0.05, seed=0)
    on_b = sample.face_index >= len(a.faces)
    both = buried(closed, sample)
    assert both[on_b].any() and both[~on_b].any()
    b.update_faces(np.arange(1, len(b.faces)))
    opened = trimesh.util.concatenate([a, b])
    sample = sample_surface(opened, 0.05, seed=0)
    only_a = buried(opened, sample)
    assert only_a.any() and (sample.face_index[only_a] >= len(a.faces)).all()
