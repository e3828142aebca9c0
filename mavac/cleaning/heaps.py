"""Dust heaps of one trial: where they lie, their bodies in the simulation, which are left.

MAVAC ("Experimental setup"): "green dust heaps are evenly distributed at intervals of 10 cm on
the surface, including within the concavities". The positions come from
:func:`mavac.geometry.machines.dust_heaps` (the rule of notebook 01: upward-facing faces,
concavities included, Poisson-disk spacing), drawn with the trial's seed, so each trial has its
own layout. Each heap is a green visual-only sphere in pybullet (the camera sees it, nothing
collides with it), present in the world only while the camera renders
(:meth:`DustField.in_view`): pybullet steps every body, collision-free or not, and a paper-scale
scene's ~150 heaps cost a quarter of every physics step.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from ..geometry.machines import Machine, dust_heaps
from ..params import DustParams
from ..seeding import rng_for
from ..validate import check_instance, check_int, check_points


def heaps_for_trial(machine: Machine, dust: DustParams, seed: int) -> np.ndarray:
    """(n, 3) heap positions (m) on ``machine`` for the trial with this ``seed``; (0, 3) when
    the machine has no upward-facing surface.

    With ``dust.density`` below 1, the trial keeps ``round(density * n)`` heaps of the full
    layout, drawn without replacement with the seed (stage ``"dust density"``), in their order:
    a sparser trial's heaps are a subset of the full trial's with the same seed."""
    check_instance("machine", machine, Machine)
    check_instance("dust", dust, DustParams)
    seed = check_int("seed", seed, 0, 2**31 - 1)
    heaps = dust_heaps(machine, spacing=dust.spacing, seed=seed)
    return heaps[density_subset(len(heaps), dust.density, seed)]


def density_subset(n: int, density: float, seed: int) -> np.ndarray:
    """(round(density * n),) int, increasing: which of a full layout's ``n`` heaps a trial with
    ``density`` and ``seed`` keeps (all of them at density 1)."""
    if density == 1.0:
        return np.arange(n)
    return np.sort(rng_for(seed, "dust density").choice(n, size=round(density * n), replace=False))


#: Ours: metres a tool centre keeps from the suction radius before :meth:`DustField.suck` skips
#: the test (far above the rounding of a distance, so skipping never changes an answer).
SUCK_SLACK = 1e-9
_NONE = np.zeros(0, dtype=np.intp)


@dataclass
class DustField:
    """The heaps of a trial: where they lie, which are left, and how they look.

    Attributes
    ----------
    positions : (n, 3) float, metres
    radius : float, metres
        Radius of each heap's sphere in the images.
    rgba : (4,) float in [0, 1]
        Colour of the heaps in the images.
    present : (n,) bool
        Heaps not vacuumed yet.
    """

    positions: np.ndarray
    radius: float
    rgba: tuple
    present: np.ndarray = field(default=None)
    # Every physics step of a vacuum move asks :meth:`suck`: the present heaps' indices and
    # positions are kept between two hits, and the tool centre of the last full test with how
    # far it may move from there before any heap can be within the radius.
    _left: np.ndarray = field(default=None, init=False, repr=False)
    _left_positions: np.ndarray = field(default=None, init=False, repr=False)
    _tested_at: tuple = field(default=None, init=False, repr=False)  # (centre (3,), radius, free distance)

    def __post_init__(self):
        if self.present is None:
            self.present = np.ones(len(self.positions), dtype=bool)

    @classmethod
    def of(cls, positions, dust: DustParams) -> DustField:
        """The heaps at ``positions`` (n, 3), m, all present, drawn as ``dust`` says."""
        check_instance("dust", dust, DustParams)
        P = check_points("positions", positions) if len(positions) else np.zeros((0, 3))
        return cls(P, float(dust.radius), tuple(dust.rgba))

    @contextmanager
    def in_view(self, world, where=None) -> Iterator[np.ndarray]:
        """The present heaps as green visual spheres in ``world`` for the duration of the block
        (a render); yields (n,) int, the pybullet body id of each heap (-1 for the others).
        ``where`` (n,) bool, optional, limits them to the heaps that can show in the image
        (creating a body costs a third of a millisecond). The bodies are removed on leaving,
        newest first, so the bodies created before keep their order in pybullet's world."""
        index = np.flatnonzero(self.present if where is None else self.present & where)
        ids = world.add_visual_spheres(self.positions[index], self.radius, self.rgba) if len(index) else []
        bodies = np.full(len(self.positions), -1, dtype=np.int64)
        bodies[index] = ids
        try:
            yield bodies
        finally:
            for body in reversed(ids):
                world.remove_body(body)

    @staticmethod
    def index_of_bodies(body_ids, bodies) -> np.ndarray:
        """Heap index of each pybullet body id (-1 for bodies that are not heaps), given the
        heaps' ``bodies`` (n,) yielded by :meth:`in_view`."""
        lookup = {int(b): i for i, b in enumerate(bodies) if b >= 0}
        return np.array([lookup.get(int(b), -1) for b in np.asarray(body_ids).reshape(-1)], dtype=np.int64)

    def suck(self, tool_centre, radius: float) -> np.ndarray:
        """Mark the present heaps within ``radius`` (m) of ``tool_centre`` (3,) float as vacuumed;
        returns their indices. Only this method changes ``present`` during a trial.

        A tool centre closer to the last fully tested one than that test's distance from the
        radius to the nearest heap (less :data:`SUCK_SLACK`) cannot reach a heap: nothing is
        computed then (the triangle inequality), and the answer is the full test's."""
        if self._tested_at is not None:
            at, r, free = self._tested_at
            m = tool_centre - at
            if r == radius and math.sqrt(m.dot(m)) < free:
                return _NONE
        if self._left is None:
            self._left = np.flatnonzero(self.present)
            self._left_positions = self.positions[self._left]
        d = self._left_positions - tool_centre
        dist = np.sqrt(np.add.reduce(d * d, axis=1))  # numpy's norm, without its overhead
        hit = self._left[dist <= radius]
        if len(hit):
            self.present[hit] = False
            self._left, self._tested_at = None, None
        else:
            free = float(dist.min()) - radius - SUCK_SLACK if len(dist) else math.inf
            self._tested_at = (np.array(tool_centre, dtype=float), radius, free)
        return hit

    @property
    def cleaned(self) -> np.ndarray:
        """(n,) bool: vacuumed heaps."""
        return ~self.present
