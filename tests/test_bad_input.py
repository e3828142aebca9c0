"""The bad-input matrix (issue 14): inputs a careful user or a fuzzer tries on the public API.

Each case names the class the issue's audit put it in (what went wrong before the
reliability pass) and what must happen now: an exception of the given type whose message names
the parameter, or, for an input that is valid, the right answer.

    dependency  crashed inside a dependency (scipy Qhull, scikit-learn, OpenCV, numpy)
    unnamed     an error whose message does not name the input
    accepted    a bad value silently accepted
    wrong       a silent wrong answer
    hang        ran for minutes (or exhausted memory) instead of failing
    process     an interrupted run left a server running or a temporary file behind

Every field of every parameter dataclass is also tried with a wrong type, NaN and infinity
(cases generated from ``dataclasses.fields``), under the class ``accepted``.

Run as a script (``python tests/test_bad_input.py``) it audits the package on the import path
instead of asserting: every hand-written case in its own process (so a hang is timed out and
killed), and prints how many cases end in each outcome, by class. Pointing ``PYTHONPATH`` at an
older checkout gives the counts before a change. The module only uses names that existed before
the reliability pass, so it imports against that code too.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import traceback
import types
import typing
import warnings
from pathlib import Path
from typing import Callable

import numpy as np
import pytest
import trimesh
from _children import HALF_WRITTEN_CSV, end, print_counts, server_left_after, start, wait_line

import mavac.params as P

CLASSES = ("dependency", "unnamed", "accepted", "wrong", "hang", "process")


@dataclasses.dataclass(frozen=True)
class Case:
    """One bad input: ``call()`` must raise ``error`` with ``names`` (a regex) in its message,
    or, with ``error=None``, return a result for which ``check`` is true."""

    klass: str
    id: str
    call: Callable[[], object]
    error: type | None = None
    names: str = ""
    check: Callable[[object], bool] | None = None


def refuse(klass, id, call, error, names):
    return Case(klass, id, call, error, names)


def answer(klass, id, call, check):
    return Case(klass, id, call, None, "", check)


# ---- shared inputs (built once, lazily) ----


@functools.lru_cache(maxsize=None)
def _bowl():
    from mavac.geometry.parts import load_part

    return load_part("bowl")


@functools.lru_cache(maxsize=None)
def _ur10():
    from mavac.robots.models import ur10_mobile

    return ur10_mobile()


def _mesh(vertices, faces):
    return trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces), process=False)


VERTICAL_TRIANGLE = ([[0, 0, 0], [1, 0, 0], [0, 0, 1]], [[0, 1, 2]])
COLLINEAR_FACES = ([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 0, 1], [1, 0, 1]], [[0, 1, 3], [1, 2, 4]])
NAN_VERTEX = ([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]], [[0, 1, 2]])
SCALED = np.diag([2.0, 2.0, 2.0, 1.0])
SHEAR = np.array([[1.0, 0.3, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
REFLECTION = np.diag([1.0, 1.0, -1.0, 1.0])
RAGGED = [[1, 0, 1], [1, 0]]


def _stain_image():
    """A rendered bowl stain (uint8) and the region of the part."""
    from mavac.vision.stain import face_index_image, render_stain_image, view_of_faces

    part = _bowl()
    stain = np.zeros(len(part.mesh.faces))
    stain[part.stain_faces] = part.intensity
    index = face_index_image(part.mesh, view_of_faces(part.mesh, part.stain_faces), (96, 96))
    image = render_stain_image(part.mesh, stain, None, face_index=index, noise_std=0.02,
                               rng=np.random.default_rng(0))
    return image, index >= 0


def _float_image_same_mask():
    from mavac.vision.stain import stain_mask_kmeans

    image, region = _stain_image()
    as_uint8 = stain_mask_kmeans(image, region_mask=region)
    as_float = stain_mask_kmeans(image / 255.0, region_mask=region)
    return as_uint8.sum() > 0 and np.array_equal(as_uint8, as_float)


def _float_image_same_passes():
    from mavac.vision.stain import passes_from_image

    image, region = _stain_image()
    return np.array_equal(passes_from_image(image, region_mask=region),
                          passes_from_image(image / 255.0, region_mask=region))


def _experiment_returning(value):
    return lambda x, rng: value


def _gpr_params():
    return P.GPRParams(max_experiments=20)


def _learn(value):
    from mavac.scrubbing.gpr import learn_parameters

    return learn_parameters(_experiment_returning(value), _gpr_params())


def _random_search(value):
    from mavac.scrubbing.gpr import random_search

    return random_search(_experiment_returning(value), _gpr_params(), budget=5)


def _dense_optimum_nan():
    from mavac.scrubbing.gpr import dense_optimum

    return dense_optimum(lambda X: np.full(len(X), np.nan), _gpr_params(), points_per_axis=(3,) * 5)


def _toolpath(world_T_part=np.eye(4), patch_ids=tuple(range(20)), **params):
    from mavac.scrubbing.toolpath import toolpath_for_setup

    return toolpath_for_setup(_bowl(), world_T_part, list(patch_ids), P.ToolpathParams(**params))


def _reachability_map_after_flip() -> bool:
    """Build a small reachability map into an empty cache, flip 4 KB in the middle of its
    pickle, build it again: the same map must come back."""
    from mavac import cache
    from mavac.inspection.reachability import reachability_map

    tiny = P.ReachabilityMapParams(voxel_size=0.1, n_directions=8, n_samples=2000, n_rotations=8, seed=5)
    old = os.environ.get("MAVAC_CACHE")
    with tempfile.TemporaryDirectory() as folder:
        os.environ["MAVAC_CACHE"] = folder
        cache.memory.cache_clear()
        try:
            first = reachability_map(_ur10(), tiny).reachable
            output = next(Path(folder).rglob("output.pkl"))
            data = bytearray(output.read_bytes())
            mid = len(data) // 2
            data[mid:mid + 4096] = bytes(b ^ 0xFF for b in data[mid:mid + 4096])
            output.write_bytes(bytes(data))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                second = reachability_map(_ur10(), tiny).reachable
        finally:
            os.environ.pop("MAVAC_CACHE") if old is None else os.environ.__setitem__("MAVAC_CACHE", old)
            cache.memory.cache_clear()
    return np.array_equal(first, second)


def _meshcat_server_left_after_sigterm() -> bool:
    """SIGTERM a process inside a meshcat scene; whether its server was left running."""
    return server_left_after(signal.SIGTERM)


def _files_after_killed_write() -> list:
    """SIGKILL a process in the middle of write_csv, write the file again: what is left."""
    import pandas as pd

    from mavac.io import write_csv

    with tempfile.TemporaryDirectory() as folder:
        target = Path(folder) / "t.csv"
        proc = start(HALF_WRITTEN_CSV, target)
        wait_line(proc, "writing")
        proc.kill()
        end(proc)
        write_csv(pd.DataFrame({"a": [1], "b": [2]}), target)
        return sorted(p.name for p in Path(folder).iterdir())


def _plate_facing_table_plan():
    """Plan of a plate resting on the table with its stained faces pointing down into it."""
    import warnings

    from mavac.geometry.parts import part_from_mesh
    from mavac.setups.setup_plan import plan_setups

    box = trimesh.creation.box(extents=[0.3, 0.2, 0.02])
    box.apply_translation([0, 0, 0.01])
    faces = np.flatnonzero(box.face_normals[:, 2] < -0.9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return plan_setups(part_from_mesh(box, faces, np.ones(len(faces), int), name="plate"))


def _zero_setups_plan():
    from mavac.planning.setcover import solve_setup_cover

    return solve_setup_cover(np.zeros((0, 4), bool), np.ones(0), method="both")


def _default_both_on_random_60x40():
    """solve_setup_cover with every default on the instance that used to run for minutes."""
    import warnings

    from mavac.planning.setcover import solve_setup_cover

    rng = np.random.default_rng(0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return solve_setup_cover(rng.random((60, 40)) < 0.3, rng.uniform(1, 2, 60), method="both")


def _setup_motion_scaled():
    from mavac.geometry.parts import load_part
    from mavac.robots.models import puma560
    from mavac.setups.viewer import setup_motion

    class Plan:
        setups = np.zeros((1, 3))
        patches = [np.arange(3)]

    return setup_motion(puma560(0.1), load_part("schwefel"), Plan(), SCALED[None])


# ---- the hand-written matrix ----


def _cases_wrong():
    from mavac.geometry import transforms as TR
    from mavac.inspection import coverage, guards
    from mavac.scrubbing import lissajous, toolpath
    from mavac.vision import camera, icp, stain

    image = lambda: _stain_image()[0]  # noqa: E731
    return [
        answer("wrong", "stain-float-image-same-mask", _float_image_same_mask, bool),
        answer("wrong", "plan-stain-facing-down-into-the-table", _plate_facing_table_plan,
               lambda plan: plan.status == "no_solution" and set(plan.uncoverable_causes) == {"below_support"}),
        answer("wrong", "setcover-zero-setups-no-solution", _zero_setups_plan,
               lambda res: res.status == "no_solution" and list(res.uncoverable) == [0, 1, 2, 3]),
        refuse("wrong", "setup_motion-scaled-base_T_parts", _setup_motion_scaled, ValueError, "base_T_parts"),
        answer("wrong", "stain-float-image-same-passes", _float_image_same_passes, bool),
        refuse("wrong", "stain-uint16-image", lambda: stain.stain_mask_kmeans(image().astype(np.uint16) * 257),
               ValueError, r"image.*dtype uint16.*range.*shape"),
        refuse("wrong", "stain-nan-image", lambda: stain.stain_mask_kmeans(np.full((8, 8, 3), np.nan)),
               ValueError, r"image.*dtype float64.*range.*shape"),
        refuse("wrong", "stain-float-image-above-1", lambda: stain.stain_mask_kmeans(image() * 1.0),
               ValueError, r"image.*range.*shape"),
        refuse("wrong", "stain-bool-image", lambda: stain.passes_from_image(image() > 100),
               ValueError, r"image.*dtype bool"),
        answer("wrong", "cache-flipped-bytes-recomputed", _reachability_map_after_flip, bool),
        refuse("wrong", "toolpath-scaled-x2-world_T_part", lambda: _toolpath(SCALED), ValueError, "world_T_part"),
        refuse("wrong", "reachable_from_robot-scaled",
               lambda: toolpath.reachable_from_robot(None, world_T_base=SCALED), ValueError, "world_T_base"),
        refuse("wrong", "transform_points-scaled", lambda: TR.transform_points(SCALED, [[1, 2, 3]]),
               ValueError, "a_T_b"),
        refuse("wrong", "points_in_frame-reflection", lambda: TR.points_in_frame(REFLECTION, [[1, 2, 3]]),
               ValueError, "a_T_b"),
        refuse("wrong", "compose-shear", lambda: TR.compose(np.eye(4), SHEAR), ValueError, r"transforms\[1\]"),
        refuse("wrong", "camera_configurations-scaled", lambda: guards.camera_configurations(
            _ur10(), None, SCALED, np.zeros((1, 3)), [[0, 0, 1]], np.random.default_rng(0)),
            ValueError, "world_T_base"),
        refuse("wrong", "fov_mask-scaled", lambda: camera.fov_mask([[1, 0, 0]], SCALED, P.CameraParams()),
               ValueError, "world_T_camera"),
        refuse("wrong", "rotation_error-not-a-rotation", lambda: icp.rotation_error(2 * np.eye(3), np.eye(3)),
               ValueError, "R_a"),
        refuse("wrong", "dense_optimum-nan-model", _dense_optimum_nan, ValueError, "experiment_mean"),
        refuse("wrong", "overlay_path-scaled-frames",
               lambda: lissajous.overlay_path([[0, 0, 0], [0.1, 0, 0]], [SCALED, SCALED]), ValueError, "frames"),
        refuse("wrong", "cleaning_performance-nan-mask", lambda: stain.cleaning_performance(
            np.full((4, 4), np.nan), np.zeros((4, 4))), ValueError, "mask_before"),
        refuse("wrong", "coverage-nan-visibility", lambda: coverage.coverage_overlap([[np.nan, 1.0]]), ValueError,
               "visible"),
    ]


def _cases_dependency():
    from mavac.geometry import machines, transforms
    from mavac.geometry.surface import sample_surface
    from mavac.planning.greedy import greedy_select
    from mavac.planning.setcover import solve_setup_cover
    from mavac.vision import camera, icp, stain
    from mavac.vision.visibility import VisibilityScene

    empty = np.zeros((0, 0, 3), np.uint8)
    return [
        refuse("dependency", "machine-vertical-triangle", lambda: machines.machine_from_mesh(_mesh(*VERTICAL_TRIANGLE)),
               ValueError, "mesh"),
        refuse("dependency", "machine-collinear-faces", lambda: machines.machine_from_mesh(_mesh(*COLLINEAR_FACES)),
               ValueError, "mesh"),
        refuse("dependency", "machine-nan-vertex", lambda: machines.machine_from_mesh(_mesh(*NAN_VERTEX)),
               ValueError, "mesh"),
        refuse("dependency", "footprint-vertical-triangle", lambda: machines.footprint_from_mesh(
            _mesh(*VERTICAL_TRIANGLE)), ValueError, "mesh"),
        refuse("dependency", "sample_surface-nan-vertex", lambda: sample_surface(_mesh(*NAN_VERTEX), 0.1),
               ValueError, "mesh"),
        refuse("dependency", "visibility-scene-nan-vertex", lambda: VisibilityScene(_mesh(*NAN_VERTEX)).visible(
            [[0, 0, 0]], [[0, 0, 1]], [[0, 0, 1]]), ValueError, "mesh"),
        refuse("dependency", "gpr-nan-result", lambda: _learn(np.nan), ValueError, "experiment"),
        refuse("dependency", "stain-empty-image", lambda: stain.stain_mask_kmeans(empty), ValueError,
               r"image.*range empty.*shape \(0, 0, 3\)"),
        refuse("dependency", "passes-empty-image", lambda: stain.passes_from_image(empty), ValueError,
               r"image.*range empty"),
        refuse("dependency", "setcover-ragged-cover", lambda: solve_setup_cover(RAGGED, [1.0, 1.0]), ValueError,
               "cover"),
        refuse("dependency", "greedy-ragged-access", lambda: greedy_select(RAGGED, 0.1), ValueError, "access"),
        refuse("dependency", "fov-ragged-points", lambda: camera.fov_masks(RAGGED, np.eye(4), P.CameraParams()),
               ValueError, "points_world"),
        refuse("dependency", "transform-ragged", lambda: transforms.check_transform("world_T_part", [[1, 0], [0]]),
               ValueError, "world_T_part"),
        refuse("dependency", "rotation_error-nan", lambda: icp.rotation_error(np.full((3, 3), np.nan), np.eye(3)),
               ValueError, "R_a"),
    ]


def _cases_unnamed():
    import pandas as pd

    from mavac.geometry.machines import dust_heaps, load_machine
    from mavac.geometry.mesh import load_mesh
    from mavac.geometry.surface import sample_surface
    from mavac.geometry.transforms import rz
    from mavac.inspection import coverage
    from mavac.io import write_csv
    from mavac.robots import kinematics
    from mavac.scrubbing import gpr
    from mavac.scrubbing.execution import cover_from_patches
    from mavac.scrubbing.lissajous import lissajous_force
    from mavac.setups.reach import base_T_part
    from mavac.scrubbing import wear
    from mavac.vision import camera, icp, stain
    from mavac.viz import meshcat_scene

    box = trimesh.creation.box()
    return [
        refuse("unnamed", "GPRParams-v_bounds-float", lambda: P.GPRParams(v_bounds=0.5), TypeError, "v_bounds"),
        refuse("unnamed", "GPRParams-seed-None", lambda: P.GPRParams(seed=None), TypeError, "seed"),
        refuse("unnamed", "SpotParams-ring_distances-float", lambda: P.SpotParams(ring_distances=0.5), TypeError,
               "ring_distances"),
        refuse("unnamed", "gpr-None-result", lambda: _learn(None), TypeError, "experiment"),
        refuse("unnamed", "gpr-experiment-not-callable", lambda: gpr.learn_parameters(3, _gpr_params()), TypeError,
               "experiment"),
        refuse("unnamed", "sample_surface-spacing-str", lambda: sample_surface(box, "0.1"), TypeError, "spacing"),
        refuse("unnamed", "dust_heaps-spacing-str", lambda: dust_heaps(load_machine("test_bench"), spacing="0.1"),
               TypeError, "spacing"),
        refuse("unnamed", "toolpath-str-patch_ids", lambda: _toolpath(patch_ids=["a"]), TypeError, "patch_ids"),
        refuse("unnamed", "face_index_image-size-1-tuple", lambda: stain.face_index_image(
            _bowl().mesh, (0, 0, -1), (96,)), ValueError, "image_size"),
        refuse("unnamed", "passes-n_clusters-None", lambda: stain.passes_from_image(
            _stain_image()[0], n_clusters=None), TypeError, "n_clusters"),
        refuse("unnamed", "rz-str", lambda: rz("a"), ValueError, "theta"),
        refuse("unnamed", "cover_counts-ragged", lambda: coverage.cover_counts(RAGGED), ValueError, "visible"),
        refuse("unnamed", "cover_from_patches-n_patches-str", lambda: cover_from_patches([[0]], "3"), TypeError,
               "n_patches"),
        refuse("unnamed", "load_mesh-path-None", lambda: load_mesh(None), TypeError, "path"),
        refuse("unnamed", "write_csv-path-None", lambda: write_csv(pd.DataFrame({"a": [1]}), None),
               TypeError, "path"),
        refuse("unnamed", "write_csv-not-a-frame", lambda: write_csv([1, 2], Path(tempfile.gettempdir()) / "x.csv"),
               TypeError, "df"),
        refuse("unnamed", "lissajous-params-None", lambda: lissajous_force([0.1], None), TypeError, "params"),
        refuse("unnamed", "base_T_part-space-None", lambda: base_T_part([[0, 0, 0]], None), TypeError, "space"),
        refuse("unnamed", "fov-camera-None", lambda: camera.fov_masks([[1, 0, 0]], np.eye(4), None), TypeError,
               "camera"),
        refuse("unnamed", "fk-robot-None", lambda: kinematics.fk(None, np.zeros(6)), TypeError, "robot"),
        refuse("unnamed", "fk-q-str", lambda: kinematics.fk(_ur10(), ["a"] * _ur10().nq), ValueError, r"\bq\b"),
        refuse("unnamed", "register_part-mesh-None", lambda: icp.register_part(
            None, np.random.default_rng(0).random((10, 3)), np.eye(4)), TypeError, "mesh"),
        refuse("unnamed", "partial_noisy_cloud-rng-None",
               lambda: icp.partial_noisy_cloud(box, np.eye(4), [0, 0, 1], 0.0, 10, None), TypeError, "rng"),
        refuse("unnamed", "dust_heaps-machine-None", lambda: dust_heaps(None), TypeError, "machine"),
        refuse("unnamed", "render_stain_image-mesh-None", lambda: stain.render_stain_image(None, [0.5], (0, 0, -1)),
               TypeError, "mesh"),
        refuse("unnamed", "cleaning_performance-ragged", lambda: stain.cleaning_performance(RAGGED, RAGGED),
               ValueError, "mask_before"),
        refuse("unnamed", "frame_camera-nan-box", lambda: meshcat_scene.frame_camera(None, [np.nan] * 3, [1, 1, 1]),
               ValueError, "lower"),
        refuse("unnamed", "scrub_faces-params-None", lambda: wear.scrub_faces([0.5], None), TypeError, "params"),
    ]


def _cases_accepted():
    from mavac.geometry.parts import part_from_mesh
    from mavac.geometry.surface import sample_surface
    from mavac.geometry.transforms import se2_to_matrix
    from mavac.parallel import map_trials
    from mavac.scrubbing.execution import cover_from_patches
    from mavac.vision import camera
    from mavac.vision.stain import view_of_faces

    return [
        refuse("accepted", "CameraParams-L_d-str", lambda: P.CameraParams(L_d="0.5"), TypeError, "L_d"),
        refuse("accepted", "LissajousParams-v-True", lambda: P.LissajousParams(v=True), TypeError, r"\bv\b"),
        refuse("accepted", "CameraParams-L_d-inf", lambda: P.CameraParams(L_d=math.inf), ValueError, "L_d"),
        refuse("accepted", "SetupPlanParams-space-None", lambda: P.SetupPlanParams(space=None), TypeError, "space"),
        refuse("accepted", "NoSParams-enabled-1", lambda: P.NoSParams(enabled=1), TypeError, "enabled"),
        refuse("accepted", "ReachParams-check_collision-str", lambda: P.ReachParams(check_collision="no"), TypeError,
               "check_collision"),
        refuse("accepted", "toolpath-float-patch_ids", lambda: _toolpath(patch_ids=[0.7, 1.2]), TypeError, "patch_ids"),
        refuse("accepted", "cover_from_patches-float", lambda: cover_from_patches([[0.7]], 3), TypeError, "patches"),
        refuse("accepted", "view_of_faces-float-faces", lambda: view_of_faces(_bowl().mesh, [0.5, 1.7]), TypeError,
               "faces"),
        refuse("accepted", "part-nan-vertex", lambda: part_from_mesh(_mesh(*NAN_VERTEX), [0], [1]), ValueError, "mesh"),
        refuse("accepted", "random_search-nan-result", lambda: _random_search(np.nan), ValueError, "experiment"),
        refuse("accepted", "gpr-str-result", lambda: _learn("0.5"), TypeError, "experiment"),
        refuse("accepted", "sample_surface-spacing-True", lambda: sample_surface(trimesh.creation.box(), True),
               TypeError, "spacing"),
        refuse("accepted", "se2_to_matrix-str", lambda: se2_to_matrix("1", 0, 0), TypeError, r"\bx\b"),
        refuse("accepted", "fov_masks-numeric-strings", lambda: camera.fov_masks(
            [["1", "0", "0"]], np.eye(4), P.CameraParams()), TypeError, "points_world"),
        refuse("accepted", "map_trials-n_jobs-str", lambda: map_trials(abs, [1, 2], n_jobs="2", progress=False),
               TypeError, "n_jobs"),
    ]


def _cases_stain_marking():
    """geometry.stain_marking (marking a stain on your own part), landed from the branch 'user'."""
    from mavac.geometry import stain_marking as SM

    box = trimesh.creation.box(extents=[0.2, 0.2, 0.1])
    return [
        refuse("unnamed", "mark_stain-nan-mesh", lambda: SM.mark_stain(_mesh(*NAN_VERTEX), faces=[0]), ValueError,
               r"mesh has 1 vertices with NaN"),
        refuse("unnamed", "mark_stain-intensity-ragged", lambda: SM.mark_stain(box, faces=[0, 1], intensity=RAGGED),
               ValueError, "intensity"),
        refuse("accepted", "mark_stain-passes-str", lambda: SM.mark_stain(box, faces=[0], passes="2"), TypeError,
               "passes"),
        refuse("accepted", "passes_from_intensity-float-range", lambda: SM.passes_from_intensity([0.5], (1.5, 3)),
               ValueError, "pass_range"),
        refuse("accepted", "mark_stain-max_patch_area-0", lambda: SM.mark_stain(box, faces=[0], max_patch_area=0),
               ValueError, "max_patch_area"),
        refuse("accepted", "subdivide_faces-nan-stained", lambda: SM.subdivide_faces(box, np.full(12, np.nan)),
               ValueError, "stained"),
        refuse("hang", "subdivide_faces-tiny-max_area", lambda: SM.subdivide_faces(
            box, np.arange(12) == 0, max_area=1e-30, max_rounds=11), ValueError, "max_area"),
    ]


def _cases_hang():
    from mavac.inspection.reachability import reachability_map
    from mavac.scrubbing import lissajous, toolpath
    from mavac.setups.sampling import uniform_setups
    from mavac.vision.stain import face_index_image

    return [
        answer("hang", "setcover-both-defaults-random-60x40", _default_both_on_random_60x40,
               lambda res: res.seconds < 120 and res.status in ("optimal", "node_limited", "timed_out")),
        refuse("hang", "toolpath-scaled-x1000-world_T_part", lambda: _toolpath(1000 * np.eye(4)), ValueError,
               "world_T_part"),
        refuse("hang", "toolpath-tiny-waypoint-spacing", lambda: _toolpath(waypoint_spacing_m=1e-7), ValueError,
               "waypoint_spacing_m"),
        refuse("hang", "toolpath-tiny-tool-width", lambda: _toolpath(tool_width_m=1e-7), ValueError, "tool_width_m"),
        refuse("hang", "face_index_image-huge", lambda: face_index_image(_bowl().mesh, (0, 0, -1), (4200, 4200)),
               ValueError, "image_size"),
        refuse("hang", "uniform_setups-tiny-resolution", lambda: uniform_setups(
            P.SetupSpaceParams(res_x=1e-5, res_y=1e-5)), ValueError, "resolution"),
        refuse("hang", "reachability_map-tiny-voxel", lambda: reachability_map(_ur10(), P.ReachabilityMapParams(
            voxel_size=1e-4, n_samples=100, n_rotations=1), cache=False), ValueError, "voxel_size"),
        refuse("hang", "resample_polyline-tiny-spacing",
               lambda: toolpath.resample_polyline(np.array([[0, 0, 0], [1.0, 0, 0]]), 1e-9), ValueError, "spacing"),
        refuse("hang", "slice_heights-tiny-spacing", lambda: toolpath.slice_heights(np.array([0, 1.0]), 1e-9),
               ValueError, "spacing"),
        refuse("hang", "overlay_path-tiny-dt", lambda: lissajous.overlay_path(
            [[0, 0, 0], [1.0, 0, 0]], [[0, 0, 1], [0, 0, 1]], dt=1e-9), ValueError, r"\bdt\b"),
        refuse("hang", "gpr-huge-n_candidates", lambda: P.GPRParams(n_candidates=10**8), ValueError, "n_candidates"),
    ]


def _cases_process():
    return [
        answer("process", "meshcat-sigterm-server-ended", _meshcat_server_left_after_sigterm, lambda left: not left),
        answer("process", "write_csv-sigkill-no-temporary-left", _files_after_killed_write,
               lambda files: files == ["t.csv"]),
    ]


def _cases_issue33():
    """The command line's input audit (issue 33), at the API the command line calls."""
    from mavac.inspection.inspection_plan import surface_elements

    big = trimesh.creation.box(extents=[1.2, 0.6, 0.9])
    return [
        refuse("accepted", "SetupPlanParams-seed-2**70", lambda: P.SetupPlanParams(seed=2**70), ValueError, "seed"),
        refuse("accepted", "InspectionParams-seed-2**70", lambda: P.InspectionParams(seed=2**70), ValueError, "seed"),
        refuse("wrong", "SetupPlannerParams-setup_time-1e308", lambda: P.SetupPlannerParams(setup_time=1e308),
               ValueError, "setup_time"),
        refuse("dependency", "Visibility-radius-1e308", lambda: P.Visibility(radius=1e308), ValueError, "radius"),
        refuse("hang", "surface_elements-spacing-3mm", lambda: surface_elements(big, 0.003, 0), ValueError,
               "surface elements"),
        *_cases_issue33_api(),
    ]


def _cases_issue33_api():
    """Type checks of the Python entry points the audit found missing."""
    from mavac.cleaning.trial import run_trial
    from mavac.experiments.mavac_online import run_trials
    from mavac.geometry.machines import load_machine
    from mavac.parallel import map_trials
    from mavac.scrubbing.gpr import random_search
    from mavac.experiments.kabir_bimanual import run_paper_part

    def trial(plan, **kw):
        return run_trial(load_machine("test_bench"), plan, **kw)

    return [
        refuse("unnamed", "run_trial-plan-None", lambda: trial(None), TypeError, "plan"),
        refuse("unnamed", "run_trial-plan-str", lambda: trial("plan"), TypeError, "plan"),
        refuse("unnamed", "run_trial-robot-str", lambda: trial(None, robot="x"), TypeError, "robot"),
        refuse("unnamed", "run_part-teapot", lambda: run_paper_part("teapot", fast=True), ValueError, "part"),
        refuse("unnamed", "run_part-42", lambda: run_paper_part(42, fast=True), TypeError, "part"),
        refuse("accepted", "run_part-fast-str", lambda: run_paper_part("bowl", fast="no"), TypeError, "fast"),
        refuse("accepted", "run_trials-trials-1.5", lambda: run_trials(trials=1.5), ValueError, "trials"),
        refuse("accepted", "run_trials-trials--3", lambda: run_trials(trials=-3), ValueError, "trials"),
        refuse("hang", "run_trials-trials-1e12", lambda: run_trials(trials=10**12), ValueError, "trials"),
        refuse("wrong", "run_trials-scenes-str", lambda: run_trials(scenes="test_bench"), TypeError, "scenes"),
        refuse("unnamed", "map_trials-fn-None", lambda: map_trials(None, [1], progress=False), TypeError, r"\bfn\b"),
        refuse("unnamed", "map_trials-items-5", lambda: map_trials(abs, 5, progress=False), TypeError, "items"),
        refuse("hang", "random_search-budget-1e12", lambda: random_search(
            _experiment_returning(0.5), _gpr_params(), budget=10**12), ValueError, "budget"),
    ]


def _cases_issue34():
    """The systematic baseline and notebook 12's online comparison and robustness sweeps."""
    from mavac.cleaning.systematic import run_systematic
    from mavac.experiments.beyond_online import comparison_items, visibility_items
    from mavac.experiments.beyond_improved import improved_items, improved_unit
    from mavac.experiments.beyond_robustness import robustness_items, sweep_unit
    from mavac.geometry.machines import load_machine

    def sweep(plan, **kw):
        return run_systematic(load_machine("test_bench"), plan, **kw)

    return [
        refuse("unnamed", "run_systematic-plan-None", lambda: sweep(None), TypeError, "plan"),
        refuse("unnamed", "run_systematic-systematic-str", lambda: sweep(None, systematic="raster"), TypeError,
               "systematic"),
        refuse("wrong", "comparison_items-density-2", lambda: comparison_items(densities=(2.0,)), ValueError,
               "densities"),
        refuse("wrong", "comparison_items-scenes-str", lambda: comparison_items(scenes="test_bench"), TypeError,
               "scenes"),
        refuse("wrong", "visibility_items-seeds-5", lambda: visibility_items(seeds=5), TypeError, "seeds"),
        refuse("wrong", "robustness_items-sweeps-unknown", lambda: robustness_items(sweeps=("wind",)), ValueError,
               "sweeps"),
        refuse("wrong", "sweep_unit-sweep-unknown", lambda: sweep_unit("test_bench", 1, "wind", 1.0), ValueError,
               "sweep"),
        refuse("wrong", "improved_unit-step-unknown", lambda: improved_unit("test_bench", 1, "teleport"), ValueError,
               "step"),
        refuse("wrong", "improved_items-scenes-str", lambda: improved_items(scenes="test_bench"), TypeError, "scenes"),
    ]


def hand_written_cases() -> list[Case]:
    return (_cases_wrong() + _cases_dependency() + _cases_unnamed() + _cases_accepted() + _cases_stain_marking()
            + _cases_hang() + _cases_process() + _cases_issue33() + _cases_issue34())


# ---- generated: every field of every parameter dataclass ----


def _parameter_classes() -> list[type]:
    return [c for c in vars(P).values()
            if isinstance(c, type) and dataclasses.is_dataclass(c) and c.__module__ == P.__name__]


def _bad_values(cls, name) -> list[tuple[str, object, type]]:
    """(label, value, expected exception) for a wrong type, NaN and infinity, from the field's
    annotation: NaN and infinity are refused as values (ValueError) where a float is meant and
    as the wrong type (TypeError) everywhere else."""
    kind = typing.get_type_hints(cls)[name]
    optional = isinstance(kind, types.UnionType)
    kind = next(k for k in typing.get_args(kind) if k is not type(None)) if optional else kind
    if kind is tuple:  # of numbers
        n = len(getattr(cls(), name))
        return [("wrong-type", "0.5", TypeError), ("nan", (math.nan,) * n, ValueError),
                ("inf", (math.inf,) * n, ValueError)]
    wrong = {float: "0.5", int: "3", bool: "yes", str: 3}.get(kind, {})  # {} for a nested dataclass
    bad_number = ValueError if kind is float else TypeError
    return [("wrong-type", wrong, TypeError), ("nan", math.nan, bad_number), ("inf", math.inf, bad_number)]


def field_cases() -> list[Case]:
    cases = []
    for cls in _parameter_classes():
        for f in dataclasses.fields(cls):
            for label, value, error in _bad_values(cls, f.name):
                call = functools.partial(cls, **{f.name: value})
                cases.append(refuse("accepted", f"{cls.__name__}.{f.name}:{label}", call, error,
                                    rf"\b{re.escape(f.name)}\b"))
    return cases


# ---- the tests ----

HAND_WRITTEN = hand_written_cases()
FIELDS = field_cases()


def _assert_case(case: Case):
    if case.error is None:
        assert case.check(case.call()), f"{case.id}: wrong answer"
        return
    with pytest.raises(case.error) as info:
        case.call()
    assert re.search(case.names, str(info.value)), f"{case.id}: message does not name {case.names!r}: {info.value}"


@pytest.mark.timeout(300)
@pytest.mark.parametrize("case", HAND_WRITTEN, ids=[c.id for c in HAND_WRITTEN])
def test_bad_input(case):
    _assert_case(case)


@pytest.mark.parametrize("case", FIELDS, ids=[c.id for c in FIELDS])
def test_every_parameter_field_refuses_wrong_type_nan_and_inf(case):
    _assert_case(case)


def test_every_class_has_a_case_and_every_field_is_tried():
    assert {c.klass for c in HAND_WRITTEN} == set(CLASSES)
    fields = {(cls.__name__, f.name) for cls in _parameter_classes() for f in dataclasses.fields(cls)}
    tried = {tuple(c.id.split(":")[0].split(".")) for c in FIELDS}
    assert tried == fields and len(FIELDS) == 3 * len(fields)


# ---- the audit (run as a script) ----

OUTCOMES = ("ok", "dependency", "unnamed", "accepted", "wrong", "hang")
MAVAC_DIR = Path(P.__file__).resolve().parent


def outcome(case: Case) -> str:
    """What the package on the import path does with ``case`` (see the module docstring):
    ``ok``, or the class of the failure."""
    try:
        result = case.call()
    except Exception as exc:  # noqa: BLE001 -- classifying every failure is the point
        if case.error is not None and isinstance(exc, case.error) and re.search(case.names, str(exc)):
            return "ok"
        frames = [f.filename for f in traceback.extract_tb(exc.__traceback__)]
        in_dependency = bool(frames) and not Path(frames[-1]).resolve().is_relative_to(MAVAC_DIR) \
            and Path(frames[-1]).resolve() != Path(__file__).resolve()
        foreign = type(exc).__module__ not in ("builtins",) and not type(exc).__module__.startswith("mavac")
        if in_dependency or foreign or isinstance(exc, (MemoryError, RecursionError)):
            return "dependency"
        return "unnamed"
    if case.error is not None:
        return "accepted"
    return "ok" if case.check(result) else "wrong"


def _audit_one_in_child(case_id: str, limit: float) -> str:
    try:
        out = subprocess.run([sys.executable, __file__, "--case", case_id], capture_output=True, text=True,
                             timeout=limit)
    except subprocess.TimeoutExpired:
        return "hang"
    lines = out.stdout.strip().splitlines()
    return lines[-1] if lines and lines[-1] in OUTCOMES else "dependency"  # died (e.g. killed by a signal)


def audit(limit: float = 60.0) -> dict:
    """Outcome counts by class: hand-written cases in child processes, then the field cases."""
    counts = {k: dict.fromkeys(OUTCOMES, 0) for k in CLASSES + ("fields",)}
    for case in HAND_WRITTEN:
        result = _audit_one_in_child(case.id, limit)
        counts[case.klass][result] += 1
        print(f"{case.klass:10s} {case.id:45s} {result}", flush=True)
    for case in FIELDS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            counts["fields"][outcome(case)] += 1
    return counts


def _main(argv):
    if len(argv) == 2 and argv[0] == "--case":
        warnings.simplefilter("ignore")
        print(outcome(next(c for c in HAND_WRITTEN if c.id == argv[1])), flush=True)
        return
    print_counts(audit(), OUTCOMES)


if __name__ == "__main__":
    _main(sys.argv[1:])
