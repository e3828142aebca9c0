import base64
import re

import numpy as np
import pytest
import trimesh

from mavac.viz import meshcat_scene, plots


def test_static_html_contains_scene_and_server_is_shut_down(tmp_path):
    box = trimesh.creation.box((1.0, 0.5, 0.2))
    with meshcat_scene.scene() as vis:
        meshcat_scene.add_mesh(vis, "machine", box, opacity=0.5)
        meshcat_scene.add_points(vis, "pts", np.random.default_rng(0).random((50, 3)))
        meshcat_scene.add_lines(vis, "rays", np.zeros((3, 3)), np.eye(3))
        meshcat_scene.add_triad(vis, "frame", np.eye(4))
        path = meshcat_scene.save_html(vis, tmp_path / "scene.html")
        proc = vis.window.server_proc
    html = path.read_text()
    assert html.lstrip().lower().startswith("<!doctype html") or "<html" in html[:200].lower()
    blobs = [base64.b64decode(b) for b in re.findall(r"base64,([A-Za-z0-9+/=]+)", html)]
    assert any(b"/meshcat/machine" in b for b in blobs), "mesh not embedded in the static HTML"
    assert any(b"/meshcat/rays" in b for b in blobs)
    assert proc.poll() is not None, "meshcat server still running after scene() exit"


def test_server_shut_down_on_error():
    with pytest.raises(RuntimeError):
        with meshcat_scene.scene() as vis:
            proc = vis.window.server_proc
            raise RuntimeError("boom")
    assert proc.poll() is not None


def test_plot_mesh_and_save(tmp_path, monkeypatch):
    monkeypatch.setenv("MAVAC_FAST", "1")
    monkeypatch.setattr(plots, "figures_dir", lambda: tmp_path)
    fig, ax = plots.new_figure(projection="3d")
    plots.plot_mesh(ax, trimesh.creation.icosphere(subdivisions=2))
    path = plots.save(fig, "sphere.png")
    assert path.exists() and path.stat().st_size > 1000


def test_robot_scene_embeds_links(tmp_path):
    from mavac.robots.models import se2_to_matrix, ur10_mobile

    robot = ur10_mobile()
    with meshcat_scene.scene() as vis:
        meshcat_scene.add_robot(vis, "robot", robot, robot.q_home, world_T_base=se2_to_matrix(1.0, 0.0, 0.5))
        html = meshcat_scene.save_html(vis, tmp_path / "r.html").read_text()
    blobs = [base64.b64decode(b) for b in re.findall(r"base64,([A-Za-z0-9+/=]+)", html)]
    assert any(b"mir200_base" in b for b in blobs) and any(b"tool_sphere" in b for b in blobs)
    with pytest.raises(ValueError, match="geometry"):
        with meshcat_scene.scene() as vis:
            meshcat_scene.add_robot(vis, "robot", robot, robot.q_home, geometry="wire")


def test_no_dead_server_url_is_printed(capsys):
    with meshcat_scene.scene() as vis:
        meshcat_scene.add_triad(vis, "frame", np.eye(4))
    out = capsys.readouterr()
    assert "http" not in out.out and "http" not in out.err


def test_legend_overlay_and_hidden_layer(tmp_path):
    with meshcat_scene.scene() as vis:
        meshcat_scene.add_lines(vis, "rays", np.zeros((2, 3)), np.eye(3)[:2])
        meshcat_scene.set_visible(vis, "rays", False)
        legend = meshcat_scene.legend_html([((1.0, 0.0, 0.0), "a <red> thing")], title="T",
                                           colorbar=("viridis", 0.0, 1.0, "score"))
        html = meshcat_scene.save_html(vis, tmp_path / "l.html", legend=legend).read_text()
    assert html.count('id="mavac-legend"') == 1 and "a &lt;red&gt; thing" in html
    assert "rgb(255,0,0)" in html and "linear-gradient" in html
    with pytest.raises(ValueError, match="same number of keys"):
        with meshcat_scene.scene() as vis:
            meshcat_scene.animate(vis, {"a": np.tile(np.eye(4), (2, 1, 1)), "b": np.tile(np.eye(4), (3, 1, 1))})
