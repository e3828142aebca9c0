"""One home for random streams: every stochastic step draws from a stream spawned from the
user's seed, the name of its stage and its indices.

``rng_for(seed, "approach", guard, area)`` is a ``numpy.random.Generator``;
``int_seed(seed, "rrt", plan)`` is an integer seed for libraries that take one (OMPL, Open3D).
Streams of different stages or indices are independent (``numpy.random.SeedSequence``), so
consecutive plans never share a seed, and adding a stage never shifts another's stream.
The seed is checked once, by :func:`check_seed`.
"""

from __future__ import annotations

import zlib

import numpy as np

from .validate import check_int

#: Largest seed accepted: Open3D and OMPL take signed 32-bit seeds.
MAX_SEED = 2**31 - 1


def check_seed(seed, name: str = "seed") -> int:
    """``seed`` as an int in ``[0, MAX_SEED]``, else ``ValueError``/``TypeError`` naming it."""
    return check_int(name, seed, 0, MAX_SEED)


def _stage_key(stage: str) -> int:
    if not isinstance(stage, str) or not stage:
        raise TypeError(f"stage must be a non-empty str, got {stage!r}")
    return zlib.crc32(stage.encode())  # stable across runs, unlike hash()


def _sequence(seed: int, stage: str, indices) -> np.random.SeedSequence:
    keys = [check_int("index", i, 0) for i in indices]
    return np.random.SeedSequence([check_seed(seed), _stage_key(stage), *keys])


def rng_for(seed: int, stage: str, *indices: int) -> np.random.Generator:
    """Generator of stage ``stage`` at ``indices`` (non-negative ints) under ``seed``."""
    return np.random.default_rng(_sequence(seed, stage, indices))


def int_seed(seed: int, stage: str, *indices: int) -> int:
    """Integer seed in ``[1, MAX_SEED]`` of stage ``stage`` at ``indices`` under ``seed``
    (never 0: OMPL treats 0 as "seed from the clock")."""
    word = int(_sequence(seed, stage, indices).generate_state(1, np.uint32)[0])
    return 1 + word % MAX_SEED
