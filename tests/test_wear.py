"""SIMULATED scrubbing black box (stands in for Kabir's physical experiments)."""

import dataclasses

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from mavac.geometry.transforms import transform_points
from mavac.params import LissajousParams, ScrubModel
from mavac.scrubbing.wear import (ContactWear, ScrubExperiment, lissajous_from_vector, measure_cp, removal_depth,
                             removal_from_vector, render_stain_states, scrub_faces, stain_hardness, stain_opacity,
                             vector_from_lissajous)


@pytest.fixture(scope="module")
def stained_sphere():
    mesh = trimesh.creation.icosphere(subdivisions=3, radius=0.1)
    rng = np.random.default_rng(0)
    stain = np.zeros(len(mesh.faces))
    cap = mesh.triangles_center[:, 2] > 0.04
    stain[cap] = rng.uniform(0.1, 1.0, cap.sum())
    return mesh, stain, stain_hardness(len(stain), rng)


def _x(**changes):
    return vector_from_lissajous(dataclasses.replace(LissajousParams(), **changes))


def test_vector_round_trip():
    p = LissajousParams()
    q = lissajous_from_vector(vector_from_lissajous(p), p)
    assert q == p
    assert lissajous_from_vector([0.2, 5, 3000, 4, 12]).A_y == 12 and lissajous_from_vector([0.2, 5, 3000, 4, 12]).kappa_y == 3000


def test_faster_travel_removes_less():
    W = removal_from_vector(np.array([_x(v=v) for v in (0.1, 0.2, 0.4, 0.8)]))
    assert np.all(np.diff(W) < 0)


def test_friction_sticks_the_oscillation():
    # Below mu f_n the tool does not slide: amplitude and frequency no longer matter.
    f_n = 20.0
    small = [ _x(f_n=f_n, A_x=a, f_x=f) for a in (1.0, 4.0) for f in (2.0, 9.0)]
    W = removal_from_vector(np.array(small), model=ScrubModel(tipping_ratio=1e3))
    assert np.allclose(W, W[0])
    assert removal_depth(dataclasses.replace(LissajousParams(), f_n=f_n, A_x=30.0)) > W[0]


def test_resonance_and_interior_force_optimum():
    model = ScrubModel()
    kappa = 5000.0
    f_r = np.sqrt(kappa / model.mass) / (2 * np.pi)
    W = removal_from_vector(np.array([_x(kappa_x=kappa, f_x=f) for f in (f_r / 3, f_r, 3 * f_r)]))
    assert W[1] > W[0] and W[1] > W[2]
    forces = np.linspace(1.0, 60.0, 60)
    Wf = removal_from_vector(np.array([_x(f_n=f) for f in forces]))
    k = int(np.argmax(Wf))
    assert 0 < k < len(forces) - 1  # pushing harder is not always better


def test_scrub_faces_noise_free_and_deterministic(stained_sphere):
    _, stain, hardness = stained_sphere
    p = LissajousParams()
    W = removal_depth(p)
    np.testing.assert_allclose(scrub_faces(stain, p, hardness=hardness), np.clip(stain - W / hardness, 0, 1))
    a = scrub_faces(stain, p, hardness=hardness, rng=np.random.default_rng(5))
    b = scrub_faces(stain, p, hardness=hardness, rng=np.random.default_rng(5))
    assert np.array_equal(a, b)
    assert np.all(a <= stain) and np.all(a[stain == 0] == 0)


def test_opacity_endpoints():
    assert stain_opacity(0.0) == 0.0 and stain_opacity(1.0) == pytest.approx(1.0)
    assert np.all(np.diff(stain_opacity(np.linspace(0, 1, 11))) > 0)


def test_measure_cp_through_images(stained_sphere):
    mesh, stain, hardness = stained_sphere
    assert measure_cp(mesh, np.zeros_like(stain), LissajousParams(), rng=np.random.default_rng(0)) == 0.0
    weak = measure_cp(mesh, stain, LissajousParams(v=1.0, f_n=1.0, A_x=0.0, A_y=0.0), rng=None, hardness=hardness,
                      image_size=(48, 48))
    strong = measure_cp(mesh, stain, LissajousParams(v=0.05, f_n=20.0), rng=None, hardness=hardness, image_size=(48, 48))
    assert weak < 0.05 and strong > 0.8
    r1 = measure_cp(mesh, stain, LissajousParams(), rng=np.random.default_rng(9), hardness=hardness, image_size=(48, 48))
    r2 = measure_cp(mesh, stain, LissajousParams(), rng=np.random.default_rng(9), hardness=hardness, image_size=(48, 48))
    assert r1 == r2


def test_experiment_mean_matches_noise_free_measurement(stained_sphere):
    mesh, stain, hardness = stained_sphere
    ex = ScrubExperiment(mesh, stain, hardness, image_size=(48, 48), table_points=64)
    X = np.array([_x(v=v, f_n=f) for v, f in ((0.3, 10.0), (0.1, 15.0), (0.6, 5.0))])
    direct = [ex(x, None) for x in X]
    np.testing.assert_allclose(ex.mean(X), direct, atol=0.03)
    noisy = [ex(X[0], np.random.default_rng(s)) for s in range(5)]
    assert np.std(noisy) > 0 and abs(np.mean(noisy) - direct[0]) < 0.05


def test_bad_inputs(stained_sphere):
    mesh, stain, hardness = stained_sphere
    p = LissajousParams()
    with pytest.raises(ValueError, match="face_stain"):
        scrub_faces(stain * 3, p)
    with pytest.raises(ValueError, match="hardness"):
        scrub_faces(stain, p, hardness=-hardness)
    with pytest.raises(ValueError, match="X"):
        removal_from_vector(np.ones((2, 4)))
    with pytest.raises(ValueError, match="kappa"):
        removal_from_vector(np.array([[0.3, 10, 0.0, 6, 30]]))
    with pytest.raises(ValueError, match="x"):
        lissajous_from_vector(np.ones((2, 5)))
    with pytest.raises(ValueError, match="face_stain"):
        ScrubExperiment(mesh, np.zeros_like(stain), hardness)
    for field in ("preston", "mass", "friction", "optical_depth", "foam_force"):
        with pytest.raises(ValueError, match=field):
            ScrubModel(**{field: 0.0})
    with pytest.raises(ValueError, match="face_noise"):
        ScrubModel(face_noise=-0.1)


def test_contact_wear_of_many_steps_equals_one_step_at_a_time(stained_sphere):
    mesh = stained_sphere[0]
    rng = np.random.default_rng(7)
    n = 200
    world_T_part = np.tile(np.eye(4), (n, 1, 1))
    world_T_part[:, :3, :3] = Rotation.from_rotvec(rng.normal(0.0, 0.3, (n, 3))).as_matrix()
    world_T_part[:, :3, 3] = rng.normal(0.0, 0.02, (n, 3))
    part_T_world = np.linalg.inv(world_T_part)
    # contact centroids on the surface, the pad axis into it, overlapping from step to step
    local = mesh.vertices[rng.integers(0, len(mesh.vertices), n)]
    centres = np.einsum("nij,nj->ni", world_T_part[:, :3, :3], local) + world_T_part[:, :3, 3]
    axes = np.einsum("nij,nj->ni", world_T_part[:, :3, :3], -local / np.linalg.norm(local, axis=1, keepdims=True))
    pressure, sliding = rng.uniform(1e3, 5e4, n), rng.uniform(0.0, 1e-3, n)
    wear = ContactWear(mesh, 0.03, 2e-4, depth=0.002)
    wear.add_steps(part_T_world, centres, axes, pressure, sliding)
    # the loop it replaces: each step's faces under the pad (part frame)
    expected = np.zeros(len(mesh.faces))
    for T, c, a, p, s in zip(part_T_world, centres, axes, pressure, sliding):
        c, a = transform_points(T, c[None])[0], T[:3, :3] @ a
        rel = mesh.triangles_center - c
        along = rel @ a
        under = ((np.abs(along) <= 0.002) & (np.linalg.norm(rel - along[:, None] * a, axis=1) <= 0.03)
                 & (mesh.face_normals @ a < 0))
        expected[under] += 2e-4 * p * s
    assert np.count_nonzero(expected) > 20
    np.testing.assert_allclose(wear.removal, expected, rtol=1e-12, atol=0)
    assert wear.deepest <= 0.002
    wear.add_steps(np.zeros((0, 4, 4)), np.zeros((0, 3)), np.zeros((0, 3)), [], [])
    np.testing.assert_allclose(wear.removal, expected, rtol=1e-12, atol=0)


def test_contact_wear_only_where_the_pad_is():
    """A pad on the rim of a bowl-like shell: the faces 5 mm under it (the inside floor, and
    the back of a thin wall) get no wear; the convex hull's ball of old credited them."""
    top = trimesh.creation.box((0.1, 0.1, 0.001)).subdivide_to_size(0.004)  # top face at z = +0.5 mm
    below = top.copy()
    below.apply_translation((0.0, 0.0, -0.005))  # a second plate 5 mm under it
    mesh = trimesh.util.concatenate([top, below])
    wear = ContactWear(mesh, 0.015, 1e-4, depth=0.002)
    T = np.eye(4)[None]
    wear.add_steps(T, np.array([[0.0, 0.0, 0.0005]]), np.array([[0.0, 0.0, -1.0]]), [1e4], [1e-3])
    z = mesh.triangles_center[:, 2]
    assert wear.removal[z > 0.0004].sum() > 0  # the top face under the pad
    assert np.all(wear.removal[z < 0.0004] == 0)  # its underside (facing away) and the lower plate
    assert wear.deepest <= 0.002


def test_render_stain_states_renders_each_state_as_render_stain_image_does():
    from mavac.vision.stain import face_index_image, render_stain_image

    mesh = trimesh.creation.icosphere(2)
    face_index = face_index_image(mesh, np.array([0.0, 0.0, -1.0]), (32, 32))
    states = [np.linspace(0.0, 2.0, len(mesh.faces)), np.zeros(len(mesh.faces))]
    images = render_stain_states(mesh, states, face_index, noise_std=0.02, rng=np.random.default_rng(3))
    rng = np.random.default_rng(3)
    for state, image in zip(states, images):
        expected = render_stain_image(mesh, stain_opacity(state), None, face_index=face_index, noise_std=0.02, rng=rng)
        assert np.array_equal(image, expected)


def test_render_stain_states_refuses_a_state_of_another_length_or_with_nan():
    from mavac.vision.stain import face_index_image

    mesh = trimesh.creation.icosphere(1)
    face_index = face_index_image(mesh, np.array([0.0, 0.0, -1.0]), (16, 16))
    good = np.zeros(len(mesh.faces))
    with pytest.raises(ValueError, match=r"states\[1\] must be a thickness per face"):
        render_stain_states(mesh, [good, good[:-1]], face_index, rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"states\[0\]"):
        render_stain_states(mesh, [np.full(len(mesh.faces), np.nan)], face_index, rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="rng is required"):
        render_stain_states(mesh, [good], face_index, noise_std=0.02)
