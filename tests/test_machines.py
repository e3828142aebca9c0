import numpy as np
import pytest
import trimesh

from mavac.geometry import machines
from mavac.geometry.machines import (MACHINE_NAMES, dust_heaps, exposed_area, load_machine,
                                     machine_from_mesh)


def _covered_from_above(mesh: trimesh.Trimesh, points: np.ndarray) -> np.ndarray:
    """(n,) bool: a vertical ray from just above each point hits the mesh (a concavity)."""
    origins = points + [0.0, 0.0, 1e-4]
    directions = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    return mesh.ray.intersects_any(origins, directions)


@pytest.mark.parametrize("name", MACHINE_NAMES)
def test_machine_is_a_clean_closed_outward_solid_on_the_floor(name):
    mesh = load_machine(name).mesh
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.body_count == (4 if name == "test_bench" else 1)  # the bench: four separate boxes
    assert mesh.volume > 0  # outward normals
    # just outside each face (along its normal) is outside the solid
    probe = mesh.triangles_center + 1e-3 * mesh.face_normals
    assert not mesh.contains(probe).any()
    lo, hi = mesh.bounds
    assert lo[2] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose((lo[:2] + hi[:2]) / 2, 0.0, atol=1e-12)


def test_test_bench_is_2_by_1_by_1_m():
    np.testing.assert_allclose(load_machine("test_bench").mesh.extents, [2.0, 1.0, 1.0], atol=1e-9)


def test_test_bench_is_four_separate_boxes_of_increasing_height():
    """MAVAC: "made of four boxes, representing varying levels of machine complexity"; they
    stand apart (gaps along x), each a closed solid with its own floor contact."""
    bodies = sorted(load_machine("test_bench").mesh.split(only_watertight=True), key=lambda b: b.bounds[0, 0])
    assert len(bodies) == 4
    x = np.array([b.bounds[:, 0] for b in bodies])
    assert np.all(x[1:, 0] - x[:-1, 1] > 0.2)  # gaps between neighbours
    heights = [b.extents[2] for b in bodies]
    assert heights == sorted(heights) and heights[-1] == pytest.approx(1.0)
    # complexity: the first box is convex, each later one has a concavity
    assert bodies[0].convex_hull.volume == pytest.approx(bodies[0].volume)
    assert all(b.convex_hull.volume - b.volume > 0.005 for b in bodies[1:])


@pytest.mark.parametrize("name", MACHINE_NAMES)
def test_exposed_area_is_5_to_6_m2(name):
    machine = load_machine(name)
    assert 5.0 <= exposed_area(machine) <= 6.0
    assert np.all((machine.mesh.extents > 0.5) & (machine.mesh.extents < 2.5))


@pytest.mark.parametrize("name", MACHINE_NAMES)
def test_machine_has_concavities(name):
    mesh = load_machine(name).mesh
    assert mesh.convex_hull.volume - mesh.volume > 0.05
    upward = mesh.face_normals[:, 2] > 0.99
    assert _covered_from_above(mesh, mesh.triangles_center[upward]).any()


@pytest.mark.parametrize("name", MACHINE_NAMES)
def test_footprint_is_ccw_and_holds_the_shadow(name):
    machine = load_machine(name)
    fp = machine.footprint
    x, y = fp[:, 0], fp[:, 1]
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0  # counter-clockwise
    edges = np.roll(fp, -1, axis=0) - fp
    rel = machine.mesh.vertices[:, None, :2] - fp[None]
    cross = edges[None, :, 0] * rel[..., 1] - edges[None, :, 1] * rel[..., 0]
    assert np.all(cross >= -1e-9)  # every vertex left of every edge: inside


def test_exposed_area_leaves_out_only_the_floor_faces():
    cube = machine_from_mesh(trimesh.creation.box([1.0, 1.0, 1.0]))
    assert exposed_area(cube) == pytest.approx(5.0)
    bench = load_machine("test_bench")
    base = 0.3 * (0.4 + 0.6 + 1.0 + 0.4)  # the four boxes' bottoms
    assert exposed_area(bench) == pytest.approx(bench.mesh.area - base)


def test_machine_from_mesh_puts_it_on_the_floor():
    box = trimesh.creation.box([0.4, 0.2, 0.3])
    box.apply_translation([1.0, 2.0, 5.0])
    machine = machine_from_mesh(box, name="crate")
    assert machine.mesh.bounds[0, 2] == pytest.approx(0.0)
    np.testing.assert_allclose(machine.mesh.bounds[0, :2], [0.8, 1.9])
    assert len(machine.footprint) == 4
    assert box.bounds[0, 2] == pytest.approx(4.85)  # input untouched


def test_machines_do_not_share_cached_arrays():
    a = load_machine("sanding_machine")
    a.mesh.apply_translation([0, 0, 1])
    assert load_machine("sanding_machine").mesh.bounds[0, 2] == 0.0


@pytest.mark.parametrize("name", MACHINE_NAMES)
def test_dust_heaps_lie_on_resting_surfaces_including_concavities(name):
    machine = load_machine(name)
    mesh = machine.mesh
    heaps = dust_heaps(machine, spacing=0.10, seed=0)
    upward = mesh.face_normals[:, 2] >= machines.DUST_MIN_NORMAL_Z
    assert len(heaps) == round(mesh.area_faces[upward].sum() / 0.10**2)
    _, distance, face = trimesh.proximity.closest_point(mesh, heaps)
    assert distance.max() < 1e-5
    assert np.all(mesh.face_normals[face, 2] >= machines.DUST_MIN_NORMAL_Z)
    assert _covered_from_above(mesh, heaps).any()  # "including within the concavities"


def test_dust_heaps_are_deterministic_and_spread():
    machine = load_machine("test_bench")
    a = dust_heaps(machine, seed=4)
    np.testing.assert_array_equal(a, dust_heaps(machine, seed=4))
    assert not np.array_equal(a, dust_heaps(machine, seed=5))
    gaps = np.linalg.norm(a[:, None] - a[None], axis=2)
    np.fill_diagonal(gaps, np.inf)
    assert gaps.min(axis=1).min() > 0.05  # no two heaps on top of each other


@pytest.mark.parametrize("kwargs, match", [
    ({"spacing": 0.0}, "spacing"),
    ({"spacing": -0.1}, "spacing"),
    ({"spacing": float("nan")}, "spacing"),
    ({"min_normal_z": 1.5}, "min_normal_z"),
])
def test_dust_heaps_refuse_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        dust_heaps(load_machine("test_bench"), **kwargs)


@pytest.mark.parametrize("footprint", [[[0, 0], [1, 0]], [[0, 0], [0, 1], [1, 0]],
                                       [[0, 0, 0], [1, 0, 0], [0, 1, 0]]])
def test_machine_refuses_bad_footprint(footprint):
    with pytest.raises(ValueError, match="footprint"):
        machines.Machine("box", trimesh.creation.box(), np.array(footprint, dtype=float))


def test_load_machine_refuses_unknown_name():
    with pytest.raises(ValueError, match="name"):
        load_machine("lathe")


def test_named_constructors_match_load_machine():
    for name, build in [("test_bench", machines.test_bench),
                        ("sanding_machine", machines.sanding_machine),
                        ("milling_machine", machines.milling_machine)]:
        machine = build()
        assert machine.name == name
        np.testing.assert_array_equal(machine.mesh.faces, load_machine(name).mesh.faces)
