"""Plane-slicing multi-pass tool paths (Kabir, Sec. VI) on small trimesh test surfaces."""

import numpy as np
import pytest
import trimesh

from mavac.geometry.parts import part_from_mesh
from mavac.params import ToolpathParams
from mavac.scrubbing.toolpath import (
    execution_time_fn,
    patches_for_pass,
    slice_curves,
    toolpath_for_setup,
)

W = 0.03
PARAMS = ToolpathParams(tool_width_m=W, waypoint_spacing_m=0.01)


def height_field(size=0.2, n=17, z=None):
    """Triangulated square [-size/2, size/2]^2 with heights z(x, y), normals up (metres)."""
    xs = np.linspace(-size / 2, size / 2, n + 1)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    Z = np.zeros_like(X) if z is None else z(X, Y)
    V = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    m = n + 1
    a = (np.arange(n)[:, None] * m + np.arange(n)[None, :]).ravel()
    F = np.vstack([np.column_stack([a, a + m, a + m + 1]), np.column_stack([a, a + m + 1, a + 1])])
    return trimesh.Trimesh(V, F, process=False)


def make_part(mesh, faces, passes=None):
    faces = np.asarray(faces)
    passes = np.ones(len(faces), int) if passes is None else np.asarray(passes)
    return part_from_mesh(mesh, faces, passes, name="test")


def distance_to(mesh, points):
    return trimesh.proximity.closest_point(mesh, points)[1]


def test_flat_square_gives_parallel_lines_spaced_by_tool_width():
    mesh = height_field()
    curves = slice_curves(mesh, [1.0, 0.0, 0.0], W)
    xs = []
    for plane in curves:
        assert len(plane) == 1  # one connected curve per plane on a convex region
        c = plane[0]
        assert np.ptp(c[:, 0]) < 1e-9  # straight line in the plane x = const
        assert np.ptp(c[:, 1]) == pytest.approx(0.2)
        xs.append(c[0, 0])
    assert np.allclose(np.diff(xs), W)
    assert xs[0] + 0.1 == pytest.approx(0.1 - xs[-1])  # planes centred on the region

    part = make_part(mesh, np.arange(len(mesh.faces)))
    tp = toolpath_for_setup(part, np.eye(4), np.arange(len(mesh.faces)), PARAMS, plane_normal=[1, 0, 0])
    assert len(tp.passes) == 1
    assert tp.repositionings == 0  # boustrophedon turns stay on the stain
    assert tp.coverage[0] >= 0.99
    # Contact path ~ one line per plane plus the turns between them.
    assert tp.path_length_m == pytest.approx(len(xs) * 0.2 + (len(xs) - 1) * W, rel=0.02)


def test_auto_sweep_frame_and_world_pose_on_curved_surface():
    mesh = height_field(z=lambda x, y: 0.03 * np.sin(20 * x) * np.cos(10 * y))
    part = make_part(mesh, np.arange(len(mesh.faces)))
    T = trimesh.transformations.rotation_matrix(0.7, [0, 0, 1])
    T[:3, 3] = [0.5, -0.2, 0.1]
    tp = toolpath_for_setup(part, T, np.arange(len(mesh.faces)), PARAMS)
    assert tp.coverage[0] >= 0.9  # slopes across the planes widen the strips beyond w
    world = part.mesh.copy().apply_transform(T)
    for seg, nrm in zip(tp.passes[0].segments, tp.passes[0].normals):
        assert distance_to(world, seg).max() < 2e-3  # on the surface up to spline sag
        assert np.allclose(np.linalg.norm(nrm, axis=1), 1.0)
        assert np.all(nrm[:, 2] > 0.5)  # outward (up) normals of the posed part


def test_pass_k_covers_only_patches_needing_at_least_k_passes():
    mesh = height_field()
    x = mesh.triangles_center[:, 0]
    passes = np.where(x < -0.03, 1, np.where(x < 0.04, 2, 3))
    part = make_part(mesh, np.arange(len(mesh.faces)), passes)
    assert np.array_equal(patches_for_pass(passes, 2), passes >= 2)
    tp = toolpath_for_setup(part, np.eye(4), np.arange(len(mesh.faces)), PARAMS)
    assert [p.pass_number for p in tp.passes] == [1, 2, 3]
    for p in tp.passes:
        k = p.pass_number
        assert set(p.patch_ids) == set(np.flatnonzero(passes >= k))
        region = mesh.submesh([np.flatnonzero(passes >= k)], append=True)
        pts = np.vstack(p.segments)
        assert distance_to(region, pts).max() < 2e-3  # never cleans patches that are done
        assert p.coverage >= 0.95
    lengths = [p.path_length_m for p in tp.passes]
    assert lengths[0] > lengths[1] > lengths[2] > 0
    # A setup holding only pass-1 patches has a single pass.
    one = toolpath_for_setup(part, np.eye(4), np.flatnonzero(passes == 1), PARAMS)
    assert len(one.passes) == 1


@pytest.mark.parametrize("shape", ["hole", "two_components"])
def test_stain_gaps_make_repositioning_moves_never_contact(shape):
    mesh = height_field()
    c = mesh.triangles_center
    if shape == "hole":
        faces = np.flatnonzero(np.linalg.norm(c[:, :2], axis=1) > 0.05)
    else:
        faces = np.flatnonzero(np.abs(c[:, 0]) > 0.04)
    part = make_part(mesh, faces)
    stain = mesh.submesh([faces], append=True)
    for normal in ([1, 0, 0], [0, 1, 0], None):
        tp = toolpath_for_setup(part, np.eye(4), np.arange(len(faces)), PARAMS, plane_normal=normal)
        p = tp.passes[0]
        assert tp.repositionings >= 1
        assert len(p.repositions) == len(p.segments) - 1
        assert p.coverage >= 0.95
        for seg in p.segments:
            # every contact point lies on the stain: nothing crosses the stain-free gap
            assert distance_to(stain, seg).max() < 2e-3
            assert np.linalg.norm(np.diff(seg, axis=0), axis=1).max() < 2 * PARAMS.waypoint_spacing_m
        for move in p.repositions:
            assert move.shape == (4, 3)  # flat part: nothing to clear
            assert move[1, 2] - move[0, 2] == pytest.approx(PARAMS.lift_height_m)  # lift along +z normal
            assert move[-2, 2] - move[-1, 2] == pytest.approx(PARAMS.lift_height_m)  # lower
    if shape == "two_components":
        for seg in tp.passes[0].segments:
            assert np.all(seg[:, 0] < 0) or np.all(seg[:, 0] > 0)


def test_repositioning_moves_clear_a_bump_between_stains():
    bump = lambda x, y: 0.08 * np.exp(-(x**2 + y**2) / 0.03**2)  # noqa: E731
    mesh = height_field(n=40, z=bump)
    faces = np.flatnonzero(np.abs(mesh.triangles_center[:, 0]) > 0.07)
    part = make_part(mesh, faces)
    tp = toolpath_for_setup(part, np.eye(4), np.arange(len(faces)), PARAMS, plane_normal=[0, 1, 0])
    across = [m for m in tp.passes[0].repositions if m[0, 0] * m[-1, 0] < 0]
    assert across  # the pass goes from one side of the bump to the other
    shift = part.mesh.metadata["mavac_part_offset"]  # part frame -> height-field frame
    for move in across:
        pts = np.vstack([np.linspace(a, b, 50) for a, b in zip(move[:-1], move[1:])]) + shift
        assert np.min(pts[:, 2] - bump(pts[:, 0], pts[:, 1])) > -1e-6  # never through the part
        assert move[:, 2].max() > bump(0.0, 0.0)  # over the top


def test_ik_failure_splits_path_and_uses_tool_axis_into_surface():
    mesh = height_field()
    part = make_part(mesh, np.arange(len(mesh.faces)))
    axes_seen = []

    def reachable(positions, axes):
        axes_seen.append(axes)
        return ~((positions[:, 1] > -0.02) & (positions[:, 1] < 0.02))

    full = toolpath_for_setup(part, np.eye(4), np.arange(len(mesh.faces)), PARAMS, plane_normal=[1, 0, 0])
    cut = toolpath_for_setup(part, np.eye(4), np.arange(len(mesh.faces)), PARAMS,
                             reachable=reachable, plane_normal=[1, 0, 0])
    assert np.allclose(np.vstack(axes_seen), [0, 0, -1])  # tool z = -outward normal
    p = cut.passes[0]
    assert cut.repositionings >= 1 and full.repositionings == 0
    pts = np.vstack(p.segments)
    assert not np.any((pts[:, 1] > -0.02 + 1e-3) & (pts[:, 1] < 0.02 - 1e-3))
    assert cut.coverage[0] < full.coverage[0]
    assert cut.path_length_m < full.path_length_m
    band = np.abs(mesh.triangles_center[:, 1]) < 0.004  # > w/2 from both band edges
    assert not p.covered[band].any() and full.passes[0].covered[band].all()


def test_puma_ik_limits_the_path_to_what_the_arm_reaches():
    from mavac.geometry.parts import bowl_part
    from mavac.params import ReachParams, SetupSpaceParams
    from mavac.robots.kinematics import ik_axis
    from mavac.robots.models import puma560
    from mavac.setups.reach import base_T_part
    from mavac.scrubbing.toolpath import reachable_from_robot

    part = bowl_part()
    robot = puma560(ReachParams().tool_length)
    # a setup at the edge of the workspace: only part of the stain is reachable
    T = base_T_part([[0.45, 0.75, 0.0]], SetupSpaceParams())[0]
    ids = np.flatnonzero(part.passes == 2)
    free = toolpath_for_setup(part, T, ids, PARAMS)
    arm = toolpath_for_setup(part, T, ids, PARAMS, reachable=reachable_from_robot(robot))
    assert 0 < arm.coverage[0] < free.coverage[0]
    pts = np.vstack(arm.passes[0].segments)
    nrm = np.vstack(arm.passes[0].normals)
    assert ik_axis(robot, pts, -nrm).success.mean() > 0.95  # spline points between waypoints too
    # The planner's interface places the part with the reach test's convention.
    mask = np.isin(np.arange(len(part.stain_faces)), ids)
    t = execution_time_fn(part, robot=robot, params=PARAMS)(mask[None], [[0.45, 0.75, 0.0]])
    assert t[0] == pytest.approx(arm.t_execution_s)


def test_execution_time_is_contact_plus_reposition():
    mesh = height_field()
    c = mesh.triangles_center
    faces = np.flatnonzero(np.linalg.norm(c[:, :2], axis=1) > 0.05)
    passes = np.where(c[faces, 0] < 0.0, 1, 2)
    part = make_part(mesh, faces, passes)
    tp = toolpath_for_setup(part, np.eye(4), np.arange(len(faces)), PARAMS)
    contact = sum(np.linalg.norm(np.diff(s, axis=0), axis=1).sum() for p in tp.passes for s in p.segments)
    moves = [m for p in tp.passes for m in p.repositions]
    travel = sum(np.linalg.norm(np.diff(m, axis=0), axis=1).sum() for m in moves)
    assert tp.repositionings == len(moves) > 0
    assert tp.t_contact_s == pytest.approx(contact / PARAMS.tool_speed_m_s)
    assert tp.t_reposition_s == pytest.approx(travel / PARAMS.reposition_speed_m_s)
    assert tp.t_execution_s == pytest.approx(tp.t_contact_s + tp.t_reposition_s)
    # The move into pass 2 starts where pass 1 ends.
    assert np.allclose(tp.passes[1].repositions[0][0], tp.passes[0].segments[-1][-1])

    # The planner interface: one t^e per cover row; an empty row costs nothing.
    def pose(s):
        T = trimesh.transformations.rotation_matrix(s[2], [0, 0, 1])
        T[:3, 3] = [s[0], s[1], 0.0]
        return T

    exec_times = execution_time_fn(part, params=PARAMS, world_T_part_from_setup=pose)
    cover = np.zeros((3, len(faces)), bool)
    cover[0] = True
    cover[1, passes == 1] = True
    setups = np.array([[0.0, 0.0, 0.0], [0.3, 0.1, 1.0], [0.0, 0.0, 0.0]])
    t = exec_times(cover, setups)
    assert t.shape == (3,)
    assert t[0] == pytest.approx(tp.t_execution_s)
    assert 0 < t[1] < t[0] and t[2] == 0.0
    with pytest.raises(ValueError, match="cover"):
        exec_times(cover[:, :5], setups)

    # ... which the setup planner takes as its cost array (eq. 1: t_s + t_e).
    from mavac.planning.setcover import setup_costs_from_times, solve_setup_cover

    cand = np.array([passes == 1, passes == 2, np.ones(len(faces), bool)])
    costs = setup_costs_from_times(exec_times(cand, np.zeros((3, 3))), 60.0)
    plan = solve_setup_cover(cand, costs)
    assert cand[plan.setups].any(axis=0).all()
    assert plan.cost == pytest.approx(costs[plan.setups].sum())


@pytest.mark.parametrize("field,value", [("tool_width_m", 0.0), ("tool_speed_m_s", -0.1),
                                         ("waypoint_spacing_m", 0.0), ("lift_height_m", -1.0),
                                         ("reposition_speed_m_s", -0.2)])
def test_bad_parameters_raise_naming_the_parameter(field, value):
    with pytest.raises(ValueError, match=field):
        ToolpathParams(**{field: value})


def test_bad_inputs_raise():
    mesh = height_field()
    part = make_part(mesh, np.arange(10))
    with pytest.raises(ValueError, match="patch_ids"):
        toolpath_for_setup(part, np.eye(4), [10], PARAMS)
    with pytest.raises(ValueError, match="world_T_part"):
        toolpath_for_setup(part, np.eye(3), [0], PARAMS)
    with pytest.raises(ValueError, match="k"):
        patches_for_pass([1, 2], 0)
    empty = toolpath_for_setup(part, np.eye(4), [], PARAMS)
    assert empty.passes == () and empty.t_execution_s == 0.0


def test_sweep_frame_keeps_strips_even_on_curved_stains_and_long_on_flat_ones():
    from mavac.scrubbing.toolpath import sweep_frame

    flat = height_field()
    flat.vertices[:, 0] *= 1.5  # 0.3 m long in x, 0.2 m in y
    normal, sweep = sweep_frame(flat)
    assert abs(normal[1]) == pytest.approx(1.0) and abs(sweep[0]) == pytest.approx(1.0)
    # Half cylinder of axis x: normals span y-z, so the planes must be perpendicular to x
    # even though the region is longer across the axis (arc 0.31 m) than along it (0.2 m).
    cyl = height_field()
    theta = cyl.vertices[:, 1] / 0.2 * np.pi
    cyl.vertices[:, 1], cyl.vertices[:, 2] = 0.1 * np.sin(theta), 0.1 * np.cos(theta)
    normal, _ = sweep_frame(cyl)
    assert abs(normal[0]) == pytest.approx(1.0, abs=1e-6)
    part = make_part(cyl, np.arange(len(cyl.faces)))
    tp = toolpath_for_setup(part, np.eye(4), np.arange(len(cyl.faces)), PARAMS)
    assert tp.coverage[0] >= 0.98


def test_the_pad_axis_is_the_plane_it_rests_on_not_one_face_normal():
    from mavac.scrubbing.toolpath import _Surface

    # a roof: two 20-degree slopes meeting at a ridge along y, in 2 mm triangles
    roof = height_field(size=0.2, n=100, z=lambda X, Y: -np.abs(X) * np.tan(np.radians(20)))
    surface = _Surface(roof, roof, 0.03)
    ridge, slope = np.array([[0.0, 0.0, 0.0], [0.05, 0.0, -0.05 * np.tan(np.radians(20))]])
    n_ridge, n_slope = surface.stain_normals(np.array([ridge, slope]))
    # on the ridge the pad straddles both slopes: its axis is vertical, not one slope's normal
    assert n_ridge == pytest.approx([0.0, 0.0, 1.0], abs=1e-6)
    # a pad radius away from it, the pad lies on one slope
    tilt = np.radians(20)
    assert n_slope == pytest.approx([np.sin(tilt), 0.0, np.cos(tilt)], abs=1e-6)


def test_a_piece_of_coincident_waypoints_makes_no_segment(monkeypatch):
    import mavac.scrubbing.toolpath as toolpath

    mesh = height_field()
    part = make_part(mesh, np.arange(len(mesh.faces)))
    fit = toolpath._fit_spline
    # the first piece's waypoints all coincide (as the spline fit returns them: one point)
    monkeypatch.setattr(toolpath, "_fit_spline", lambda pts: fit(pts)[:1] if pts[0, 0] < -0.05 else fit(pts))
    reach = lambda p, a: np.abs(p[:, 0]) > 0.04  # noqa: E731 (two separate pieces per plane)
    tp = toolpath_for_setup(part, np.eye(4), np.arange(len(mesh.faces)), PARAMS, plane_normal=[0, 1, 0],
                            reachable=reach)
    assert tp.passes[0].segments and all(len(seg) >= 2 for seg in tp.passes[0].segments)
