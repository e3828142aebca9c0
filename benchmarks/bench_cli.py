"""Time the command line as a user runs it, and compare coverage C under HPR and ray casting.

Every subcommand runs as ``python -m mavac ...`` in a subprocess (interpreter start and imports
included) on meshes written to a temporary folder: MAVAC's three machines (procedural, shipped),
the cabinet with a pocket and the step under a slab that the tests generate, and a thin open frame
(four legs and a rim of 4 cm bars, where hidden point removal is most optimistic). ``inspect`` runs
with ``--visibility hpr`` and ``--visibility raycast`` side by side, and the HPR plan's own poses are
re-scored by exact ray casting (what HPR claims against what those poses see); ``reach`` and
``setups`` run once.
The CLI's defaults are used (paper-scale S at 5 cm) unless ``--fast``.

Prints a table and ends with ``SECONDS cli_inspect_test_bench_raycast <t>``. With
``--screenshots DIR`` it also writes the README's screenshots of the HTML pages (needs Chromium).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _meshes(folder: Path) -> dict:
    """name -> (file, units, kind) for the inputs of the benchmark."""
    import numpy as np
    import trimesh

    from mavac.geometry.machines import load_machine

    out = {}
    for name in ("test_bench", "sanding_machine", "milling_machine"):
        path = folder / f"{name}.stl"
        load_machine(name).mesh.export(path)
        out[name] = (path, "m", "machine")
    body = trimesh.creation.box(bounds=[[0, 0, 0], [1200, 600, 900]])
    pocket = trimesh.creation.box(bounds=[[300, 150, 500], [900, 450, 1000]])
    trimesh.boolean.difference([body, pocket], engine="manifold").export(folder / "cabinet.stl")
    out["cabinet"] = (folder / "cabinet.stl", "mm", "machine")
    step = trimesh.boolean.union([trimesh.creation.box(bounds=[[0, 0, 0], [0.6, 1.0, 0.3]]),
                                  trimesh.creation.box(bounds=[[0, 0.5, 0.3], [0.6, 1.0, 1.0]]),
                                  trimesh.creation.box(bounds=[[0, 0, 0.6], [0.6, 1.0, 0.7]])], engine="manifold")
    step.export(folder / "step_under_slab.stl")
    out["step_under_slab"] = (folder / "step_under_slab.stl", "m", "machine")
    bar = 0.04
    parts = [trimesh.creation.box(bounds=[[x, y, 0], [x + bar, y + bar, 0.8]])
             for x in (0.0, 1.2 - bar) for y in (0.0, 0.8 - bar)]
    parts += [trimesh.creation.box(bounds=[[0, y, 0.8 - bar], [1.2, y + bar, 0.8]]) for y in (0.0, 0.8 - bar)]
    parts += [trimesh.creation.box(bounds=[[x, 0, 0.8 - bar], [x + bar, 0.8, 0.8]]) for x in (0.0, 1.2 - bar)]
    trimesh.boolean.union(parts, engine="manifold").export(folder / "open_frame.stl")
    out["open_frame"] = (folder / "open_frame.stl", "m", "machine")
    dome = trimesh.creation.icosphere(subdivisions=3, radius=60.0)
    dome.export(folder / "dome.ply")
    out["dome"] = (folder / "dome.ply", "mm", "part")
    box = trimesh.creation.box([0.1, 0.1, 0.1])
    v, f = trimesh.remesh.subdivide(box.vertices, box.faces)
    painted = trimesh.Trimesh(v, f, process=False)
    colours = np.tile([235, 235, 225, 255], (len(v), 1)).astype(np.uint8)
    colours[v[:, 0] > 0.02] = [90, 60, 30, 255]
    painted.visual.vertex_colors = colours
    painted.export(folder / "painted_box.ply")
    out["painted_box"] = (folder / "painted_box.ply", "m", "part")
    return out


def _hpr_plan_rescored(path: Path, units: str, fast: bool) -> tuple[float, float]:
    """C that HPR claims for its own plan, and C of the same poses by exact ray casting."""
    import warnings

    from mavac.experiments.mavac_offline import fast_params
    from mavac.geometry.machines import machine_from_mesh
    from mavac.geometry.mesh import load_mesh
    from mavac.inspection.coverage import coverage_overlap
    from mavac.inspection.inspection_plan import plan_inspection
    from mavac.params import InspectionParams, Visibility
    from mavac.vision.visibility import VisibilityScene, visible_from

    params = (fast_params() if fast else InspectionParams()).with_visibility("hpr")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_inspection(machine_from_mesh(load_mesh(path, units=units, role="machine")), params=params)
    exact = visible_from(plan.points, plan.normals, plan.world_T_camera, params.camera, Visibility("raycast"),
                         scene=VisibilityScene(plan.mesh))
    return plan.C, coverage_overlap(exact, len(plan.points))[0]


def _run(argv: list[str]) -> float:
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "mavac", *argv, "--quiet"], capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"mavac {' '.join(argv)} failed:\n{done.stderr}")
    return seconds


def main() -> None:
    from mavac.params import VISIBILITY_METHODS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="pass --fast to inspect and reach")
    ap.add_argument("--screenshots", type=Path, default=None, help="write README screenshots here")
    args = ap.parse_args()
    fast = ["--fast"] if args.fast else []
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        meshes = _meshes(tmp)
        _run(["reach", str(meshes["cabinet"][0]), "--units", "mm", "--fast", "--out", str(tmp / "warm.html")])
        print(f"{'mesh':16s} {'command':32s} {'seconds':>8s}  result")
        for name, (path, units, kind) in meshes.items():
            if kind != "machine":
                continue
            for vis in VISIBILITY_METHODS:
                out = tmp / f"{name}_{vis}.html"
                s = _run(["inspect", str(path), "--units", units, "--visibility", vis, "--out", str(out), *fast])
                plan = json.loads(out.with_suffix(".json").read_text())
                rows.append((name, f"inspect --visibility {vis}", s, plan["C"]))
                print(f"{name:16s} {'inspect --visibility ' + vis:32s} {s:8.1f}  C = {plan['C']:.3f} "
                      f"({plan['visibility']}), {len(plan['spots'])} spots, {len(plan['poses'])} poses", flush=True)
            claimed, exact = _hpr_plan_rescored(path, units, args.fast)
            print(f"{name:16s} {'(HPR plan, re-scored exactly)':32s} {'':8s}  HPR says C = {claimed:.3f}, "
                  f"ray casting of the same poses C = {exact:.3f}", flush=True)
        for name in ("test_bench", "cabinet"):
            path, units, _ = meshes[name]
            out = tmp / f"{name}_reach.html"
            s = _run(["reach", str(path), "--units", units, "--out", str(out), *fast])
            import pandas as pd

            df = pd.read_csv(out.with_suffix(".csv"))
            print(f"{name:16s} {'reach':32s} {s:8.1f}  {100 * (df.score > 0).mean():.1f} % of S reached and seen "
                  f"(raycast)", flush=True)
        for name, stain in (("dome", ["--stain", "up:60"]), ("painted_box", ["--stain", "colors", "--subdivide"])):
            path, units, _ = meshes[name]
            out = tmp / f"{name}_setups.html"
            s = _run(["setups", str(path), "--units", units, *stain, "--out", str(out)])
            plan = json.loads(out.with_suffix(".json").read_text())
            print(f"{name:16s} {'setups ' + ' '.join(stain):32s} {s:8.1f}  {len(plan['setups'])} setups, "
                  f"T = {plan['cost_s']:.0f} s, {plan['status']}", flush=True)
        if args.screenshots is not None:
            from mavac.viz.screenshot import screenshot_html

            args.screenshots.mkdir(parents=True, exist_ok=True)
            for page, png in (("test_bench_raycast.html", "cli_inspect_test_bench.png"),
                              ("test_bench_reach.html", "cli_reach_test_bench.png"),
                              ("dome_setups.html", "cli_setups_dome.png")):
                screenshot_html(tmp / page, args.screenshots / png, size=(1200, 750), budget_ms=6000)
                print(f"wrote {args.screenshots / png}")
    t = next(s for n, c, s, _ in rows if n == "test_bench" and c.endswith("raycast"))
    print(f"SECONDS cli_inspect_test_bench_raycast {t:.2f}")


if __name__ == "__main__":
    main()
