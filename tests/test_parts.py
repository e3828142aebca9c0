import networkx as nx
import numpy as np
import pytest
import trimesh

from mavac.geometry import parts
from mavac.geometry.parts import PART_NAMES, Part, load_part, part_from_mesh, stain_from_field

# Kabir Fig. 6 (synthetic, mm -> m) and Sec. IX-C (physical, cm -> m; see parts.py docstring)
PAPER_EXTENTS = {
    "sine": (1.6, 1.6, 0.5),
    "schwefel": (0.6, 0.6, 0.35),
    "concave_bowl": (1.2, 1.2, 0.53),
    "hyperboloid": (1.2, 1.2, 0.412),
    "bowl": (0.215, 0.215, 0.095),
    "hull": (0.201, 0.180, 0.140),
}
SYNTHETIC = ("sine", "schwefel", "concave_bowl", "hyperboloid")
PAPER_TRIANGLES = {"bowl": 15644, "hull": 22764}


def _stain_components(part: Part) -> int:
    adjacency = part.mesh.face_adjacency
    inside = np.isin(adjacency, part.stain_faces).all(axis=1)
    graph = nx.Graph()
    graph.add_nodes_from(part.stain_faces.tolist())
    graph.add_edges_from(adjacency[inside].tolist())
    return nx.number_connected_components(graph)


@pytest.mark.parametrize("name", PART_NAMES)
def test_extents_and_part_frame(name):
    mesh = load_part(name).mesh
    np.testing.assert_allclose(mesh.extents, PAPER_EXTENTS[name], rtol=1e-6)
    lo, hi = mesh.bounds
    np.testing.assert_allclose([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]], 0.0, atol=1e-12)


@pytest.mark.parametrize("name", SYNTHETIC)
def test_synthetic_faces_and_stain_match_paper(name):
    part = load_part(name, seed=3)
    assert part.mesh.area_faces.max() < parts.SYNTHETIC_MAX_FACE_AREA
    assert 4000 <= len(part.stain_faces) <= 5000
    assert set(np.unique(part.passes)) == {1, 2, 3}
    assert len(part.mesh.faces) < 1_000_000


@pytest.mark.parametrize("name, n_stain", [("bowl", 1000), ("hull", 5709)])
def test_physical_parts_match_paper(name, n_stain):
    part = load_part(name)
    assert part.mesh.area_faces.max() < parts.PHYSICAL_MAX_FACE_AREA
    assert len(part.stain_faces) == n_stain
    assert abs(len(part.mesh.faces) - PAPER_TRIANGLES[name]) / PAPER_TRIANGLES[name] < 0.02


def test_physical_pass_counts_follow_paper():
    assert set(np.unique(load_part("bowl").passes)) == {2, 3}  # "three and two passes"
    assert set(np.unique(load_part("hull").passes)) == {1}  # "a single cleaning pass"


@pytest.mark.parametrize("name", PART_NAMES)
def test_surface_is_one_consistently_wound_sheet(name):
    mesh = load_part(name).mesh
    assert mesh.is_winding_consistent
    assert mesh.body_count == 1
    assert mesh.area_faces.min() > 0


@pytest.mark.parametrize("name", ["sine", "schwefel", "concave_bowl", "bowl"])
def test_height_field_normals_point_up(name):
    assert np.all(load_part(name).mesh.face_normals[:, 2] > 0)


def test_hyperboloid_normals_point_away_from_axis():
    mesh = load_part("hyperboloid").mesh
    radial = mesh.triangles_center[:, :2]
    assert np.all(np.einsum("ij,ij->i", mesh.face_normals[:, :2], radial) > 0)


def test_hull_normals_point_out_of_the_hull():
    mesh = load_part("hull").mesh
    away = mesh.triangles_center.copy()
    away[:, 0] = 0.0  # from the keel-line axis (x axis at deck level)
    agreement = np.einsum("ij,ij->i", mesh.face_normals, away)
    assert np.mean(agreement > 0) > 0.95


@pytest.mark.parametrize("name", PART_NAMES)
def test_stain_is_a_few_blobs_with_valid_intensity(name):
    part = load_part(name, seed=1)
    assert _stain_components(part) <= 6
    assert np.all((part.intensity > 0) & (part.intensity <= 1))
    order = np.argsort(part.intensity)
    assert np.all(np.diff(part.passes[order]) >= 0)  # more intense never needs fewer passes


@pytest.mark.parametrize("name", ["sine", "hull"])
def test_stain_is_deterministic_for_a_seed(name):
    a, b, c = load_part(name, seed=7), load_part(name, seed=7), load_part(name, seed=8)
    np.testing.assert_array_equal(a.stain_faces, b.stain_faces)
    np.testing.assert_array_equal(a.passes, b.passes)
    np.testing.assert_array_equal(a.intensity, b.intensity)
    assert not np.array_equal(a.stain_faces, c.stain_faces)


def test_parts_do_not_share_cached_arrays():
    a = load_part("bowl")
    a.mesh.vertices += 1.0
    b = load_part("bowl")
    assert b.mesh.bounds[0, 2] == 0.0


def test_patch_properties_agree_with_mesh():
    part = load_part("hull", seed=2)
    k = len(part.stain_faces)
    assert part.patch_vertices.shape == (k, 3, 3)
    np.testing.assert_array_equal(part.patch_vertices, part.mesh.triangles[part.stain_faces])
    np.testing.assert_allclose(np.linalg.norm(part.patch_normals, axis=1), 1.0)
    np.testing.assert_allclose(part.patch_areas.sum(), part.stain_mesh.area)
    np.testing.assert_allclose(part.stain_mesh.face_normals, part.patch_normals, atol=1e-9)


def _square():
    return trimesh.Trimesh([[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], [[0, 1, 2], [0, 2, 3]],
                           process=False)


def test_part_from_mesh_moves_into_part_frame():
    part = part_from_mesh(_square(), [1], [2], name="tile")
    np.testing.assert_allclose(part.mesh.bounds, [[-0.5, -0.5, 0], [0.5, 0.5, 0]])
    np.testing.assert_allclose(part.mesh.metadata["mavac_part_offset"], [0.5, 0.5, 1.0])
    np.testing.assert_allclose(part.intensity, [2 / 3])
    assert part.name == "tile"


@pytest.mark.parametrize("kwargs, match", [
    ({"stain_faces": [2], "passes": [1]}, "stain_faces"),
    ({"stain_faces": [0, 0], "passes": [1, 1]}, "stain_faces"),
    ({"stain_faces": [], "passes": []}, "stain_faces"),
    ({"stain_faces": [0.5], "passes": [1]}, "stain_faces"),
    ({"stain_faces": [0], "passes": [4]}, "passes"),
    ({"stain_faces": [0], "passes": [1, 2]}, "passes"),
    ({"stain_faces": [0], "passes": [1], "intensity": [0.0]}, "intensity"),
    ({"stain_faces": [0], "passes": [1], "intensity": [1.5]}, "intensity"),
])
def test_part_refuses_bad_stain(kwargs, match):
    with pytest.raises(ValueError, match=match):
        part_from_mesh(_square(), **kwargs)


def test_part_from_mesh_refuses_empty_mesh():
    with pytest.raises(ValueError, match="mesh"):
        part_from_mesh(trimesh.Trimesh(), [0], [1])


def test_load_part_refuses_unknown_name_and_bad_seed():
    with pytest.raises(ValueError, match="name"):
        load_part("teapot")
    with pytest.raises(ValueError, match="seed"):
        load_part("sine", seed=-1)


def test_stain_from_field_exact_count_and_range_check():
    mesh = load_part("bowl").mesh
    stain, passes, intensity = stain_from_field(mesh, 123, np.random.default_rng(0))
    assert len(stain) == 123 == len(np.unique(stain))
    assert passes.min() >= 1 and passes.max() <= 3
    assert intensity.max() == 1.0
    with pytest.raises(ValueError, match="n_stain"):
        stain_from_field(mesh, len(mesh.faces), np.random.default_rng(0))
