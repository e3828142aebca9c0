"""Dust heaps of one trial: where they lie, their bodies in the simulation, which are left.

MAVAC ("Experimental setup"): "green dust heaps are evenly distributed at intervals of 10 cm on
the surface, including within the concavities". The positions come from
:func:`mavac.geometry.machines.dust_heaps` (the rule of notebook 01: upward-facing faces,
concavities included, Poisson-disk spacing), drawn with the trial's seed, so each trial has its
own layout. Each heap is a green visual-only sphere in pybullet (the camera sees it, nothing
collides with it); a vacuumed heap's body is removed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.machines import Machine, dust_heaps
from ..params import DustParams
from ..validate import check_instance, check_int, check_points


def heaps_for_trial(machine: Machine, dust: DustParams, seed: int) -> np.ndarray:
    """(n, 3) heap positions (m) on ``machine`` for the trial with this ``seed``; (0, 3) when
    the machine has no upward-facing surface."""
    check_instance("machine", machine, Machine)
    check_instance("dust", dust, DustParams)
    seed = check_int("seed", seed, 0, 2**31 - 1)
    return dust_heaps(machine, spacing=dust.spacing, seed=seed)


@dataclass
class DustField:
    """The heaps of a trial inside a :class:`mavac.sim.world.SimWorld`.

    Attributes
    ----------
    positions : (n, 3) float, metres
    bodies : (n,) int
        pybullet body id of each heap.
    present : (n,) bool
        Heaps not vacuumed yet.
    """

    positions: np.ndarray
    bodies: np.ndarray
    present: np.ndarray = field(default=None)

    def __post_init__(self):
        if self.present is None:
            self.present = np.ones(len(self.positions), dtype=bool)

    @classmethod
    def add_to(cls, world, positions, dust: DustParams) -> DustField:
        """Create one green visual sphere per heap in ``world``."""
        P = check_points("positions", positions) if len(positions) else np.zeros((0, 3))
        ids = world.add_visual_spheres(P, dust.radius, dust.rgba) if len(P) else []
        return cls(P, np.asarray(ids, dtype=np.int64))

    def index_of_bodies(self, body_ids) -> np.ndarray:
        """Heap index of each pybullet body id (-1 for bodies that are not heaps)."""
        lookup = {int(b): i for i, b in enumerate(self.bodies)}
        return np.array([lookup.get(int(b), -1) for b in np.asarray(body_ids).reshape(-1)], dtype=np.int64)

    def suck(self, world, tool_centre, radius: float) -> np.ndarray:
        """Remove the present heaps within ``radius`` (m) of ``tool_centre`` (3,); returns their
        indices."""
        if not self.present.any():
            return np.zeros(0, dtype=np.int64)
        d = np.linalg.norm(self.positions - np.asarray(tool_centre, dtype=float), axis=1)
        hit = np.flatnonzero(self.present & (d <= radius))
        for i in hit:
            world.remove_body(int(self.bodies[i]))
        self.present[hit] = False
        return hit

    @property
    def cleaned(self) -> np.ndarray:
        """(n,) bool: vacuumed heaps."""
        return ~self.present
