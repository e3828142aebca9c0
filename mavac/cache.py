"""On-disk cache for expensive stages (reachability maps, reach sweeps).

Built on ``joblib.Memory``: the key is the function's code and its hashed arguments
(robot name, parameter dataclasses, arrays), so a change of input or parameter recomputes.
joblib recomputes an entry it cannot load, so a corrupt entry is never trusted.
"""

from __future__ import annotations

import functools


@functools.lru_cache(maxsize=1)
def memory():
    """The package's ``joblib.Memory`` under :func:`mavac.config.cache_dir`."""
    from joblib import Memory

    from .config import cache_dir

    return Memory(cache_dir(), verbose=0)


def cached(fn):
    """Decorator: cache ``fn`` on disk; the wrapped function is created lazily on first call."""
    state = {}

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if "f" not in state:
            state["f"] = memory().cache(fn)
        return state["f"](*args, **kwargs)

    wrapper.uncached = fn
    return wrapper
