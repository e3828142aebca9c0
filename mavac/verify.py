"""Prove the committed numbers: rerun the notebooks into a scratch folder, compare file by file.

``make verify`` executes the paper-scale notebooks with ``MAVAC_OUT`` pointing to a scratch
folder, then compares every result file they wrote with the committed one:

* CSV and JSON: byte for byte, except the columns (fields) declared in :data:`WALL_CLOCK`
  (never compared), in :data:`RELATIVE_TOLERANCE` (compared within a relative tolerance) and in
  :data:`ONLY_WHERE_SUCCEEDED` (CSV columns compared in the rows where a run succeeded);
* ``.npz`` planner instances: byte for byte.

The notebook runner of ``make reproduce`` and ``make verify`` lives here too: it executes one
notebook, records its wall and CPU time in ``reproduce_times.csv`` and, in ``provenance.json``,
the commit, date and settings that made each result file. :func:`stale_results` uses that record
to find results older than the last change of the code they depend on.

Command lines (``python -m mavac.verify ...``)::

    --fresh build/verify --committed . [--only 05] [--fast]   compare; exit 1 on any difference
    run 05 --out DIR --executed DIR                            execute one notebook, record it
    finish --out DIR --started EPOCH                           add the run's ``total`` row
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import datetime
import fcntl
import fnmatch
import functools
import hashlib
import json
import math
import os
import platform
import re
import resource
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .config import ROOT, is_fast
from .io import write_csv, write_json

#: Where each kind of result lives under an output root, at paper scale (``False``) and in
#: fast mode (``True``), as :func:`mavac.config.results_dir` / ``instances_dir`` place them.
FOLDERS = {False: {"results": "data/results", "instances": "data/instances"},
           True: {"results": "build/results", "instances": "build/instances"}}
#: Suffixes of the result files that are compared (figures are not).
SUFFIXES = (".csv", ".json", ".npz")

#: Files each notebook writes, as ``<kind>/<glob>`` keys (kind: a key of :data:`FOLDERS`).
#: Read off the notebooks' ``write_csv`` / ``to_json`` / ``write_table2_instances`` calls;
#: ``tests/test_verify.py`` checks this table against the notebooks and the committed files.
OUTPUTS: dict[str, tuple[str, ...]] = {
    "00": (),
    "01": ("results/machines.csv", "results/parts.csv", "results/ik_accuracy.csv"),
    "02": ("results/mavac_table1_trials.csv", "results/mavac_table1.csv", "results/mavac_hpr_radius_spots.csv",
           "results/mavac_table1_machines.csv"),
    "03": ("results/mavac_fig6.csv", "results/mavac_k1_effect.csv", "results/mavac_visibility.csv",
           "results/mavac_hpr_radius.csv"),
    "04": ("results/mavac_plans.csv", "results/mavac_plan_*.json", "results/mavac_fig7.csv"),
    "05": ("results/mavac_table2_trials.csv", "results/mavac_table2.csv", "results/mavac_online_misses.csv",
           "results/mavac_online_times.csv", "results/mavac_table2_sensitivity.csv", "results/mavac_table2_unseen.csv"),
    "06": ("results/kabir_setup_space.csv", "results/kabir_coverage.csv", "results/kabir_table2.csv",
           "instances/kabir_table2_*.npz", "results/kabir_table2_draws.csv", "results/kabir_table2_summary.csv",
           "results/kabir_table2_collision.csv", "results/kabir_table2_collision_summary.csv"),
    "07": ("results/kabir_table3.csv", "results/kabir_table4_runs.csv", "results/kabir_table4.csv",
           "results/kabir_fig8_paths.csv"),
    "08": ("results/kabir_table5.csv", "results/kabir_table6.csv", "results/kabir_fig9.csv"),
    "09": ("results/kabir_toolpaths.csv", "results/kabir_toolpath_passes.csv", "results/kabir_icp.csv",
           "results/kabir_icp_trials.csv"),
    "10": ("results/kabir_gpr.csv", "results/kabir_gpr_speedup.csv"),
    "11": ("results/kabir_cell_square.csv", "results/kabir_preston.csv", "results/kabir_table7.csv",
           "results/kabir_execution.csv"),
    "12": ("results/beyond_iess_optimality.csv", "results/beyond_iess_by_estimate.csv",
           "results/beyond_visibility_offline.csv", "results/beyond_adaptive_vs_systematic_runs.csv",
           "results/beyond_adaptive_vs_systematic.csv", "results/beyond_visibility_online_runs.csv",
           "results/beyond_visibility_online.csv", "results/beyond_robustness_runs.csv",
           "results/beyond_robustness.csv", "results/beyond_robustness_breaking.csv",
           "results/beyond_improved_runs.csv", "results/beyond_improved.csv", "results/beyond_improved_tube.csv"),
}

#: The runner's records of a run (not written by a notebook).
TIMES = "results/reproduce_times.csv"
PROVENANCE = "results/provenance.json"
#: Files never compared, with the reason.
EXCLUDED = {PROVENANCE: "commit, date and versions of the run that wrote each file: differ between runs by design"}

#: ``(file, column) -> reason``: columns that measure wall-clock or CPU time, so they change
#: with the machine's load and are never compared. The one place they are declared.
WALL_CLOCK: dict[tuple[str, str], str] = {
    ("results/kabir_table6.csv", "seconds"):
        "DFBnB run time: time.perf_counter span of dfbnb_setup_cover (planning/setcover.py)",
    ("results/kabir_table7.csv", "planning_time_ours"):
        "plan_setups' time.perf_counter span, SetupPlan.seconds (setups/setup_plan.py)",
    ("results/mavac_visibility.csv", "hpr_seconds"):
        "time.perf_counter span of HPR in hpr_error_rates (vision/visibility.py)",
    ("results/mavac_visibility.csv", "raycast_seconds"):
        "time.perf_counter span of exact ray casting in hpr_error_rates (vision/visibility.py)",
    (TIMES, "wall_s"): "wall time of each notebook, measured by the runner (this module)",
    (TIMES, "cpu_s"): "CPU time of each notebook (getrusage of its processes), measured by the runner",
}

#: ``(file, field) -> (rtol, reason)``: fields whose floating-point kernels differ between
#: processors, compared within ``rtol``. None is declared: docs/reproduce.md ("Tolerances")
#: gives the measurements that rule out the candidates (Open3D ICP results, the online trials'
#: simulated times and forces).
RELATIVE_TOLERANCE: dict[tuple[str, str], tuple[float, str]] = {}

#: ``(file, column) -> (flag column, reason)``: columns compared only in the rows whose flag is
#: ``True`` in either run (the flag itself is compared). For values that diverge when the run
#: failed, so that their digits are chaos even on one machine.
ONLY_WHERE_SUCCEEDED: dict[tuple[str, str], tuple[str, str]] = {
    ("results/kabir_icp_trials.csv", column): (
        "success", "error of a registration that diverged (success False): two runs of notebook 09 on one "
                   "machine gave a translation error of 2287.12 m and 2521.33 m for the same row (docs/reproduce.md)")
    for column in ("translation_error_m", "rotation_error_rad", "adds_m")
}

#: Files outside ``mavac/`` that a module reads at run time (their values reach the results).
DATA_INPUTS = {"mavac/paper.py": ("data/paper_values.csv",)}


# ---------------------------------------------------------------- which files


def check_notebook(name: str, value) -> str:
    """Two-digit notebook number (``"5"`` -> ``"05"``); ``ValueError`` naming ``name`` if unknown."""
    number = str(value).strip().zfill(2)
    if number not in OUTPUTS:
        raise ValueError(f"{name} must be a notebook number ({', '.join(OUTPUTS)}), got {value!r}")
    return number


def owner(key: str) -> str | None:
    """Notebook number that writes ``key`` (``"run"`` for the runner's records, None if nobody)."""
    if key in (TIMES, PROVENANCE):
        return "run"
    for number, patterns in OUTPUTS.items():
        if any(fnmatch.fnmatchcase(key, p) for p in patterns):
            return number
    return None


def display_path(key: str, fast: bool = False) -> str:
    """Path of ``key`` (``<kind>/<name>``) relative to the output root."""
    kind, name = key.split("/", 1)
    return f"{FOLDERS[fast][kind]}/{name}"


def result_files(root, fast: bool = False) -> dict[str, Path]:
    """Result files (:data:`SUFFIXES`) under the output root ``root``, by ``<kind>/<name>`` key."""
    files = {}
    for kind, folder in FOLDERS[fast].items():
        directory = Path(root) / folder
        for path in sorted(directory.iterdir()) if directory.is_dir() else ():
            if path.is_file() and path.suffix in SUFFIXES:
                files[f"{kind}/{path.name}"] = path
    return files


def selected(fresh, committed, only: str | None = None) -> list[str]:
    """Keys to compare: all but :data:`EXCLUDED`; with ``only``, that notebook's files plus any
    fresh file that no notebook declares (so an unexpected output still shows)."""
    keys = (set(fresh) | set(committed)) - set(EXCLUDED)
    if only is not None:
        only = check_notebook("only", only)
        keys = {k for k in keys if owner(k) == only or (k in fresh and owner(k) is None)}
    return sorted(keys)


def rules(key: str) -> tuple[frozenset, dict, dict]:
    """Ignored wall-clock columns, ``{column: rtol}`` and ``{column: flag column}``
    (:data:`ONLY_WHERE_SUCCEEDED`) declared for ``key``."""
    ignore = frozenset(col for (k, col) in WALL_CLOCK if k == key)
    rtol = {col: tol for (k, col), (tol, _) in RELATIVE_TOLERANCE.items() if k == key}
    when = {col: flag for (k, col), (flag, _) in ONLY_WHERE_SUCCEEDED.items() if k == key}
    return ignore, rtol, when


# ---------------------------------------------------------------- comparisons


def _same_text(a: np.ndarray, b: np.ndarray, rtol: float | None) -> np.ndarray:
    """Cell-wise equality of two (n,) string arrays; numbers within ``rtol`` when given."""
    same = a == b
    if rtol is not None:
        x, y = pd.to_numeric(pd.Series(a), errors="coerce"), pd.to_numeric(pd.Series(b), errors="coerce")
        same |= np.isclose(x.to_numpy(float), y.to_numpy(float), rtol=rtol, atol=0.0)
    return same


def compare_csv(fresh, committed, ignore=frozenset(), rtol=None, when=None) -> str | None:
    """None when two CSVs agree, else ``"N rows, columns a, b"``.

    Cells are compared as text (byte for byte), positionally; columns in ``ignore`` are
    skipped, those in ``rtol`` (``{column: relative tolerance}``) compared as numbers, and those
    in ``when`` (``{column: flag column}``) only in rows whose flag is ``True`` in either file.
    """
    rtol, when = rtol or {}, when or {}
    fresh, committed = Path(fresh), Path(committed)
    if fresh.read_bytes() == committed.read_bytes():
        return None
    a, b = (pd.read_csv(p, dtype=str, keep_default_na=False) for p in (fresh, committed))
    n = min(len(a), len(b))
    bad, cols = np.zeros(n, dtype=bool), []
    for col in (c for c in b.columns if c in a.columns and c not in ignore):
        differs = ~_same_text(a[col].to_numpy()[:n], b[col].to_numpy()[:n], rtol.get(col))
        flag = when.get(col)
        if flag in a.columns and flag in b.columns:
            differs &= (a[flag].to_numpy()[:n] == "True") | (b[flag].to_numpy()[:n] == "True")
        if differs.any():
            bad |= differs
            cols.append(col)
    header = [c for c in (*b.columns, *a.columns) if (c in a.columns) != (c in b.columns)]
    rows = max(len(a), len(b)) if header else int(bad.sum()) + abs(len(a) - len(b))
    if not rows:  # only ignored / tolerated cells differ, or formatting alone
        return None if set(ignore) | set(rtol) | set(when) else "0 rows (bytes differ, values equal)"
    lengths = f" ({len(a)} rows fresh, {len(b)} committed)" if len(a) != len(b) else ""
    return f"{rows} rows, columns {', '.join(cols + header) or '-'}{lengths}"


def flatten(value, path: str = "") -> dict[str, object]:
    """Leaves of parsed JSON by path (``poses[3].q[1]``)."""
    if isinstance(value, dict):
        items = ((f"{path}.{k}" if path else str(k), v) for k, v in value.items())
    elif isinstance(value, list):
        items = ((f"{path}[{i}]", v) for i, v in enumerate(value))
    else:
        return {path: value}
    out = {}
    for sub, v in items:
        out.update(flatten(v, sub))
    return out


def field_name(path: str) -> str:
    """Rule name of a JSON leaf: its path without list indices (``poses[].q[]``)."""
    return re.sub(r"\[\d+\]", "[]", path)


def _same_value(a, b, rtol: float | None) -> bool:
    if type(a) is not type(b):  # 1 vs 1.0 vs True: different bytes
        return False
    if isinstance(a, float) and math.isnan(a) and math.isnan(b):
        return True
    if rtol is not None and isinstance(a, (int, float)) and not isinstance(a, bool):
        return math.isclose(a, b, rel_tol=rtol, abs_tol=0.0)
    return a == b


def compare_json(fresh, committed, ignore=frozenset(), rtol=None) -> str | None:
    """None when two JSON files agree, else ``"N values, fields a, b"``.

    Parsed leaves are compared by path; ``ignore`` and ``rtol`` name fields as
    :func:`field_name` spells them.
    """
    rtol = rtol or {}
    fresh, committed = Path(fresh), Path(committed)
    if fresh.read_bytes() == committed.read_bytes():
        return None
    a, b = (flatten(json.loads(p.read_text())) for p in (fresh, committed))
    bad: dict[str, int] = {}
    for path in sorted(a.keys() | b.keys()):
        field = field_name(path)
        if field in ignore:
            continue
        if path not in a or path not in b or not _same_value(a[path], b[path], rtol.get(field)):
            bad[field] = bad.get(field, 0) + 1
    if not bad:
        return None if set(ignore) | set(rtol) else "0 values (bytes differ, values equal)"
    return f"{sum(bad.values())} values, fields {', '.join(bad)}"


def compare_npz(fresh, committed) -> str | None:
    """None when two ``.npz`` files are byte-identical, else the arrays that differ."""
    fresh, committed = Path(fresh), Path(committed)
    if fresh.read_bytes() == committed.read_bytes():
        return None
    with np.load(fresh, allow_pickle=False) as a, np.load(committed, allow_pickle=False) as b:
        names = sorted(set(a.files) ^ set(b.files))
        names += [k for k in sorted(set(a.files) & set(b.files))
                  if (a[k].dtype, a[k].shape, a[k].tobytes()) != (b[k].dtype, b[k].shape, b[k].tobytes())]
    return f"arrays {', '.join(names)}" if names else "bytes differ, arrays equal"


@dataclass(frozen=True)
class Outcome:
    """Verdict on one file: ``status`` is identical, differs, missing or extra."""

    path: str
    status: str
    detail: str = ""

    def line(self) -> str:
        """``path: status[: detail]``, the line ``make verify`` prints."""
        return f"{self.path}: {self.status}" + (f": {self.detail}" if self.detail else "")


def compare_file(key: str, fresh: Path | None, committed: Path | None, fast: bool = False) -> Outcome:
    """Compare one result file (``None``: not there) under the rules declared for ``key``."""
    path = display_path(key, fast)
    if fresh is None or committed is None:
        return Outcome(path, "missing" if fresh is None else "extra")
    ignore, rtol, when = rules(key)
    if key.endswith(".csv"):
        detail = compare_csv(fresh, committed, ignore, rtol, when)
    elif key.endswith(".json"):
        detail = compare_json(fresh, committed, ignore, rtol)
    else:
        detail = compare_npz(fresh, committed)
    return Outcome(path, "identical") if detail is None else Outcome(path, "differs", detail)


def verify(fresh_root, committed_root, *, only: str | None = None, fast: bool = False) -> list[Outcome]:
    """Compare the result files under two output roots (a fresh run, the checkout).

    Parameters
    ----------
    fresh_root, committed_root : str or Path
        Output roots (``MAVAC_OUT`` of the fresh run; the checkout).
    only : str, optional
        Notebook number: compare only its files (and undeclared fresh ones).
    fast : bool
        Fast-mode layout (``build/results``) instead of ``data/results``.

    Returns
    -------
    list of Outcome
        One per file, sorted by key.
    """
    fresh, committed = result_files(fresh_root, fast), result_files(committed_root, fast)
    return [compare_file(k, fresh.get(k), committed.get(k), fast) for k in selected(fresh, committed, only)]


# ---------------------------------------------------------------- running notebooks


def notebooks(root=ROOT) -> dict[str, Path]:
    """Numbered notebooks under ``root/notebooks`` by two-digit number."""
    return {p.name[:2]: p for p in sorted((Path(root) / "notebooks").glob("[0-9][0-9]_*.ipynb"))}


def run_notebook(number: str, out, executed, *, env=None, root=ROOT) -> dict:
    """Execute one notebook with ``MAVAC_OUT=out`` (nbconvert, no time limit) and time it.

    Returns
    -------
    dict
        ``number``, ``notebook`` (file stem), ``wall_s`` and ``cpu_s`` (s; CPU of the nbconvert process and
        the kernel and workers it waited for), ``started`` (epoch, s).
    """
    path = notebooks(root)[check_notebook("notebook", number)]
    env = dict(os.environ if env is None else env, MAVAC_OUT=str(Path(out).resolve()))
    cmd = [sys.executable, "-m", "nbconvert", "--to", "notebook", "--execute", "--ExecutePreprocessor.timeout=-1",
           "--output-dir", str(Path(executed).resolve()), str(path)]
    before, started, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.time(), time.monotonic()
    subprocess.run(cmd, env=env, check=True)
    wall, after = time.monotonic() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    return dict(number=path.name[:2], notebook=path.stem, wall_s=round(wall, 1), cpu_s=round(cpu, 1), started=started)


def _git(repo, *args) -> str:
    return subprocess.run(["git", "-C", str(repo), *args], capture_output=True, text=True, check=True).stdout.strip()


def git_state(paths, root=ROOT) -> dict:
    """``commit`` (``HEAD`` of ``root``), ``uncommitted_changes`` (any of ``paths`` differs from
    it) and ``inputs`` (:func:`inputs_digest` of ``paths`` as on disk); None outside a checkout."""
    try:
        # --no-optional-locks: a status that refreshes the index would lock it against other git users
        status = _git(root, "--no-optional-locks", "status", "--porcelain", "--", *paths)
        return dict(commit=_git(root, "rev-parse", "HEAD"), uncommitted_changes=bool(status),
                    inputs=inputs_digest(root, paths))
    except (OSError, subprocess.CalledProcessError):
        return dict(commit=None, uncommitted_changes=None, inputs=None)


def provenance_entries(written, notebook_file: str, git: dict, env, date: str) -> dict[str, dict]:
    """``provenance.json`` entries of the files one notebook wrote: notebook, git state
    (:func:`git_state`), date, settings (``MAVAC_*``, ``OMP_NUM_THREADS``), Python / numpy versions."""
    entry = dict(notebook=Path(notebook_file).name[:2], notebook_file=notebook_file, **git, date=date,
                 MAVAC_FAST=env.get("MAVAC_FAST", "0"),
                 MAVAC_JOBS=env.get("MAVAC_JOBS", "1"), OMP_NUM_THREADS=env.get("OMP_NUM_THREADS"),
                 python=platform.python_version(), numpy=np.__version__)
    return {path: dict(entry) for path in written}


def merged_times(times: pd.DataFrame | None, row: dict) -> pd.DataFrame:
    """``reproduce_times.csv`` with ``row`` (one notebook) replacing that notebook's row; the
    ``total`` row is dropped (:func:`with_total` adds it when the run ends)."""
    new = pd.DataFrame([{k: row[k] for k in ("notebook", "wall_s", "cpu_s")}])
    if times is None:
        return new
    keep = times[~times["notebook"].isin([row["notebook"], "total"])]
    return pd.concat([keep, new], ignore_index=True).sort_values("notebook", ignore_index=True)


def with_total(times: pd.DataFrame, wall_s: float) -> pd.DataFrame:
    """``times`` plus a ``total`` row: the whole run's wall time and the notebooks' CPU sum."""
    rows = times[times["notebook"] != "total"]
    total = pd.DataFrame([dict(notebook="total", wall_s=round(wall_s, 1), cpu_s=round(rows["cpu_s"].sum(), 1))])
    return pd.concat([rows, total], ignore_index=True)


@contextlib.contextmanager
def _locked(path: Path):
    """Exclusive lock: two notebooks running side by side update the same records."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def _read_times(path: Path) -> pd.DataFrame | None:
    return pd.read_csv(path, dtype={"notebook": str}) if path.is_file() else None


def record_run(row: dict, out, executed, *, env=None, fast: bool = False, root=ROOT) -> list[str]:
    """After a notebook: its row in ``reproduce_times.csv`` and its files' ``provenance.json``
    entries (files it declares, written since it started); returns those files."""
    env = os.environ if env is None else env
    written = sorted(display_path(k, fast) for k, p in result_files(out, fast).items()
                     if owner(k) == row["number"] and p.stat().st_mtime >= row["started"])
    git = git_state(notebook_dependencies(row["number"], root), root)
    date = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    notebook_file = notebooks(root)[row["number"]].relative_to(root).as_posix()
    entries = provenance_entries(written, notebook_file, git, env, date)
    times_path, prov_path = (Path(out) / display_path(k, fast) for k in (TIMES, PROVENANCE))
    with _locked(Path(executed) / "reproduce.lock"):
        write_csv(merged_times(_read_times(times_path), row), times_path)
        prov = json.loads(prov_path.read_text()) if prov_path.is_file() else {}
        write_json({**prov, **entries}, prov_path)
    return written


def finish_run(out, started: float, executed, *, fast: bool = False) -> Path:
    """Add the ``total`` row (wall time since ``started``, epoch s) to ``reproduce_times.csv``."""
    path = Path(out) / display_path(TIMES, fast)
    with _locked(Path(executed) / "reproduce.lock"):
        times = _read_times(path)
        if times is None:
            raise ValueError(f"out: no {display_path(TIMES, fast)} under {out}: no notebook ran")
        return write_csv(with_total(times, time.time() - float(started)), path)


# ---------------------------------------------------------------- staleness


def _mavac_imports(tree: ast.AST, module: str, is_package: bool) -> set[str]:
    """Dotted names ``tree`` imports from ``mavac`` (modules or names in them); ``module`` is
    the importing module's name (for relative imports)."""
    package = module if is_package else module.rpartition(".")[0]
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names if a.name.split(".")[0] == "mavac"}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1] + ([base] if base else []))
            if base.split(".")[0] == "mavac":
                names |= {base} | {f"{base}.{a.name}" for a in node.names}
    return names


def _module_file(name: str, root: Path) -> Path | None:
    parts = name.split(".")
    for path in (root.joinpath(*parts).with_suffix(".py"), root.joinpath(*parts, "__init__.py")):
        if path.is_file():
            return path
    return None


@functools.lru_cache(maxsize=None)
def _file_imports(path: Path, module: str) -> frozenset:
    """:func:`_mavac_imports` of one module file (parsed once per process)."""
    return frozenset(_mavac_imports(ast.parse(path.read_text()), module, path.name == "__init__.py"))


def module_closure(names, root=ROOT) -> set[Path]:
    """Files of the ``mavac`` modules ``names`` import, directly or not (packages included)."""
    root, todo, seen = Path(root), list(names), set()
    while todo:
        parts = todo.pop().split(".")
        for i in range(1, len(parts) + 1):  # importing a.b.c runs a and a.b too
            path = _module_file(".".join(parts[:i]), root)
            if path is None or path in seen:
                continue
            seen.add(path)
            todo.extend(_file_imports(path, ".".join(parts[:i])))
    return seen


def notebook_dependencies(number: str, root=ROOT) -> list[str]:
    """Paths (relative to ``root``) a notebook's results depend on: the notebook, the ``mavac``
    modules it imports (transitively) and the data files they read (:data:`DATA_INPUTS`)."""
    root = Path(root)
    path = notebooks(root)[check_notebook("number", number)]
    cells = json.loads(path.read_text())["cells"]
    source = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
    source = re.sub(r"^\s*[%!].*$", "", source, flags=re.M)  # IPython magics are not Python
    files = {p.relative_to(root).as_posix() for p in module_closure(_mavac_imports(ast.parse(source), "", False), root)}
    files |= {d for f in files for d in DATA_INPUTS.get(f, ())}
    return sorted(files | {path.relative_to(root).as_posix()})


def last_change(repo, paths) -> str | None:
    """Commit that last changed any of ``paths`` in the git repository ``repo`` (None: never)."""
    return _git(repo, "log", "-1", "--format=%H", "--", *paths) or None


def inputs_digest(repo, paths, rev: str | None = None) -> str:
    """SHA-256 over the git blob ids of ``paths`` (relative to ``repo``): as on disk (``rev``
    None) or as committed in ``rev``; a path missing from ``rev`` changes the digest."""
    paths = sorted(paths)
    if rev is None:
        ids = dict(zip(paths, _git(repo, "hash-object", "--", *paths).split()))
    else:
        lines = _git(repo, "ls-tree", "-r", rev, "--", *paths).splitlines()
        ids = {line.split("\t", 1)[1]: line.split()[2] for line in lines}
    return hashlib.sha256(json.dumps(ids, sort_keys=True).encode()).hexdigest()


def is_ancestor(repo, older: str, newer: str) -> bool:
    """``older`` is ``newer`` or one of its ancestors (False when either is unknown to ``repo``)."""
    return subprocess.run(["git", "-C", str(repo), "merge-base", "--is-ancestor", older, newer],
                          capture_output=True).returncode == 0


def stale_results(repo, provenance: dict, dependencies: dict) -> dict[str, str]:
    """Result files made before the last change of what they depend on.

    Parameters
    ----------
    repo : str or Path
        git checkout.
    provenance : dict
        ``provenance.json``: file -> entry with ``notebook`` (number) and ``commit``.
    dependencies : dict
        Notebook number -> paths its results depend on (:func:`notebook_dependencies`).

    Returns
    -------
    dict
        File -> why it is stale. A file is current when its run's commit descends from (or is)
        the last change of its notebook's dependencies; a run with uncommitted changes to them
        is current when ``HEAD`` holds exactly the files it ran (its ``inputs`` digest).
    """
    stale, last = {}, {}
    for path, entry in sorted(provenance.items()):
        number, commit = entry["notebook"], entry.get("commit")
        if number not in dependencies:
            stale[path] = f"notebook {number} no longer exists"
            continue
        if number not in last:
            last[number] = last_change(repo, dependencies[number])
        if last[number] and not _is_current(repo, entry, dependencies[number], last[number]):
            stale[path] = f"made by notebook {number} at {commit}, but its code changed in {last[number]}" + (
                " (run with uncommitted changes that HEAD does not hold)" if entry.get("uncommitted_changes") else "")
    return stale


def _is_current(repo, entry: dict, paths, last: str) -> bool:
    if entry.get("uncommitted_changes"):  # the code it ran may be committed after the run
        return entry.get("inputs") is not None and entry["inputs"] == inputs_digest(repo, paths, "HEAD")
    return bool(entry.get("commit")) and is_ancestor(repo, last, entry["commit"])


def unrecorded_notebooks(provenance: dict) -> list[str]:
    """Notebooks that write results but have no ``provenance.json`` entry yet."""
    recorded = {entry["notebook"] for entry in provenance.values()}
    return [number for number, patterns in OUTPUTS.items() if patterns and number not in recorded]


# ---------------------------------------------------------------- command line


def _compare_main(argv) -> int:
    parser = argparse.ArgumentParser(prog="python -m mavac.verify", description="Compare a fresh run's result "
                                     "files with the committed ones; exit 1 on any difference.")
    parser.add_argument("--fresh", required=True, help="output root of the fresh run (its MAVAC_OUT)")
    parser.add_argument("--committed", default=str(ROOT), help="output root to compare with (the checkout)")
    parser.add_argument("--only", help="notebook number: compare only the files it writes")
    parser.add_argument("--fast", action="store_true", help="fast-mode layout (build/results)")
    args = parser.parse_args(argv)
    outcomes = verify(args.fresh, args.committed, only=args.only, fast=args.fast)
    for outcome in outcomes:
        print(outcome.line())
    counts = {s: sum(o.status == s for o in outcomes) for s in ("identical", "differs", "missing", "extra")}
    print(f"{len(outcomes)} files: " + ", ".join(f"{n} {s}" for s, n in counts.items()))
    return 0 if counts["identical"] == len(outcomes) else 1


def _run_main(argv) -> int:
    parser = argparse.ArgumentParser(prog="python -m mavac.verify run", description="Execute one notebook "
                                     "(MAVAC_OUT=--out) and record its times and provenance.")
    parser.add_argument("notebook", help="notebook number, e.g. 05")
    parser.add_argument("--out", required=True, help="output root (MAVAC_OUT)")
    parser.add_argument("--executed", required=True, help="folder of the executed notebooks")
    args = parser.parse_args(argv)
    row = run_notebook(args.notebook, args.out, args.executed)
    written = record_run(row, args.out, args.executed, fast=is_fast())
    print(f"{row['notebook']}: {row['wall_s']} s wall, {row['cpu_s']} s CPU, {len(written)} result files")
    return 0


def _finish_main(argv) -> int:
    parser = argparse.ArgumentParser(prog="python -m mavac.verify finish",
                                     description="Add the run's total row to reproduce_times.csv.")
    parser.add_argument("--out", required=True, help="output root (MAVAC_OUT)")
    parser.add_argument("--executed", required=True, help="folder of the executed notebooks (holds the lock)")
    parser.add_argument("--started", required=True, type=float, help="start of the run, epoch seconds")
    args = parser.parse_args(argv)
    print(f"times: {finish_run(args.out, args.started, args.executed, fast=is_fast())}")
    return 0


def main(argv=None) -> int:
    """``python -m mavac.verify``: compare (default), ``run`` or ``finish``; returns the exit status
    (1: files differ, 2: bad input)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    command = {"run": _run_main, "finish": _finish_main}.get(argv[0] if argv else "", None)
    try:
        return command(argv[1:]) if command else _compare_main(argv)
    except ValueError as exc:
        print(f"mavac.verify: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
