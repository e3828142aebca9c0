"""Two readings of MAVAC: the paper's text, and the authors' own implementation.

The MAVAC authors published their ROS code (GitHub ``will-44/cleaning``, under
``rubyrhod_ws/src/cleaning/``, no licence: we take facts and parameters from it, with a
citation beside each in :mod:`mavac.params`, and copy no code). Where the text is silent or
differs, :func:`online_params` and :func:`inspection_params` give either reading; the package
defaults are the paper's text (or ours where the text gives no value).

=========================== =============================== ===================================
parameter                   "paper" (package default)       "authors" (will-44/cleaning)
=========================== =============================== ===================================
online depth validity       sensor range 0.25-2.88 m; the   same (the code has no depth cut)
                            text has no online cut at L_d
reach filter                shoulder reach + tool, 1.7 m    same (ours; the tip filter is
                                                            stricter)
tip-distance filter         none (the text has none)        < 0.5 m from the vacuum tip
                                                            (online.py; dust.py, filter_dust)
duplicate filter            off (in neither)                off
DBSCAN eps, min_samples     0.15 m, 1 (ours: no value)      0.1 m, 2 (dust.py, dust_path;
                                                            pyclustering neighbours=1)
node order in an area       TSP (Algorithm 1, line 4)       TSP (older online.py TSPs all
                                                            nodes; the last keeps DBSCAN's
                                                            expansion order)
area order                  detection (text silent)         TSP (dust.py, dust_path)
approach delta, alpha       0.10 m, 15 deg (ours)           0.05 m, 0 (online.py:
                                                            vacuum_safe_tcp, exact guard pose)
vacuum motion               linear moves (text)             linear + spiral, 2 turns, 10 mm,
                                                            5 s at the last node (online.py)
impedance stiffness         1000 N/m, 30 N m/rad (ours)     100 N/m, 20 N m/rad (online.py,
                                                            set_compliance)
vacuum speed                0.10 m/s (ours)                 0.02 m/s (doosan.py, dsr_go_to_l)
FOV half-angles, depth      package default (text: L_d)     45 deg, 35 deg, 0.7 m "A definir"
                                                            (class_fov_emulator.py)
guard stand-off             L_d along the normal (text)     0.4 m (offline.py,
                                                            generate_pcd_guard)
HPR radius                  package default                 absolute 10
                                                            (get_visible_point_pyramid)
=========================== =============================== ===================================

Files read (will-44/cleaning, stored versions): ``script/online.py`` at bc1a1a1 (the last
version, JSON offline trajectory; d604abf is the older one that TSPs every node and pushes
30 mm along the tool axis without compliance), ``script/dust.py``, ``script/offline.py`` and
``script/class_fov_emulator.py`` at 1d03546, ``script/open3d_tools.py`` at 1439c0c,
``script/robot.py`` and ``rubyrhod_ws/src/utility/script/utility/doosan.py`` at 4a4038c.

Facts of the authors' code not made options: they solve the TSP with ``fast_tsp.find_tour``
under a 2 s wall-clock budget (``script/robot.py``, ``Robot.generate_trajectory``; we solve
deterministically, :func:`mavac.cleaning.clustering.tsp_order`); after an area the tool goes
back to its first node then 75 mm back along the tool axis (``online.py``,
``dsr_go_relatif([0, 0, -75, 0, 0, 0])``), where we return to the approach point as the text
says.
"""

from __future__ import annotations

import math
from dataclasses import fields, is_dataclass, replace

from ..params import ApproachParams, CameraParams, DetectionParams, DustParams, OnlineParams, VacuumParams

#: the two readings, paper's text first
READINGS = ("paper", "authors")
#: fast mode's heap spacing, m (as :func:`mavac.experiments.mavac_online.online_params`)
FAST_SPACING = 0.2


def check_reading(reading) -> str:
    """``reading`` if it is one of :data:`READINGS`; ``ValueError`` (``TypeError`` for a
    non-string) naming the legal values otherwise."""
    if not isinstance(reading, str):
        raise TypeError(f"reading must be a string, one of {READINGS}, got {reading!r}")
    if reading not in READINGS:
        raise ValueError(f"reading must be one of {READINGS}, got {reading!r}")
    return reading


def _authors_online() -> OnlineParams:
    """The online parameters of will-44/cleaning (sources in :mod:`mavac.params`)."""
    return OnlineParams(
        detection=DetectionParams(max_tip_distance=0.5),
        approach=ApproachParams(cluster_eps=0.1, cluster_min_samples=2, node_order="tsp", area_order="tsp",
                                delta=0.05, alpha=0.0, n_orientations=1),
        vacuum=VacuumParams(stiffness=100.0, rotational_stiffness=20.0, speed=0.02, pattern="spiral",
                            spiral_radius=0.010, spiral_turns=2.0, spiral_time=5.0, spiral_nodes="last"),
    )


def online_params(reading: str = "paper", *, fast: bool = False) -> OnlineParams:
    """Online (Algorithm 1) parameters of one reading.

    Parameters
    ----------
    reading : {"paper", "authors"}
        ``"paper"``: the package defaults (the paper's text); ``"authors"``: the authors' code.
    fast : bool
        Fast mode (CI): heaps :data:`FAST_SPACING` apart instead of 0.1 m, as
        :func:`mavac.experiments.mavac_online.online_params`; same code paths. The authors'
        DBSCAN radius (0.1 m, the heap spacing at paper scale) is scaled with the spacing:
        with ``min_samples`` 2 a radius below the spacing would make every node noise.

    Returns
    -------
    OnlineParams
    """
    params = _authors_online() if check_reading(reading) == "authors" else OnlineParams()
    if not fast:
        return params
    if reading == "authors":
        scale = FAST_SPACING / params.dust.spacing
        params = replace(params, approach=replace(params.approach, cluster_eps=params.approach.cluster_eps * scale))
    return replace(params, dust=DustParams(spacing=FAST_SPACING))


def inspection_params(reading: str = "paper"):
    """Offline (inspection) parameters of one reading.

    ``"paper"`` is :class:`mavac.params.InspectionParams` as it stands. ``"authors"`` changes
    the camera pyramid to half-angles 45 deg (camera XY plane) and 35 deg (XZ plane) cut at
    0.7 m, HPR at an absolute radius of 10 (``script/class_fov_emulator.py``,
    ``FovEmulator.__init__`` and ``get_visible_point_pyramid``, the one ``script/offline.py``,
    ``Offline.send_next_valid_config`` calls), and guard candidates 0.4 m along the surface
    normal (``script/offline.py``, ``Offline.generate_pcd_guard``, default ``dist=0.4``).

    Returns
    -------
    InspectionParams
    """
    from ..params import InspectionParams

    if check_reading(reading) == "paper":
        return InspectionParams()
    from ..params import GuardParams, Visibility  # standoff, Visibility: the offline work of issue 20

    camera = replace(CameraParams(), theta_a=math.radians(45.0), theta_b=math.radians(35.0), L_d=0.7)
    return replace(InspectionParams(), camera=camera, guard=replace(GuardParams(), standoff=0.4),
                   visibility=Visibility("hpr", radius=10.0))


def _flat_fields(params, prefix: str = "") -> dict:
    """``{"approach.delta": 0.1, ...}``: every leaf field of a nested parameter dataclass."""
    out = {}
    for f in fields(params):
        value = getattr(params, f.name)
        if is_dataclass(value):
            out |= _flat_fields(value, f"{prefix}{f.name}.")
        else:
            out[f"{prefix}{f.name}"] = value
    return out


def differences(*, fast: bool = False):
    """Every parameter where the two readings differ, read from the parameter objects.

    Returns
    -------
    pandas.DataFrame
        Columns ``stage`` ("offline" or "online"), ``parameter`` (dotted field path) and one
        column per reading.
    """
    import pandas as pd

    rows = []
    for stage, make in (("offline", lambda r: inspection_params(r)), ("online", lambda r: online_params(r, fast=fast))):
        values = {r: _flat_fields(make(r)) for r in READINGS}
        for name, value in values[READINGS[0]].items():
            if any(values[r][name] != value for r in READINGS[1:]):
                rows.append(dict(stage=stage, parameter=name) | {r: values[r][name] for r in READINGS})
    return pd.DataFrame(rows, columns=["stage", "parameter", *READINGS])
