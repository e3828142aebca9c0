"""On-disk cache for expensive stages (reachability maps, reach sweeps).

Callers wrap their function with ``memory().cache(fn, ignore=[...])``, leaving out of the key
what does not change the result (worker counts) or hashes slowly (robot objects, which they
replace by a kinematic fingerprint). The key is the function's code and its hashed
arguments, so a change of input or parameter recomputes; joblib recomputes an entry it cannot
load, so a corrupt entry is never trusted.
"""

from __future__ import annotations

import functools

from joblib import Memory

from .config import cache_dir


@functools.lru_cache(maxsize=1)
def memory():
    """The package's ``joblib.Memory`` under :func:`mavac.config.cache_dir`."""
    return Memory(cache_dir(), verbose=0)

