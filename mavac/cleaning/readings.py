"""Two readings of MAVAC: the paper's text, and the authors' own implementation.

The MAVAC authors published their ROS code (GitHub ``will-44/cleaning``, under
``rubyrhod_ws/src/cleaning/``, no licence: we take facts and parameters from it, with a
citation beside each, and copy no code). The "authors" reading is one commit of it, 4a4038c
("End of test", 2023-11-30, the last commit before the article-video one); the "paper" reading
is the paper's text, with the authors' values where the text gives none (alpha, delta) and ours
where neither does. Package defaults (:mod:`mavac.params`) stay ours for users: ray casting
offline, alpha 15 deg and delta 0.10 m.

Citations are ``file:line`` at 4a4038c (``script/`` = ``rubyrhod_ws/src/cleaning/script/``,
``doosan.py`` = ``rubyrhod_ws/src/utility/script/utility/doosan.py``).

=========================== =============================== ===================================
parameter                   "paper"                         "authors" (4a4038c)
=========================== =============================== ===================================
offline visibility          HPR (the text, "Camera FOV"),   HPR, absolute radius 10
                            radius factor 10 (ours);        (class_fov_emulator.py:105-106)
                            Table 2 also with ray casting
FOV half-angles, depth      package default (text: L_d)     45 deg, 35 deg, 0.7 m "A definir"
                                                            (class_fov_emulator.py:81-83)
guard stand-off             L_d along the normal (text)     0.4 m (offline.py:426,
                                                            generate_pcd_guard dist=0.4)
online depth validity       sensor range 0.25-2.88 m        same (the code has no depth cut)
tip-distance filter         none (the text has none)        < 0.7 m from the vacuum tip
                                                            (online.py:191, filter_dust
                                                            dist=0.7; dust.py:108)
DBSCAN eps, min_samples     0.15 m, 1 (ours: no value)      0.13 m, noise kept as one-node
                                                            areas (dust.py:138-141: pyclustering
                                                            neighbours=1, noise appended as
                                                            clusters = scikit-learn
                                                            min_samples 1)
area order                  detection (text silent)         TSP (dust.py:130-160, dust_path)
approach delta              0.05 m (authors' code)          0.05 m (online.py:182-184,
                                                            vacuum_safe_tcp "add 5cm")
approach alpha (eq. 5)      20 deg (authors' code)          20 deg (doosan.py:399 go_to_l,
                                                            :417 set_goal_orientation_tolerance
                                                            (np.deg2rad(20)); RRTConnect at
                                                            doosan.py:58-59)
vacuum motion               linear moves (text)             linear + spiral, 2 turns, 10 mm,
                                                            5 s at the last node (online.py:273)
impedance stiffness         1000 N/m, 30 N m/rad (ours)     100 N/m, 20 N m/rad (online.py:255)
vacuum speed                0.10 m/s (ours)                 0.02 m/s (doosan.py:522, move_line
                                                            velocity [20, 0] mm/s)
=========================== =============================== ===================================

The article-video commit bc1a1a1 ("Modif for creation of article video") differs: tip filter
0.5 m (``script/online.py:198``) and DBSCAN eps 0.05 m, noise kept (``script/dust.py:143-145``).
An earlier reading of ours mixed bc1a1a1's tip filter with 1d03546's DBSCAN (eps 0.1 m, noise
dropped). Not modelled: ``filter_dust`` also drops nodes within 5 cm of the tool along its axis
(``dust.py:113``); the authors solve the TSP with ``fast_tsp`` under a 2 s wall-clock budget
(``script/robot.py``; we solve deterministically, :func:`mavac.cleaning.clustering.tsp_order`);
after an area the tool goes back to its first node then 75 mm back along the tool axis
(``online.py:289-297``), where we return to the approach point as the text says.
"""

from __future__ import annotations

import math
from dataclasses import fields, is_dataclass, replace

from ..params import ApproachParams, CameraParams, DetectionParams, DustParams, OnlineParams, VacuumParams

#: the two readings, paper's text first
READINGS = ("paper", "authors")
#: offline visibility methods (:data:`mavac.params.VISIBILITY_METHODS`)
OFFLINE_METHODS = ("hpr", "raycast")
#: Table 2's variants, (reading, offline method): each reading with the paper's HPR, and the
#: paper reading again with ray casting (the package default for users)
VARIANTS = (("paper", "hpr"), ("paper", "raycast"), ("authors", "hpr"))
#: fast mode's heap spacing, m (as :func:`mavac.experiments.mavac_online.online_params`)
FAST_SPACING = 0.2
#: eq. 5's alpha and delta of the authors' code (doosan.py:417; online.py:182-184 at 4a4038c),
#: taken by both readings since the paper gives no value
AUTHORS_ALPHA, AUTHORS_DELTA = math.radians(20.0), 0.05


def check_reading(reading) -> str:
    """``reading`` if it is one of :data:`READINGS`; ``ValueError`` (``TypeError`` for a
    non-string) naming the legal values otherwise."""
    if not isinstance(reading, str):
        raise TypeError(f"reading must be a string, one of {READINGS}, got {reading!r}")
    if reading not in READINGS:
        raise ValueError(f"reading must be one of {READINGS}, got {reading!r}")
    return reading


def check_offline(offline) -> str:
    """``offline`` if it is one of :data:`OFFLINE_METHODS`; ``ValueError`` otherwise."""
    if offline not in OFFLINE_METHODS:
        raise ValueError(f"offline must be one of {OFFLINE_METHODS}, got {offline!r}")
    return offline


def _paper_online() -> OnlineParams:
    """The package defaults with eq. 5's alpha and delta of the authors' code."""
    params = OnlineParams()
    return replace(params, approach=replace(params.approach, alpha=AUTHORS_ALPHA, delta=AUTHORS_DELTA))


def _authors_online() -> OnlineParams:
    """The online parameters of will-44/cleaning at 4a4038c (sources in the module docstring)."""
    return OnlineParams(
        detection=DetectionParams(max_tip_distance=0.7),
        approach=ApproachParams(cluster_eps=0.13, cluster_min_samples=1, node_order="tsp", area_order="tsp",
                                delta=AUTHORS_DELTA, alpha=AUTHORS_ALPHA),
        vacuum=VacuumParams(stiffness=100.0, rotational_stiffness=20.0, speed=0.02, pattern="spiral",
                            spiral_radius=0.010, spiral_turns=2.0, spiral_time=5.0, spiral_nodes="last"),
    )


def online_params(reading: str = "paper", *, fast: bool = False) -> OnlineParams:
    """Online (Algorithm 1) parameters of one reading.

    Parameters
    ----------
    reading : {"paper", "authors"}
        ``"paper"``: the package defaults with the authors' alpha and delta (the paper gives
        none); ``"authors"``: the authors' code at 4a4038c.
    fast : bool
        Fast mode (CI): heaps :data:`FAST_SPACING` apart instead of 0.1 m, as
        :func:`mavac.experiments.mavac_online.online_params`; same code paths. The authors'
        DBSCAN radius (0.13 m, 1.3 heap spacings at paper scale) is scaled with the spacing so
        that neighbouring heaps still share an area.

    Returns
    -------
    OnlineParams
    """
    params = _authors_online() if check_reading(reading) == "authors" else _paper_online()
    if not fast:
        return params
    if reading == "authors":
        scale = FAST_SPACING / params.dust.spacing
        params = replace(params, approach=replace(params.approach, cluster_eps=params.approach.cluster_eps * scale))
    return replace(params, dust=DustParams(spacing=FAST_SPACING))


def inspection_params(reading: str = "paper", *, offline: str = "hpr"):
    """Offline (inspection) parameters of one reading.

    ``"paper"`` is :class:`mavac.params.InspectionParams` with the visibility ``offline``
    (the paper's HPR by default, "Camera FOV"; its radius factor is ours). ``"authors"``
    changes the camera pyramid to half-angles 45 deg (camera XY plane) and 35 deg (XZ plane)
    cut at 0.7 m (``class_fov_emulator.py:81-83``), HPR at an absolute radius of 10
    (``class_fov_emulator.py:105-106``, ``get_visible_point_pyramid``), and guard candidates
    0.4 m along the surface normal (``offline.py:426``, ``generate_pcd_guard``, ``dist=0.4``),
    all at 4a4038c; with ``offline="raycast"`` ray casting replaces its HPR.

    Returns
    -------
    InspectionParams
    """
    from ..params import InspectionParams

    check_offline(offline)
    if check_reading(reading) == "paper":
        return InspectionParams().with_visibility(offline)
    from ..params import GuardParams, Visibility  # standoff, Visibility: the offline work of issue 20

    camera = replace(CameraParams(), theta_a=math.radians(45.0), theta_b=math.radians(35.0), L_d=0.7)
    visibility = Visibility("hpr", radius=10.0) if offline == "hpr" else Visibility("raycast")
    return replace(InspectionParams(), camera=camera, guard=replace(GuardParams(), standoff=0.4),
                   visibility=visibility)


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
