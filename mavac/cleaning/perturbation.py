"""The world departing from the offline plan's and the robot's assumptions
(:class:`mavac.params.PerturbationParams`): where the plan breaks.

Two frames. The *plan's* frame is the world the robot believes in: the machine where it was
scanned and planned, the base at the spot it drove to. The *true* frame is the simulator's: the
machine mesh and its heaps never move there. A machine moved by ``plan_T_moved`` after planning is
the same, for the robot, as every base pose landing at ``inv(plan_T_moved)`` of where it
believes (the floor is a plane, so nothing else changes); a localisation error ``E`` at a spot
``B`` puts the base at ``B @ E``. :func:`true_base_pose` composes both.

Perception noise is added to the rendered images (:func:`noisy_images`); decoys (green-ish
machine parts) are static spheres of the dust's look placed with :func:`decoy_positions`.

Every draw takes its own stream from :mod:`mavac.seeding` (stages ``"machine moved"``,
``"localisation"``, ``"image noise"``, ``"decoys"``), so an unperturbed trial draws nothing and
equals the paper's trial of the same seed.
"""

from __future__ import annotations

import numpy as np
import trimesh

from ..geometry.transforms import rz, se2_to_matrix
from ..params import PerturbationParams
from ..seeding import rng_for


def machine_motion(mesh: trimesh.Trimesh, perturbation: PerturbationParams, seed: int) -> np.ndarray:
    """(4, 4) ``plan_T_moved``: the rigid motion of the machine after planning, in the plan's frame.

    A shift of ``machine_shift`` (m) in a horizontal direction drawn uniformly, after a turn of
    ``machine_rotation`` (deg, sign drawn) about the vertical through the centre of the mesh's
    axis-aligned bounds. Both draws are made whatever the sizes, so the direction and sign of a
    trial do not depend on the sweep point.
    """
    p = perturbation
    rng = rng_for(seed, "machine moved")
    heading, sign = rng.uniform(0.0, 2.0 * np.pi), rng.choice((-1.0, 1.0))
    if p.machine_shift == 0.0 and p.machine_rotation == 0.0:
        return np.eye(4)
    centre = np.r_[mesh.bounds.mean(axis=0)[:2], 0.0]
    turn = np.eye(4)
    turn[:3, :3] = rz(sign * np.radians(p.machine_rotation))
    turn[:3, 3] = centre - turn[:3, :3] @ centre
    shift = np.eye(4)
    shift[:2, 3] = p.machine_shift * np.array([np.cos(heading), np.sin(heading)])
    return shift @ turn


def localisation_error(perturbation: PerturbationParams, seed: int, drive: int) -> np.ndarray:
    """(4, 4) ``believed_T_true``: where the base really stops, in the frame of the spot it
    believes it reached, at the ``drive``-th drive of a trial (Gaussian, per axis and heading)."""
    p = perturbation
    if p.base_position_sigma == 0.0 and p.base_heading_sigma == 0.0:
        return np.eye(4)
    rng = rng_for(seed, "localisation", drive)
    dx, dy = rng.normal(0.0, p.base_position_sigma, 2)
    return se2_to_matrix(dx, dy, np.radians(rng.normal(0.0, p.base_heading_sigma)))


def true_base_pose(plan_T_base, plan_T_moved, believed_T_true) -> np.ndarray:
    """(4, 4) the base's pose in the true (simulator) frame, from the pose it believes
    ``plan_T_base``, the machine's motion and the localisation error (see the module)."""
    return np.linalg.inv(plan_T_moved) @ np.asarray(plan_T_base, dtype=float) @ believed_T_true


def noisy_images(rgb, depth, perturbation: PerturbationParams, seed: int, image: int):
    """``(rgb, depth)`` with the perturbation's per-pixel Gaussian noise (the inputs unchanged
    when there is none).

    Parameters
    ----------
    rgb : (h, w, 3) uint8
    depth : (h, w) float, metres (``inf``: nothing hit; stays ``inf``)
    perturbation : PerturbationParams
    seed, image : int
        The trial's seed and the image's index in it (its own noise stream).
    """
    p = perturbation
    if p.colour_noise == 0.0 and p.depth_noise == 0.0:
        return rgb, depth
    rng = rng_for(seed, "image noise", image)
    colour = rng.normal(0.0, p.colour_noise, np.shape(rgb)) if p.colour_noise else 0.0
    rgb = np.clip(np.rint(np.asarray(rgb, dtype=float) + colour), 0, 255).astype(np.uint8)
    depth = np.asarray(depth, dtype=float) + (rng.normal(0.0, p.depth_noise, np.shape(depth)) if p.depth_noise else 0.0)
    return rgb, depth


def decoy_positions(mesh: trimesh.Trimesh, n: int, seed: int) -> np.ndarray:
    """(n, 3) points (m) drawn uniformly by area on the whole machine surface: the centres of
    the green-ish machine parts (:attr:`PerturbationParams.decoys`)."""
    if n == 0:
        return np.zeros((0, 3))
    points, _ = trimesh.sample.sample_surface(mesh, int(n), seed=rng_for(seed, "decoys"))
    return np.asarray(points, dtype=float)
