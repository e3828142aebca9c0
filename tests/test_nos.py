"""Non-observed surfaces: DBSCAN clusters, ray fans, gateways, spot choice."""

import numpy as np
import pytest
import trimesh

from mavac.inspection import nos
from mavac.params import NoSParams


def _box_with_hole(hole_center_x=0.2):
    """A closed hollow box (1 m, walls 0.1 m) with one square hole through its top."""
    outer = trimesh.creation.box([1.0, 1.0, 1.0])
    outer.apply_translation([0, 0, 0.5])
    inner = trimesh.creation.box([0.8, 0.8, 0.8])
    inner.apply_translation([0, 0, 0.5])
    hole = trimesh.creation.box([0.2, 0.2, 0.3])
    hole.apply_translation([hole_center_x, 0, 0.95])
    return trimesh.boolean.difference([outer, inner, hole], engine="manifold")


def test_sphere_directions_are_unit_and_spread():
    d = nos.sphere_directions(200)
    assert d.shape == (200, 3)
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.linalg.norm(d.mean(axis=0)) < 0.05


def test_gateway_found_through_hole_in_closed_box():
    mesh = _box_with_hole()
    # a small patch of unobserved points on the cavity floor, under the hole
    grid = np.stack(np.meshgrid(np.linspace(0.1, 0.3, 5), np.linspace(-0.1, 0.1, 5)), -1).reshape(-1, 2)
    pts = np.column_stack([grid, np.full(len(grid), 0.1)])
    nrm = np.tile([0.0, 0.0, 1.0], (len(pts), 1))
    clusters = nos.nos_clusters(mesh, pts, nrm, np.zeros(len(pts), bool),
                                NoSParams(eps_factor=1.0, min_samples=3, n_rays=800, ray_length=2.0), spacing=0.08)
    assert len(clusters) == 1
    c = clusters[0]
    assert len(c.gateways) == 1  # the hole is the only way out
    g = c.best_gateway
    assert g.n_rays >= 3
    # every escaping ray passes through the hole's opening at the top (z = 1)
    t = (1.0 - g.origin[2]) / g.ray_directions[:, 2]
    xy = g.origin[:2] + t[:, None] * g.ray_directions[:, :2]
    assert np.all(np.abs(xy[:, 0] - 0.2) <= 0.1 + 1e-6) and np.all(np.abs(xy[:, 1]) <= 0.1 + 1e-6)
    assert g.direction[2] > 0.9


def test_closed_box_has_no_gateway():
    outer = trimesh.creation.box([1.0, 1.0, 1.0])
    outer.apply_translation([0, 0, 0.5])
    inner = trimesh.creation.box([0.8, 0.8, 0.8])
    inner.apply_translation([0, 0, 0.5])
    mesh = trimesh.boolean.difference([outer, inner], engine="manifold")
    pts = np.array([[0.0, 0.0, 0.1], [0.02, 0.0, 0.1], [0.0, 0.02, 0.1]])
    clusters = nos.nos_clusters(mesh, pts, np.tile([0, 0, 1.0], (3, 1)), np.zeros(3, bool),
                                NoSParams(eps_factor=1.0, min_samples=2, n_rays=300, ray_length=2.0), spacing=0.05)
    assert len(clusters) == 1 and clusters[0].best_gateway is None


def test_group_gateways_two_separate_caps():
    d = nos.sphere_directions(500)
    esc = (d[:, 2] > 0.8) | (d[:, 0] > 0.9)
    groups = nos.group_gateways(d, esc)
    assert len(groups) == 2
    assert sorted(len(g) for g in groups) == sorted([int((d[:, 2] > 0.8).sum()), int((d[:, 0] > 0.9).sum())])
    assert len(groups[0]) >= len(groups[1])
    assert nos.group_gateways(d, np.zeros(500, bool)) == []


def test_cluster_unobserved_ignores_observed_and_separates_far_patches():
    a = np.random.default_rng(0).uniform(0, 0.1, (20, 3))
    b = a + [2.0, 0, 0]
    pts = np.vstack([a, b, [[5.0, 5.0, 5.0]]])
    observed = np.zeros(len(pts), bool)
    observed[:5] = True
    lab = nos.cluster_unobserved(pts, observed, eps=0.1, min_samples=3)
    assert np.all(lab[:5] == -1)
    assert lab[-1] == -1  # isolated point is noise
    assert len(set(lab[5:20])) == 1 and len(set(lab[20:40])) == 1 and lab[5] != lab[20]


def test_spot_along_direction():
    spots = np.array([[3.0, 0.0], [0.0, 3.0], [-3.0, 0.0]])
    assert nos.spot_along_direction(spots, [0, 0, 1], [0.0, 1.0, 0.2]) == 1
    assert nos.spot_along_direction(spots, [0, 0, 1], [-1.0, 0.1, 0.0]) == 2
    # vertical exit: nearest spot on the floor
    assert nos.spot_along_direction(spots, [2.5, 0.1, 1], [0, 0, 1.0]) == 0


@pytest.mark.parametrize("kw,name", [(dict(eps=0.0), "eps"), (dict(min_samples=0), "min_samples")])
def test_bad_dbscan_parameters(kw, name):
    args = dict(points=np.zeros((3, 3)), observed=np.zeros(3, bool), eps=0.1, min_samples=2)
    args.update(kw)
    with pytest.raises(ValueError, match=name):
        nos.cluster_unobserved(**args)


def test_bad_inputs():
    with pytest.raises(ValueError, match="n_rays"):
        nos.sphere_directions(2)
    with pytest.raises(ValueError, match="observed"):
        nos.cluster_unobserved(np.zeros((3, 3)), np.zeros(2, bool), 0.1, 2)
    with pytest.raises(ValueError, match="ray_length"):
        NoSParams(ray_length=0.0)
    with pytest.raises(ValueError, match="spacing"):
        nos.nos_clusters(_box_with_hole(), np.zeros((3, 3)), np.zeros((3, 3)), np.zeros(3, bool), NoSParams(),
                         spacing=0.0)
