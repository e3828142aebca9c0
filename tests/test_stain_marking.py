import numpy as np
import pytest
import trimesh

from mavac.geometry import stain_marking as S
from mavac.geometry.mesh import load_mesh


def _fine_box(size=0.1, edge=0.01):
    b = trimesh.creation.box([size, size, size])
    v, f = trimesh.remesh.subdivide_to_size(b.vertices, b.faces, max_edge=edge)
    return trimesh.Trimesh(v, f, process=False)


def test_cone_box_and_sphere_select_by_normal_and_centre():
    mesh = _fine_box()
    up = S.faces_in_cone(mesh, (0, 0, 1), 30)
    np.testing.assert_array_equal(up, mesh.face_normals[:, 2] > 0.99)
    side = S.faces_in_cone(mesh, (1, 0, 0), 89)  # +x face only: the others are at 90 deg or more
    np.testing.assert_array_equal(side, mesh.face_normals[:, 0] > 0.99)
    inside = S.faces_in_box(mesh, (-1, -1, 0.049), (1, 1, 1))
    np.testing.assert_array_equal(inside, mesh.triangles_center[:, 2] >= 0.049)
    ball = S.faces_in_sphere(mesh, (0, 0, 0.05), 0.02)
    assert ball.any() and np.all(np.linalg.norm(mesh.triangles_center[ball] - [0, 0, 0.05], axis=1) <= 0.02)


def test_mark_stain_combines_selectors_and_takes_passes_from_intensity():
    mesh = _fine_box()
    intensity = np.clip(mesh.triangles_center[:, 0] / 0.05, 0.01, 1.0)  # rises along +x
    part = S.mark_stain(mesh, cone=((0, 0, 1), 30), box=((0.0, -1, -1), (1, 1, 1)), intensity=intensity,
                        name="lid")
    centres = mesh.triangles_center[part.stain_faces]
    normals = mesh.face_normals[part.stain_faces]
    assert np.all(normals[:, 2] > 0.99) and np.all(centres[:, 0] >= 0.0)
    expected = S.passes_from_intensity(intensity[part.stain_faces])
    np.testing.assert_array_equal(part.passes, expected)
    assert set(np.unique(part.passes)) == {1, 2, 3}
    const = S.mark_stain(mesh, cone=((0, 0, 1), 30), passes=2)
    assert np.all(const.passes == 2)


def test_mark_stain_refuses_empty_and_total_selections():
    mesh = _fine_box()
    with pytest.raises(ValueError, match="picked no face"):
        S.mark_stain(mesh, sphere=((5, 5, 5), 0.01))
    with pytest.raises(ValueError, match="picked every face"):
        S.mark_stain(mesh, box=((-1, -1, -1), (1, 1, 1)))
    with pytest.raises(ValueError, match="at least one stain selector"):
        S.mark_stain(mesh)
    with pytest.raises(ValueError, match="passes must be integers in 1..3"):
        S.mark_stain(mesh, cone=((0, 0, 1), 30), passes=4)


def test_large_stain_triangles_warn_and_subdivide_below_the_tool_tip():
    coarse = trimesh.creation.box([0.1, 0.1, 0.1])  # 50 cm^2 triangles
    with pytest.warns(UserWarning, match=r"2 of 2 stain patches are larger than the tool tip \(1.5 cm\^2"):
        S.mark_stain(coarse, cone=((0, 0, 1), 10))
    part = S.mark_stain(coarse, cone=((0, 0, 1), 10), passes=3, subdivide=True)
    assert part.patch_areas.max() <= S.TOOL_TIP_AREA
    assert part.patch_areas.sum() == pytest.approx(0.01)  # the whole 10 x 10 cm top, nothing else
    assert np.all(part.patch_normals[:, 2] > 0.99) and np.all(part.passes == 3)


def test_stain_from_painted_vertex_colours(tmp_path):
    mesh = _fine_box()
    colours = np.tile([230, 230, 220, 255], (len(mesh.vertices), 1)).astype(np.uint8)
    dark = mesh.vertices[:, 0] > 0.02
    colours[dark] = [80, 50, 30, 255]
    mesh.visual.vertex_colors = colours
    mesh.export(tmp_path / "painted.ply")
    loaded = load_mesh(tmp_path / "painted.ply", units="m", role="part")
    stained, intensity = S.faces_from_colors(loaded)
    all_dark = dark[np.asarray(loaded.faces)].all(axis=1)
    assert np.all(stained[all_dark])  # every face painted dark is stain
    assert not stained[~dark[np.asarray(loaded.faces)].any(axis=1)].any()  # no clean face is
    assert intensity[all_dark].min() == pytest.approx(1.0)
    part = S.mark_stain(loaded, colors={})
    assert len(part.stain_faces) == int(stained.sum())
    by_colour, _ = S.faces_from_colors(loaded, stain_color=(80 / 255, 50 / 255, 30 / 255), tolerance=0.05)
    np.testing.assert_array_equal(by_colour, all_dark)


def test_colourless_mesh_refused():
    with pytest.raises(ValueError, match="no per-vertex or per-face colours"):
        S.faces_from_colors(_fine_box())


@pytest.mark.parametrize("spec, key", [("up:30", "cone"), ("0,0,1:45", "cone"), ("box:0,0,0,10,10,10", "box"),
                                       ("sphere:0,0,50,20", "sphere"), ("colors", "colors"),
                                       ("colors:#503c1e", "colors"), ("faces:1,2,3", "faces")])
def test_parse_stain(spec, key):
    assert key in S.parse_stain(spec, scale=0.001)


def test_parse_stain_scales_lengths_and_combines():
    kw = S.parse_stain("down:20,sphere:10,0,0,5", scale=0.001)
    assert kw["cone"] == ((0, 0, -1), 20.0)
    np.testing.assert_allclose(kw["sphere"][0], [0.01, 0, 0])
    assert kw["sphere"][1] == pytest.approx(0.005)
    with pytest.raises(ValueError, match="stain spec 'left:5' not understood"):
        S.parse_stain("left:5")
    with pytest.raises(ValueError, match="not understood"):
        S.parse_stain("box:1,2,3")


# Every form ``mavac setups --help`` shows, joined with ',' (issue 33: '+x:45' was split on '+').
@pytest.mark.parametrize("spec, key", [
    ("up:30", "cone"), ("down:45", "cone"), ("+x:45", "cone"), ("-x:45", "cone"), ("+y", "cone"),
    ("-y:10", "cone"), ("+z:5", "cone"), ("-z:5", "cone"), ("x:45", "cone"), ("y", "cone"), ("z:20", "cone"),
    ("0,0,1:30", "cone"), ("-1,0,0", "cone"), ("box:0,0,0,1,1,1", "box"), ("sphere:0,0,0,1", "sphere"),
    ("colors", "colors"), ("colors:#503c1e", "colors"), ("faces:0,1,2", "faces"),
    ("up:30,box:0,0,0,1,1,1", "box"), ("box:0,0,0,1,1,1,-x:45", "cone"), ("faces:0,1,0,0,1:30", "cone"),
    ("sphere:0,0,0,1,0,0,1:30", "cone"), ("+x:45,faces:3,4", "faces")])
def test_parse_stain_every_form_of_the_help(spec, key):
    assert key in S.parse_stain(spec)


def test_parse_stain_signs_are_directions_not_joins():
    assert S.parse_stain("+x:45")["cone"] == ((1, 0, 0), 45.0)
    assert S.parse_stain("-x:45")["cone"] == ((-1, 0, 0), 45.0)
    assert S.parse_stain("x")["cone"] == ((1, 0, 0), 30.0)
    kw = S.parse_stain("faces:0,1,0,0,1:30")
    assert kw["faces"].tolist() == [0, 1] and kw["cone"] == ((0.0, 0.0, 1.0), 30.0)


def test_cones_of_one_spec_are_united():
    box = trimesh.creation.box([1, 1, 1])
    up = S.mark_stain(box, **S.parse_stain("up:30"), name="b")
    both = S.mark_stain(box, **S.parse_stain("up:30,down:30"), name="b")
    assert len(both.stain_faces) == 2 * len(up.stain_faces) == 4
    wide = S.mark_stain(box, **S.parse_stain("up:10,+x:60"), name="b")
    assert len(wide.stain_faces) == 4
    same = S.mark_stain(box, **S.parse_stain("up:10,up:60"), name="b")
    assert len(same.stain_faces) == len(up.stain_faces)
    # different kinds intersect: the top faces inside the box x > 0.2 (none of them: only corners)
    kw = S.parse_stain("up:30,down:30,box:-1,-1,-1,1,1,0")
    assert len(S.mark_stain(box, **kw, name="b").stain_faces) == 2  # the bottom only


def test_parse_stain_refuses_huge_face_indices_and_old_plus_joins():
    with pytest.raises(ValueError, match="faces"):
        S.parse_stain("faces:" + "9" * 30)
    with pytest.raises(ValueError, match="not understood.*','"):
        S.parse_stain("up:30+box:0,0,0,1,1,1")
    with pytest.raises(ValueError, match="colors"):
        S.parse_stain("colors,colors:#000000")
