"""Command line: ``mavac inspect``, ``mavac setups``, ``mavac reach``, ``mavac clean``, ``mavac
scrub`` (also ``python -m mavac``).

From a mesh file to a result a person can read without the source: an HTML page (framed, with a
legend, the robot animated), a JSON or CSV file, and a summary on the terminal that names the
visibility method behind every coverage. Bad input exits with status 1 and the reason, no
traceback; a setup search that ends without a plan exits with status 3 (its files say why);
Ctrl-C or a closed terminal (SIGHUP) exits with status 130 and leaves no half-written file (the
outputs are renamed into place together at the end) and no meshcat server running.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import gc
import hashlib
import json
import os
import re
import signal
import sys
import threading
import time
import warnings
from pathlib import Path

import numpy as np

from . import __version__
from .config import cache_dir, user_output_dir
from .io import atomic_paths, json_safe, write_json

#: exit status of a run that ended without a plan (its files say why); 1 is bad input, 130 Ctrl-C
NO_PLAN = 3
UNITS_HELP = ("unit of the coordinates in the file: m, cm, mm or in (default: the unit a COLLADA file "
              "declares, metres for STL/OBJ/PLY)")
VISIBILITY_HELP = ("how 'the camera sees a surface element' is decided: raycast = exact ray casting against "
                   "the mesh with a back-face test; hpr = hidden point removal, the MAVAC paper's method")


def _stage_bar(stages: list[str], quiet: bool):
    from tqdm.auto import tqdm

    # disable=None: bars only on a terminal (a log file gets the summary lines, not bar redraws)
    return tqdm(total=len(stages), desc=stages[0], disable=True if quiet else None, file=sys.stderr, leave=False,
                bar_format="{desc:<28} {bar:20} {n_fmt}/{total_fmt} [{elapsed}]")


def _bars(args) -> bool:
    return not args.quiet and sys.stderr.isatty()


def _next(bar, label: str):
    bar.update(1)
    bar.set_description_str(label)


def _checked_output(flag: str, path: Path) -> Path:
    """``path`` if a file can be written there, else ValueError naming ``flag`` (before any work)."""
    if path.is_dir():
        raise ValueError(f"{flag} {path} is a directory; give a file name, e.g. {path / 'result.html'}")
    folder = path.absolute().parent
    while not folder.exists():  # atomic writes create the missing folders
        folder = folder.parent
    if not folder.is_dir():
        raise ValueError(f"{flag} {path}: {folder} is a file, not a directory")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ValueError(f"{flag} {path}: cannot write into {folder} (read-only)")
    return path


def _outputs(args, source: str, stem: str, companion: str, suffix: str = "html") -> tuple[Path, Path]:
    """The main output (an HTML page, or ``clean``'s JSON) and its ``.json`` or ``.csv``
    companion, checked before any work.

    The main output defaults to ``<stem>.<suffix>`` in the user's output folder; the companion to
    its name with its own suffix. Neither may be the input, nor both the same file.
    """
    cache_dir()  # refuses a MAVAC_CACHE that names a file, now rather than after the work
    paths = {}
    for flag, value, default in (("--out", args.out, None), (f"--{companion}", getattr(args, companion), companion)):
        if value is not None and not value.strip():
            raise ValueError(f"{flag} is empty; give a file name")
        if value is not None:
            paths[flag] = Path(value).expanduser()
        else:
            paths[flag] = (paths["--out"].with_suffix(f".{default}") if default
                           else user_output_dir() / f"{stem}.{suffix}")
        if paths[flag].resolve() == Path(source).resolve():
            raise ValueError(f"{flag} {paths[flag]} is the input mesh; give another file name")
        _checked_output(flag, paths[flag])
    out, other = paths.values()
    if out.resolve() == other.resolve():
        raise ValueError(f"both --out and --{companion} name {out}; give two different files")
    return out, other


#: ``--up`` -> rotation turning that axis of the file onto +z (signed permutations: exact)
UP_TURNS = {"x": [[0, 0, -1], [0, 1, 0], [1, 0, 0]], "-x": [[0, 0, 1], [0, 1, 0], [-1, 0, 0]],
            "y": [[1, 0, 0], [0, 0, -1], [0, 1, 0]], "-y": [[1, 0, 0], [0, 0, 1], [0, -1, 0]],
            "-z": [[1, 0, 0], [0, -1, 0], [0, 0, -1]]}
UP_CHOICES = ("+x", "-x", "+y", "-y", "+z", "-z", "x", "y", "z")


def _load(path, units, role, up):
    from .geometry.mesh import load_mesh

    try:
        mesh = load_mesh(path, units=units, role=role)
    except ValueError as exc:  # name the flag, not the keyword argument
        raise ValueError(re.sub(r"units='(\w+)'", r"--units \1", str(exc))) from None
    if (up or "z").lstrip("+") != "z":  # e.g. a y-up export (many COLLADA/OBJ files)
        turn = np.eye(4)
        turn[:3, :3] = UP_TURNS[up.lstrip("+")]
        mesh.apply_transform(turn)
    return mesh


def _inspection_params(args):
    from .params import InspectionParams

    if args.fast:
        from .experiments.mavac_offline import fast_params

        params = fast_params()
    else:
        params = InspectionParams()
    if args.hpr_radius is not None and args.visibility != "hpr":
        raise ValueError("--hpr-radius applies only with --visibility hpr")
    spot = dataclasses.replace(params.spot, P_s=getattr(args, "P_s", params.spot.P_s))  # inspect only
    guard = dataclasses.replace(params.guard, P_g=getattr(args, "P_g", params.guard.P_g))
    nos = dataclasses.replace(params.nos, enabled=not getattr(args, "no_nos", False))
    visibility = dataclasses.replace(params.visibility, method=args.visibility, radius=args.hpr_radius)
    spacing = params.surface_spacing if args.spacing is None else args.spacing
    return dataclasses.replace(params, surface_spacing=spacing, seed=args.seed, spot=spot, guard=guard, nos=nos,
                               visibility=visibility)


def cmd_inspect(args) -> int:
    """MAVAC offline plan of a machine: spots, guards, NoS guards, the pose set T."""
    from .geometry.machines import machine_from_mesh
    from .inspection.inspection_plan import plan_from_context, prepare_offline, warn_low_coverage

    stem = Path(args.mesh).stem
    out, js = _outputs(args, args.mesh, f"{stem}_plan", "json")
    params = _inspection_params(args)
    t0 = time.perf_counter()
    bar = _stage_bar(["loading mesh", "surface, map, spots", "guards and NoS guards", "writing"], args.quiet)
    with bar:
        machine = machine_from_mesh(_load(args.mesh, args.units, "machine", args.up), name=stem)
        _next(bar, "surface, map, spots")
        ctx = prepare_offline(machine, params=params)
        _next(bar, "guards and NoS guards")
        plan = plan_from_context(ctx, progress=_bars(args))
        warn_low_coverage(ctx, plan)
        _next(bar, "writing")
        with atomic_paths(out, js) as (tmp_out, tmp_js):
            write_json({**plan.to_dict(), "mesh": _mesh_doc(args)}, tmp_js)
            plan.to_html(tmp_out)
        _next(bar, "done")
    print(plan.summary())
    _print_frame(machine)
    print(f"wrote {out} and {js} in {time.perf_counter() - t0:.1f} s")
    return 0


def _mesh_doc(args) -> dict:
    """How the mesh file was read: its name, content digest, unit and up axis (a plan file's
    ``mesh`` entry, which ``clean --plan`` checks)."""
    with open(args.mesh, "rb") as f:
        digest = hashlib.file_digest(f, "sha256").hexdigest()
    return {"file": Path(args.mesh).name, "sha256": digest, "units": args.units, "up": args.up or "z"}


def _unrepeated(make, listed=lambda result: result.warnings):
    """``make()``, its warnings shown once each, except those its summary lists
    (``listed(result)``)."""
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        result = make()
    said = set(listed(result))
    for w in {str(w.message): w for w in seen}.values():
        if str(w.message) not in said:
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return result


def _print_frame(machine) -> None:
    """Say where the machine frame is in the file, when it is not the file's own origin."""
    if np.any(machine.file_offset):
        x, y, z = machine.file_offset
        print(f"coordinates are in the machine frame (floor z = 0, centred): add ({x:g}, {y:g}, {z:g}) m "
              "for the file's (after --units and --up)")


def _intensity(value) -> np.ndarray | None:
    """The ``--intensity`` file's numbers (a .npy array, else text), or ValueError naming it."""
    if value is None:
        return None
    path = Path(value)
    if not path.is_file():
        raise ValueError(f"--intensity {value!r} is {'a directory' if path.is_dir() else 'not a file'}")
    try:
        array = np.load(path, allow_pickle=False) if path.suffix == ".npy" else np.loadtxt(path, ndmin=1)
    except (ValueError, OSError, EOFError) as exc:  # pickled, truncated, garbage (UnicodeDecodeError too)
        # numpy's own text for a pickle invites allow_pickle, which would run the file's code
        reason = "it holds pickled Python objects, which are not loaded" if "pickle" in str(exc) else str(exc)
        raise ValueError(f"--intensity {value!r} is not a .npy array or a text file of numbers ({reason})") from None
    if not isinstance(array, np.ndarray) or array.dtype.kind not in "biuf":
        raise ValueError(f"--intensity {value!r} holds no numeric array (a .npz archive or a structured array)")
    return array.astype(float)


def _stain_kwargs(args, scale: float, intensity) -> dict:
    from .geometry.stain_marking import parse_stain

    kw = parse_stain(args.stain, scale=scale)
    if args.passes is not None:
        kw["passes"] = args.passes
    if intensity is not None:
        kw["intensity"] = intensity
    return kw


def _marked_part(args, bar, intensity):
    """The part mesh of ``args.part`` with its ``--stain`` marked (setups, scrub)."""
    from .geometry.stain_marking import mark_stain

    mesh = _load(args.part, args.units, "part", args.up)
    _next(bar, "marking the stain")
    with warnings.catch_warnings():  # the plan's summary says it
        warnings.filterwarnings("ignore", message=".*larger than the tool tip")
        part = mark_stain(mesh, subdivide=args.subdivide, name=Path(args.part).stem,
                          **_stain_kwargs(args, float(mesh.metadata["mavac_scale"]), intensity))
    # the part is a copy; the loaded mesh and its trimesh caches (about 0.6 kB per face) sit in
    # reference cycles that only the cyclic collector frees, and it may not run for minutes
    del mesh
    gc.collect()
    return part


#: what the poses of a setup or scrub JSON file mean
POSE_FRAMES = ("base_T_part: the part frame (bounding-box bottom centre, z up) in the robot's base frame; "
               "base_T_file: the mesh file's own frame (after --units and --up) in the robot's base frame; metres")


def _file_poses(base_T_parts, part) -> list:
    """``base_T_file`` of each ``base_T_part`` (k, 4, 4): the mesh file's frame (after ``--units``
    and ``--up``) in the robot's base frame, so a real cell can place the part from its file."""
    part_T_file = np.eye(4)
    part_T_file[:3, 3] = -np.asarray(part.mesh.metadata.get("mavac_part_offset", np.zeros(3)), dtype=float)
    return [np.asarray(T, dtype=float) @ part_T_file for T in base_T_parts]


def _setups_doc(plan, part, params) -> dict:
    """The setup plan's JSON, each setup with its full pose (``base_T_part``, ``base_T_file``)."""
    from .setups.reach import base_T_part

    doc = plan.to_dict()
    poses = base_T_part(plan.setups, params.space) if len(plan.setups) else []
    for setup, T, T_file in zip(doc["setups"], poses, _file_poses(poses, part)):
        setup["base_T_part"], setup["base_T_file"] = T.tolist(), T_file.tolist()
    doc["frames"] = POSE_FRAMES
    return doc


def cmd_setups(args) -> int:
    """Kabir et al. setup plan of a stained part: fewest, fastest setups on the Puma 560."""
    from .params import ReachParams, SetupPlanParams, SetupPlannerParams
    from .setups.setup_plan import plan_setups

    stem = Path(args.part).stem
    out, js = _outputs(args, args.part, f"{stem}_setups", "json")
    intensity = _intensity(args.intensity)
    if args.t_max is not None and args.method not in ("dfbnb", "both"):
        raise ValueError(f"--t-max applies only with --method dfbnb or both (the search it bounds), not {args.method}")
    t_max = 10.0 if args.t_max is None else args.t_max
    # a plan that drives the arm through the part is wrong: collision checking on unless asked off
    params = SetupPlanParams(seed=args.seed, method=args.method, reach=ReachParams(check_collision=not args.no_collision),
                             planner=SetupPlannerParams(t_max=t_max, setup_time=args.setup_time))
    t0 = time.perf_counter()
    bar = _stage_bar(["loading part", "marking the stain", "reach test and planning", "writing"], args.quiet)
    with bar:
        part = _marked_part(args, bar, intensity)
        _next(bar, "reach test and planning")
        plan = _unrepeated(lambda: plan_setups(part, params=params))
        _next(bar, "writing")
        with atomic_paths(out, js) as (tmp_out, tmp_js):
            write_json(_setups_doc(plan, part, params), tmp_js)
            plan.to_html(tmp_out, part, params=params)
        _next(bar, "done")
    print(f"{stem}: stain of {len(part.stain_faces)} patches, {part.patch_areas.sum() * 1e4:.1f} cm^2, "
          f"passes {np.bincount(part.passes, minlength=4)[1:].tolist()} (1/2/3)")
    print(plan.summary())
    if params.reach.check_collision:
        print(f"collision check on: {plan.collision_refused} stain patches refused (reachable only by an arm "
              "passing through the part or its table)")
    print(f"wrote {out} and {js} in {time.perf_counter() - t0:.1f} s")
    if not plan.found:
        hint = "; raise --t-max or use --method auto" if plan.status == "timed_out" else ""
        print(f"mavac setups: no plan ({plan.status}){hint}", file=sys.stderr)
        return NO_PLAN
    return 0


def cmd_reach(args) -> int:
    """REACH-style reach study of a machine: best reach-and-visibility score per surface element."""
    from .geometry.machines import machine_from_mesh
    from .inspection.reach_study import reach_study

    stem = Path(args.mesh).stem
    out, csv = _outputs(args, args.mesh, f"{stem}_reach", "csv")
    params = _inspection_params(args)
    t0 = time.perf_counter()
    bar = _stage_bar(["loading mesh", "reach study", "writing"], args.quiet)
    with bar:
        machine = machine_from_mesh(_load(args.mesh, args.units, "machine", args.up), name=stem)
        _next(bar, "reach study")
        study = reach_study(machine, params=params, progress=_bars(args))
        _next(bar, "writing")
        with atomic_paths(out, csv) as (tmp_out, tmp_csv):
            study.to_csv(tmp_csv)
            study.to_html(tmp_out)
        _next(bar, "done")
    print(study.summary())
    _print_frame(machine)
    print(f"wrote {out} and {csv} in {time.perf_counter() - t0:.1f} s")
    return 0


#: most trials of one ``mavac clean`` run (each is seconds to minutes of simulation)
MAX_CLEAN_TRIALS = 1_000


def _clean_setup(args):
    """``clean``'s parameters, checked before any work: (inspection params, online params, seeds)."""
    from .experiments.mavac_offline import fast_params
    from .params import DustParams, InspectionParams, OnlineParams
    from .seeding import check_seed

    if not 1 <= args.trials <= MAX_CLEAN_TRIALS:
        raise ValueError(f"--trials must be in [1, {MAX_CLEAN_TRIALS}], got {args.trials}")
    if args.jobs is not None and (args.jobs == 0 or args.jobs < -1):
        raise ValueError(f"--jobs must be a positive worker count or -1 (every core), got {args.jobs}")
    if args.jobs is not None and args.scheduler is not None:
        raise ValueError("--jobs with --scheduler: the dask cluster's workers run the trials; leave --jobs out")
    check_seed(args.seed)
    try:
        check_seed(args.seed + args.trials - 1)
    except ValueError:
        raise ValueError(f"--seed {args.seed} with --trials {args.trials}: the last trial's seed "
                         f"{args.seed + args.trials - 1} is above 2**31 - 1") from None
    online = OnlineParams(dust=DustParams(spacing=DustParams.spacing if args.spacing is None else args.spacing,
                                          density=args.density))
    offline = fast_params() if args.fast else InspectionParams()
    return dataclasses.replace(offline, seed=args.seed), online, list(range(args.seed, args.seed + args.trials))


def _plan_file(args) -> dict | None:
    """``clean --plan``'s document, checked against the mesh file before any work: the plan
    file says how the mesh was read (unit, up axis), so ``--units``, ``--up`` and ``--fast`` are
    refused beside it."""
    if args.plan is None:
        return None
    for flag, given in (("--fast", args.fast), ("--units", args.units is not None), ("--up", args.up is not None)):
        if given:
            raise ValueError(f"{flag} with --plan: the plan file sets the plan and how its mesh was read; "
                             f"leave {flag} out")
    path = Path(args.plan).expanduser()
    try:
        doc = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ValueError(f"--plan {path}: cannot read a JSON plan ({type(exc).__name__}: {exc})") from None
    mesh = doc.get("mesh") if isinstance(doc, dict) else None
    if not isinstance(mesh, dict) or not {"sha256", "units", "up"} <= set(mesh):
        raise ValueError(f"--plan {path}: not a plan file written by 'mavac inspect' (it has no 'mesh' entry)")
    if mesh["sha256"] != _mesh_doc(args)["sha256"]:
        raise ValueError(f"--plan {path} was made from {mesh.get('file')!r}, whose content differs from {args.mesh}")
    return doc


def _clean_plan(machine, plan_doc, offline):
    """The inspection plan of ``clean``: read back from ``--plan``, else computed."""
    from .inspection.inspection_plan import InspectionPlan, plan_inspection

    if plan_doc is None:
        return _unrepeated(lambda: plan_inspection(machine, params=offline))
    try:
        return InspectionPlan.from_dict(plan_doc, machine)
    except ValueError as exc:
        raise ValueError(f"--plan: {exc}") from None


#: seconds ``--scheduler`` waits for a dask scheduler to answer
SCHEDULER_TIMEOUT_S = 10


@contextlib.contextmanager
def _trial_backend(address: str | None):
    """Where ``clean``'s trials run: in this process or its workers (None), or on the dask
    scheduler at ``address``, through joblib's dask backend (yields the worker count to ask for)."""
    if address is None:
        yield None
        return
    try:
        import distributed
        import joblib
    except ImportError:
        raise ValueError("--scheduler needs dask's distributed package: pip install 'mavac[dask]'") from None
    try:
        client = distributed.Client(address, timeout=SCHEDULER_TIMEOUT_S, set_as_default=False)
    except (OSError, ValueError, TypeError) as exc:
        raise ValueError(f"--scheduler {address}: no dask scheduler answered ({type(exc).__name__}: {exc})") from None
    with client, joblib.parallel_backend("dask", client=client):
        yield -1


def _clean_trial(item):
    """One trial of ``mavac clean`` (module level, so that worker processes can run it)."""
    from .cleaning.trial import run_trial

    machine, plan, params, seed, progress = item
    return run_trial(machine, plan, params=params, seed=seed, progress=progress)


def _clean_report(args, results, plan, online) -> tuple[dict, object]:
    """The JSON document and the per-heap table (one row per heap per trial) of a clean run."""
    import pandas as pd

    from .cleaning.misses import cause_counts

    table = pd.concat([r.heap_table().assign(seed=r.seed) for r in results], ignore_index=True)
    table = table[["seed"] + [c for c in table.columns if c != "seed"]]
    heaps, cleaned = len(table), int(table["cleaned"].sum())
    reasons = sorted({r.reason for r in results if r.reason})
    trials = [dict(r.row(), trial=i + 1, reason=r.reason, warnings=list(r.warnings),
                   misses=r.miss_counts()) for i, r in enumerate(results)]
    doc = {
        "mesh": str(Path(args.mesh).resolve()), "machine": results[0].machine,
        "status": "; ".join(reasons) if reasons else "ok",
        "parameters": {"units": args.units, "up": args.up or "z", "spacing": online.dust.spacing,
                       "density": online.dust.density,
                       "seed": args.seed, "trials": args.trials, "fast": args.fast, "plan_file": args.plan,
                       "inspection": dataclasses.asdict(plan.params), "online": dataclasses.asdict(online)},
        "plan": {"C": plan.C, "O": plan.O, "visibility": plan.visibility, "spots": plan.n_spots,
                 "guards": plan.n_guards, "nos_guards": plan.n_nos_guards, "poses": int(len(plan.poses)),
                 "warnings": list(plan.warnings)},
        "summary": {"trials": len(results), "heaps": heaps, "cleaned": cleaned,
                    "cleaning_pct": round(100.0 * cleaned / heaps, 3) if heaps else 0.0,
                    "cleaning_pct_mean_of_trials": round(float(np.mean([r.cleaning_pct for r in results])), 3),
                    "misses": cause_counts(table["cause"].to_numpy()),
                    "sim_time_s": round(sum(r.times.sim_time_s for r in results), 3),
                    "wall_s": round(sum(r.wall_s for r in results), 2)},
        "trials": trials,
    }
    return json_safe(doc), table


def cmd_clean(args) -> int:
    """MAVAC online cleaning of a machine in simulation: plan (or ``--plan``), then trials of Algorithm 1."""
    from .cleaning.heaps import heaps_for_trial
    from .geometry.machines import machine_from_mesh
    from .parallel import map_trials

    stem = Path(args.mesh).stem
    out, csv = _outputs(args, args.mesh, f"{stem}_clean", "csv", suffix="json")
    html = _replay_output(args, args.mesh, out, csv)
    offline, online, seeds = _clean_setup(args)
    plan_doc = _plan_file(args)
    units, up = (args.units, args.up) if plan_doc is None else (plan_doc["mesh"]["units"], plan_doc["mesh"]["up"])
    t0 = time.perf_counter()
    bar = _stage_bar(["loading mesh", "inspection plan", "cleaning trials", "writing"], args.quiet)
    with _trial_backend(args.scheduler) as remote_jobs, bar:
        machine = machine_from_mesh(_load(args.mesh, units, "machine", up), name=stem)
        try:  # a heap spacing the machine cannot take is refused before the plan
            heaps_for_trial(machine, online.dust, seeds[0])
        except ValueError as exc:
            raise ValueError(f"--spacing: {exc}") from None
        _next(bar, "inspection plan" if plan_doc is None else "reading the plan")
        plan = _clean_plan(machine, plan_doc, offline)
        _next(bar, "cleaning trials")
        jobs = remote_jobs or args.jobs or 1
        each = _bars(args) and jobs == 1  # a bar over the guard poses of each trial, run here
        results = map_trials(_clean_trial, [(machine, plan, online, s, each) for s in seeds], n_jobs=jobs,
                             desc="cleaning trials", progress=_bars(args))
        _next(bar, "writing")
        doc, table = _clean_report(args, results, plan, online)
        with atomic_paths(out, csv, html) as (tmp_out, tmp_csv, tmp_html):
            tmp_out.write_text(json.dumps(doc, indent=2, sort_keys=True, allow_nan=False))
            table.to_csv(tmp_csv, index=False, float_format="%.6g")
            _replay_page(results[0], machine, tmp_html)
        _next(bar, "done")
    _print_clean(stem, plan, results, doc)
    _print_frame(machine)
    print(f"wrote {out}, {csv} and {html} in {time.perf_counter() - t0:.1f} s")
    return 0


def _print_clean(stem: str, plan, results, doc) -> None:
    print(plan.summary())
    for r in results:
        print(r.summary())
    if len(results) > 1:
        s = doc["summary"]
        print(f"{stem}: {s['cleaned']} of {s['heaps']} heaps cleaned over {s['trials']} trials "
              f"({s['cleaning_pct']:.1f} %; mean of the trials {s['cleaning_pct_mean_of_trials']:.1f} %)")


def _replay_output(args, source: str, out: Path, csv: Path) -> Path:
    """``clean``'s or ``scrub``'s replay page: ``--html``, else beside the JSON file; checked
    before any work."""
    if args.html is not None and not args.html.strip():
        raise ValueError("--html is empty; give a file name")
    html = Path(args.html).expanduser() if args.html is not None else out.with_suffix(".html")
    for flag, other in (("the input mesh", Path(source)), ("--out", out), ("--csv", csv)):
        if html.resolve() == other.resolve():
            raise ValueError(f"--html {html} is {flag}; give another file name")
    return _checked_output("--html", html)


def _replay_page(result, machine, path: Path) -> None:
    """The first trial's meshcat replay, or a page that says why there is none."""
    if result.replay is not None:
        result.to_html(path, machine)
    else:
        from html import escape

        path.write_text(f"<!DOCTYPE html><title>{escape(machine.name)}</title><p>No replay: {escape(result.reason)}</p>\n")


#: ``scrub --operation`` -> the part whose operating parameters Kabir et al. report (Sec. IX-C)
OPERATIONS = ("hull", "bowl")


def _scrub_cell(args):
    """``scrub``'s cell parameters and operating parameters, checked before any work."""
    from .params import BimanualCellParams
    from .scrubbing.holding import check_payload
    from .experiments.kabir_bimanual import paper_lissajous

    cell = BimanualCellParams(part_mass=args.mass, max_rounds=args.rounds)
    check_payload(cell)
    return cell, paper_lissajous(args.operation)


def _narrowed_cell(cell, part):
    """``cell`` with its setup square placed by the paper's narrowing over ``part``'s stain."""
    from dataclasses import replace

    from .params import ToolpathParams
    from .scrubbing.cell_space import narrowed_cell_space

    try:
        space, _ = narrowed_cell_space({part.name: part}, cell, ToolpathParams())
    except ValueError as exc:  # no presentable setup reaches the stain anywhere
        raise ValueError(f"--narrow: no placement of the part lets the holding arm present it and the pad reach "
                         f"its stain ({exc})") from exc
    return replace(cell, space=space)


def cmd_scrub(args) -> int:
    """Kabir et al.'s two-arm cell on a stained part, simulated: plan, hold, scrub, look, re-plan."""
    from .experiments.kabir_bimanual import run_params
    from .scrubbing.run import cell_plan, run_part
    from .seeding import check_seed

    stem = Path(args.part).stem
    out, csv = _outputs(args, args.part, f"{stem}_scrub", "csv", suffix="json")
    html = _replay_output(args, args.part, out, csv)
    intensity = _intensity(args.intensity)
    check_seed(args.seed)
    cell, lissajous = _scrub_cell(args)
    t0 = time.perf_counter()
    stages = ["loading part", "marking the stain", *(["placing the setup square"] if args.narrow else []),
              "planning and scrubbing", "writing"]
    bar = _stage_bar(stages, args.quiet)
    with bar:
        part = _marked_part(args, bar, intensity)
        if args.narrow:
            _next(bar, "placing the setup square")
            cell = _narrowed_cell(cell, part)
        _next(bar, "planning and scrubbing")
        params = run_params(lissajous, fast=args.fast, cell=cell)
        run = _unrepeated(lambda: run_part(part, cell_plan(part, params), params=params, seed=args.seed,
                                           snapshots=False),
                          listed=lambda run: [w for plan in run.plans for w in plan.warnings])  # each round re-plans
        _next(bar, "writing")
        with atomic_paths(out, csv, html) as (tmp_out, tmp_csv, tmp_html):
            write_json(_scrub_doc(run, part), tmp_out)
            _pass_table(run).to_csv(tmp_csv, index=False, float_format="%.6g")
            run.to_html(tmp_html, cell=cell)
        _next(bar, "done")
    for plan in run.plans:
        print(plan.summary())
    print(run.summary())
    print(f"wrote {out}, {csv} and {html} in {time.perf_counter() - t0:.1f} s")
    if run.status == "no setup":
        print("mavac scrub: no setup of the cell reaches the stain (the plan's warnings say why)", file=sys.stderr)
        return NO_PLAN
    return 0


def _scrub_doc(run, part) -> dict:
    """The run's JSON, each setup with the mesh file's pose too (``base_T_file``)."""
    doc = run.to_dict()
    for setup, T_file in zip(doc["setups"], _file_poses([s["base_T_part"] for s in doc["setups"]], part)):
        setup["base_T_file"] = T_file.tolist()
    doc["frame"] += "; base_T_file: the mesh file's own frame (after --units and --up) in the same base frame"
    return doc


def _pass_table(run):
    """One row per pass: the setup, its pose in the cleaning arm's base frame, its contact measures."""
    import pandas as pd

    rows = []
    for s in run.setup_records():
        x, y, z = s["base_T_part"][:3, 3]
        for r in s["passes"]:
            rows.append(dict(setup=s["label"], part_x_m=x, part_y_m=y, part_z_m=z, **r))
    return pd.DataFrame(rows)


def _common(p: argparse.ArgumentParser, *, role: str) -> None:
    p.add_argument("--units", choices=("m", "cm", "mm", "in"), default=None, help=UNITS_HELP)
    p.add_argument("--up", choices=UP_CHOICES, default=None, metavar="{+x,-x,+y,-y,+z,-z}",
                   help="which axis of the file points up (x = +x; the mesh is turned so that it becomes +z) "
                        "(default: z)")
    p.add_argument("--seed", type=int, default=0, help="seed of every random choice (same seed, same result)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(role=role)


def _machine_options(p: argparse.ArgumentParser) -> None:
    from .params import VISIBILITY_METHODS, Visibility

    p.add_argument("--visibility", choices=VISIBILITY_METHODS, default=Visibility.method, help=VISIBILITY_HELP)
    p.add_argument("--hpr-radius", dest="hpr_radius", type=float, default=None,
                   help="HPR radius in metres for every viewpoint (default: a factor of the farthest point distance)")
    p.add_argument("--spacing", type=float, default=None,
                   help="distance between surface elements of S, metres (default 0.05; 0.10 with --fast)")
    p.add_argument("--fast", action="store_true",
                   help="coarser surface (0.10 m), reachability map and guard clusters: seconds, less coverage")


def _plan_options(p: argparse.ArgumentParser) -> None:
    """Options of ``inspect`` alone (``reach`` scores every element; it picks no spots or guards)."""
    p.add_argument("--P-s", dest="P_s", type=float, default=0.02,
                   help="spot threshold P_s in [0, 1] (MAVAC recommends 0.02)")
    p.add_argument("--P-g", dest="P_g", type=float, default=0.15,
                   help="guard threshold P_g in [0, 1] (MAVAC recommends 0.15)")
    p.add_argument("--no-nos", action="store_true", help="skip the non-observed-surface stage (no RRT-Connect)")


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Shows a default only when there is one worth showing."""

    def _get_help_string(self, action):
        if action.default in (None, False, argparse.SUPPRESS) or "default" in (action.help or ""):
            return action.help
        return super()._get_help_string(action)


def _stain_options(p: argparse.ArgumentParser) -> None:
    """The stain options of ``setups`` and ``scrub``."""
    from .geometry.stain_marking import STAIN_GRAMMAR

    p.add_argument("--stain", required=True,
                   help=f"which faces are stained: {STAIN_GRAMMAR}. A cone (up:30) is the faces whose normal is "
                        "within the angle of the direction; box and sphere take face centres, in the file's units; "
                        "colors the stain painted in the file. Example: --stain up:30,down:30,box:0,0,0,50,50,80")
    p.add_argument("--passes", type=int, choices=(1, 2, 3), default=None,
                   help="cleaning passes of every stained face (default: from --intensity or the colours, else 1)")
    p.add_argument("--intensity", default=None,
                   help=".npy or text file of stain intensities in (0, 1], one per face of the mesh; passes come "
                        "from it in three equal bands")
    p.add_argument("--subdivide", action="store_true",
                   help="split stained triangles larger than the tool tip (1.5 cm^2) before planning")


def _simulation_outputs(p: argparse.ArgumentParser, source: str, command: str, rows: str, page: str) -> None:
    """``--out`` (the JSON result), ``--csv`` and ``--html`` of a simulating command (clean, scrub)."""
    p.add_argument("--out", help=f"JSON result (default: <{source}>_{command}.json in $MAVAC_OUT or the current "
                                 "directory)")
    p.add_argument("--csv", help=f"CSV, {rows} (default: <{source}>_{command}.csv beside the JSON file)")
    p.add_argument("--html", help=f"{page} (default: beside the JSON file)")


def _scrub_parser(sub, fmt) -> None:
    """The ``scrub`` subcommand's parser (Kabir et al.'s two-arm cell in simulation)."""
    from .params import BimanualCellParams

    p = sub.add_parser("scrub", formatter_class=fmt, help="simulated scrubbing of a stained part (Kabir et al.)",
                       description="Kabir et al.'s execution on your part, simulated in pybullet: one KUKA iiwa "
                                   "holds the part and presents it at each setup of the plan, the other scrubs "
                                   "each pass of its plane-slicing tool path under force control with the "
                                   "Lissajous overlay, a camera measures the stain left after each pass, and "
                                   "what is left is re-planned. Writes a JSON file (status, setups with the "
                                   "part's pose in the cleaning arm's base frame, passes, force tracking, duty, "
                                   "stain removed per setup), a CSV with one row per pass and an HTML replay in "
                                   "which the stain fades as it is removed. The part should be 5-25 cm across "
                                   "(the cell's setup square is 30 cm) and is held at the centre of its bottom.")
    p.add_argument("part", help="part mesh: .stl, .obj, .ply or .dae")
    _stain_options(p)
    p.add_argument("--operation", choices=OPERATIONS, default="hull",
                   help="operating parameters (speed, force, stiffness, Lissajous frequency and amplitude): those "
                        "Kabir et al. report for their hull or their bowl (Sec. IX-C)")
    p.add_argument("--mass", type=float, default=BimanualCellParams.part_mass,
                   help="mass of the part, kg (at most 7, the holding arm's payload; default: a plastic part of "
                        f"about 20 cm, {BimanualCellParams.part_mass:g} kg)")
    p.add_argument("--rounds", type=int, default=BimanualCellParams.max_rounds,
                   help="re-planning rounds for the stain the camera still sees after the plan (0-20)")
    p.add_argument("--fast", action="store_true",
                   help="one sampling level, the first setup only, no re-planning: a quick look")
    p.add_argument("--narrow", action="store_true",
                   help="place the cell's 30 cm setup square by the paper's narrowing over this part's stain (a "
                        "coarse sweep of where the holding arm presents it and the pad reaches it; about a "
                        "minute) instead of the default square 0.45-0.75 m in front of the cleaning arm")
    _simulation_outputs(p, "part", "scrub", "one row per pass",
                        "meshcat replay: both arms, the part, its stain fading pass by pass")
    _common(p, role="part")
    p.set_defaults(func=cmd_scrub)


def _clean_parser(sub, fmt) -> None:
    """The ``clean`` subcommand's parser (MAVAC's online loop in simulation)."""
    p = sub.add_parser("clean", formatter_class=fmt, help="simulated cleaning of a machine (MAVAC online stage)",
                       description="MAVAC's online loop on your machine, simulated in pybullet: green dust heaps "
                                   "on every upward-facing surface, then, for each pose of the inspection plan, "
                                   "look, detect the dust, plan an approach and vacuum it (Algorithm 1). The "
                                   "inspection plan is computed first, as 'mavac inspect' does, or read from "
                                   "the JSON file 'mavac inspect' wrote (--plan). Writes a JSON file "
                                   "(summary, one entry per trial, parameters), a CSV with one row per heap "
                                   "per trial (position, cleaned, cause of the miss, the pose that saw it) and "
                                   "an HTML replay of the first trial. The machine should be 0.3-5 m across.")
    p.add_argument("mesh", help="machine mesh: .stl, .obj, .ply or .dae")
    p.add_argument("--spacing", type=float, default=None,
                   help="distance between dust heaps, metres (default 0.10, the paper's)")
    p.add_argument("--density", type=float, default=1.0,
                   help="share of those heaps each trial keeps, drawn with its seed, in (0, 1] (default 1: every "
                        "heap, as in the paper)")
    p.add_argument("--trials", type=int, default=1,
                   help="trials, each with its own heap layout: seeds --seed .. --seed + trials - 1")
    p.add_argument("--jobs", type=int, default=None, help="trials run at a time (-1: every core) (default: 1)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the trials on the dask cluster whose scheduler is at ADDRESS (e.g. "
                        "tcp://10.0.0.5:8786; needs pip install 'mavac[dask]'; joblib runs them here when the "
                        "cluster has a single core)")
    p.add_argument("--plan", default=None, metavar="PLAN.json",
                   help="the inspection plan 'mavac inspect' wrote for this mesh file (its JSON file), instead "
                        "of planning again; it sets the unit and up axis")
    p.add_argument("--fast", action="store_true",
                   help="coarser inspection plan (as 'mavac inspect --fast'): seconds, fewer guards")
    _simulation_outputs(p, "mesh", "clean", "one row per heap per trial",
                        "meshcat replay of the first trial: the robot through its poses, heaps vanishing as they "
                        "are vacuumed, misses coloured by cause")
    _common(p, role="machine")
    p.set_defaults(func=cmd_clean)


def build_parser() -> argparse.ArgumentParser:
    from .params import SETUP_COVER_METHODS

    fmt = _HelpFormatter
    parser = argparse.ArgumentParser(
        prog="mavac", formatter_class=fmt,
        description="Plan robotic cleaning from a mesh: MAVAC inspection plans for machines (UR10 on a mobile "
                    "base, camera on the tool), MAVAC's simulated cleaning of those machines, Kabir et al. setup "
                    "plans for stained parts (Puma 560) and their simulated two-arm scrubbing, and REACH-style "
                    "reach studies. Every length is in metres "
                    "unless a flag says otherwise.")
    parser.add_argument("--version", action="version", version=f"mavac {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="{inspect,setups,reach,clean,scrub}")

    p = sub.add_parser("inspect", formatter_class=fmt, help="inspection plan of a machine (MAVAC offline stage)",
                       description="MAVAC's offline computation on your machine: spots for the mobile base, guard "
                                   "configurations of the arm, NoS guards, the ordered pose set T. Writes an HTML "
                                   "page (robot animated through T) and a JSON file with every pose and joint "
                                   "configuration. The machine should be 0.3-5 m across.")
    p.add_argument("mesh", help="machine mesh: .stl, .obj, .ply or .dae")
    p.add_argument("--out", help="HTML page (default: <mesh>_plan.html in $MAVAC_OUT or the current directory)")
    p.add_argument("--json", help="JSON plan (default: <mesh>_plan.json beside the HTML page)")
    _common(p, role="machine")
    _machine_options(p)
    _plan_options(p)
    p.set_defaults(func=cmd_inspect)

    p = sub.add_parser("setups", formatter_class=fmt, help="setup plan of a stained part (Kabir et al.)",
                       description="Kabir et al.'s setup planning on your part: the fewest, fastest placements of "
                                   "the part in front of a Puma 560 that let it reach every stain patch, proven optimal "
                                   "(or the paper's depth-first branch and bound with --method dfbnb). The part should be "
                                   "2 cm-2 m across.")
    p.add_argument("part", help="part mesh: .stl, .obj, .ply or .dae")
    _stain_options(p)
    p.add_argument("--setup-time", type=float, default=60.0, help="time to re-place the part, s (Kabir Table VI)")
    p.add_argument("--method", choices=SETUP_COVER_METHODS, default="auto",
                   help="auto = the proven optimum (reduction, size bound, enumeration, integer program; node budgets "
                        "only); milp = the integer program alone; dfbnb = the paper's depth-first branch and bound; "
                        "both = DFBnB's plan with the proven optimum beside it")
    p.add_argument("--t-max", type=float, default=None,
                   help="time bound of the paper's branch-and-bound search, s (methods dfbnb and both only; "
                        "default 10)")
    p.add_argument("--no-collision", action="store_true",
                   help="reach test by IK alone, as in the paper (default: the arm must also clear the part and its "
                        "table, checked with coal)")
    p.add_argument("--out", help="HTML page (default: <part>_setups.html in $MAVAC_OUT or the current directory)")
    p.add_argument("--json", help="JSON plan (default: <part>_setups.json beside the HTML page)")
    _common(p, role="part")
    p.set_defaults(func=cmd_setups)

    p = sub.add_parser("reach", formatter_class=fmt, help="REACH-style reach heat map of a machine",
                       description="A reach study as ROS-Industrial's REACH does it: every surface element is scored "
                                   "by the best maneuverability index of a collision-free arm configuration, over "
                                   "all candidate spots, that holds the camera on its normal and sees it. Writes "
                                   "an HTML heat map with a colour bar and a CSV with one row per element.")
    p.add_argument("mesh", help="machine mesh: .stl, .obj, .ply or .dae")
    p.add_argument("--out", help="HTML heat map (default: <mesh>_reach.html in $MAVAC_OUT or the current directory)")
    p.add_argument("--csv", help="CSV, one row per surface element (default: <mesh>_reach.csv beside the HTML page)")
    _common(p, role="machine")
    _machine_options(p)
    p.set_defaults(func=cmd_reach)

    _clean_parser(sub, fmt)
    _scrub_parser(sub, fmt)
    return parser


#: parameter fields the command line sets -> their flags, to name the flag in an error
FIELD_FLAGS = {"radius": "--hpr-radius", "surface_spacing": "--spacing", "spacing": "--spacing", "P_s": "--P-s",
               "P_g": "--P-g", "setup_time": "--setup-time", "t_max": "--t-max", "seed": "--seed",
               "part_mass": "--mass", "max_rounds": "--rounds", "density": "--density"}


def _with_flag(message: str) -> str:
    """``message`` led by the flag of the parameter it starts with (``radius must be ...``)."""
    field = re.match(r"(\w+)(?: \(\w+\))? (must|=)", message)
    flag = FIELD_FLAGS.get(field.group(1)) if field else None
    return f"{flag}: {message}" if flag else message


def _signed_values(argv) -> list[str]:
    """``--stain -x:45`` and ``--up -y`` as ``--stain=-x:45``: argparse would take a value that
    starts with '-' for an option."""
    argv, out = list(argv), []
    while argv:
        arg = argv.pop(0)
        if arg == "--":
            return out + [arg] + argv
        if arg in ("--stain", "--up") and argv and re.match(r"-([xyz]|\d|\.\d)", argv[0]):
            arg = f"{arg}={argv.pop(0)}"
        out.append(arg)
    return out


@contextlib.contextmanager
def _hangup_as_interrupt():
    """SIGHUP (the terminal closed) raises KeyboardInterrupt, as Ctrl-C does, so the cleanup
    runs: no half-written file, no meshcat server left. Main thread only; under ``nohup``
    (SIGHUP ignored) it stays ignored."""
    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGHUP) == signal.SIG_IGN:
        yield
        return
    previous = signal.signal(signal.SIGHUP, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGHUP, previous)


def _show_warning(message, category, filename, lineno, file=None, line=None):
    print(f"mavac: warning: {message}", file=sys.stderr)


def main(argv=None) -> int:
    """Entry point of the ``mavac`` console script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(_signed_values(sys.argv[1:] if argv is None else argv))
    with warnings.catch_warnings(), _hangup_as_interrupt():
        warnings.simplefilter("always", UserWarning)
        warnings.showwarning = _show_warning
        try:
            return args.func(args)
        except (ValueError, TypeError, OSError) as exc:
            print(f"mavac {args.command}: error: {_with_flag(str(exc))}", file=sys.stderr)
            return 1
        except KeyboardInterrupt:
            print(f"mavac {args.command}: interrupted", file=sys.stderr)
            return 130
        except ImportError as exc:  # Ctrl-C inside a pybind11 module's initialisation (open3d's)
            if not isinstance(exc.__cause__, KeyboardInterrupt):
                raise
            print(f"mavac {args.command}: interrupted", file=sys.stderr)
            return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
