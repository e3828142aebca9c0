"""Each subcommand of the ``mavac`` command line on small procedural meshes (fast options)."""

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import trimesh

from mavac import cli


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("meshes")
    # a 1.2 x 0.6 x 0.9 m cabinet with an open-top pocket, exported in millimetres
    body = trimesh.creation.box(bounds=[[0, 0, 0], [1200, 600, 900]])
    pocket = trimesh.creation.box(bounds=[[300, 150, 500], [900, 450, 1000]])
    trimesh.boolean.difference([body, pocket], engine="manifold").export(d / "cabinet.stl")
    # a 12 cm dome in millimetres (faces well under 1.5 cm^2)
    trimesh.creation.icosphere(subdivisions=3, radius=60.0).export(d / "dome.ply")
    # a 10 cm box with its +x half painted brown, in metres, large faces
    box = trimesh.creation.box([0.1, 0.1, 0.1])
    v, f = trimesh.remesh.subdivide(box.vertices, box.faces)
    painted = trimesh.Trimesh(v, f, process=False)
    colours = np.tile([235, 235, 225, 255], (len(v), 1)).astype(np.uint8)
    colours[v[:, 0] > 0.02] = [90, 60, 30, 255]
    painted.visual.vertex_colors = colours
    painted.export(d / "painted.ply")
    return d


def run(argv, capsys):
    code = cli.main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_inspect_writes_a_plan_that_names_its_visibility(files, tmp_path, capsys):
    code, out, err = run(["inspect", str(files / "cabinet.stl"), "--units", "mm", "--fast", "--quiet",
                          "--out", str(tmp_path / "plan.html")], capsys)
    assert code == 0, err
    plan = json.loads((tmp_path / "cabinet_plan.json").read_text())  # beside the HTML page
    assert plan["visibility"] == "raycast"
    assert plan["params"]["visibility"]["method"] == "raycast"
    assert 0.0 < plan["C"] <= 1.0 and plan["poses"] and len(plan["poses"][0]["q"]) == 6
    assert "(raycast visibility)" in out and "wrote" in out
    html = (tmp_path / "plan.html").read_text()
    assert "mavac-legend" in html and "raycast visibility" in html


def test_inspect_with_hpr_and_default_output_folder(files, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("MAVAC_OUT", str(tmp_path / "out"))
    code, out, err = run(["inspect", str(files / "cabinet.stl"), "--units", "mm", "--fast", "--quiet",
                          "--no-nos", "--visibility", "hpr"], capsys)
    assert code == 0, err
    plan = json.loads((tmp_path / "out" / "cabinet_plan.json").read_text())
    assert plan["visibility"] == "hpr" and "(hpr visibility)" in out
    assert (tmp_path / "out" / "cabinet_plan.html").is_file()


@pytest.mark.parametrize("argv, message", [
    (["inspect", "{cabinet}", "--fast"], "1200 m across after reading it in 'm'.* pass --units mm"),
    (["inspect", "{missing}"], "does not exist"),
    (["inspect", "{cabinet}", "--units", "mm", "--P-s", "1.5"], "P_s must be in"),
    (["inspect", "{cabinet}", "--units", "mm", "--visibility", "hpr", "--hpr-radius", "-1"], "radius must be in"),
    (["reach", "{cabinet}", "--units", "mm", "--spacing", "-0.1"], "surface_spacing must be in"),
    (["setups", "{dome}", "--units", "mm", "--stain", "left:3"], "stain spec 'left:3' not understood"),
    (["setups", "{dome}", "--units", "mm", "--stain", "sphere:500,500,500,1"], "picked no face"),
])
def test_bad_input_exits_1_with_the_reason_and_no_traceback(files, tmp_path, capsys, argv, message):
    paths = {"cabinet": str(files / "cabinet.stl"), "dome": str(files / "dome.ply"),
             "missing": str(files / "missing.stl")}
    argv = [a.format(**paths) for a in argv] + ["--quiet", "--out", str(tmp_path / "x.html")]
    code, _, err = run(argv, capsys)
    assert code == 1
    assert err.startswith(f"mavac {argv[0]}: error: ")
    assert pytest.importorskip("re").search(message, err), err
    assert "Traceback" not in err
    assert not list(tmp_path.iterdir())  # nothing written


def test_setups_plans_a_stained_part(files, tmp_path, capsys):
    code, out, err = run(["setups", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--passes", "2",
                          "--quiet", "--out", str(tmp_path / "dome.html")], capsys)
    assert code == 0, err
    plan = json.loads((tmp_path / "dome_setups.json").read_text())
    assert plan["status"] == "optimal" and plan["setups"] and plan["method"] == "auto"
    assert plan["certificate_cost_s"] == pytest.approx(plan["cost_s"]) == pytest.approx(plan["certificate_bound_s"])
    assert plan["certificate_proof"] in ("reduction", "enumeration", "milp") and "proven optimal" in out
    covered = sorted(i for s in plan["setups"] for i in s["patches"])
    assert covered + plan["uncoverable"] == sorted(covered + plan["uncoverable"])
    assert "setup 1:" in out and "passes [0, " in out
    assert "mavac-legend" in (tmp_path / "dome.html").read_text()


def test_setups_method_dfbnb_is_the_papers_search_without_a_certificate(files, tmp_path, capsys):
    code, out, err = run(["setups", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--quiet",
                          "--method", "dfbnb", "--out", str(tmp_path / "dome.html")], capsys)
    assert code == 0, err
    plan = json.loads((tmp_path / "dome_setups.json").read_text())
    assert plan["method"] == "dfbnb" and plan["certificate_cost_s"] is None and plan["node_expansions"] > 0
    assert "proven" not in out


def test_setups_from_painted_colours_subdivides_large_patches(files, tmp_path, capsys):
    code, out, err = run(["setups", str(files / "painted.ply"), "--stain", "colors", "--subdivide", "--quiet",
                          "--out", str(tmp_path / "p.html")], capsys)
    assert code == 0, err
    assert "larger than the tool tip" not in err  # subdivided below 1.5 cm^2 first
    code, out, err = run(["setups", str(files / "painted.ply"), "--stain", "colors", "--quiet",
                          "--out", str(tmp_path / "q.html")], capsys)
    assert code == 0 and "mavac: warning: " in err and "larger than the tool tip" in err


def test_reach_writes_a_heat_map_and_a_csv(files, tmp_path, capsys):
    code, out, err = run(["reach", str(files / "cabinet.stl"), "--units", "mm", "--fast", "--quiet",
                          "--out", str(tmp_path / "reach.html")], capsys)
    assert code == 0, err
    df = pd.read_csv(tmp_path / "cabinet_reach.csv")
    assert {"x", "y", "z", "reached", "visible", "maneuverability", "score", "best_spot", "q1", "q6"} <= set(df)
    assert df.score.between(0, 1).all() and (df.score > 0).any()
    assert ((df.score > 0) <= (df.reached & df.visible)).all()
    html = (tmp_path / "reach.html").read_text()
    assert "mavac-cbar" in html and "raycast visibility" in html
    assert "(raycast visibility)" in out


def test_interrupt_exits_130_and_leaves_no_file(files, tmp_path, capsys, monkeypatch):
    import mavac.setups.setup_plan as plan_module

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(plan_module, "plan_setups", interrupted)
    code, _, err = run(["setups", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--quiet",
                        "--out", str(tmp_path / "d.html")], capsys)
    assert code == 130 and "interrupted" in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("command", ["inspect", "setups", "reach"])
def test_help_gives_units_and_defaults(command, capsys):
    with pytest.raises(SystemExit) as exit_:
        cli.main([command, "--help"])
    assert exit_.value.code == 0
    text = capsys.readouterr().out
    assert "--units" in text and "metres" in text and "default" in text


def test_python_dash_m_runs_the_command_line(files, tmp_path):
    done = subprocess.run([sys.executable, "-m", "mavac", "inspect", str(files / "cabinet.stl"), "--quiet"],
                          capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 1 and "pass --units mm" in done.stderr and "Traceback" not in done.stderr
    assert "mavac" in subprocess.run([sys.executable, "-m", "mavac", "--version"], capture_output=True,
                                     text=True).stdout
