"""The command line's bad-input and interrupt audit (issue 33), one case per failure it named.

Issue 33's audit tried 197 inputs and interrupts on ``mavac inspect``, ``setups`` and ``reach``
and on the Python entry points they call. This module holds one case for each failure it named,
with the class the audit put it in (what went wrong before the fixes, from 0c87bd5 on):

    unclear    an error whose message does not say what was wrong, or blames the wrong thing
    lost-data  a file replaced or lost, or something left behind (a file, a running server)
    traceback  a traceback instead of a reason
    wrong      a silent wrong answer
    accepted   a bad input silently accepted
    hang       ran for minutes instead of refusing
    memory     exhausted memory instead of refusing

and what must happen now: the command exits with status 1 and a message naming the flag (2 for
an option argparse refuses), a ValueError or TypeError naming the parameter, no file replaced or
left behind, or the right answer. Cases run on small meshes (a 0.6 m box machine, a 20 cm box
part) with ``--fast``.

Where another test module already holds a test of the same failure, the case reuses its helper
(``_children.server_left_after``, ``test_cli.bad_intensity_file``, ``test_mesh.sliver_box``) or
its case (the Python API rows of ``test_bad_input``). A case marked ``fixed=False`` still fails
on main; pytest runs it as a strict xfail, so it reports when it is fixed.

Run as a script (``python tests/test_cli_audit.py``) it audits the package on the import path
instead of asserting: every case in its own process, under a 3 GB address-space limit and a
120 s timeout, and prints each case's outcome and the counts by class:

    ok      the case passes
    fails   the answer or message is not the one required
    error   an exception escaped (the user sees a traceback)
    hang    the timeout ended it
    memory  MemoryError under the limit

``PYTHONPATH`` pointed at an older checkout gives the counts before the fixes. Only names that
existed before issue 33's work are imported at module level, so it imports against that code.
"""

from __future__ import annotations

import atexit
import contextlib
import dataclasses
import functools
import io
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Callable

import numpy as np
import pytest
import trimesh
from _children import (IN_MESHCAT_SCENE, ctrl_c_as_from_a_terminal, gone_within, listening_ips, print_counts,
                       server_left_after)

CLASSES = ("unclear", "lost-data", "traceback", "wrong", "accepted", "hang", "memory")
OUTCOMES = ("ok", "fails", "error", "hang", "memory")


@dataclasses.dataclass(frozen=True)
class Case:
    """One named failure: ``call()`` must raise ``error`` with ``names`` (a regex) in its
    message, or, with ``error=None``, return a value for which ``check`` is true."""

    klass: str
    id: str
    call: Callable[[], object]
    error: type | tuple | None = None
    names: str = ""
    check: Callable[[object], bool] | None = None
    fixed: bool = True  # False: still fails on main (a strict xfail), reason in ``why``
    why: str = ""


def refuse(klass, id, call, error, names, **kw) -> Case:
    return Case(klass, id, call, error, names, **kw)


def answer(klass, id, call, check, **kw) -> Case:
    return Case(klass, id, call, None, "", check, **kw)


# ---- running the command line in this process ----


@dataclasses.dataclass
class Ran:
    """A command's exit status, what it printed, and the files of its folder afterwards."""

    code: int
    out: str
    err: str
    files: list = dataclasses.field(default_factory=list)

    def error(self, command: str, message: str) -> bool:
        """Exit status 1, stderr ``mavac <command>: error: <message>...`` and no traceback."""
        return (self.code == 1 and self.err.startswith(f"mavac {command}: error: ") and message in self.err
                and "Traceback" not in self.err)


class _Stop(Exception):
    """Raised by a replaced stage to end the command once what the case reads is recorded."""


def cli(*argv) -> Ran:
    """``mavac argv`` through :func:`mavac.cli.main`, stdout and stderr captured."""
    from mavac import cli as command_line

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = command_line.main([str(a) for a in argv])
        except SystemExit as exc:  # argparse
            code = exc.code
    return Ran(code, out.getvalue(), err.getvalue())


@contextlib.contextmanager
def replaced(module, name, value):
    """``module.name`` is ``value`` inside the block."""
    old = getattr(module, name)
    setattr(module, name, value)
    try:
        yield
    finally:
        setattr(module, name, old)


@contextlib.contextmanager
def environment(**values):
    """Environment variables set inside the block, restored after."""
    old = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in old.items():
            os.environ.pop(k) if v is None else os.environ.__setitem__(k, v)


@contextlib.contextmanager
def folder():
    with tempfile.TemporaryDirectory() as d:
        yield Path(d)


def _listing(d: Path) -> list[str]:
    return sorted(str(p.relative_to(d)) for p in d.rglob("*"))


@functools.lru_cache(maxsize=None)
def meshes() -> Path:
    """A folder (removed at exit) with ``m.stl``, a 0.6 x 0.4 x 0.5 m box machine, ``c.stl``, a
    1.2 x 0.6 x 0.9 m one, and ``p.stl``, a 20 cm box part, all in metres."""
    d = Path(tempfile.mkdtemp(prefix="mavac_audit_"))
    atexit.register(shutil.rmtree, d, True)
    trimesh.creation.box([0.6, 0.4, 0.5]).export(d / "m.stl")
    trimesh.creation.box([1.2, 0.6, 0.9]).export(d / "c.stl")
    trimesh.creation.box([0.2, 0.2, 0.2]).export(d / "p.stl")
    return d


def _copy(name: str, into: Path) -> Path:
    shutil.copy(meshes() / name, into / name)
    return into / name


MACHINE = ["--fast", "--quiet"]
INSPECT = MACHINE + ["--no-nos"]
SETUPS = ["--stain", "up:30", "--quiet"]


# ---- output paths ----


def _run_in(d: Path, *argv, env=None) -> Ran:
    """The command run with its outputs in ``d`` (the working folder's files listed after)."""
    with environment(**(env or {})):
        ran = cli(*argv)
    ran.files = _listing(d)
    return ran


def _onto_input(command: str, flag: str) -> tuple[Ran, bool]:
    """``command`` with ``flag`` naming its input mesh: what it said, and whether the mesh is
    byte for byte the same after."""
    with folder() as d:
        mesh = _copy("p.stl" if command == "setups" else "m.stl", d)
        before = mesh.read_bytes()
        extra = SETUPS if command == "setups" else INSPECT if command == "inspect" else MACHINE
        other = [] if flag == "--out" else ["--out", d / "x.html"]
        ran = _run_in(d, command, mesh, *extra, *other, flag, mesh)
        return ran, mesh.read_bytes() == before


def _out_and_json_same() -> Ran:
    with folder() as d:
        return _run_in(d, "inspect", meshes() / "m.stl", *INSPECT, "--out", d / "x.html", "--json", d / "x.html")


def _out_is_default_json() -> Ran:
    with folder() as d:
        return _run_in(d, "inspect", meshes() / "m.stl", *INSPECT, "--out", d / "m_plan.json")


def _out_is_directory() -> Ran:
    with folder() as d:
        (d / "dir").mkdir()
        return _run_in(d, "reach", meshes() / "m.stl", *MACHINE, "--out", d / "dir")


def _out_read_only() -> Ran:
    """``--out`` in a folder without write permission (as another user than root sees it)."""
    with folder() as d:
        ro = d / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        access = os.access
        try:
            with replaced(os, "access", lambda p, mode, **kw: Path(p) != ro and access(p, mode, **kw)):
                if os.geteuid() == 0:  # root writes anywhere: make the write fail as it would for a user
                    with _no_writes_into(ro):
                        return _run_in(d, "reach", meshes() / "m.stl", *MACHINE, "--out", ro / "x.html")
                return _run_in(d, "reach", meshes() / "m.stl", *MACHINE, "--out", ro / "x.html")
        finally:
            ro.chmod(0o755)


@contextlib.contextmanager
def _no_writes_into(ro: Path):
    """Opening a file for writing under ``ro`` raises PermissionError (what a user gets)."""
    import builtins

    real_open, real_os_open = builtins.open, os.open

    def guarded_open(file, mode="r", *args, **kwargs):
        if isinstance(file, (str, Path)) and Path(file).absolute().is_relative_to(ro) and set(mode) & set("wax+"):
            raise PermissionError(13, "Permission denied", str(file))
        return real_open(file, mode, *args, **kwargs)

    def guarded_os_open(path, flags, *args, **kwargs):
        if Path(path).absolute().is_relative_to(ro) and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT):
            raise PermissionError(13, "Permission denied", str(path))
        return real_os_open(path, flags, *args, **kwargs)

    with replaced(builtins, "open", guarded_open), replaced(os, "open", guarded_os_open):
        yield


def _out_under_file() -> Ran:
    with folder() as d:
        (d / "plain").write_text("a file")
        return _run_in(d, "reach", meshes() / "m.stl", *MACHINE, "--out", d / "plain" / "x.html")


def _env_names_file(variable: str) -> Ran:
    with folder() as d:
        (d / "plain").write_text("a file")
        out = [] if variable == "MAVAC_OUT" else ["--out", d / "x.html"]
        return _run_in(d, "reach", meshes() / "m.stl", *MACHINE, *out, env={variable: str(d / "plain")})


def _out_empty() -> Ran:
    with folder() as d:
        return _run_in(d, "reach", meshes() / "m.stl", *MACHINE, "--out", "", env={"MAVAC_OUT": str(d)})


def _companions_of(out_name: str) -> list:
    with folder() as d:
        return _run_in(d, "reach", meshes() / "m.stl", *MACHINE, "--out", d / out_name).files


def _cases_output_paths():
    nothing = lambda ran: not ran.files  # noqa: E731
    return [
        answer("lost-data", "inspect-out-is-the-input", lambda: _onto_input("inspect", "--out"),
               lambda r: r[1] and r[0].error("inspect", "is the input")),
        answer("lost-data", "setups-json-is-the-input", lambda: _onto_input("setups", "--json"),
               lambda r: r[1] and r[0].error("setups", "is the input")),
        answer("lost-data", "reach-csv-is-the-input", lambda: _onto_input("reach", "--csv"),
               lambda r: r[1] and r[0].error("reach", "is the input")),
        answer("lost-data", "inspect-out-and-json-same-file", _out_and_json_same,
               lambda r: r.error("inspect", "both --out and --json") and nothing(r)),
        answer("lost-data", "inspect-out-is-the-default-json", _out_is_default_json,
               lambda r: r.error("inspect", "both --out and --json") and nothing(r)),
        answer("lost-data", "reach-out-directory", _out_is_directory,
               lambda r: r.error("reach", "is a directory") and r.files == ["dir"]),
        answer("traceback", "reach-out-read-only-folder", _out_read_only,
               lambda r: r.error("reach", "cannot write") and r.files == ["ro"]),
        answer("traceback", "reach-out-under-a-file", _out_under_file,
               lambda r: r.error("reach", "not a directory") and r.files == ["plain"]),
        answer("traceback", "reach-MAVAC_CACHE-names-a-file", lambda: _env_names_file("MAVAC_CACHE"),
               lambda r: r.error("reach", "MAVAC_CACHE") and r.files == ["plain"]),
        answer("traceback", "reach-MAVAC_OUT-names-a-file", lambda: _env_names_file("MAVAC_OUT"),
               lambda r: r.error("reach", "MAVAC_OUT") and r.files == ["plain"]),
        answer("accepted", "reach-out-empty", _out_empty, lambda r: r.error("reach", "--out is empty") and nothing(r)),
        answer("lost-data", "reach-csv-named-after-out", lambda: _companions_of("heat.html"),
               lambda files: files == ["heat.csv", "heat.html"]),
    ]


# ---- signals ----

#: IN_MESHCAT_SCENE with SIGHUP as a terminal gives it (default), even under nohup
IN_MESHCAT_SCENE_HUP = "import signal\nsignal.signal(signal.SIGHUP, signal.SIG_DFL)\n" + IN_MESHCAT_SCENE


def _server_left_after_early_ctrl_c() -> bool:
    """Ctrl-C just after the meshcat server process started, before the scene is open: whether
    the server is still running 10 s after the KeyboardInterrupt."""
    from mavac.viz.meshcat_scene import scene

    servers, Popen = [], subprocess.Popen

    class Recorded(Popen):
        def __init__(self, args, *rest, **kwargs):
            super().__init__(args, *rest, **kwargs)
            if "meshcat" in " ".join(map(str, args if isinstance(args, (list, tuple)) else [args])):
                servers.append(self)
                os.kill(os.getpid(), signal.SIGINT)

    with ctrl_c_as_from_a_terminal(servers):
        with replaced(subprocess, "Popen", Recorded), contextlib.suppress(KeyboardInterrupt):
            with scene():
                pass
        assert servers, "no meshcat server was started"
        return not all(gone_within(p.pid, 10) or p.poll() is not None for p in servers)


def _server_addresses() -> set:
    from mavac.viz.meshcat_scene import scene

    with scene() as vis:
        return listening_ips(vis)


def _interrupted_over_old_outputs() -> tuple:
    """Ctrl-C while ``setups`` writes over an earlier run's page and plan: what is left."""
    from mavac.setups.setup_plan import SetupPlan

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    with folder() as d:
        (d / "d.html").write_text("old page")
        (d / "d.json").write_text("old plan")
        with replaced(SetupPlan, "to_html", interrupted):
            ran = _run_in(d, "setups", meshes() / "p.stl", *SETUPS, "--out", d / "d.html")
        return ran.code, ran.files, (d / "d.html").read_text(), (d / "d.json").read_text()


def _ctrl_c_while_importing_open3d() -> Ran:
    """A Ctrl-C while ``import open3d`` runs its pybind11 module's initialisation surfaces as
    ``ImportError('initialization failed')`` caused by the KeyboardInterrupt (seen when SIGINT
    lands 0.1-0.45 s into the import). The first stage of ``inspect`` raises just that."""
    import mavac.geometry.mesh as mesh_module

    def importing(*args, **kwargs):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise ImportError("initialization failed") from exc

    with replaced(mesh_module, "load_mesh", importing):
        return cli("inspect", meshes() / "m.stl", *INSPECT, "--out", Path(tempfile.gettempdir()) / "never.html")


def _cases_signals():
    return [
        answer("lost-data", "meshcat-SIGHUP-server-left", lambda: server_left_after(signal.SIGHUP, IN_MESHCAT_SCENE_HUP),
               lambda left: not left),
        answer("lost-data", "meshcat-SIGKILL-server-left", lambda: server_left_after(signal.SIGKILL),
               lambda left: not left),
        answer("lost-data", "meshcat-early-ctrl-c-server-left", _server_left_after_early_ctrl_c, lambda left: not left),
        answer("wrong", "meshcat-listens-on-every-interface", _server_addresses, lambda ips: ips == {"127.0.0.1"}),
        answer("lost-data", "setups-ctrl-c-over-old-outputs", _interrupted_over_old_outputs,
               lambda r: r == (130, ["d.html", "d.json"], "old page", "old plan")),
        answer("traceback", "ctrl-c-during-import-open3d", _ctrl_c_while_importing_open3d,
               lambda r: r.code == 130 and "interrupted" in r.err and "Traceback" not in r.err),
    ]


# ---- files ----


def _dae(meter: str | None, cut: bool = False):
    """load_mesh on a 1.5 m box in COLLADA with ``<unit meter=...>`` (or cut after 600 bytes)."""
    from test_mesh import _dae_with_unit

    from mavac.geometry.mesh import load_mesh

    with folder() as d:
        path = _dae_with_unit(d / "b.dae", 1.5, 1.0)
        text = path.read_text()
        path.write_text(text[:600] if cut else text.replace('meter="1"', f'meter="{meter}"')
                        .replace('meter="1.0"', f'meter="{meter}"'))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return load_mesh(path)


def _watertight_warnings() -> list:
    from test_mesh import loading_warnings, sliver_box

    with folder() as d:
        return loading_warnings(sliver_box(d / "sliver.ply"))


def _overlapping_boxes_C() -> tuple[float, float]:
    """C of two overlapping boxes written as one mesh (their faces cross), and of their union."""
    a = trimesh.creation.box(bounds=[[0, 0, 0], [1.0, 0.6, 0.6]])
    b = trimesh.creation.box(bounds=[[0.5, 0, 0], [1.5, 0.6, 0.9]])
    C = []
    with folder() as d:
        for name, mesh in (("two", trimesh.util.concatenate([a, b])),
                           ("union", trimesh.boolean.union([a, b], engine="manifold"))):
            mesh.export(d / f"{name}.stl")
            ran = cli("inspect", d / f"{name}.stl", *INSPECT, "--out", d / f"{name}.html", "--json", d / f"{name}.json")
            assert ran.code == 0, ran.err
            C.append(json.loads((d / f"{name}.json").read_text())["C"])
    return tuple(C)


def _tool_tip_warnings() -> int:
    """How often ``setups`` on the 20 cm box (2 stain patches of 200 cm^2) says 'larger than the
    tool tip'."""
    with folder() as d:
        ran = cli("setups", meshes() / "p.stl", *SETUPS, "--out", d / "p.html")
        assert ran.code == 0, ran.err
        return (ran.out + ran.err).count("larger than the tool tip")


def _cases_files():
    return [
        refuse("unclear", "dae-malformed-blamed-on-pycollada", lambda: _dae(None, cut=True), ValueError,
               r"(?s)^(?!.*pycollada).*could not be read as a mesh"),
        *[refuse("accepted", f"dae-unit-{meter}-read-as-metres", functools.partial(_dae, meter), ValueError,
                 r"<unit meter=.*pass units=") for meter in ("metre", "0", "-0.001", "nan")],
        answer("wrong", "overlapping-boxes-buried-points-occluded", _overlapping_boxes_C,
               lambda C: abs(C[0] - C[1]) < 0.03),
        answer("wrong", "not-watertight-after-own-repair", _watertight_warnings,
               lambda said: any("degenerate" in w for w in said) and not any("not watertight" in w for w in said)),
        answer("unclear", "tool-tip-warning-three-times", _tool_tip_warnings, lambda n: n == 1),
    ]


# ---- placement ----


def _C_here_and_10_km_away(suffix: str) -> tuple[float, float]:
    """C of ``inspect`` on the box machine at the origin and 10 km away, in a ``suffix`` file."""
    box = trimesh.load(meshes() / "m.stl")
    C = []
    with folder() as d:
        for name, shift in (("here", 0.0), ("far", 1e4)):
            box.copy().apply_translation([shift, shift, 0]).export(d / f"{name}{suffix}")
            ran = cli("inspect", d / f"{name}{suffix}", *INSPECT, "--out", d / f"{name}.html", "--json",
                      d / f"{name}.json")
            assert ran.code == 0, ran.err
            C.append(json.loads((d / f"{name}.json").read_text())["C"])
    return tuple(C)


def _cases_placement():
    # OBJ: the moved machine is the same mesh bit for bit (machine_from_mesh rounds to 1 nm). STL
    # stores float32, so 10 km away the box itself moves by up to 0.2 mm: C is equal here (0.944),
    # but only within the tolerance, not by construction (ties between guard-cluster members and
    # the 1 cm ring steps of the candidate spots still follow such differences).
    return [answer("wrong", f"C-10-km-away-{suffix[1:]}", functools.partial(_C_here_and_10_km_away, suffix),
                   lambda C: abs(C[0] - C[1]) < 0.01) for suffix in (".obj", ".stl")]


# ---- stain ----


def _parsed(*argv):
    """The namespace ``main`` hands ``setups`` (the command replaced by a recorder), or the exit
    status if the command line is refused."""
    from mavac import cli as command_line

    seen = {}
    with replaced(command_line, "cmd_setups", lambda args: seen.setdefault("args", args) and 0):
        ran = cli("setups", "p.stl", *argv)
    return seen.get("args", ran.code)


def _stain_cone(spec: str):
    from mavac.geometry.stain_marking import parse_stain

    args = _parsed("--stain", spec)
    try:
        return args if isinstance(args, int) else parse_stain(args.stain).get("cone")
    except ValueError as exc:  # what the command would say (status 1)
        return str(exc)


def _marked(path, *argv):
    """The stained part ``setups`` would plan for (the planner replaced), or its exit status."""
    import mavac.setups.setup_plan as plan_module

    seen, ran = {}, None

    def planned(part, *args, **kwargs):
        seen["part"] = part
        raise _Stop

    with replaced(plan_module, "plan_setups", planned), contextlib.suppress(_Stop):
        ran = cli("setups", path, "--quiet", "--out", Path(tempfile.gettempdir()) / "never.html", *argv)
    return seen.get("part", ran)


def _stained_centres(*specs) -> list:
    """Centres (mm, rounded) of the stained faces of a 6 cm dome for each stain spec (None where
    it is refused)."""
    with folder() as d:
        trimesh.creation.icosphere(subdivisions=2, radius=0.06).export(d / "dome.stl")
        parts = [_marked(d / "dome.stl", "--stain", spec) for spec in specs]
    return [None if isinstance(p, Ran) else set(map(tuple, np.round(1e3 * p.mesh.triangles_center[p.stain_faces])))
            for p in parts]


def _cases_stain():
    huge = "faces:" + "9" * 30
    return [
        answer("unclear", "stain-+x:20-never-parses", lambda: _stain_cone("+x:20"),
               lambda cone: cone == ((1, 0, 0), 20.0)),
        answer("unclear", "stain--x:20-needs-equals", lambda: _stain_cone("-x:20"),
               lambda cone: cone == ((-1, 0, 0), 20.0)),
        answer("traceback", "stain-faces-huge-int", lambda: _marked(meshes() / "p.stl", "--stain", huge),
               lambda r: isinstance(r, Ran) and r.error("setups", "faces")),
        # the join was '+' (now a sign, see test_stain_marking): the same combination is spelled ','
        answer("wrong", "stain-up:30,down:30-keeps-last-cone", lambda: _stained_centres("up:30,down:30", "up:30",
                                                                                        "down:30"),
               lambda f: None not in f and f[0] == f[1] | f[2] and len(f[1]) > 0 and len(f[2]) > 0),
        answer("wrong", "stain-up:60,up:10-keeps-last-cone", lambda: _stained_centres("up:60,up:10", "up:60", "up:10"),
               lambda f: None not in f and f[0] == f[1] | f[2] and len(f[1]) > len(f[2]) > 0),
    ]


# ---- planner numbers ----


def _setups_doc(*argv) -> tuple[Ran, object]:
    """``setups`` on the 20 cm box: what it said and its JSON read strictly (no Infinity/NaN:
    the string 'not JSON' if it holds one, None if not written)."""
    def refuse_constant(constant):
        raise ValueError(constant)

    with folder() as d:
        ran = _run_in(d, "setups", meshes() / "p.stl", *SETUPS, "--out", d / "p.html", *argv)
        if not (d / "p.json").exists():
            return ran, None
        try:
            return ran, json.loads((d / "p.json").read_text(), parse_constant=refuse_constant)
        except ValueError:
            return ran, "not JSON"


def _no_plan_said(r) -> bool:
    """Either a plan (status 0, setups, a finite cost) or status 3 with NO SOLUTION and strict JSON."""
    ran, doc = r
    if not isinstance(doc, dict):
        return False
    if ran.code == 0:
        return bool(doc["setups"]) and doc["cost_s"] is not None
    return ran.code == 3 and "NO SOLUTION" in ran.out and not doc["setups"] and doc["cost_s"] is None


def _machine_run(*argv, mesh="m.stl") -> Ran:
    with folder() as d:
        return _run_in(d, argv[0], meshes() / mesh, *INSPECT, *argv[1:], "--out", d / "x.html")


def _cases_planner():
    # --t-max bounds only the paper's search now (--method dfbnb or both): the cases ask for it
    return [
        answer("wrong", "setups-t-max-1e-9-infinity", lambda: _setups_doc("--method", "dfbnb", "--t-max", "1e-9"),
               _no_plan_said),
        answer("wrong", "setups-t-max-1e-3-infinity", lambda: _setups_doc("--method", "dfbnb", "--t-max", "1e-3"),
               _no_plan_said),
        answer("wrong", "setups-setup-time-1e308-optimal", lambda: _setups_doc("--setup-time", "1e308"),
               lambda r: r[0].error("setups", "--setup-time") and not r[0].files),
        answer("accepted", "setups-seed-2**70", lambda: _setups_doc("--seed", str(2**70)),
               lambda r: r[0].error("setups", "--seed") and not r[0].files),
        answer("traceback", "inspect-hpr-radius-1e308-qhull",
               lambda: _machine_run("inspect", "--visibility", "hpr", "--hpr-radius", "1e308"),
               lambda r: r.error("inspect", "--hpr-radius") and not r.files),
        # the audit's machine: 4.7 m^2, about 520,000 elements 3 mm apart
        answer("hang", "inspect-spacing-3-mm", lambda: _machine_run("inspect", "--spacing", "0.003", mesh="c.stl"),
               lambda r: r.error("inspect", "--spacing") and "surface elements" in r.err and not r.files),
    ]


# ---- --intensity ----


def _intensity(kind: str) -> Ran:
    from test_cli import bad_intensity_file

    with folder() as d:
        bad = bad_intensity_file(kind, d)
        return cli("setups", meshes() / "p.stl", *SETUPS, "--intensity", bad, "--out", d / "p.html")


def _cases_intensity():
    said = {"pickled": "--intensity", "truncated": "--intensity", "garbage": "--intensity", "text": "--intensity",
            "directory": "is a directory"}
    return [answer("unclear", f"intensity-{kind}-file", functools.partial(_intensity, kind),
                   lambda r, m=message: r.error("setups", "--intensity") and m in r.err and "allow_pickle" not in r.err)
            for kind, message in said.items()]


# ---- the Python API ----

#: the cases of test_bad_input's matrix that are this audit's API failures, with this audit's class
#: (and, where the old message also held the parameter's name, a stricter pattern)
BAD_INPUT_CASES = {
    "run_trial-plan-None": "unclear", "run_trial-plan-str": "unclear", "run_trial-robot-str": "unclear",
    "run_part-teapot": ("unclear", r"^part must be one of"), "run_part-42": "unclear", "run_trials-trials-1.5": "unclear",
    "map_trials-fn-None": "unclear", "map_trials-items-5": "unclear", "run_trials-scenes-str": "unclear",
    "run_part-fast-str": "wrong", "run_trials-trials--3": "accepted", "run_trials-trials-1e12": "memory",
    "random_search-budget-1e12": "hang",
}


def _trial_with_the_puma():
    """An online trial of the box machine's plan (made for the UR10) run with the Puma 560."""
    from mavac.cleaning.trial import run_trial
    from mavac.experiments.mavac_offline import fast_params
    from mavac.geometry.machines import machine_from_mesh
    from mavac.inspection.inspection_plan import plan_inspection
    from mavac.robots.models import puma560

    machine = machine_from_mesh(trimesh.load(meshes() / "m.stl"), name="m")
    params = fast_params()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_inspection(machine, params=dataclasses.replace(params, nos=dataclasses.replace(
            params.nos, enabled=False)))
    return run_trial(machine, plan, robot=puma560())


def _cases_api():
    import test_bad_input

    by_id = {c.id: c for c in test_bad_input.HAND_WRITTEN}
    reused = [Case(k, i, by_id[i].call, by_id[i].error, by_id[i].names) if isinstance(k, str)
              else Case(k[0], i, by_id[i].call, by_id[i].error, k[1]) for i, k in BAD_INPUT_CASES.items()]
    return reused + [
        refuse("unclear", "run_trial-robot-puma560-fails-deep-inside", _trial_with_the_puma, (ValueError, TypeError),
               r"\brobot\b.*(UR10|ur10|plan)"),
    ]


# ---- the rest of the issue ----


def _up_minus_y() -> bool:
    """A block turned so that its top faces -y, read with ``--up -y``: the same part as the block
    read as it is (vertex for vertex)."""
    block = trimesh.creation.box([0.10, 0.06, 0.04])
    turned = block.copy().apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    with folder() as d:
        block.export(d / "block.ply")
        turned.export(d / "turned.ply")
        parts = [_marked(d / "block.ply", "--stain", "up:30", "--up", "z"),
                 _marked(d / "turned.ply", "--stain", "up:30", "--up", "-y")]
    if any(isinstance(p, Ran) for p in parts):
        return False
    a, b = (p.mesh.vertices for p in parts)
    return a.shape == b.shape and np.allclose(a, b, atol=1e-9) and parts[0].stain_faces.tolist() == \
        parts[1].stain_faces.tolist()


def _reach_with_inspect_options() -> Ran:
    with folder() as d:
        return _run_in(d, "reach", meshes() / "m.stl", *MACHINE, "--P-s", "0.9", "--P-g", "0.9", "--no-nos",
                       "--out", d / "x.html")


def _cases_issue_body():
    return [
        answer("wrong", "setups-up-minus-y-upside-down", _up_minus_y, bool),
        answer("accepted", "reach-P-s-P-g-no-nos-ignored", lambda: _reach_with_inspect_options(),
               lambda r: r.code == 2 and "unrecognized arguments: --P-s 0.9 --P-g 0.9 --no-nos" in r.err),
    ]


def all_cases() -> list[Case]:
    return (_cases_output_paths() + _cases_signals() + _cases_files() + _cases_placement() + _cases_stain()
            + _cases_planner() + _cases_intensity() + _cases_api() + _cases_issue_body())


# ---- the tests ----

CASES = all_cases()


@pytest.mark.parametrize("case", [pytest.param(c, id=c.id, marks=() if c.fixed else pytest.mark.xfail(
    strict=True, reason=c.why)) for c in CASES])
def test_named_failure(case):
    from test_bad_input import _assert_case  # the same assertion as the bad-input matrix's

    _assert_case(case)


def test_every_class_has_a_case_and_ids_are_unique():
    assert {c.klass for c in CASES} == set(CLASSES)
    assert len({c.id for c in CASES}) == len(CASES)


# ---- the audit (run as a script) ----

#: a child's address-space limit: a case that would exhaust memory gets MemoryError instead
MEMORY_LIMIT = 3 * 2**30


def outcome(case: Case) -> str:
    """What the package on the import path does with ``case`` (see the module docstring)."""
    try:
        result = case.call()
    except MemoryError:
        return "memory"
    except Exception as exc:  # noqa: BLE001 -- classifying every failure is the point
        if case.error is not None and isinstance(exc, case.error):
            return "ok" if re.search(case.names, str(exc)) else "fails"
        return "error"
    if case.error is not None:
        return "fails"
    try:
        return "ok" if case.check(result) else "fails"
    except Exception:  # noqa: BLE001 -- a result of another shape
        return "fails"


def _limit_memory():
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def _audit_one_in_child(case_id: str, limit: float) -> str:
    try:
        # from a neutral folder: a ``python -c`` grandchild puts its working folder first on sys.path
        out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--case", case_id], capture_output=True,
                             text=True, timeout=limit, preexec_fn=_limit_memory, cwd=tempfile.gettempdir())
    except subprocess.TimeoutExpired:
        return "hang"
    lines = out.stdout.strip().splitlines()
    return lines[-1] if lines and lines[-1] in OUTCOMES else "error"  # died (e.g. killed by a signal)


def audit(limit: float = 120.0) -> dict:
    """Outcome counts by class, each case in a child process."""
    counts = {k: dict.fromkeys(OUTCOMES, 0) for k in CLASSES}
    for case in CASES:
        result = _audit_one_in_child(case.id, limit)
        counts[case.klass][result] += 1
        print(f"{case.klass:10s} {case.id:48s} {result}", flush=True)
    return counts


def _main(argv):
    os.environ.setdefault("MAVAC_FAST", "1")  # as conftest.py: nothing lands in data/results
    if len(argv) == 2 and argv[0] == "--case":
        warnings.simplefilter("ignore")
        print(outcome(next(c for c in CASES if c.id == argv[1])), flush=True)
        return
    print_counts(audit(), OUTCOMES, total=True)


if __name__ == "__main__":
    _main(sys.argv[1:])
