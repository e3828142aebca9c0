"""HTML views: framing camera, hidden ray layers, legend, animations of T and of the setups,
and a headless-Chromium screenshot that is not blank."""

import base64
import re
import warnings

import numpy as np
import pytest
import trimesh
import umsgpack

from mavac.experiments.mavac_offline import fast_params
from mavac.geometry.machines import machine_from_mesh
from mavac.inspection.inspection_plan import plan_inspection
from mavac.viz import scenes
from mavac.viz.screenshot import find_chromium, screenshot_html


def commands(html: str) -> list[dict]:
    """The meshcat commands embedded in a static page (geometry blobs umsgpack refuses are skipped)."""
    out = []
    for b in re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html):
        try:
            out.append(umsgpack.unpackb(base64.b64decode(b)))
        except umsgpack.UnpackException:
            pass
    return out


@pytest.fixture(scope="module")
def plan():
    body = trimesh.creation.box(bounds=[[0, 0, 0], [1.2, 0.6, 0.9]])
    pocket = trimesh.creation.box(bounds=[[0.3, 0.15, 0.5], [0.9, 0.45, 1.0]])
    mesh = trimesh.boolean.difference([body, pocket], engine="manifold")
    p = fast_params()
    params = p.with_visibility("raycast")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a low-coverage warning is not what this module tests
        return plan_inspection(machine_from_mesh(mesh, name="cabinet"), params=params)


@pytest.fixture(scope="module")
def plan_html(plan, tmp_path_factory):
    path = tmp_path_factory.mktemp("html") / "plan.html"
    plan.to_html(path)
    return path


def test_pose_set_motion_moves_the_base_only_with_the_arm_home():
    home = np.zeros(2)
    spots = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, np.pi / 2]])
    q = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    times, bases, qs = scenes.pose_set_motion(spots, np.array([0, 0, 1]), q, home)
    assert np.all(np.diff(times) > 0)
    moved = np.flatnonzero(np.any(np.diff(bases, axis=0) != 0, axis=1))
    assert len(moved) == 1  # one base move, between the two spots
    k = moved[0]
    np.testing.assert_array_equal(qs[k], home)
    np.testing.assert_array_equal(qs[k + 1], home)
    for qi in q:  # every pose is reached and held
        assert np.any(np.all(qs == qi, axis=1))
    np.testing.assert_array_equal(bases[-1], spots[1])


def test_plan_page_frames_hides_rays_animates_and_has_a_legend(plan, plan_html):
    html = plan_html.read_text()
    cmds = commands(html)
    camera = [c for c in cmds if c.get("path", "").startswith("/Cameras/default")]
    assert any(c["type"] == "set_transform" for c in camera)
    target = next(c for c in camera if c["type"] == "set_transform")["matrix"]
    centre = (np.asarray(plan.mesh.bounds[0]) + plan.mesh.bounds[1]) / 2
    assert abs(target[12] - centre[0]) < 1.0 and abs(target[13] - centre[1]) < 1.0  # aimed near the machine
    hidden = {c["path"] for c in cmds if c["type"] == "set_property" and c["property"] == "visible" and not c["value"]}
    assert "/meshcat/guard_rays" in hidden
    anim = [c for c in cmds if c["type"] == "set_animation"]
    assert len(anim) == 1
    paths = {a["path"] for a in anim[0]["animations"]}
    assert "/meshcat/robot" in paths and any(p.startswith("/meshcat/robot/visuals/") for p in paths)
    assert "raycast visibility" in html and "mavac-legend" in html
    assert "127.0.0.1" not in html.split("<script>")[0]


def test_setup_page_animates_the_part_through_its_setups(tmp_path):
    from mavac.geometry.stain_marking import mark_stain
    from mavac.setups.setup_plan import plan_setups

    part = mark_stain(trimesh.creation.icosphere(subdivisions=3, radius=0.06), cone=((0, 0, 1), 60), passes=1)
    plan = plan_setups(part)
    path = plan.to_html(tmp_path / "setups.html", part)
    cmds = commands(path.read_text())
    anim = next(c for c in cmds if c["type"] == "set_animation")
    part_clip = next(a["clip"] for a in anim["animations"] if a["path"] == "/meshcat/part")
    tracks = {t["name"]: t["keys"] for t in part_clip["tracks"]}
    # A placement is position and orientation: two setups may differ in alpha alone.
    placed = {tuple(np.round(np.r_[p["value"], q["value"]], 6))
              for p, q in zip(tracks[".position"], tracks[".quaternion"])}
    assert len(placed) == len(plan.setups)  # one placement per setup


def _centre_colours(png) -> int:
    import matplotlib.image as mpimg

    img = (mpimg.imread(png)[..., :3] * 255).astype(np.uint8)
    h, w = img.shape[:2]
    return len(np.unique(img[h // 4: 3 * h // 4, w // 4: 3 * w // 4].reshape(-1, 3), axis=0))


def test_screenshot_of_the_plan_is_not_blank(plan_html, tmp_path):
    if find_chromium() is None:
        pytest.skip("no Chromium on PATH: `make` installs Debian's chromium (as root); "
                    "otherwise `sudo apt-get install chromium`")
    from mavac.viz import meshcat_scene as ms

    with ms.scene() as vis:  # an empty page: background gradient and grid only
        empty = ms.save_html(vis, tmp_path / "empty.html")
    shots = {name: _centre_colours(screenshot_html(page, tmp_path / f"{name}.png", size=(800, 600), budget_ms=4000))
             for name, page in (("empty", empty), ("plan", plan_html))}
    # the empty page has a few hundred colours (gradient, grid); the plan many thousands
    assert shots["plan"] > 5 * shots["empty"], shots


def test_hidden_nodes_vanish_at_their_frame_and_bad_frames_are_refused(tmp_path):
    from mavac.viz import meshcat_scene as ms

    with ms.scene() as vis:
        ms.add_spheres(vis, "heaps", [[0, 0, 0], [1, 0, 0]], [(0, 1, 0), (1, 0, 0)], radius=0.05)
        ms.animate(vis, {"heaps/0": np.tile(np.eye(4), (3, 1, 1))}, times=[0, 5, 9], hide_at={"heaps/1": 7})
        page = ms.save_html(vis, tmp_path / "vanish.html")
        with pytest.raises(ValueError, match=r"hide_at\['heaps/1'\] must be a frame >= 1, got 0"):
            ms.animate(vis, {"heaps/0": np.tile(np.eye(4), (3, 1, 1))}, hide_at={"heaps/1": 0})
    anim = next(c for c in commands(page.read_text()) if c["type"] == "set_animation")
    clip = next(a["clip"] for a in anim["animations"] if a["path"] == "/meshcat/heaps/1")
    track = next(t for t in clip["tracks"] if t["name"] == ".visible")
    assert track["type"] == "boolean" and [(k["time"], k["value"]) for k in track["keys"]] == [(0, True), (7, False)]


def test_setup_colours_stay_clear_of_the_reserved_colours_and_of_each_other():
    def clear_of(reserved):
        for k in range(1, 21):
            colors = scenes.setup_colors(k)
            assert colors.shape == (k, 3)
            assert np.linalg.norm(colors[:, None] - np.array(reserved)[None], axis=2).min() > 0.25, k

    # the setup page's red (unreached stain), grey (clean surface) and table colour mean something else
    clear_of([scenes.RED, scenes.GREY])
    clear_of([scenes.WOOD])
    ten = scenes.setup_colors(10)
    apart = np.linalg.norm(ten[:, None] - ten[None], axis=2)[np.triu_indices(10, 1)]
    assert apart.min() > 0.15


def test_setup_page_table_reads_as_a_table(tmp_path):
    from mavac.geometry.stain_marking import mark_stain
    from mavac.setups.setup_plan import plan_setups

    part = mark_stain(trimesh.creation.icosphere(subdivisions=3, radius=0.06), cone=((0, 0, 1), 60), passes=1)
    cmds = commands(plan_setups(part).to_html(tmp_path / "setups.html", part).read_text())
    table = next(c for c in cmds if c["type"] == "set_object" and c["path"] == "/meshcat/table")
    material = table["object"]["materials"][0]
    rgb = np.array([(material["color"] >> s) & 255 for s in (16, 8, 0)]) / 255
    assert material.get("opacity", 1.0) >= 0.8  # see-through at 0.35, the brown read grey-violet
    assert min(np.linalg.norm(rgb - np.array(c)) for c in (scenes.RED, scenes.GREY)) > 0.25


def test_reach_page_colour_bar_names_the_quantity_its_unit_and_how_to_read_it(tmp_path):
    from types import SimpleNamespace

    from mavac.robots.models import ur10_mobile

    robot = ur10_mobile()
    mesh = trimesh.creation.box(bounds=[[0, 0, 0], [0.6, 0.6, 0.6]])
    points, normals = mesh.triangles_center, mesh.face_normals
    score = np.linspace(0.0, 0.008, len(points))
    study = SimpleNamespace(robot_name="ur10_mobile", score=score, mesh=mesh, points=points, normals=normals,
                            params=SimpleNamespace(surface_spacing=0.05), candidates=np.array([[-1.0, 0.3, 0.0]]),
                            best_spot=np.zeros(len(points), int), best_q=np.tile(robot.q_home, (len(points), 1)),
                            machine_name="box", reach_fraction=float(np.mean(score > 0)), visibility="raycast")
    html = scenes.reach_study_html(study, tmp_path / "reach.html", robot=robot).read_text()
    bar = html.split('class="mavac-cbar-label">')[1].split("</div>")[0]
    assert "maneuverability index" in bar and "dimensionless" in bar
    assert "higher = better reach" in html


def test_plan_page_draws_a_bounded_number_of_camera_triads(plan, tmp_path, monkeypatch):
    cap = 5
    assert len(plan.world_T_camera) > cap  # the fixture plan has more poses than this cap
    monkeypatch.setattr(scenes, "MAX_TRIADS", cap)
    html = scenes.inspection_plan_html(plan, tmp_path / "capped.html").read_text()
    triads = {c["path"] for c in commands(html)
              if c["type"] == "set_object" and c["path"].startswith("/meshcat/cameras/")}
    assert len(triads) == cap
    h = len(plan.world_T_camera)
    # first and last pose of T among the drawn ones
    assert any(p.endswith("_0") for p in triads) and any(p.endswith(f"_{h - 1}") for p in triads)
    assert f"small triads at {cap} of the {h} cameras" in html
