"""Registration of the part's CAD mesh to an RGB-D point cloud with ICP (Kabir, Sec. VII).

Kabir et al. locate the part by matching its CAD model to the camera's point cloud with the
iterative closest point algorithm. We use Open3D's point-to-plane ICP with the **cloud as
source** and a dense sample of the CAD surface (with its exact face normals) as target: the
partial cloud then has a correspondence for every point at the right pose (fitness ~ 1), and
no normals need to be estimated from the noisy cloud.

:func:`partial_noisy_cloud` simulates the sensor (a viewpoint on one side of the part, only
surface points facing it and unoccluded, depth noise along the viewing rays) and
:func:`icp_error_study` measures the pose error over random setups of the part on the table
(Kabir's (x, y, alpha) setup space), noise levels and initial errors (basin of convergence).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import trimesh
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ..geometry.mesh import check_mesh
from ..geometry.transforms import check_rotation, check_transform
from ..parallel import map_trials
from ..params import ICPParams
from ..validate import check_instance, check_int, check_nonnegative, check_points, check_positive
from .visibility import raycast_visible


# Model points over which the symmetry-aware error (ADD-S) is averaged.
_ADDS_POINTS = 2000


def rotation_error(R_a, R_b) -> float:
    """Angle of the rotation ``R_a^T R_b``, rad in [0, pi] (via the quaternion: accurate near 0)."""
    R_a, R_b = check_rotation("R_a", R_a), check_rotation("R_b", R_b)
    return float(Rotation.from_matrix(R_a.T @ R_b).magnitude())


def model_samples(mesh: trimesh.Trimesh, n_points: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Area-uniform samples of the CAD surface with their face normals (part frame).

    Returns
    -------
    points : (n, 3) float, metres
    normals : (n, 3) float, unit
    """
    check_mesh("mesh", mesh)
    points, faces = trimesh.sample.sample_surface(mesh, check_int("n_points", n_points, lo=1), seed=seed)
    return np.asarray(points), np.asarray(mesh.face_normals[faces])


def register_part(cad_mesh: trimesh.Trimesh, cloud_points, init_T, params: ICPParams = ICPParams(),
                  *, seed: int = 0) -> tuple[np.ndarray, float, float]:
    """Pose of the part from a point cloud: Open3D point-to-plane ICP (Kabir, Sec. VII).

    Parameters
    ----------
    cad_mesh : trimesh.Trimesh
        Part model in the part frame, metres.
    cloud_points : (n, 3) float, metres
        Measured points in the world (camera) frame, n >= 3.
    init_T : (4, 4) float
        Initial guess of ``world_T_part``.
    params : ICPParams
        Correspondence distance, convergence criteria, model sample size.
    seed : int
        Seed of the CAD surface sample.

    Returns
    -------
    world_T_part : (4, 4) float
        Registered pose.
    fitness : float
        Fraction of cloud points with a model point within ``max_correspondence_m``.
    rmse : float
        RMS point-to-point distance of those correspondences, metres.
    """
    import open3d as o3d

    cloud = check_points("cloud_points", cloud_points)
    if len(cloud) < 3:
        raise ValueError(f"cloud_points needs at least 3 points, got {len(cloud)}")
    T0 = check_transform("init_T", init_T)
    check_instance("params", params, ICPParams)
    model, normals = model_samples(cad_mesh, params.model_points, seed)
    source = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(cloud))
    target = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(model))
    target.normals = o3d.utility.Vector3dVector(normals)
    criteria = o3d.pipelines.registration.ICPConvergenceCriteria(
        relative_fitness=params.relative_fitness, relative_rmse=params.relative_rmse,
        max_iteration=params.max_iterations)
    # The cloud moves onto the model: the result is part_T_world.
    result = o3d.pipelines.registration.registration_icp(
        source, target, params.max_correspondence_m, np.linalg.inv(T0),
        o3d.pipelines.registration.TransformationEstimationPointToPlane(), criteria)
    return np.linalg.inv(np.asarray(result.transformation)), float(result.fitness), float(result.inlier_rmse)


def partial_noisy_cloud(mesh: trimesh.Trimesh, world_T_part, view_dir, noise_std: float, n_points: int,
                        rng: np.random.Generator, distance: float | None = None) -> np.ndarray:
    """Simulated single-view RGB-D cloud of the part: partial (visible side only) and noisy.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Part mesh in the part frame, metres; normals on the visible (outer) side.
    world_T_part : (4, 4) float
        True pose of the part.
    view_dir : (3,) float
        Direction the sensor looks along (sensor -> part), world frame.
    noise_std : float
        Standard deviation of the depth noise along each viewing ray, metres (>= 0).
    n_points : int
        Points returned (fewer if less of the surface is visible).
    rng : numpy.random.Generator
    distance : float, optional
        Sensor distance from the part centre, metres (default 3 x the bounding-box diagonal).

    Returns
    -------
    (k, 3) float, metres, world frame, k <= n_points
        Samples of the surface facing the sensor and not occluded (exact ray casting,
        :func:`mavac.vision.visibility.raycast_visible`), moved along their ray by the noise.
    """
    T = check_transform("world_T_part", world_T_part)
    d = check_points("view_dir", view_dir)[0]
    if np.linalg.norm(d) == 0:
        raise ValueError("view_dir must be non-zero")
    d = d / np.linalg.norm(d)
    check_nonnegative("noise_std", noise_std)
    n_points = check_int("n_points", n_points, lo=1)
    check_instance("rng", rng, np.random.Generator)
    world = check_mesh("mesh", mesh).copy()
    world.apply_transform(T)
    dist = 3.0 * float(np.linalg.norm(world.extents)) if distance is None else check_positive("distance", distance)
    sensor = world.bounds.mean(axis=0) - dist * d
    # Oversample: at most about half of a single-sided part faces one viewpoint.
    points, faces = trimesh.sample.sample_surface(world, 4 * n_points, seed=int(rng.integers(2**31)))
    visible = raycast_visible(world, points, world.face_normals[faces], sensor)[0]
    points = points[visible]
    if len(points) > n_points:
        points = points[np.sort(rng.choice(len(points), n_points, replace=False))]
    rays = points - sensor
    rays /= np.linalg.norm(rays, axis=1, keepdims=True)
    return points + rays * rng.normal(0.0, noise_std, size=(len(points), 1))


def _random_setup_pose(rng: np.random.Generator, xy_range: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("z", rng.uniform(0.0, 2.0 * np.pi)).as_matrix()
    T[:2, 3] = rng.uniform(-xy_range, xy_range, size=2)
    return T


def _random_view_dir(rng: np.random.Generator, max_tilt: float) -> np.ndarray:
    tilt = np.arccos(rng.uniform(np.cos(max_tilt), 1.0))  # uniform on the spherical cap
    az = rng.uniform(0.0, 2.0 * np.pi)
    return np.array([np.sin(tilt) * np.cos(az), np.sin(tilt) * np.sin(az), -np.cos(tilt)])


def _perturbed(T: np.ndarray, angle: float, offset: float, rng: np.random.Generator) -> np.ndarray:
    axis = rng.normal(size=3)
    direction = rng.normal(size=3)
    P = T.copy()
    P[:3, :3] = T[:3, :3] @ Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix()
    P[:3, 3] += offset * direction / np.linalg.norm(direction)
    return P


def _pose_trial(args) -> list[dict]:
    """All noise levels x perturbations for one random pose (picklable for map_trials)."""
    mesh, pose_index, seed, noise_levels, perturbations, params, n_points, xy_range, max_tilt = args
    rng = np.random.default_rng(seed)
    T_true = _random_setup_pose(rng, xy_range)
    view = _random_view_dir(rng, max_tilt)
    model, _ = model_samples(mesh, _ADDS_POINTS, seed=0)
    true_pts = model @ T_true[:3, :3].T + T_true[:3, 3]
    tree = cKDTree(true_pts)
    rows = []
    for noise in noise_levels:
        cloud = partial_noisy_cloud(mesh, T_true, view, noise, n_points, rng)
        for angle, offset in perturbations:
            T0 = _perturbed(T_true, angle, offset, rng)
            T, fitness, rmse = register_part(mesh, cloud, T0, params)
            # Open3D's parallel reductions differ run to run at ~1e-17: round them away so the
            # same seed gives the same table.
            T, rmse = np.round(T, 12), round(rmse, 15)
            t_err = float(np.linalg.norm(T[:3, 3] - T_true[:3, 3]))
            r_err = rotation_error(T[:3, :3], T_true[:3, :3])
            # Symmetry-aware error (ADD-S): mean distance from the estimated model to the true one.
            adds = float(tree.query(model @ T[:3, :3].T + T[:3, 3])[0].mean())
            rows.append(dict(pose=pose_index, noise_std_m=float(noise), init_angle_rad=float(angle),
                             init_offset_m=float(offset), cloud_points=len(cloud),
                             translation_error_m=t_err, rotation_error_rad=r_err, adds_m=adds,
                             fitness=fitness, rmse_m=rmse,
                             success=bool(t_err <= params.success_translation_m
                                          and r_err <= params.success_rotation_rad)))
    return rows


def icp_error_study(mesh: trimesh.Trimesh, n_poses: int, noise_levels, init_perturbations,
                    rng: np.random.Generator, *, params: ICPParams = ICPParams(), n_points: int = 2000,
                    xy_range: float = 0.2, max_tilt: float = np.radians(45.0),
                    n_jobs: int | None = None) -> pd.DataFrame:
    """ICP pose error against the true pose over random poses, noise levels and initial errors.

    Each pose places the part on the table at a random (x, y) in ``[-xy_range, xy_range]^2``
    and a random yaw (Kabir's setup space), seen from a random direction within ``max_tilt``
    of straight down. For every noise level a partial cloud is simulated; for every initial
    perturbation ``(angle, offset)`` the initial guess is the true pose rotated by ``angle``
    about a random axis through the part origin and shifted by ``offset`` in a random
    direction.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Part model, part frame, metres.
    n_poses : int
    noise_levels : sequence of float
        Depth-noise standard deviations, metres.
    init_perturbations : sequence of (float, float)
        ``(angle_rad, offset_m)`` pairs.
    rng : numpy.random.Generator
        Draws one seed per pose (results do not depend on ``n_jobs``).
    params : ICPParams
    n_points : int
        Cloud size.
    xy_range, max_tilt : float
        Pose box half-width (m) and view-cone half-angle (rad).
    n_jobs : int, optional
        Workers for :func:`mavac.parallel.map_trials`.

    Notes
    -----
    Rows whose ICP converges are identical for the same ``rng`` seed (poses are rounded to
    1e-12). From far-off initial guesses ICP is chaotic: a last-bit difference in Open3D's
    parallel reductions can change a nearest-neighbour correspondence and so the (failed)
    answer's digits; the ``success`` flags and the summary statistics are unaffected.

    Returns
    -------
    pandas.DataFrame
        One row per (pose, noise, perturbation): ``pose, noise_std_m, init_angle_rad,
        init_offset_m, cloud_points, translation_error_m, rotation_error_rad, adds_m, fitness,
        rmse_m, success`` (both errors within ``params.success_*``).
    """
    n_poses = check_int("n_poses", n_poses, lo=1)
    noise = [float(check_nonnegative("noise_levels", s)) for s in np.atleast_1d(noise_levels)]
    perturb = np.asarray(init_perturbations, dtype=float)
    if perturb.ndim != 2 or perturb.shape[1] != 2 or len(perturb) == 0:
        raise ValueError(f"init_perturbations must be (k, 2) pairs (angle_rad, offset_m), got shape {perturb.shape}")
    if np.any(perturb < 0) or not np.all(np.isfinite(perturb)):
        raise ValueError("init_perturbations must be finite and >= 0")
    check_positive("xy_range", xy_range)
    check_positive("max_tilt", max_tilt)
    seeds = rng.integers(2**31, size=n_poses)
    items = [(mesh, i, int(s), noise, [tuple(p) for p in perturb], params, n_points, xy_range, max_tilt)
             for i, s in enumerate(seeds)]
    rows = map_trials(_pose_trial, items, n_jobs=n_jobs, desc="ICP poses")
    return pd.DataFrame([r for trial in rows for r in trial])


def icp_summary(study: pd.DataFrame) -> pd.DataFrame:
    """Per (noise, perturbation): success rate (basin of convergence) and error statistics.

    Parameters
    ----------
    study : DataFrame from :func:`icp_error_study`.

    Returns
    -------
    pandas.DataFrame
        ``noise_std_m, init_angle_rad, init_offset_m, trials, success_rate,
        median_translation_error_m, median_rotation_error_rad, median_adds_m, mean_fitness``.
    """
    keys = ["noise_std_m", "init_angle_rad", "init_offset_m"]
    g = study.groupby(keys, sort=True)
    return g.agg(trials=("success", "size"), success_rate=("success", "mean"),
                 median_translation_error_m=("translation_error_m", "median"),
                 median_rotation_error_rad=("rotation_error_rad", "median"),
                 median_adds_m=("adds_m", "median"),
                 mean_fitness=("fitness", "mean")).reset_index()
