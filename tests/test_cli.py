"""Each subcommand of the ``mavac`` command line on small procedural meshes (fast options)."""

import argparse
import json
import os
import subprocess
from pathlib import Path
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
    plan = json.loads((tmp_path / "plan.json").read_text())  # the HTML page's name
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
    (["setups", "{dome}", "--units", "mm", "--stain", "up:60", "--setup-time", "1e308"], "setup_time must be in"),
    (["setups", "{dome}", "--units", "mm", "--stain", "up:60", "--seed", str(2**70)], "seed must be in"),
    (["inspect", "{cabinet}", "--units", "mm", "--visibility", "hpr", "--hpr-radius", "1e308"], "radius must be in"),
    (["inspect", "{cabinet}", "--units", "mm", "--spacing", "0.003"], "surface elements"),
    (["setups", "{dome}", "--units", "mm", "--stain", "up:60", "--t-max", "5"], "--t-max applies only"),
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
    plan = json.loads((tmp_path / "dome.json").read_text())
    assert plan["status"] == "optimal" and plan["setups"] and plan["method"] == "auto"
    assert plan["certificate_cost_s"] == pytest.approx(plan["cost_s"]) == pytest.approx(plan["certificate_bound_s"])
    assert plan["certificate_proof"] in ("reduction", "enumeration", "milp") and "proven optimal" in out
    covered = sorted(i for s in plan["setups"] for i in s["patches"])
    assert covered + plan["uncoverable"] == sorted(covered + plan["uncoverable"])
    assert "setup 1:" in out and "passes [0, " in out
    assert "mavac-legend" in (tmp_path / "dome.html").read_text()
    # full poses: the part frame and the file's frame (the dome's centre, 6 cm above its bottom)
    from mavac.params import SetupPlanParams
    from mavac.setups.reach import base_T_part

    for setup in plan["setups"]:
        T = base_T_part(np.array([[setup["x"], setup["y"], setup["alpha"]]]), SetupPlanParams().space)[0]
        assert np.allclose(setup["base_T_part"], T)
        assert np.allclose(setup["base_T_file"], T @ trimesh.transformations.translation_matrix([0, 0, 0.06]))


def test_setups_method_dfbnb_is_the_papers_search_without_a_certificate(files, tmp_path, capsys):
    code, out, err = run(["setups", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--quiet",
                          "--method", "dfbnb", "--out", str(tmp_path / "dome.html")], capsys)
    assert code == 0, err
    plan = json.loads((tmp_path / "dome.json").read_text())
    assert plan["method"] == "dfbnb" and plan["certificate_cost_s"] is None and plan["node_expansions"] > 0
    assert "proven" not in out


def test_setups_from_painted_colours_subdivides_large_patches(files, tmp_path, capsys):
    # reach without collision checking: this test is about the patches, not the arm (CI time)
    code, out, err = run(["setups", str(files / "painted.ply"), "--stain", "colors", "--subdivide", "--quiet",
                          "--no-collision", "--out", str(tmp_path / "p.html")], capsys)
    assert code == 0, err
    assert "larger than the tool tip" not in err  # subdivided below 1.5 cm^2 first
    code, out, err = run(["setups", str(files / "painted.ply"), "--stain", "colors", "--quiet", "--no-collision",
                          "--out", str(tmp_path / "q.html")], capsys)
    assert code == 0 and "warning: " in out and "larger than the tool tip" in out  # in the summary, once


def test_the_loaded_mesh_is_freed_once_the_stain_is_marked(files, monkeypatch):
    # issue 33: the loaded mesh and its trimesh caches (1.5 GB at 2 M faces) sat in reference
    # cycles through the whole plan; with the cyclic collector off only an explicit collect frees it
    import gc
    import weakref

    loaded = []

    def load(*args):
        mesh = load_mesh(*args)
        loaded.append(weakref.ref(mesh))
        return mesh

    load_mesh = cli._load
    monkeypatch.setattr(cli, "_load", load)
    args = cli.build_parser().parse_args(["setups", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60"])
    monkeypatch.setattr(cli, "_next", lambda *a, **k: None)
    gc.disable()
    try:
        part = cli._marked_part(args, None, None)
    finally:
        gc.enable()
    assert len(part.stain_faces) and loaded[0]() is None


def test_reach_writes_a_heat_map_and_a_csv(files, tmp_path, capsys):
    code, out, err = run(["reach", str(files / "cabinet.stl"), "--units", "mm", "--fast", "--quiet",
                          "--out", str(tmp_path / "reach.html")], capsys)
    assert code == 0, err
    df = pd.read_csv(tmp_path / "reach.csv")  # the HTML page's name
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


@pytest.mark.parametrize("command", ["inspect", "setups", "reach", "clean", "scrub"])
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


# ---- issue 33: the command line's input handling -------------------------------------------------

def _parsed(monkeypatch, argv) -> argparse.Namespace:
    """The namespace ``main`` hands a command (the command itself replaced by a recorder)."""
    seen = {}
    for name in ("cmd_inspect", "cmd_setups", "cmd_reach", "cmd_clean", "cmd_scrub"):
        monkeypatch.setattr(cli, name, lambda args: seen.setdefault("args", args) and 0)
    assert cli.main(argv) == 0
    return seen["args"]


@pytest.mark.parametrize("value", ["+x:45", "-x:45", "-y", "-1,0,0:45", "up:30,down:30", "x:10,-z:20"])
def test_every_stain_form_reaches_the_command(monkeypatch, value):
    for argv in (["setups", "p.stl", "--stain", value], ["setups", "p.stl", f"--stain={value}"]):
        assert _parsed(monkeypatch, argv).stain == value


@pytest.mark.parametrize("value", ["+x", "-x", "+y", "-y", "+z", "-z", "x", "y", "z"])
def test_up_takes_every_signed_axis(monkeypatch, value):
    assert _parsed(monkeypatch, ["inspect", "m.stl", "--up", value]).up == value


def test_a_part_turned_so_its_up_is_minus_y_plans_as_the_original(tmp_path, capsys):
    block = trimesh.creation.box([0.10, 0.06, 0.04])
    block.export(tmp_path / "block.ply")
    turned = block.copy()
    turned.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))  # z -> -y
    assert np.allclose(turned.face_normals[np.argmax(block.face_normals[:, 2])], [0, -1, 0])
    turned.export(tmp_path / "turned.ply")
    plans = []
    for name, up in (("block", "z"), ("turned", "-y")):
        code, _, err = run(["setups", str(tmp_path / f"{name}.ply"), "--stain", "up:30", "--up", up, "--quiet",
                            "--out", str(tmp_path / f"{name}_out.html")], capsys)
        assert code == 0, err
        plan = json.loads((tmp_path / f"{name}_out.json").read_text())
        plans.append({k: v for k, v in plan.items() if k != "part"})
    assert plans[0] == plans[1]


@pytest.mark.parametrize("option", [["--P-s", "0.9"], ["--P-g", "0.9"], ["--no-nos"]])
def test_reach_refuses_the_options_it_does_not_use(option, capsys):
    with pytest.raises(SystemExit) as exit_:
        cli.main(["reach", "m.stl", *option])
    assert exit_.value.code == 2 and "unrecognized arguments" in capsys.readouterr().err


def test_hpr_radius_without_hpr_is_refused(files, tmp_path, capsys):
    code, _, err = run(["inspect", str(files / "cabinet.stl"), "--units", "mm", "--hpr-radius", "3",
                        "--out", str(tmp_path / "x.html")], capsys)
    assert code == 1 and "--hpr-radius" in err and "--visibility hpr" in err


def test_companion_files_follow_the_out_stem(files, tmp_path, capsys):
    code, _, err = run(["reach", str(files / "cabinet.stl"), "--units", "mm", "--fast", "--quiet",
                        "--out", str(tmp_path / "heat.html")], capsys)
    assert code == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["heat.csv", "heat.html"]


@pytest.fixture
def no_compute(monkeypatch):
    """Any computation fails the test: output paths must be checked before it starts."""
    import mavac.geometry.mesh as mesh_module

    def computed(*args, **kwargs):
        raise AssertionError("computed before refusing the output path")

    monkeypatch.setattr(mesh_module, "load_mesh", computed)


@pytest.mark.parametrize("case", ["input", "same", "empty", "directory", "under_file", "readonly", "env_out",
                                  "env_cache"])
def test_bad_output_paths_are_refused_before_computing(files, tmp_path, capsys, monkeypatch, no_compute, case):
    mesh = str(files / "cabinet.stl")
    (tmp_path / "plain").write_text("a file")
    readonly = tmp_path / "ro"
    readonly.mkdir()
    readonly.chmod(0o555)
    out, extra, message = str(tmp_path / "x.html"), [], "--out"
    if case == "input":
        out, message = mesh, "is the input"
    elif case == "same":
        extra, message = ["--csv", out], "both --out and --csv"
    elif case == "empty":
        out, message = "", "--out is empty"
    elif case == "directory":
        out, message = str(tmp_path), "is a directory"
    elif case == "under_file":
        out, message = str(tmp_path / "plain" / "x.html"), "not a directory"
    elif case == "readonly":
        out, message = str(readonly / "x.html"), "cannot write"
    elif case == "env_out":
        monkeypatch.setenv("MAVAC_OUT", str(tmp_path / "plain"))
        out, message = None, "MAVAC_OUT"
    elif case == "env_cache":
        monkeypatch.setenv("MAVAC_CACHE", str(tmp_path / "plain"))
        message = "MAVAC_CACHE"
    argv = ["reach", mesh, "--units", "mm", "--fast", "--quiet", *extra] + ([] if out is None else ["--out", out])
    if case == "readonly" and os.access(readonly, os.W_OK):  # root writes anywhere: as the others see it
        access = os.access
        monkeypatch.setattr(os, "access", lambda path, mode: Path(path) != readonly and access(path, mode))
    try:
        code, _, err = run(argv, capsys)
    finally:
        readonly.chmod(0o755)
    assert code == 1 and message in err and "Traceback" not in err, err


def test_an_interrupt_while_writing_keeps_the_old_outputs_together(files, tmp_path, capsys, monkeypatch):
    from mavac.setups.setup_plan import SetupPlan

    out, js = tmp_path / "d.html", tmp_path / "d.json"
    out.write_text("old page")
    js.write_text("old plan")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(SetupPlan, "to_html", interrupted)
    code, _, err = run(["setups", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--quiet",
                        "--out", str(out)], capsys)
    assert code == 130
    assert (out.read_text(), js.read_text()) == ("old page", "old plan")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.html", "d.json"]


def _strict_json(path):
    def refuse(constant):
        raise AssertionError(f"{constant} in {path}")
    return json.loads(Path(path).read_text(), parse_constant=refuse)


def test_a_search_that_finds_no_plan_exits_non_zero_with_strict_json(files, tmp_path, capsys):
    code, out, err = run(["setups", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--quiet",
                          "--method", "dfbnb", "--t-max", "1e-9", "--out", str(tmp_path / "d.html")], capsys)
    assert code == 3 and "NO SOLUTION" in out and "--t-max" in err, (out, err)
    plan = _strict_json(tmp_path / "d.json")
    assert plan["status"] == "timed_out" and plan["cost_s"] is None and not plan["setups"]


def bad_intensity_file(kind: str, folder: Path) -> Path:
    """An ``--intensity`` file of ``kind`` (pickled, truncated, garbage, text, directory, npz) in
    a new ``folder/in``."""
    bad = folder / "in" / ("i.npz" if kind == "npz" else "i.txt" if kind == "text" else "i.npy")
    bad.parent.mkdir()
    if kind == "pickled":
        np.save(bad, np.array([{"a": 1}], dtype=object), allow_pickle=True)
    elif kind == "truncated":
        np.save(bad, np.full(642, 0.5))
        bad.write_bytes(bad.read_bytes()[:200])
    elif kind == "garbage":
        bad.write_bytes(bytes(range(256)) * 4)
    elif kind == "text":
        bad.write_text("half\nfull\n")
    elif kind == "directory":
        bad.mkdir()
    else:
        np.savez(bad, a=np.full(642, 0.5))
    return bad


@pytest.mark.parametrize("kind", ["pickled", "truncated", "garbage", "text", "directory", "npz"])
def test_a_bad_intensity_file_names_the_option(files, tmp_path, capsys, kind):
    bad = bad_intensity_file(kind, tmp_path)
    code, _, err = run(["setups", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--quiet",
                        "--intensity", str(bad), "--out", str(tmp_path / "d.html")], capsys)
    assert code == 1 and err.startswith("mavac setups: error: --intensity") and "Traceback" not in err, err


def test_the_tool_tip_warning_is_printed_once(files, tmp_path, capsys):
    code, out, err = run(["setups", str(files / "painted.ply"), "--stain", "colors", "--quiet",
                          "--out", str(tmp_path / "q.html")], capsys)
    assert code == 0 and (out + err).count("larger than the tool tip") == 1, (out, err)


def test_sighup_is_an_interrupt(tmp_path):
    """A closed terminal (SIGHUP) ends the command as Ctrl-C does: status 130, cleanup run."""
    # a terminal's SIGHUP, with its default disposition even when the tests run under nohup
    code = ("import os, signal, sys, time\nfrom mavac import cli\n"
            "signal.signal(signal.SIGHUP, signal.SIG_DFL)\n"
            "def hung_up(args):\n    os.kill(os.getpid(), signal.SIGHUP)\n    time.sleep(30)\n"
            "cli.cmd_setups = hung_up\n"
            "sys.exit(cli.main(['setups', 'p.stl', '--stain', 'up:30']))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=60)
    assert done.returncode == 130 and "interrupted" in done.stderr, (done.returncode, done.stderr)


@pytest.mark.parametrize("argv, flag", [
    (["inspect", "{cabinet}", "--visibility", "hpr", "--hpr-radius", "1e308"], "--hpr-radius"),
    (["inspect", "{cabinet}", "--spacing", "0.003"], "--spacing"),
    (["inspect", "{cabinet}", "--P-g", "2"], "--P-g"),
    (["setups", "{dome}", "--stain", "up:60", "--setup-time", "1e308"], "--setup-time"),
    (["setups", "{dome}", "--stain", "up:60", "--seed", str(2**70)], "--seed"),
])
def test_a_refused_parameter_is_named_by_its_flag(files, tmp_path, capsys, argv, flag):
    paths = {"cabinet": str(files / "cabinet.stl"), "dome": str(files / "dome.ply")}
    argv = [a.format(**paths) for a in argv] + ["--units", "mm", "--quiet", "--out", str(tmp_path / "x.html")]
    code, _, err = run(argv, capsys)
    assert code == 1 and err.startswith(f"mavac {argv[0]}: error: {flag}: "), err


# ---- mavac clean: MAVAC's simulated online cleaning of a user's machine -----------------------------

#: small sizes: the coarse plan (--fast) and heaps 20 cm apart (about 15 on the box): seconds a trial
CLEAN_FAST = ["--fast", "--spacing", "0.2", "--quiet"]


@pytest.fixture(scope="module")
def cleaned(tmp_path_factory):
    """A 1.0 x 0.6 x 0.6 m box (metres, STL) cleaned in two trials (seeds 0 and 1)."""
    d = tmp_path_factory.mktemp("clean")
    trimesh.creation.box(bounds=[[0, 0, 0], [1.0, 0.6, 0.6]]).export(d / "box.stl")
    code = cli.main(["clean", str(d / "box.stl"), *CLEAN_FAST, "--seed", "0", "--trials", "2",
                     "--out", str(d / "out" / "run.json")])
    return d, code


def test_clean_writes_a_summary_json_and_one_csv_row_per_heap(cleaned):
    d, code = cleaned
    assert code == 0
    # the CSV and the replay page take --out's stem
    assert sorted(p.name for p in (d / "out").iterdir()) == ["run.csv", "run.html", "run.json"]
    assert "mavac-legend" in (d / "out" / "run.html").read_text()
    doc = _strict_json(d / "out" / "run.json")
    table = pd.read_csv(d / "out" / "run.csv", keep_default_na=False)
    assert list(table.columns) == ["seed", "heap", "x", "y", "z", "cleaned", "cause", "seen_by_pose"]
    assert table["cleaned"].dtype == bool and sorted(set(table["seed"])) == [0, 1]
    s = doc["summary"]
    assert s["trials"] == 2 and s["heaps"] == len(table) > 0 and s["cleaned"] == table["cleaned"].sum()
    assert s["cleaning_pct"] == pytest.approx(100.0 * table["cleaned"].mean(), abs=1e-3)
    assert (table["cause"] == "").tolist() == table["cleaned"].tolist()
    assert s["misses"] == {c: int((table["cause"] == c).sum()) for c in s["misses"]}
    assert [t["seed"] for t in doc["trials"]] == [0, 1] and [t["trial"] for t in doc["trials"]] == [1, 2]
    for t in doc["trials"]:
        assert t["heaps"] == (table["seed"] == t["seed"]).sum() and "cleaning_pct" in t and "sim_time_s" in t
    assert doc["status"] == "ok" and doc["parameters"]["spacing"] == 0.2 and doc["parameters"]["trials"] == 2
    assert doc["plan"]["poses"] > 0 and doc["plan"]["visibility"] == "raycast"


def test_clean_same_seed_gives_the_same_csv_byte_for_byte(cleaned, tmp_path, capsys):
    d, _ = cleaned
    code, out, err = run(["clean", str(d / "box.stl"), *CLEAN_FAST, "--seed", "0", "--trials", "2",
                          "--out", str(tmp_path / "again.json")], capsys)
    assert code == 0, err
    assert (tmp_path / "again.csv").read_bytes() == (d / "out" / "run.csv").read_bytes()
    assert "box, seed 0: " in out and "box, seed 1: " in out and "heaps cleaned over 2 trials" in out
    assert "simulated time" in out and "wrote " in out


def test_clean_density_keeps_a_share_of_the_same_layout(cleaned, tmp_path, capsys):
    d, _ = cleaned
    code, _, err = run(["clean", str(d / "box.stl"), *CLEAN_FAST, "--seed", "0", "--density", "0.5",
                        "--out", str(tmp_path / "half.json")], capsys)
    assert code == 0, err
    full = pd.read_csv(d / "out" / "run.csv").query("seed == 0")
    half = pd.read_csv(tmp_path / "half.csv")
    assert len(half) == round(0.5 * len(full)) > 0
    xyz = ["x", "y", "z"]
    assert set(map(tuple, half[xyz].round(9).values)) <= set(map(tuple, full[xyz].round(9).values))
    assert _strict_json(tmp_path / "half.json")["parameters"]["density"] == 0.5


@pytest.mark.parametrize("argv, message", [
    (["--trials", "0"], "--trials must be in [1, "),
    (["--spacing", "-1"], "--spacing: spacing must be in"),
    (["--density", "0"], "--density: density must be in (0.0, 1.0]"),
    (["--density", "1.5"], "--density: density must be in (0.0, 1.0]"),
    (["--out", "{mesh}"], "--out {mesh} is the input mesh"),
    (["--jobs", "0"], "--jobs must be a positive worker count"),
    (["--seed", str(2**31 - 1), "--trials", "2"], "--seed 2147483647 with --trials 2"),
    (["--seed", "-3"], "--seed: seed must be in"),
    (["--html", "{mesh}"], "--html {mesh} is the input mesh"),
    (["--out", "{tmp}/r.json", "--html", "{tmp}/r.json"], "--html {tmp}/r.json is --out"),
    (["--csv", "{tmp}/r.csv", "--html", "{tmp}/r.csv"], "--html {tmp}/r.csv is --csv"),
    (["--html", ""], "--html is empty"),
])
def test_clean_refuses_bad_input_before_any_work(cleaned, tmp_path, capsys, no_compute, argv, message):
    mesh = str(cleaned[0] / "box.stl")
    argv = [a.format(mesh=mesh, tmp=tmp_path) for a in argv]
    out = [] if "--out" in argv else ["--out", str(tmp_path / "x.json")]
    code, _, err = run(["clean", mesh, "--quiet", *out, *argv], capsys)
    assert code == 1 and err.startswith(f"mavac clean: error: {message.format(mesh=mesh, tmp=tmp_path)}"), err
    assert "Traceback" not in err and not list(tmp_path.iterdir())


def test_clean_refuses_a_heap_spacing_the_machine_cannot_take_before_planning(cleaned, tmp_path, capsys,
                                                                            monkeypatch):
    import mavac.inspection.inspection_plan as plan_module

    def planned(*args, **kwargs):
        raise AssertionError("planned before refusing --spacing")

    monkeypatch.setattr(plan_module, "plan_inspection", planned)
    code, _, err = run(["clean", str(cleaned[0] / "box.stl"), "--quiet", "--spacing", "5",
                        "--out", str(tmp_path / "x.json")], capsys)
    assert code == 1 and err.startswith("mavac clean: error: --spacing: ") and "larger than the mesh" in err, err
    assert not list(tmp_path.iterdir())


def test_clean_interrupted_exits_130_and_leaves_no_file(cleaned, tmp_path, capsys, monkeypatch):
    import mavac.parallel as parallel

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(parallel, "map_trials", interrupted)
    code, _, err = run(["clean", str(cleaned[0] / "box.stl"), *CLEAN_FAST, "--out", str(tmp_path / "c.json")],
                       capsys)
    assert code == 130 and "interrupted" in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())


def test_clean_reads_the_plan_inspect_wrote_and_cleans_as_if_it_had_planned(cleaned, tmp_path, capsys):
    d, _ = cleaned
    code, _, err = run(["inspect", str(d / "box.stl"), "--fast", "--quiet", "--out", str(tmp_path / "p.html")], capsys)
    assert code == 0, err
    mesh = json.loads((tmp_path / "p.json").read_text())["mesh"]
    assert mesh["file"] == "box.stl" and mesh["up"] == "z" and mesh["units"] is None and len(mesh["sha256"]) == 64
    code, _, err = run(["clean", str(d / "box.stl"), "--plan", str(tmp_path / "p.json"), "--spacing", "0.2",
                        "--quiet", "--trials", "2", "--out", str(tmp_path / "c.json")], capsys)
    assert code == 0, err
    assert (tmp_path / "c.csv").read_bytes() == (d / "out" / "run.csv").read_bytes()
    doc, ref = _strict_json(tmp_path / "c.json"), _strict_json(d / "out" / "run.json")
    assert doc["plan"] == ref["plan"] and doc["parameters"]["inspection"] == ref["parameters"]["inspection"]
    assert doc["parameters"]["plan_file"] == str(tmp_path / "p.json") and ref["parameters"]["plan_file"] is None


@pytest.mark.parametrize("argv, message", [
    (["--plan", "{plan}", "--fast"], "--fast with --plan: the plan file sets the plan"),
    (["--plan", "{plan}", "--up", "y"], "--up with --plan"),
    (["--plan", "{plan}", "--units", "mm"], "--units with --plan"),
    (["--plan", "{other}"], "--plan {other} was made from 'cabinet.stl', whose content differs from {mesh}"),
    (["--plan", "{mesh}"], "--plan {mesh}: cannot read a JSON plan (UnicodeDecodeError"),
    (["--plan", "{tmp}/none.json"], "--plan {tmp}/none.json: cannot read a JSON plan (FileNotFoundError"),
    (["--plan", "{bare}"], "--plan {bare}: not a plan file written by 'mavac inspect' (it has no 'mesh' entry)"),
    (["--scheduler", "tcp://127.0.0.1:1", "--jobs", "2"], "--jobs with --scheduler"),
])
def test_clean_refuses_a_plan_file_or_scheduler_it_cannot_use_before_any_work(cleaned, tmp_path, capsys,
                                                                              no_compute, argv, message):
    files = {"mesh": str(cleaned[0] / "box.stl"), "tmp": str(tmp_path), "plan": str(tmp_path / "p.json"),
             "other": str(tmp_path / "other.json"), "bare": str(tmp_path / "bare.json")}
    mesh_doc = {"file": "cabinet.stl", "sha256": "0" * 64, "units": None, "up": "z"}
    (tmp_path / "other.json").write_text(json.dumps({"mesh": mesh_doc}))
    (tmp_path / "p.json").write_text(json.dumps({"mesh": mesh_doc}))
    (tmp_path / "bare.json").write_text(json.dumps({"poses": []}))
    made = set(tmp_path.iterdir())
    code, _, err = run(["clean", files["mesh"], "--quiet", "--out", str(tmp_path / "x.json"),
                        *[a.format(**files) for a in argv]], capsys)
    assert code == 1 and err.startswith(f"mavac clean: error: {message.format(**files)}"), err
    assert "Traceback" not in err and set(tmp_path.iterdir()) == made


def test_clean_runs_its_trials_on_a_dask_cluster_and_cleans_the_same(cleaned, tmp_path, capsys):
    import distributed  # the dask extra, installed by make

    class Finished(distributed.diagnostics.plugin.SchedulerPlugin):
        keys: list = []

        def transition(self, key, start, finish, *args, **kwargs):
            if finish == "memory":
                self.keys.append(str(key))

    d, _ = cleaned
    # two workers: joblib runs the trials here when the cluster has a single core
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=None) as cluster:
        cluster.scheduler.add_plugin(Finished())
        code, _, err = run(["clean", str(d / "box.stl"), *CLEAN_FAST, "--seed", "0", "--trials", "2",
                            "--scheduler", cluster.scheduler_address, "--out", str(tmp_path / "dask.json")], capsys)
    ran = [key for key in Finished.keys if "clean_trial" in key]
    assert code == 0, err
    assert ran, "the trials did not run on the cluster's workers"
    assert (tmp_path / "dask.csv").read_bytes() == (d / "out" / "run.csv").read_bytes()


def test_clean_names_a_scheduler_that_does_not_answer(cleaned, tmp_path, capsys, monkeypatch):
    import mavac.cli as cli_module

    monkeypatch.setattr(cli_module, "SCHEDULER_TIMEOUT_S", 0.5)
    code, _, err = run(["clean", str(cleaned[0] / "box.stl"), "--quiet", "--out", str(tmp_path / "x.json"),
                        "--scheduler", "tcp://127.0.0.1:1"], capsys)
    assert code == 1 and err.startswith("mavac clean: error: --scheduler tcp://127.0.0.1:1: no dask scheduler "
                                        "answered"), err
    assert not list(tmp_path.iterdir())


def test_setups_refuses_patches_only_a_colliding_arm_reaches_and_says_how_many(tmp_path, capsys):
    # a bottle with a 4.4 cm neck, 36 cm tall, stained on its inside floor (1 cm up)
    profile = np.array([(0, 0), (0.08, 0), (0.08, 0.30), (0.03, 0.33), (0.03, 0.36), (0.022, 0.36),
                        (0.022, 0.33), (0.072, 0.30), (0.072, 0.01), (0, 0.01)])
    trimesh.creation.revolve(profile, sections=32).export(tmp_path / "vase.stl")
    argv = ["setups", str(tmp_path / "vase.stl"), "--stain", "up:10,box:-0.07,-0.07,0.005,0.07,0.07,0.015", "--quiet"]
    code, out, err = run(argv + ["--out", str(tmp_path / "on.html")], capsys)
    plan = json.loads((tmp_path / "on.json").read_text())
    assert code == cli.NO_PLAN and plan["status"] == "no_solution"
    assert plan["collision_refused"] == len(plan["uncoverable"]) == 32
    assert "collision check on: 32 stain patches refused" in out
    code, out, err = run(argv + ["--no-collision", "--out", str(tmp_path / "off.html")], capsys)
    plan = json.loads((tmp_path / "off.json").read_text())
    assert code == 0 and plan["uncoverable"] == [] and plan["collision_refused"] == 0  # IK alone: through the neck
    assert "collision check on" not in out


# ---- mavac scrub: Kabir's two-arm cell on a user's part ----------------------------------------------

@pytest.fixture(scope="module")
def scrubbed(files, tmp_path_factory):
    """The 12 cm dome (millimetres), its top stained, through the cell in fast mode."""
    d = tmp_path_factory.mktemp("scrub")
    code = cli.main(["scrub", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--fast", "--quiet",
                     "--out", str(d / "run.json")])
    return d, code


def test_scrub_writes_poses_passes_and_a_fading_replay(scrubbed):
    d, code = scrubbed
    assert code == 0
    assert sorted(p.name for p in d.iterdir()) == ["run.csv", "run.html", "run.json"]  # --out's stem
    doc = _strict_json(d / "run.json")
    assert doc["simulated"] is True and doc["status"] in ("clean", "residue left") and doc["part"] == "dome"
    assert doc["operation"]["f_n"] > 0 and doc["setups"]
    table = pd.read_csv(d / "run.csv")
    assert len(table) == sum(len(s["passes"]) for s in doc["setups"]) > 0
    for column in ("setup", "part_x_m", "pass", "duty", "force_error_all", "nonpad_part_steps", "arm_arm_steps"):
        assert column in table.columns
    assert ((0 <= table["duty"]) & (table["duty"] <= 1)).all()
    for setup in doc["setups"]:
        T = np.array(setup["base_T_part"])
        assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-6) and np.allclose(T[3], [0, 0, 0, 1])
        # the dome's file origin is its centre, 6 cm above the part frame's origin
        assert np.allclose(setup["base_T_file"], T @ trimesh.transformations.translation_matrix([0, 0, 0.06]))
        assert len(setup["q_holder"]) == 7
    # the stain removed per setup adds up to the whole run's
    assert sum(s["stain_removed"] for s in doc["setups"]) == pytest.approx(doc["stain_removed"])
    html = (d / "run.html").read_text()
    assert "mavac-legend" in html and "fades" in html


@pytest.mark.parametrize("argv, message", [
    (["--mass", "9"], "--mass: part_mass must be at most 7 kg, the holding arm's rated payload"),
    (["--mass", "-1"], "--mass: part_mass must be in"),
    (["--mass", "nan"], "--mass: part_mass (BimanualCellParams) must be finite"),
    (["--rounds", "21"], "--rounds: max_rounds must be in [0, 20]"),
    (["--seed", "-3"], "--seed: seed must be in"),
    (["--out", "{mesh}"], "--out {mesh} is the input mesh"),
    (["--out", "{tmp}/r.json", "--html", "{tmp}/r.json"], "--html {tmp}/r.json is --out"),
])
def test_scrub_refuses_bad_input_before_any_work(files, tmp_path, capsys, no_compute, argv, message):
    mesh = str(files / "dome.ply")
    argv = [a.format(mesh=mesh, tmp=tmp_path) for a in argv]
    out = [] if "--out" in argv else ["--out", str(tmp_path / "x.json")]
    code, _, err = run(["scrub", mesh, "--units", "mm", "--stain", "up:60", "--quiet", *out, *argv], capsys)
    assert code == 1 and err.startswith(f"mavac scrub: error: {message.format(mesh=mesh, tmp=tmp_path)}"), err
    assert "Traceback" not in err and not list(tmp_path.iterdir())


def test_scrub_refuses_a_part_too_large_for_the_cell(tmp_path, capsys):
    trimesh.creation.box([0.6, 0.6, 0.2]).export(tmp_path / "crate.stl")
    code, _, err = run(["scrub", str(tmp_path / "crate.stl"), "--stain", "up:30", "--fast", "--quiet",
                        "--out", str(tmp_path / "out" / "c.json")], capsys)
    assert code == 1 and "mavac scrub: error: part (0.60 x 0.60 x 0.20 m) is too large for the cell" in err, err
    assert "Traceback" not in err and not (tmp_path / "out").exists()


def test_scrub_narrow_presents_the_part_in_the_square_the_narrowing_places(files, tmp_path, capsys, monkeypatch):
    import mavac.scrubbing.cell_space as cell_space

    squares = []

    def spy(*args, **kwargs):
        squares.append(real(*args, **kwargs)[0])
        return squares[-1], None

    real = cell_space.narrowed_cell_space
    monkeypatch.setattr(cell_space, "narrowed_cell_space", spy)
    code, _, err = run(["scrub", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--fast", "--quiet",
                        "--narrow", "--out", str(tmp_path / "n.json")], capsys)
    assert code == 0, err
    (space,) = squares
    doc = _strict_json(tmp_path / "n.json")
    assert doc["setups"]
    for setup in doc["setups"]:
        x, y = np.array(setup["base_T_part"])[:2, 3]  # as the part was met: the holding arm sags a little
        assert space.origin_x - 0.01 <= x <= space.origin_x + space.x_max + 0.01
        assert space.origin_y - 0.01 <= y <= space.origin_y + space.y_max + 0.01


def test_scrub_narrow_that_finds_no_square_says_so_and_writes_nothing(files, tmp_path, capsys, monkeypatch):
    import mavac.scrubbing.cell_space as cell_space

    monkeypatch.setattr(cell_space.HeldSetups, "__call__", lambda self, setups: np.zeros(len(setups), dtype=bool))
    code, _, err = run(["scrub", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--fast", "--quiet",
                        "--narrow", "--out", str(tmp_path / "n.json")], capsys)
    assert code == 1 and "mavac scrub: error: --narrow: no placement of the part lets the holding arm" in err, err
    assert "Traceback" not in err and not list(tmp_path.iterdir())


def test_scrub_interrupted_exits_130_and_leaves_no_file(files, tmp_path, capsys, monkeypatch):
    import mavac.scrubbing.run as run_module

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(run_module, "run_part", interrupted)
    code, _, err = run(["scrub", str(files / "dome.ply"), "--units", "mm", "--stain", "up:60", "--quiet",
                        "--out", str(tmp_path / "s.json")], capsys)
    assert code == 130 and "interrupted" in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())


def _documented_commands() -> list[list[str]]:
    """Every ``mavac ...`` line of the README's and docs/cli.md's shell blocks, as argv."""
    import re
    import shlex

    root = Path(__file__).resolve().parents[1]
    lines = []
    for doc in (root / "README.md", root / "docs" / "cli.md"):
        for block in re.findall(r"```bash\n(.*?)```", doc.read_text(), flags=re.S):
            lines += [ln.split("#")[0].strip() for ln in block.splitlines() if ln.startswith("mavac ")]
    return [shlex.split(ln)[1:] for ln in lines if "--help" not in ln]


@pytest.mark.parametrize("argv", _documented_commands(), ids=" ".join)
def test_every_documented_command_line_parses(monkeypatch, argv):
    args = _parsed(monkeypatch, argv)
    assert args.command == argv[0]
    if getattr(args, "stain", None):
        from mavac.geometry.stain_marking import parse_stain

        assert parse_stain(args.stain, scale=1.0)


def test_the_stain_example_of_the_help_marks_faces(capsys):
    import re

    from mavac.geometry.stain_marking import mark_stain, parse_stain

    for command in ("setups", "scrub"):
        with pytest.raises(SystemExit):
            cli.main([command, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        example = re.search(r"Example: --stain (\S+)", text).group(1)
        # in millimetres, as the help's box says: a 12 cm dome, its top and bottom inside the box
        dome = trimesh.creation.icosphere(subdivisions=3, radius=0.06)
        part = mark_stain(dome, **parse_stain(example, scale=1e-3))
        assert 0 < len(part.stain_faces) < len(dome.faces)
